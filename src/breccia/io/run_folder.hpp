#pragma once
// Runs an experiment spec into a self-describing run folder: manifest.json (version, seed, threads,
// machine, resolved spec, status), history.csv, cracks.csv, summary.json. The manifest is written
// first with status "running" and rewritten at the end, so a run killed on the way is visibly
// incomplete; an interrupted run (Ctrl-C, SIGTERM) keeps its tables and says "interrupted".
#include <atomic>
#include <functional>
#include <string>

#include "breccia/io/experiment.hpp"

namespace breccia {

struct RunOptions {
  std::string command_line;
  const std::atomic<bool>* interrupt = nullptr;  // set from a signal handler to stop cleanly
  bool show_progress = false;                    // progress bar on stderr
  std::function<void(const std::string&)> log;   // human-readable messages
};

struct RunResult {
  std::string folder;
  std::string status;  // complete | interrupted | failed
  std::string stop_reason;
  double peak_stress = 0.0, strain_at_peak = 0.0, youngs_modulus = 0.0;
  std::size_t particles = 0, bonds = 0, cracks = 0, tensile = 0, shear = 0;
  std::uint64_t steps = 0;
  double wall_seconds = 0.0;
  double energy_residual_relative = 0.0;
};

RunResult run_experiment(const ExperimentSpec& spec, const RunOptions& options);

// A description of this machine for manifests and benchmark records.
std::string machine_description();

}  // namespace breccia
