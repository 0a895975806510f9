#pragma once
// One table per law: every parameter with its key, SI unit, default, allowed range and a one-line
// description. The same table validates input files, fills defaults and generates the docs
// (ARCHITECTURE.md, "How to add...").
#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <variant>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// An allowed interval of a real value, with the text that error messages and docs show.
struct Range {
  double min = -kInf, max = kInf;
  bool min_inclusive = true, max_inclusive = true;
  std::string unit = "-";  // "-" for dimensionless
  bool whole = false;      // whole numbers only (counts)

  bool contains(double v) const noexcept {
    if (!std::isfinite(v)) return false;
    if (whole && v != std::floor(v)) return false;
    if (min_inclusive ? v < min : v <= min) return false;
    if (max_inclusive ? v > max : v >= max) return false;
    return true;
  }
  std::string allowed() const {
    std::string s = whole ? "allowed: a whole number, " : "allowed: ";
    if (min > -kInf && max < kInf)
      s += num(min) + (min_inclusive ? " <= " : " < ") + "value" +
           (max_inclusive ? " <= " : " < ") + num(max);
    else if (min > -kInf)
      s += "value" + std::string(min_inclusive ? " >= " : " > ") + num(min);
    else if (max < kInf)
      s += "value" + std::string(max_inclusive ? " <= " : " < ") + num(max);
    else
      s += "any finite value";
    if (unit != "-" && !unit.empty()) s += " " + unit;
    return s;
  }
};

template <class P>
struct ParamField {
  std::string_view key;
  std::string_view unit;  // "-" for dimensionless
  std::variant<double P::*, bool P::*> member;
  double min = -kInf;  // ignored for flags
  double max = kInf;
  bool min_inclusive = true;
  bool max_inclusive = true;
  std::string_view doc;
  bool whole = false;  // a count: whole numbers only

  bool is_flag() const noexcept { return std::holds_alternative<bool P::*>(member); }

  Range range() const { return {min, max, min_inclusive, max_inclusive, std::string(unit), whole}; }
  std::string allowed() const { return is_flag() ? "must be true or false" : range().allowed(); }
  bool in_range(double v) const noexcept { return range().contains(v); }

  // Sets a real parameter, throwing an InputError naming `where` if it is out of range.
  void set(P& p, double v, const std::string& where, const std::string& prefix = "") const {
    if (is_flag()) throw InputError(where, prefix + std::string(key), num(v), allowed());
    if (!in_range(v)) throw InputError(where, prefix + std::string(key), num(v), allowed());
    p.*std::get<double P::*>(member) = v;
  }
  void set_flag(P& p, bool v, const std::string& where, const std::string& prefix = "") const {
    if (!is_flag())
      throw InputError(where, prefix + std::string(key), v ? "true" : "false",
                       "expects a number: " + allowed());
    p.*std::get<bool P::*>(member) = v;
  }
  std::string default_text(const P& defaults) const {
    if (is_flag()) return defaults.*std::get<bool P::*>(member) ? "true" : "false";
    return num(defaults.*std::get<double P::*>(member));
  }
};

// Checks every field of an already-filled Params against its table (for Params built in C++).
template <class Law>
void validate_params(const typename Law::Params& p, const std::string& where) {
  for (const auto& f : Law::fields()) {
    if (f.is_flag()) continue;
    const double v = p.*std::get<double Law::Params::*>(f.member);
    if (!f.in_range(v)) throw InputError(where, std::string(f.key), num(v), f.allowed());
  }
}

}  // namespace breccia
