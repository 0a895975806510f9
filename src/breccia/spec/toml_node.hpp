#pragma once
// What an input error says about a TOML value: where it came from and how it was written. Shared
// by the experiment and calibration files so that both name a bad value the same way.
#include <toml++/toml.h>

#include <sstream>
#include <string>

namespace breccia {

// "file:line" when known, the `--set` option that gave the value, or else the source's name.
inline std::string where_of(const std::string& source, const toml::node& n) {
  const auto& src = n.source();
  if (src.path && src.path->rfind("--set ", 0) == 0) return *src.path;
  if (src.begin.line > 0) return source + ":" + std::to_string(src.begin.line);
  return source;
}

// Where a table came from: a table that `--set section.key=...` made has no place in the file,
// so the option that made it is named instead.
inline std::string where_of_table(const std::string& source, const toml::node& n) {
  if (n.source().begin.line == 0 && n.is_table())
    for (auto&& [k, v] : *n.as_table())
      if (const std::string w = where_of(source, v); w != source) return w;
  return where_of(source, n);
}

// The value as the user wrote it (strings quoted).
inline std::string show(const toml::node& n) {
  std::ostringstream s;
  if (n.is_string())
    s << '"' << n.as_string()->get() << '"';
  else
    n.visit([&](const auto& v) { s << v; });
  return s.str();
}

}  // namespace breccia
