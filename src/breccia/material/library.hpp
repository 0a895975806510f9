#pragma once
// The material library: presets made by `breccia calibrate`, each shipped as the experiment
// fragment the calibration wrote (materials/<name>/material.toml) with its calibration record
// (materials/<name>/record.json: targets and sources, achieved mean and spread over packing
// seeds, sample, laws, the command that reproduces it). Both are compiled in, so a preset works
// from any folder. A preset without a record does not ship (a test refuses it).
#include <string>
#include <string_view>
#include <vector>

namespace breccia {

struct EmbeddedMaterial {
  std::string_view name, fragment, record;
};
// Every folder of materials/ (generated at configure time).
const std::vector<EmbeddedMaterial>& embedded_materials();

// One line for `material.preset`'s allowed values: the rock, the laws and the verdicts.
std::string describe_material(const EmbeddedMaterial& m);
// The honesty checks a shipped preset must pass, over its verification tests: both crack modes
// occur (a shear share of at least kMinShearShare in every compression test; a Brazilian disc
// splits in tension and is not checked) and the UCS does not crush an
// end (no end quarter holds more than kMaxEndQuarterShare of the cracks, on average). Returns
// one line per failed check; empty when all pass.
inline constexpr double kMinShearShare = 0.01;
inline constexpr double kMaxEndQuarterShare = 0.40;
std::vector<std::string> honesty_failures(const EmbeddedMaterial& m);

// How far a test is from quasi-static goes with its platens' speed over the grains' wave speed,
// v sqrt(s) for one rock at density scaling s (docs/physics.md §6.1). A run of a preset that
// loads more than this many times faster than the preset's verification tests (the record's
// "loading") warns: its peak and modulus carry inertia the preset's values do not.
inline constexpr double kPresetLoadingTolerance = 1.5;

// docs/materials.md: one table of every preset (rock, source, each target, achieved, error),
// then each record in full.
std::string materials_docs();

}  // namespace breccia
