#pragma once
// The calibration file (TOML): lab targets with tolerances, the experiment that defines the sample
// and the laws ([experiment], the keys of an experiment file), the micro-parameters that are free
// (with bounds) or tied to a free one, and how to verify. Everything is checked here, before any
// run starts, with errors that name the file, the line, the key and what is allowed.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "breccia/spec/experiment.hpp"

namespace breccia {

// The staged scheme (ARCHITECTURE.md "Calibration"): elastic properties first, then strengths,
// then the friction that shapes the strength envelope.
enum class CalibrationStage { Elastic, Strength, Friction };
std::string_view stage_name(CalibrationStage s) noexcept;

// What a lab test measures and a calibration can target.
enum class Property {
  YoungsModulus,
  PoissonRatio,
  UniaxialStrength,
  TensileStrength,
  Cohesion,
  FrictionAngle,
  CrackInitiationRatio,
  StrainAtPeak,
};

struct PropertyInfo {
  Property property;
  std::string_view key, unit, doc;
  CalibrationStage stage;
  bool relative;     // tolerance as a fraction of the target (else in the property's unit)
  double tolerance;  // default tolerance
  // The loosest tolerance a target may ask for: beyond it every trial would count as met and
  // the calibration would fit nothing (a fraction for relative targets).
  double max_tolerance;
};
const std::vector<PropertyInfo>& property_table();
const PropertyInfo& info(Property p);

struct Target {
  Property property;
  double value = 0.0;
  double tolerance = 0.0;
  bool relative = true;
  std::string source;  // where the lab value comes from (for the record)
};

struct FreeParameter {
  std::string key;  // an experiment key, "section.name" (e.g. "bond.modulus")
  double lower = 0.0, upper = 0.0, start = 0.0;
  bool log_scale = true;  // searched in log space (bounds both above zero)
  CalibrationStage stage = CalibrationStage::Elastic;
};

// A key that follows a free parameter: value = factor x the free parameter's value.
struct TiedParameter {
  std::string key, follows;
  double factor = 1.0;
};

struct CalibrationSpec {
  std::string name;
  std::string rock;  // the rock's name in the material library ("Berea sandstone")
  std::string path;  // the calibration file
  std::string text;  // its contents (trial experiments are parsed from its [experiment] table)
  std::vector<Target> targets;
  std::vector<FreeParameter> free;
  std::vector<TiedParameter> tied;
  std::vector<double> confining_stresses;  // triaxial (biaxial) tests for the envelope, Pa
  // The test that measures tensile_strength: "brazilian" (a disc split across a diameter) or
  // "direct_tension" (the compression prism pulled apart by its ends).
  std::string tensile_test = "brazilian";
  double disc_diameter = 0.0, disc_thickness = 0.0, disc_platen_speed = 0.02;  // Brazilian
  double grip_speed = 0.02;  // direct tension: each grip's speed, m/s
  std::int64_t trials_per_stage = 10;
  std::int64_t passes = 2;
  // Fraction of each tolerance a trial must reach to count as met during the search; below 1 it
  // leaves room for the drift from the calibration sample to the verification sample.
  double aim = 1.0;
  // Packing seeds the search measures each trial on, its properties the mean over them (empty:
  // the [experiment]'s one packing). Several packings average out the scatter of one.
  std::vector<std::int64_t> fit_seeds;
  std::vector<std::int64_t> verify_seeds{1, 2, 3};
  std::vector<std::string> verify_set;  // experiment overrides for the verification (full size)
  // Rounds of size correction after the search: measure at the verification's size and
  // packings, shift the search's targets by the gap between the two sizes and search again on
  // the small sample (output space mapping). 0: none.
  std::int64_t size_corrections = 0;
  ExperimentSpec base;  // the experiment at the start values

  // The sample sets the search measures on: "calibration", or "fit-<seed>" per fit seed.
  std::vector<std::string> fit_sets() const;
  bool has_target(Property p) const;
  const Target* target(Property p) const;
  bool needs_tensile() const { return has_target(Property::TensileStrength); }
  bool needs_disc() const { return needs_tensile() && tensile_test == "brazilian"; }
  bool needs_envelope() const {
    return has_target(Property::Cohesion) || has_target(Property::FrictionAngle);
  }
};

// Reads and checks a calibration file; throws InputError.
CalibrationSpec load_calibration(const std::string& path);
CalibrationSpec parse_calibration(const std::string& text, const std::string& source);

// "section.key=value" overrides that set the free parameters to `values` and the tied ones.
std::vector<std::string> parameter_overrides(const CalibrationSpec& c,
                                             const std::vector<double>& values);

// Reference of the calibration file's keys (Markdown), for docs/calibration.md.
std::string calibration_docs();

}  // namespace breccia
