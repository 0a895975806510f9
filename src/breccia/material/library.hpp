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
// docs/materials.md: one table of every preset (rock, source, each target, achieved, error),
// then each record in full.
std::string materials_docs();

}  // namespace breccia
