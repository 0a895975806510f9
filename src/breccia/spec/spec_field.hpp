#pragma once
// The experiment file as data: one SpecField per key (its section, name, unit, where its value
// lives in ExperimentSpec, the allowed range or words, and what it means), like the laws' and
// tests' ParamField tables. Parsing, validation, the resolved experiment.toml, `--set` and the
// generated docs/experiment.md all read these tables (spec/sections.cpp); a new key is one row.
//
// The sections [contact], [bond], [joint] and [test] name a registered type (a law, a lab test)
// whose own table holds their further keys: a RegistrySection reaches that table.
#include <toml++/toml.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

struct ExperimentSpec;

// Where a key's value lives in the spec: a function that returns a reference to it.
template <class V>
using SpecRef = V& (*)(ExperimentSpec&);

// s.*Member, and (s.*Outer).*Inner for the keys of a nested struct (the engine's settings).
template <auto Member>
auto& spec_member(ExperimentSpec& s) {
  return s.*Member;
}
template <auto Outer, auto Inner>
auto& spec_nested(ExperimentSpec& s) {
  return (s.*Outer).*Inner;
}

// A key whose value is none of the plain kinds (the lattice's cells, the joint planes, a
// registered type's name, the material preset): its own parse, TOML text and allowed text.
struct CustomValue {
  void (*set)(ExperimentSpec&, const toml::node&, const std::string& where, const std::string& key);
  std::string (*get)(const ExperimentSpec&);
  std::string (*allowed)();
  std::string_view type;
};

struct SpecField {
  std::string_view section;  // "" for the top level
  std::string_view key;
  std::string_view unit;  // "" when dimensionless or not a number
  std::variant<SpecRef<double>, SpecRef<std::int64_t>, SpecRef<std::uint64_t>, SpecRef<bool>,
               SpecRef<std::string>, SpecRef<std::vector<double>>, CustomValue>
      value;
  std::string_view doc;
  // Numbers: the allowed interval (integers: inclusive bounds). Words: the most characters of
  // free text when `choices` is empty. Lists: the smallest entry.
  double min = -kInf, max = kInf;
  bool min_inclusive = true, max_inclusive = true;
  std::vector<std::string> choices;  // words: the allowed ones
  std::string_view allowed_text;     // replaces the generated "allowed: ..." when given

  std::string type() const;     // "number", "integer", "string", ...
  std::string allowed() const;  // what an error and the docs say is allowed
  bool is_integer() const noexcept;
  // Reads `node` into the spec; InputError naming `where` and `full_key` when it is not allowed.
  void set(ExperimentSpec& s, const toml::node& node, const std::string& where,
           const std::string& full_key) const;
  std::string get(const ExperimentSpec& s) const;  // the value as TOML text
};

// A section whose `selector` key ("law", "kind") names a registered type, and whose further keys
// come from that type's own table.
struct RegistrySection {
  std::string_view section, selector;
  std::string_view what;  // "law", "test kind": in messages and docs
  // Sets `key` of the chosen type's parameters; false when it has no such key.
  bool (*set_key)(ExperimentSpec&, const std::string& key, const toml::node&,
                  const std::string& where, const std::string& full_key);
  std::string (*chosen)(const ExperimentSpec&);    // the chosen type's name
  std::string (*key_list)(const ExperimentSpec&);  // its keys, comma-separated
  std::string (*dump)(const ExperimentSpec&);      // its "key = value" lines
  // A table per registered type, headed "`section` selector `name`".
  std::string (*docs)(std::string_view section, std::string_view selector);
};

// Every key of the experiment file, section by section, in the order of the resolved file and
// the docs: the top level, [engine], [material], [sample], [contact], [bond], [joint], [test],
// [output], [ae].
const std::vector<SpecField>& spec_fields();
const std::vector<RegistrySection>& registry_sections();
// The section names in order ("" first: the top level).
const std::vector<std::string_view>& spec_sections();

// Typed reads of a TOML value: InputError naming `where` and `key` when it has another type.
double toml_real(const toml::node& n, const std::string& where, const std::string& key);
std::int64_t toml_integer(const toml::node& n, const std::string& where, const std::string& key);
bool toml_bool(const toml::node& n, const std::string& where, const std::string& key);
std::string toml_string(const toml::node& n, const std::string& where, const std::string& key);
// A TOML basic string: quotes, backslashes and control characters escaped.
std::string toml_quoted(const std::string& v);

}  // namespace breccia

namespace breccia {

// Sets `name` of a registered type's parameters (a law's, a test's) from its own table; false
// when the table has no such key.
template <class T>
bool set_table_key(typename T::Params& p, const std::string& name, const toml::node& n,
                   const std::string& where, const std::string& full_key) {
  for (const auto& f : T::fields()) {
    if (f.key != name) continue;
    if (f.is_flag()) {
      f.set_flag(p, toml_bool(n, where, full_key), where, "");
    } else {
      const double v = toml_real(n, where, full_key);
      if (!f.in_range(v)) throw InputError(where, full_key, num(v), f.allowed());
      p.*std::get<double T::Params::*>(f.member) = v;
    }
    return true;
  }
  return false;
}

}  // namespace breccia
