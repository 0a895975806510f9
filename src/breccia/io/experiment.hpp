#pragma once
// The experiment file (TOML, SI units) and its validation. One table of keys drives parsing,
// validation, defaults and the generated docs (docs/experiment.md). The spec is plain data; the
// runner builds a Simulation from it.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "breccia/engine/simulation.hpp"
#include "breccia/protocol/platen_compression.hpp"

namespace breccia {

struct ExperimentSpec {
  std::string name = "demo-compression";
  // [engine]
  std::int64_t dimension = 3;
  std::int64_t threads = 0;  // 0 = all cores
  double gravity = 0.0;      // m/s^2 along -z (3D) or -y (2D)
  EngineConfig engine;       // gravity is filled from `gravity` when the simulation is built
  // [sample]
  std::string sample_source = "lattice";  // "lattice" (FCC in 3D, hexagonal in 2D) or "file"
  std::array<std::int64_t, 3> cells{6, 6, 12};
  double radius = 0.5e-3;
  double density = 2650.0;
  double thickness = 1e-3;  // 2D only
  std::string geometry_file;
  double bond_gap_tolerance = 1e-9;  // bonds between pairs with gap <= this when none are listed
  // [contact]
  std::string contact_law = "linear";
  LinearContact::Params linear;
  HertzMindlin::Params hertz;
  double wall_friction = 0.0;
  // [bond]
  std::string bond_law = "parallel_bond";
  ParallelBond::Params parallel_bond;
  // [loading]
  PlatenCompressionSettings loading;
  // [output]
  std::string output_directory = "runs";
  std::int64_t history_interval = 200;  // steps
  bool progress = true;

  std::string source;  // file the spec came from ("built-in default" otherwise)
};

ExperimentSpec default_experiment();

// Reads a TOML experiment file and applies `overrides` ("section.key=value", value in TOML
// syntax). Throws InputError naming the file, the key, the value and what is allowed.
ExperimentSpec load_experiment(const std::string& path, const std::vector<std::string>& overrides);
// Same, from TOML text (`source` names it in errors); empty text gives the default experiment.
ExperimentSpec parse_experiment(const std::string& text, const std::string& source,
                                const std::vector<std::string>& overrides);

// The fully resolved spec as TOML text (every key, defaults included), for the run manifest.
std::string to_toml(const ExperimentSpec& spec);

// Reference documentation of every key, generated from the validation tables (Markdown).
std::string experiment_docs();

}  // namespace breccia
