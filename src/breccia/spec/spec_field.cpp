#include "breccia/spec/spec_field.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/spec/experiment.hpp"
#include "breccia/spec/toml_node.hpp"

namespace breccia {

double toml_real(const toml::node& n, const std::string& where, const std::string& key) {
  if (auto v = n.value<double>(); v && (n.is_floating_point() || n.is_integer())) return *v;
  throw InputError(where, key, show(n), "expected a number");
}
std::int64_t toml_integer(const toml::node& n, const std::string& where, const std::string& key) {
  if (n.is_integer()) return n.as_integer()->get();
  throw InputError(where, key, show(n), "expected an integer");
}
bool toml_bool(const toml::node& n, const std::string& where, const std::string& key) {
  if (n.is_boolean()) return n.as_boolean()->get();
  throw InputError(where, key, show(n), "expected true or false");
}
std::string toml_string(const toml::node& n, const std::string& where, const std::string& key) {
  if (n.is_string()) return n.as_string()->get();
  throw InputError(where, key, show(n), "expected a string");
}

std::string toml_quoted(const std::string& v) {
  std::string out = "\"";
  for (const char c : v) {
    if (c == '"' || c == '\\')
      out += std::string("\\") + c;
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      out += fmt::format("\\u{:04x}", static_cast<unsigned>(static_cast<unsigned char>(c)));
    else
      out += c;
  }
  return out + "\"";
}

namespace {

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};

Range range_of(const SpecField& f) {
  return {f.min, f.max, f.min_inclusive, f.max_inclusive,
          f.unit.empty() ? "-" : std::string(f.unit)};
}

template <class Int>
Int integer_in_range(const SpecField& f, const toml::node& n, const std::string& where,
                     const std::string& key) {
  const std::int64_t v = toml_integer(n, where, key);
  if (static_cast<double>(v) < f.min || static_cast<double>(v) > f.max)
    throw InputError(where, key, std::to_string(v), f.allowed());
  return static_cast<Int>(v);
}

std::string word(const SpecField& f, const toml::node& n, const std::string& where,
                 const std::string& key) {
  std::string v = toml_string(n, where, key);
  if (!f.choices.empty()) {
    if (std::find(f.choices.begin(), f.choices.end(), v) == f.choices.end())
      throw InputError(where, key, "\"" + v + "\"", f.allowed());
  } else if (static_cast<double>(v.size()) > f.max) {
    throw InputError(where, key,
                     "\"" + v.substr(0, 40) + "...\" (" + std::to_string(v.size()) + " characters)",
                     fmt::format("at most {} characters", f.max));
  }
  return v;
}

std::vector<double> number_list(const SpecField& f, const toml::node& n, const std::string& where,
                                const std::string& key) {
  const auto* arr = n.as_array();
  if (!arr) throw InputError(where, key, show(n), "expected an array of numbers, e.g. [1, 2]");
  std::vector<double> v;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const double x = toml_real(*arr->get(i), where, key);
    if (!(x >= f.min))
      throw InputError(where, key, show(n), "every value must be >= " + num(f.min));
    v.push_back(x);
  }
  return v;
}

}  // namespace

std::string SpecField::type() const {
  return std::visit(
      Overloaded{[](SpecRef<double>) { return std::string("number"); },
                 [](SpecRef<std::int64_t>) { return std::string("integer"); },
                 [](SpecRef<std::uint64_t>) { return std::string("integer"); },
                 [](SpecRef<bool>) { return std::string("boolean"); },
                 [](SpecRef<std::string>) { return std::string("string"); },
                 [](SpecRef<std::vector<double>>) { return std::string("array of numbers"); },
                 [](const CustomValue& c) { return std::string(c.type); }},
      value);
}

bool SpecField::is_integer() const noexcept {
  return std::holds_alternative<SpecRef<std::int64_t>>(value) ||
         std::holds_alternative<SpecRef<std::uint64_t>>(value);
}

std::string SpecField::allowed() const {
  if (!allowed_text.empty()) return std::string(allowed_text);
  if (is_integer())
    return fmt::format("allowed: integer {} <= value <= {}", static_cast<std::int64_t>(min),
                       static_cast<std::int64_t>(max));
  return std::visit(Overloaded{[&](SpecRef<double>) { return range_of(*this).allowed(); },
                               [](SpecRef<bool>) { return std::string("true or false"); },
                               [&](SpecRef<std::string>) {
                                 if (choices.empty())
                                   return fmt::format("text of at most {} characters", max);
                                 std::string s = "allowed: ";
                                 for (std::size_t i = 0; i < choices.size(); ++i)
                                   s += (i ? ", " : "") + std::string("\"") + choices[i] + "\"";
                                 return s;
                               },
                               [&](SpecRef<std::vector<double>>) { return "each >= " + num(min); },
                               [](const CustomValue& c) { return c.allowed(); },
                               [](auto) { return std::string(); }},
                    value);
}

void SpecField::set(ExperimentSpec& s, const toml::node& n, const std::string& where,
                    const std::string& full_key) const {
  std::visit(Overloaded{[&](SpecRef<double> ref) {
                          const double v = toml_real(n, where, full_key);
                          if (!range_of(*this).contains(v))
                            throw InputError(where, full_key, num(v), allowed());
                          ref(s) = v;
                        },
                        [&](SpecRef<std::int64_t> ref) {
                          ref(s) = integer_in_range<std::int64_t>(*this, n, where, full_key);
                        },
                        [&](SpecRef<std::uint64_t> ref) {
                          ref(s) = integer_in_range<std::uint64_t>(*this, n, where, full_key);
                        },
                        [&](SpecRef<bool> ref) { ref(s) = toml_bool(n, where, full_key); },
                        [&](SpecRef<std::string> ref) { ref(s) = word(*this, n, where, full_key); },
                        [&](SpecRef<std::vector<double>> ref) {
                          ref(s) = number_list(*this, n, where, full_key);
                        },
                        [&](const CustomValue& c) { c.set(s, n, where, full_key); }},
             value);
}

std::string SpecField::get(const ExperimentSpec& spec) const {
  // The references are to the spec's own members; reading through them changes nothing.
  ExperimentSpec& s = const_cast<ExperimentSpec&>(spec);
  return std::visit(
      Overloaded{[&](SpecRef<double> ref) { return fmt::format("{}", ref(s)); },
                 [&](SpecRef<std::int64_t> ref) { return std::to_string(ref(s)); },
                 [&](SpecRef<std::uint64_t> ref) { return std::to_string(ref(s)); },
                 [&](SpecRef<bool> ref) { return std::string(ref(s) ? "true" : "false"); },
                 [&](SpecRef<std::string> ref) { return toml_quoted(ref(s)); },
                 [&](SpecRef<std::vector<double>> ref) {
                   std::string out = "[";
                   for (std::size_t i = 0; i < ref(s).size(); ++i)
                     out += (i ? ", " : "") + fmt::format("{}", ref(s)[i]);
                   return out + "]";
                 },
                 [&](const CustomValue& c) { return c.get(spec); }},
      value);
}

}  // namespace breccia
