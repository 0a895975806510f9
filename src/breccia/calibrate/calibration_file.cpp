#include "breccia/calibrate/calibration_file.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "breccia/core/error.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/spec/toml_node.hpp"

namespace breccia {

std::string_view stage_name(CalibrationStage s) noexcept {
  switch (s) {
    case CalibrationStage::Elastic:
      return "elastic";
    case CalibrationStage::Strength:
      return "strength";
    case CalibrationStage::Friction:
      return "friction";
  }
  return "?";
}

const std::vector<PropertyInfo>& property_table() {
  using S = CalibrationStage;
  static const std::vector<PropertyInfo> table{
      {Property::YoungsModulus, "youngs_modulus", "Pa",
       "Young's modulus E_t50 of the UCS test (ISRM tangent at 50 % of the peak, read with the "
       "sample gauge)",
       S::Elastic, true, 0.05, 0.5},
      {Property::PoissonRatio, "poisson_ratio", "-",
       "Poisson's ratio of the UCS test (lateral over axial strain at 50 % of the peak)",
       S::Elastic, false, 0.03, 0.2},
      {Property::UniaxialStrength, "uniaxial_strength", "Pa", "UCS: peak axial stress, sigma_3 = 0",
       S::Strength, true, 0.05, 0.5},
      {Property::TensileStrength, "tensile_strength", "Pa",
       "tensile strength: Brazilian 2 F / (pi D t), or direct F / A with calibration.tensile_test "
       "= \"direct_tension\"",
       S::Strength, true, 0.10, 0.5},
      {Property::CrackInitiationRatio, "crack_initiation_ratio", "-",
       "crack-initiation stress over the UCS", S::Strength, false, 0.05, 0.3},
      {Property::StrainAtPeak, "strain_at_peak", "-",
       "axial strain at the UCS peak (critical strain)", S::Strength, true, 0.10, 0.5},
      {Property::Cohesion, "cohesion", "Pa",
       "Mohr-Coulomb cohesion from the UCS and the triaxial peaks", S::Friction, true, 0.10, 0.5},
      {Property::FrictionAngle, "friction_angle_deg", "deg",
       "Mohr-Coulomb friction angle from the UCS and the triaxial peaks", S::Friction, false, 2.0,
       15.0},
  };
  return table;
}

const PropertyInfo& info(Property p) {
  for (const auto& i : property_table())
    if (i.property == p) return i;
  throw InternalError("unknown property");
}

std::vector<std::string> CalibrationSpec::fit_sets() const {
  if (fit_seeds.empty()) return {"calibration"};
  std::vector<std::string> sets;
  for (auto seed : fit_seeds) sets.push_back(fmt::format("fit-{}", seed));
  return sets;
}

bool CalibrationSpec::has_target(Property p) const {
  return target(p) != nullptr;
}
const Target* CalibrationSpec::target(Property p) const {
  for (const auto& t : targets)
    if (t.property == p) return &t;
  return nullptr;
}

namespace {

// The micro-parameters a calibration may free, and the stage that fits each.
struct FreeKeyInfo {
  std::string_view key;
  CalibrationStage stage;
};
constexpr FreeKeyInfo kFreeKeys[] = {
    {"bond.modulus", CalibrationStage::Elastic},
    {"bond.stiffness_ratio", CalibrationStage::Elastic},
    {"bond.shear_modulus", CalibrationStage::Elastic},
    {"bond.poisson_ratio", CalibrationStage::Elastic},
    {"bond.radius_multiplier", CalibrationStage::Elastic},
    {"contact.modulus", CalibrationStage::Elastic},
    {"contact.stiffness_ratio", CalibrationStage::Elastic},
    {"contact.shear_modulus", CalibrationStage::Elastic},
    {"contact.poisson_ratio", CalibrationStage::Elastic},
    {"sample.bond_gap_tolerance", CalibrationStage::Elastic},
    {"bond.tensile_strength", CalibrationStage::Strength},
    {"bond.cohesion", CalibrationStage::Strength},
    {"bond.tensile_strength_sd", CalibrationStage::Strength},
    {"bond.cohesion_sd", CalibrationStage::Strength},
    {"bond.moment_factor", CalibrationStage::Strength},
    {"bond.bonded_fraction", CalibrationStage::Strength},
    {"bond.gapped_fraction", CalibrationStage::Strength},
    {"bond.installation_gap", CalibrationStage::Strength},
    {"contact.friction", CalibrationStage::Friction},
    {"contact.rolling_friction", CalibrationStage::Friction},
    {"contact.twisting_friction", CalibrationStage::Friction},
    {"bond.friction_angle_deg", CalibrationStage::Friction},
    {"bond.friction", CalibrationStage::Friction},
    {"bond.residual_cohesion", CalibrationStage::Friction},
};

std::string free_key_list() {
  std::string s;
  for (const auto& k : kFreeKeys) s += (s.empty() ? "" : ", ") + std::string(k.key);
  return s;
}

double real_of(const toml::node& n, const std::string& where, const std::string& key) {
  if (auto v = n.value<double>();
      v && (n.is_floating_point() || n.is_integer()) && std::isfinite(*v))
    return *v;
  throw InputError(where, key, show(n), "expected a finite number");
}

std::int64_t int_of(const toml::node& n, const std::string& where, const std::string& key,
                    std::int64_t lo, std::int64_t hi) {
  if (!n.is_integer()) throw InputError(where, key, show(n), "expected an integer");
  const std::int64_t v = n.as_integer()->get();
  if (v < lo || v > hi)
    throw InputError(where, key, show(n), fmt::format("allowed: {} to {}", lo, hi));
  return v;
}

// Packing seeds: integers from 0, each once.
std::vector<std::int64_t> seeds_of(const toml::node& n, const std::string& where,
                                   const std::string& key) {
  const auto* a = n.as_array();
  if (!a) throw InputError(where, key, show(n), "expected an array of seeds (integers)");
  std::vector<std::int64_t> seeds;
  for (const auto& s : *a) {
    const std::int64_t seed = int_of(s, where, key, 0, std::numeric_limits<std::int64_t>::max());
    if (std::find(seeds.begin(), seeds.end(), seed) != seeds.end())
      throw InputError(where, key, show(n), fmt::format("seed {} twice: each seed once", seed));
    seeds.push_back(seed);
  }
  return seeds;
}

std::string string_of(const toml::node& n, const std::string& where, const std::string& key) {
  if (!n.is_string()) throw InputError(where, key, show(n), "expected a string");
  return n.as_string()->get();
}

std::vector<double> reals_of(const toml::node& n, const std::string& where,
                             const std::string& key) {
  const auto* a = n.as_array();
  if (!a) throw InputError(where, key, show(n), "expected an array of numbers");
  std::vector<double> out;
  for (const auto& v : *a) out.push_back(real_of(v, where, key));
  return out;
}

// The value of an experiment key ("section.name") in the resolved spec, if it is a number.
std::optional<double> resolved_number(const ExperimentSpec& spec, const std::string& key) {
  const toml::table t = toml::parse(to_toml(spec), std::string_view("resolved"));
  if (key.find('.') == std::string::npos) return std::nullopt;
  const auto* node = t.at_path(key).node();
  if (!node || !(node->is_floating_point() || node->is_integer())) return std::nullopt;
  return node->value<double>();
}

Target read_target(const std::string& name, const toml::node& n, const std::string& source) {
  const std::string where = where_of(source, n), key = "targets." + name;
  const PropertyInfo* pi = nullptr;
  for (const auto& i : property_table())
    if (i.key == name) pi = &i;
  if (!pi) {
    std::string allowed;
    for (const auto& i : property_table())
      allowed += (allowed.empty() ? "" : ", ") + std::string(i.key);
    throw InputError(where, key, "", "unknown target; allowed: " + allowed);
  }
  Target t{pi->property, 0.0, pi->tolerance, pi->relative, ""};
  if (const auto* tbl = n.as_table()) {
    for (const auto& [k, v] : *tbl) {
      const std::string item(k.str()), w = where_of(source, v);
      if (item == "value")
        t.value = real_of(v, w, key + ".value");
      else if (item == "tolerance")
        t.tolerance = real_of(v, w, key + ".tolerance");
      else if (item == "source")
        t.source = string_of(v, w, key + ".source");
      else
        throw InputError(w, key + "." + item, show(v),
                         "unknown key; allowed: value, tolerance, source");
    }
    if (!tbl->contains("value")) throw InputError(where, key, "", "needs a value");
  } else {
    t.value = real_of(n, where, key);
  }
  const std::string unit = t.relative ? "a fraction of the target, e.g. 0.05"
                                      : fmt::format("in {}, e.g. {}", pi->unit, pi->tolerance);
  if (!(t.tolerance > 0.0 && t.tolerance <= pi->max_tolerance))
    throw InputError(where, key + ".tolerance", fmt::format("{}", t.tolerance),
                     fmt::format("allowed: above 0 and at most {} ({}); a looser tolerance "
                                 "would count every trial as met",
                                 pi->max_tolerance, unit));
  const bool ok = pi->property == Property::PoissonRatio           ? t.value > -1 && t.value < 0.5
                  : pi->property == Property::FrictionAngle        ? t.value > 0 && t.value < 90
                  : pi->property == Property::CrackInitiationRatio ? t.value > 0 && t.value < 1
                                                                   : t.value > 0;
  if (!ok)
    throw InputError(where, key + ".value", fmt::format("{}", t.value),
                     pi->property == Property::PoissonRatio    ? "allowed: -1 < nu < 0.5"
                     : pi->property == Property::FrictionAngle ? "allowed: 0 < phi < 90 degrees"
                     : pi->property == Property::CrackInitiationRatio
                         ? "allowed: between 0 and 1"
                         : "must be above 0 (" + std::string(pi->unit) + ")");
  return t;
}

// A free parameter: "bond.modulus" = [lower, upper] or { lower, upper, stage, scale }.
FreeParameter read_free(const std::string& name, const toml::node& n, const std::string& source) {
  const std::string where = where_of(source, n), key = "free.\"" + name + "\"";
  const FreeKeyInfo* fk = nullptr;
  for (const auto& k : kFreeKeys)
    if (k.key == name) fk = &k;
  if (!fk)
    throw InputError(where, key, "",
                     "not a micro-parameter calibration can free; allowed: " + free_key_list());
  FreeParameter f{name, 0.0, 0.0, 0.0, true, fk->stage};
  std::string scale;
  if (const auto* a = n.as_array()) {
    const auto v = reals_of(*a, where, key);
    if (v.size() != 2) throw InputError(where, key, show(n), "expected [lower, upper]");
    f.lower = v[0];
    f.upper = v[1];
  } else if (const auto* tbl = n.as_table()) {
    bool lo = false, hi = false;
    for (const auto& [k, v] : *tbl) {
      const std::string item(k.str()), w = where_of(source, v);
      if (item == "lower") {
        f.lower = real_of(v, w, key + ".lower");
        lo = true;
      } else if (item == "upper") {
        f.upper = real_of(v, w, key + ".upper");
        hi = true;
      } else if (item == "scale") {
        scale = string_of(v, w, key + ".scale");
        if (scale != "log" && scale != "linear")
          throw InputError(w, key + ".scale", show(v), "allowed: \"log\", \"linear\"");
      } else if (item == "stage") {
        const std::string s = string_of(v, w, key + ".stage");
        bool found = false;
        for (auto st :
             {CalibrationStage::Elastic, CalibrationStage::Strength, CalibrationStage::Friction})
          if (stage_name(st) == s) {
            f.stage = st;
            found = true;
          }
        if (!found)
          throw InputError(w, key + ".stage", show(v),
                           "allowed: \"elastic\", \"strength\", \"friction\"");
      } else {
        throw InputError(w, key + "." + item, show(v),
                         "unknown key; allowed: lower, upper, scale, stage");
      }
    }
    if (!lo || !hi) throw InputError(where, key, "", "needs lower and upper");
  } else {
    throw InputError(where, key, show(n),
                     "expected [lower, upper] or { lower = ..., upper = ... }");
  }
  if (!(f.lower < f.upper))
    throw InputError(where, key, fmt::format("[{}, {}]", f.lower, f.upper),
                     "impossible bounds: lower must be below upper");
  f.log_scale = scale.empty() ? f.lower > 0.0 : scale == "log";
  if (f.log_scale && !(f.lower > 0.0))
    throw InputError(where, key, fmt::format("[{}, {}]", f.lower, f.upper),
                     "a log-scale parameter needs bounds above 0 (or scale = \"linear\")");
  return f;
}

TiedParameter read_tied(const std::string& name, const toml::node& n, const std::string& source) {
  const std::string where = where_of(source, n), key = "tied.\"" + name + "\"";
  TiedParameter t{name, "", 1.0};
  const auto* tbl = n.as_table();
  if (!tbl) throw InputError(where, key, show(n), "expected { follows = \"...\", factor = ... }");
  for (const auto& [k, v] : *tbl) {
    const std::string item(k.str()), w = where_of(source, v);
    if (item == "follows") {
      t.follows = string_of(v, w, key + ".follows");
    } else if (item == "factor") {
      t.factor = real_of(v, w, key + ".factor");
      // A tie is a proportion between two micro-parameters of one sign (moduli, strengths,
      // frictions): a factor of 0 or below would send the tied key out of its range.
      if (!(t.factor > 0.0)) throw InputError(w, key + ".factor", show(v), "must be above 0");
    } else {
      throw InputError(w, key + "." + item, show(v), "unknown key; allowed: follows, factor");
    }
  }
  if (t.follows.empty()) throw InputError(where, key, "", "needs follows = \"<free parameter>\"");
  return t;
}

void read_settings(CalibrationSpec& c, const toml::table& tbl, const std::string& source) {
  for (const auto& [k, v] : tbl) {
    const std::string item(k.str()), w = where_of(source, v), key = "calibration." + item;
    if (item == "name") {
      c.name = string_of(v, w, key);
      const bool ok = !c.name.empty() && c.name.size() <= 100 &&
                      std::all_of(c.name.begin(), c.name.end(), [](char ch) {
                        return std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' ||
                               ch == '_' || ch == '.';
                      });
      if (!ok)
        throw InputError(w, key, show(v),
                         "1 to 100 letters, digits, '-', '_' or '.' (it names the folder)");
    } else if (item == "rock") {
      c.rock = string_of(v, w, key);
      if (c.rock.size() > 100) throw InputError(w, key, show(v), "at most 100 characters");
    } else if (item == "confining_stresses") {
      c.confining_stresses = reals_of(v, w, key);
      for (double s : c.confining_stresses)
        if (!(s > 0.0))
          throw InputError(w, key, show(v),
                           "every confining stress must be above 0 Pa (the UCS is always run)");
      std::sort(c.confining_stresses.begin(), c.confining_stresses.end());
      if (std::adjacent_find(c.confining_stresses.begin(), c.confining_stresses.end()) !=
          c.confining_stresses.end())
        throw InputError(w, key, show(v), "confining stresses must differ");
    } else if (item == "trials_per_stage") {
      c.trials_per_stage = int_of(v, w, key, 1, 200);
    } else if (item == "passes") {
      c.passes = int_of(v, w, key, 1, 5);
    } else if (item == "aim") {
      c.aim = real_of(v, w, key);
      if (!(c.aim >= 0.1 && c.aim <= 1.0))
        throw InputError(w, key, show(v), "a fraction of each tolerance from 0.1 to 1");
    } else if (item == "verify_seeds") {
      c.verify_seeds = seeds_of(v, w, key);
    } else if (item == "fit_seeds") {
      c.fit_seeds = seeds_of(v, w, key);
    } else if (item == "verify_set") {
      const auto* a = v.as_array();
      if (!a) throw InputError(w, key, show(v), "expected an array of \"section.key=value\"");
      c.verify_set.clear();
      for (const auto& s : *a) c.verify_set.push_back(string_of(s, w, key));
    } else if (item == "size_corrections") {
      c.size_corrections = int_of(v, w, key, 0, 5);
    } else if (item == "brazilian_diameter") {
      c.disc_diameter = real_of(v, w, key);
      if (!(c.disc_diameter > 0.0)) throw InputError(w, key, show(v), "must be above 0 m");
    } else if (item == "brazilian_thickness") {
      c.disc_thickness = real_of(v, w, key);
      if (!(c.disc_thickness > 0.0)) throw InputError(w, key, show(v), "must be above 0 m");
    } else if (item == "brazilian_platen_speed") {
      c.disc_platen_speed = real_of(v, w, key);
      if (!(c.disc_platen_speed > 0.0)) throw InputError(w, key, show(v), "must be above 0 m/s");
    } else if (item == "tensile_test") {
      c.tensile_test = string_of(v, w, key);
      if (c.tensile_test != "brazilian" && c.tensile_test != "direct_tension")
        throw InputError(w, key, show(v), "expected \"brazilian\" or \"direct_tension\"");
    } else if (item == "grip_speed") {
      c.grip_speed = real_of(v, w, key);
      if (!(c.grip_speed > 0.0)) throw InputError(w, key, show(v), "must be above 0 m/s");
    } else {
      throw InputError(w, key, show(v),
                       "unknown key; allowed: name, rock, confining_stresses, trials_per_stage, "
                       "passes, aim, fit_seeds, verify_seeds, verify_set, size_corrections, "
                       "tensile_test, brazilian_diameter, brazilian_thickness, "
                       "brazilian_platen_speed, grip_speed");
    }
  }
}

// A setting of a test the calibration does not run is refused, so that nobody takes it for one
// that shaped the result.
void check_settings_in_use(const CalibrationSpec& c, const toml::table& tbl,
                           const std::string& source) {
  if (const toml::node* v = tbl.get("confining_stresses"); v && !c.needs_envelope())
    throw InputError(where_of(source, *v), "calibration.confining_stresses", show(*v),
                     "the triaxial tests at these stresses run only for a targets.cohesion or "
                     "targets.friction_angle_deg, and neither is given");
  if (const toml::node* v = tbl.get("verify_set"); v && c.verify_seeds.empty())
    throw InputError(where_of(source, *v), "calibration.verify_set", show(*v),
                     "a setting of the verification tests, and calibration.verify_seeds = [] "
                     "runs none");
  const bool direct = c.tensile_test == "direct_tension";
  for (const std::string item : {"tensile_test", "brazilian_diameter", "brazilian_thickness",
                                 "brazilian_platen_speed", "grip_speed"}) {
    const toml::node* v = tbl.get(item);
    if (v && !c.needs_tensile())
      throw InputError(where_of(source, *v), "calibration." + item, show(*v),
                       "a setting of the tensile test, which runs only for a "
                       "targets.tensile_strength, and none is given");
    if (item == "tensile_test") continue;
    const bool for_direct = item == "grip_speed";
    if (v && for_direct != direct)
      throw InputError(where_of(source, *v), "calibration." + item, show(*v),
                       fmt::format("a setting of the {} test, which does not run: "
                                   "calibration.tensile_test is \"{}\"",
                                   for_direct ? "direct tension" : "Brazilian", c.tensile_test));
  }
}

// Every free parameter drives a stage with targets; every target the tests cannot measure is
// refused before anything runs.
void check_coverage(const CalibrationSpec& c, const toml::table& root, const std::string& source) {
  if (c.targets.empty())
    throw InputError(source, "[targets]", "", "a calibration needs at least one target");
  if (c.free.empty())
    throw InputError(source, "[free]", "", "a calibration needs at least one free parameter");
  for (const auto& f : c.free) {
    bool has = false;
    std::string stage_targets;
    for (const auto& i : property_table())
      if (i.stage == f.stage)
        stage_targets += (stage_targets.empty() ? "" : ", ") + std::string(i.key);
    for (const auto& t : c.targets) has |= info(t.property).stage == f.stage;
    if (!has)
      throw InputError(where_of(source, *root.at_path("free").as_table()->get(f.key)),
                       "free.\"" + f.key + "\"", "",
                       fmt::format("the {} stage fits it, and none of that stage's targets ({}) "
                                   "is given; fix it in [experiment] or add a target",
                                   stage_name(f.stage), stage_targets));
  }
  if (c.needs_envelope() && c.confining_stresses.empty()) {
    const Property p =
        c.has_target(Property::Cohesion) ? Property::Cohesion : Property::FrictionAngle;
    throw InputError(
        where_of(source, *root.at_path("targets").as_table()->get(std::string(info(p).key))),
        "targets." + std::string(info(p).key), "",
        "cannot be measured without triaxial tests: set calibration.confining_stresses "
        "(e.g. [5e6, 10e6])");
  }
}

// The sample and the laws come from [experiment]: without it the calibration would fit the
// built-in default sample, which the user did not ask for.
void check_experiment_table(const toml::table& root, const std::string& source) {
  const auto* e = root["experiment"].as_table();
  if (!e || e->empty())
    throw InputError(source, "[experiment]", e ? "(empty)" : "(missing)",
                     "a calibration needs the experiment it calibrates: the sample and the laws "
                     "as [experiment.sample], [experiment.contact], [experiment.bond], ... "
                     "(docs/calibration.md)");
}

// Bounds must be values the experiment accepts, and the start inside them.
void check_parameters(CalibrationSpec& c, const toml::table& root, const std::string& source) {
  const auto* free_tbl = root.at_path("free").as_table();
  for (auto& f : c.free) {
    const std::string where = where_of(source, *free_tbl->get(f.key));
    const std::string key = "free.\"" + f.key + "\"";
    for (double b : {f.lower, f.upper}) {
      try {
        (void)parse_experiment_table(c.text, source, "experiment",
                                     {fmt::format("{}={:.17g}", f.key, b)});
      } catch (const InputError& e) {
        throw InputError(where, key, fmt::format("{}", b),
                         "bound not accepted by the experiment: " + std::string(e.what()));
      }
    }
    const auto start = resolved_number(c.base, f.key);
    if (!start)
      throw InputError(where, key, "",
                       "not a number of this experiment's laws (contact law \"" +
                           std::string(c.base.contact_law()) + "\")");
    f.start = *start;
    if (f.start < f.lower || f.start > f.upper)
      throw InputError(where, key, fmt::format("[{}, {}]", f.lower, f.upper),
                       fmt::format("the start value {} (from [experiment]) lies outside the "
                                   "bounds",
                                   f.start));
  }
  for (const auto& t : c.tied) {
    const std::string where = where_of(source, *root.at_path("tied").as_table()->get(t.key));
    const bool follows_free = std::any_of(c.free.begin(), c.free.end(),
                                          [&](const auto& f) { return f.key == t.follows; });
    if (!follows_free)
      throw InputError(where, "tied.\"" + t.key + "\".follows", "\"" + t.follows + "\"",
                       "must name a free parameter");
    if (std::any_of(c.free.begin(), c.free.end(), [&](const auto& f) { return f.key == t.key; }))
      throw InputError(where, "tied.\"" + t.key + "\"", "", "is also free");
    if (is_integer_key(t.key))
      throw InputError(where, "tied.\"" + t.key + "\"", "",
                       "an integer key cannot follow a free parameter (it would take fractional "
                       "values); tie a real-valued micro-parameter");
    if (!resolved_number(c.base, t.key))
      throw InputError(where, "tied.\"" + t.key + "\"", "",
                       "not a number of this experiment's laws");
    // The tied key takes factor x the free value: both ends of the free range must give a value
    // the experiment accepts.
    const FreeParameter& f = *std::find_if(c.free.begin(), c.free.end(),
                                           [&](const auto& x) { return x.key == t.follows; });
    for (double b : {f.lower, f.upper}) {
      try {
        (void)parse_experiment_table(c.text, source, "experiment",
                                     {fmt::format("{}={:.17g}", t.key, t.factor * b)});
      } catch (const InputError& e) {
        throw InputError(where, "tied.\"" + t.key + "\"", fmt::format("{} x {}", t.factor, b),
                         fmt::format("at the bound {} of {} the tied value is not accepted by the "
                                     "experiment: {}",
                                     b, t.follows, e.what()));
      }
    }
  }
}

void default_disc(CalibrationSpec& c) {
  const ExperimentSpec& b = c.base;
  const double across = b.dimension == 2        ? b.width
                        : b.shape == "cylinder" ? b.diameter
                                                : std::min(b.width, b.depth);
  if (c.disc_diameter <= 0.0) c.disc_diameter = across;
  if (c.disc_thickness <= 0.0) c.disc_thickness = b.dimension == 2 ? b.thickness : 0.5 * across;
}

}  // namespace

CalibrationSpec parse_calibration(const std::string& text, const std::string& source) {
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw InputError(source + ":" + std::to_string(e.source().begin.line), "", "",
                     std::string("TOML syntax error: ") + std::string(e.description()));
  }
  CalibrationSpec c;
  c.path = source;
  c.text = text;
  c.name = std::filesystem::path(source).stem().string();
  for (const auto& [k, v] : root) {
    const std::string name(k.str());
    if (name != "calibration" && name != "experiment" && name != "targets" && name != "free" &&
        name != "tied")
      throw InputError(where_of(source, v), name, "",
                       "unknown table; allowed: [calibration], [experiment], [targets], [free], "
                       "[tied]");
    if (!v.is_table()) throw InputError(where_of(source, v), name, show(v), "expected a table");
  }
  if (const auto* t = root["calibration"].as_table()) {
    read_settings(c, *t, source);
  }
  if (const auto* t = root["targets"].as_table())
    for (const auto& [k, v] : *t) c.targets.push_back(read_target(std::string(k.str()), v, source));
  if (const auto* t = root["free"].as_table())
    for (const auto& [k, v] : *t) c.free.push_back(read_free(std::string(k.str()), v, source));
  if (const auto* t = root["tied"].as_table())
    for (const auto& [k, v] : *t) c.tied.push_back(read_tied(std::string(k.str()), v, source));
  if (const auto* t = root["calibration"].as_table()) check_settings_in_use(c, *t, source);
  check_coverage(c, root, source);
  check_experiment_table(root, source);
  c.base = parse_experiment_table(text, source, "experiment", {});
  if (c.base.sample_source != "generate")
    throw InputError(source, "experiment.sample.source", "\"" + c.base.sample_source + "\"",
                     "a calibration packs its own samples (the prism, the Brazilian disc and one "
                     "per verification seed): allowed: \"generate\" (the default)");
  for (const auto& o : c.verify_set) {
    try {
      (void)parse_experiment_table(text, source, "experiment", {o});
    } catch (const InputError& e) {
      throw InputError(source, "calibration.verify_set", "\"" + o + "\"", e.what());
    }
  }
  if (c.size_corrections > 0 && c.verify_seeds.empty())
    throw InputError(source, "calibration.size_corrections", std::to_string(c.size_corrections),
                     "a size correction measures at the verification's size and packings: give "
                     "verify_seeds (and verify_set for another size), or size_corrections = 0");
  check_parameters(c, root, source);
  default_disc(c);
  return c;
}

CalibrationSpec load_calibration(const std::string& path) {
  return parse_calibration(read_text_file(path, "a calibration file (TOML)"), path);
}

std::vector<std::string> parameter_overrides(const CalibrationSpec& c,
                                             const std::vector<double>& values) {
  std::vector<std::string> o;
  for (std::size_t i = 0; i < c.free.size(); ++i)
    o.push_back(fmt::format("{}={:.17g}", c.free[i].key, values[i]));
  for (const auto& t : c.tied)
    for (std::size_t i = 0; i < c.free.size(); ++i)
      if (c.free[i].key == t.follows)
        o.push_back(fmt::format("{}={:.17g}", t.key, t.factor * values[i]));
  return o;
}

namespace {

// The [calibration] table's keys, for the reference.
std::string calibration_settings_docs() {
  return "### [calibration]\n\n| key | default | meaning |\n|---|---|---|\n"
         "| `name` | the file's stem | names the folder `<output>/<name>/` (letters, digits, -, _, "
         ".) "
         "|\n"
         "| `rock` | the name | the rock's name in the material library |\n"
         "| `confining_stresses` | none | sigma_3 of the triaxial (2D: biaxial) tests, Pa, above "
         "0; "
         "needed for `cohesion` and `friction_angle_deg` (fitted with the UCS as sigma_3 = 0) |\n"
         "| `trials_per_stage` | 10 | trials of one stage in one pass, 1 to 200 |\n"
         "| `passes` | 2 | passes over the three stages, 1 to 5 (stops early when every target is "
         "met) |\n"
         "| `aim` | 1 | fraction of each tolerance a trial must reach to count as met during the "
         "search, 0.1 to 1; the verdicts keep the full tolerance. Below 1 it leaves room for the "
         "drift between the calibration sample and a larger verification sample |\n"
         "| `fit_seeds` | [] | packing seeds of the search: each trial runs its tests on one "
         "packing per seed (the [experiment]'s sample with `engine.seed` set) and is judged on the "
         "mean of their properties, so that one packing's scatter does not steer the search; each "
         "trial then costs that many times the tests. Empty: the [experiment]'s own packing |\n"
         "| `verify_seeds` | [1, 2, 3] | packing seeds of the verification (empty: no "
         "verification; "
         "the verdict is then the calibration sample's) |\n"
         "| `verify_set` | [] | experiment overrides (`\"section.key=value\"`) of the "
         "verification, "
         "e.g. the shipping sample size |\n"
         "| `size_corrections` | 0 | rounds of size correction after the search, 0 to 5: each "
         "measures the parameters on the verification's size and packings; where a target is "
         "missed there, the search's targets are shifted by the gap between the two sizes "
         "(relative targets by their ratio, the others by their difference) and the search runs "
         "again on the small sample. It stops when every target is met at the verification size; "
         "each round costs one verification. Needs `verify_seeds` |\n"
         "| `tensile_test` | \"brazilian\" | the test that measures `tensile_strength`: "
         "\"brazilian\" (a disc split across a diameter, 2 F / (pi D t); its own packing) or "
         "\"direct_tension\" (the compression sample held by its ends in grips that pull apart, "
         "F / A; the test's default grips, two largest grain diameters). The two differ for a "
         "bonded-grain rock, whose disc fails under a stress gradient with its contacts compressed "
         "across the split (docs/analysis.md §1.11) |\n"
         "| `brazilian_diameter`, `brazilian_thickness` | the prism's width, half of it | the "
         "Brazilian disc, m, above 0 |\n"
         "| `brazilian_platen_speed` | 0.02 | m/s |\n"
         "| `grip_speed` | 0.02 | direct tension: each grip's speed, m/s, above 0 |\n\n"
         "The `brazilian_*` keys belong to the Brazilian test and `grip_speed` to direct tension; "
         "a key of the test that does not run is refused, and so is every key of the tensile test "
         "(`tensile_test` included) without a `tensile_strength` target, `confining_stresses` "
         "without a `cohesion` or `friction_angle_deg` target, and `verify_set` with `verify_seeds "
         "= []`.\n\n";
}

}  // namespace

std::string calibration_docs() {
  std::string s =
      "# Calibration file reference\n\n"
      "Generated by `build/breccia docs --calibration --output docs/calibration.md`; do not "
      "edit. A calibration file is TOML with the tables below; `breccia calibrate FILE` runs it "
      "(ARCHITECTURE.md, \"Calibration\", says how). Example: "
      "`examples/calibrate-berea.toml`.\n\n" +
      calibration_settings_docs() +
      "### [experiment]\n\nRequired. The keys of an experiment file (docs/experiment.md) as "
      "sub-tables (`[experiment.sample]`, `[experiment.bond]`, ...): the sample, the laws, the "
      "fixed micro-parameters and the start values of the free ones. The calibration sets the "
      "test kind itself (UCS, triaxial, Brazilian or direct tension) and packs its own samples, so "
      "`sample.source` is `\"generate\"`. Before the first trial (and with `--check`) the "
      "samples of every set are packed and each test is built on them at the start values and "
      "with every free parameter at its lower, then its upper bound: a test that could not run "
      "there (a disc too small for its grains, a run too long at the stiffest bound) is refused "
      "before anything runs.\n\n"
      "### [targets]\n\nEach target is `name = value` (the default tolerance) or "
      "`name = { value = ..., tolerance = ..., source = \"...\" }`.\n\n"
      "| target | unit | stage | default tolerance | loosest allowed | what is measured |\n"
      "|---|---|---|---|---|---|\n";
  auto tolerance = [](const PropertyInfo& i, double t) {
    return i.relative ? fmt::format("{:g} % of the target", 100 * t)
                      : fmt::format("{:g} {}", t, i.unit);
  };
  for (const auto& i : property_table())
    s += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", i.key, i.unit, stage_name(i.stage),
                     tolerance(i, i.tolerance), tolerance(i, i.max_tolerance), i.doc);
  s += "\n### [free]\n\n`\"section.key\" = [lower, upper]` or `{ lower, upper, scale = "
       "\"log\"|\"linear\", stage = ... }`. The keys a calibration can free, with the stage that "
       "fits each:\n\n| key | stage |\n|---|---|\n";
  for (const auto& k : kFreeKeys) s += fmt::format("| `{}` | {} |\n", k.key, stage_name(k.stage));
  s += "\n`sample.bond_gap_tolerance` is part of the sample's genesis: the gap up to which "
       "neighbours are bonded sets the bonds per grain, and with them the shear modulus and "
       "Poisson's ratio (docs/physics.md §7.6). Each value a trial asks for gets packings of its "
       "own, made as a run with that gap makes them (samples/<set>-bond_gap_tolerance=<value>-"
       "*.geom), and the calibrated rock's material.toml carries the gap in its [sample] table, "
       "so that a run of the preset bonds its grains as the calibration did. Bound it above 0 "
       "for a log scale, or give scale = \"linear\" to start from 0 (touching pairs only).\n";
  s += "\n### [tied]\n\n`\"section.key\" = { follows = \"<free key>\", factor = 1.0 }`: the "
       "key takes factor x the free parameter's value in every trial (e.g. contact modulus = "
       "bond modulus). The factor is above 0, the key a real-valued one (not the seed or a "
       "count), and factor x each bound of the free parameter a value the experiment accepts.\n";
  return s;
}

}  // namespace breccia
