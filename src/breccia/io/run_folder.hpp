#pragma once
// Runs an experiment spec into a self-describing run folder: manifest.json (version, seed, threads,
// machine, resolved spec, status), history.csv, cracks.csv, summary.json. The manifest is written
// first with status "running" and rewritten at the end, so a run killed on the way is visibly
// incomplete; an interrupted run (Ctrl-C, SIGTERM) keeps its tables, says "interrupted" and
// leaves a checkpoint (checkpoint.bin) that `resume_run` continues exactly.
#include <atomic>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "breccia/io/experiment.hpp"
#include "breccia/io/geometry_file.hpp"
#include "breccia/sample/packing.hpp"

namespace breccia {

struct RunOptions {
  std::string command_line;
  const std::atomic<bool>* interrupt = nullptr;  // set from a signal handler to stop cleanly
  bool show_progress = false;                    // progress bar on stderr
  std::function<void(const std::string&)> log;   // human-readable messages
  // Stop cleanly, with a checkpoint, once the engine has taken this many steps in all (0 = no
  // limit): for splitting a long test into jobs, and for the restart tests.
  std::uint64_t stop_at_step = 0;
  // Sweeps: the runs at once as child processes of `executable` (the breccia command), each
  // with its share of the cores (0: as many as cores allow; 1: one after another, in this
  // process). Without an executable a sweep runs in this process.
  int jobs = 0;
  std::string executable;
};

struct ResumeOptions {
  int threads = -1;  // OpenMP threads for the rest of the run (-1: as recorded)
};

struct RunResult {
  std::string folder;
  std::string status;  // complete | interrupted | failed
  std::string stop_reason;
  double peak_stress = 0.0, strain_at_peak = 0.0, youngs_modulus = 0.0;
  double confining_stress = 0.0, sigma1_at_peak = 0.0, poisson = 0.0;
  std::size_t particles = 0, bonds = 0, cracks = 0, tensile = 0, shear = 0;
  std::uint64_t steps = 0;
  double wall_seconds = 0.0;
  double energy_residual_relative = 0.0;
};

RunResult run_experiment(const ExperimentSpec& spec, const RunOptions& options);
// Continues an interrupted run from its checkpoint.bin, in the same folder: the tables are cut
// back to the checkpoint and continued, and the result is the one the uninterrupted run gives.
RunResult resume_run(const std::string& folder, const ResumeOptions& resume,
                     const RunOptions& options);

// A generated sample and its packing report (JSON object).
struct GeneratedSample {
  GeometryData geometry;
  nlohmann::json report;
};
PackingSettings packing_settings(const ExperimentSpec& spec);
// The contact law of the experiment (particles and walls).
ContactModel contact_model(const ExperimentSpec& spec);
// Packs the sample of `spec` ([sample] keys) and, when `path` is not empty, writes it there as a
// breccia-geometry file with the report beside it (`path`.json).
GeneratedSample generate_sample(const ExperimentSpec& spec, const std::string& path,
                                const std::function<void(const std::string&)>& log);

// Runs the experiment once per confining stress on copies of one sample; writes a sweep folder
// with the run folders, sweep.json and the Mohr-Coulomb and Hoek-Brown fits. Returns its path.
struct SweepResult {
  std::string folder;
  std::vector<RunResult> runs;
  std::string status;
};
SweepResult run_sweep(const ExperimentSpec& spec, const std::vector<double>& confining_stresses,
                      const RunOptions& options);

// Human-readable headline results of a run folder (summary.json) or sweep folder (sweep.json).
std::string summarise_folder(const std::string& folder);
// Draws stress_strain.png in a run folder (scripts/plot_run.py); false with a message if not.
bool plot_run(const std::string& folder);
// Writes report.html and report/*.png of a run or sweep folder (scripts/report.py); false with the
// script's messages in report.log if not.
bool write_report(const std::string& folder);

// Runs scripts/<script> <folder> with Debian's Python; its output goes to <folder>/<log_name>,
// removed when it succeeds. False if it failed.
bool run_python_script(const std::string& script, const std::string& folder,
                       const std::string& log_name);

// A description of this machine for manifests and benchmark records.
std::string machine_description();

}  // namespace breccia
