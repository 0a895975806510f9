#pragma once
// From an experiment spec to a simulation ready to load: the sample (packed, read from the cache
// or imported), its bonds and joints, the lab test with its boundaries and consolidation, and the
// checks of the run's size before any step is taken.
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "breccia/engine/simulation.hpp"
#include "breccia/protocol/protocol.hpp"
#include "breccia/sample/geometry_file.hpp"
#include "breccia/sample/packing.hpp"
#include "breccia/spec/experiment.hpp"

namespace breccia {

// A generated sample and its packing report (JSON object).
struct GeneratedSample {
  GeometryData geometry;
  nlohmann::json report;
};
PackingSettings packing_settings(const ExperimentSpec& spec);
// The instruction set the experiment's kernels run in (engine.instruction_set, "auto" = the best
// this CPU runs); InputError naming the file when the CPU does not run the one it names.
InstructionSet instruction_set_of(const ExperimentSpec& spec);
// The contact law of the experiment (particles and walls).
ContactModel contact_model(const ExperimentSpec& spec);
// Packs the sample of `spec` ([sample] keys) and, when `path` is not empty, writes it there as a
// breccia-geometry file with the report beside it (`path`.json).
GeneratedSample generate_sample(const ExperimentSpec& spec, const std::string& path,
                                const std::function<void(const std::string&)>& log);

// `breccia generate`: the experiment's sample (packed, a lattice, or read from its file) written
// to `path` with its report beside it (`path`.json). Refused, naming `option` (how the caller
// calls the path) and the value, before any work: an empty path, a folder, a path of a file the
// experiment reads, and a file that is not a sample (or not a sample's report). A failed write
// leaves no temporary behind.
GeneratedSample write_sample(const ExperimentSpec& spec, const std::string& path,
                             const std::string& option,
                             const std::function<void(const std::string&)>& log);

// The sample of an experiment: generated (and cached in output.directory/samples), read from a
// geometry file, or a lattice; `report` describes it and `info` tells the test its shape.
GeometryData load_sample(const ExperimentSpec& spec, nlohmann::json& report, SampleInfo& info,
                         const std::function<void(const std::string&)>& log);

// A simulation built and consolidated, its test ready to load.
struct Built {
  Simulation sim;
  std::unique_ptr<Protocol> protocol;
  double bar_wave_speed = 0.0;
  nlohmann::json sample_report;
  std::uint64_t consolidation_steps = 0;
};
Built build(const ExperimentSpec& spec, const std::function<void(const std::string&)>& log);
// Builds the run as `build` does, without consolidating or loading it, and discards it: every
// check of the sample, the test and the run's size; throws InputError.
void check_buildable(const ExperimentSpec& spec);

}  // namespace breccia
