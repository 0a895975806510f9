#pragma once
// Shortest round-trip text of a number, for error messages and files.
#include <fmt/format.h>

#include <string>

namespace breccia {
inline std::string num(double v) {
  return fmt::format("{}", v);
}
}  // namespace breccia
