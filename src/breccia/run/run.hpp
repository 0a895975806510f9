#pragma once
// Runs an experiment spec into a self-describing run folder: manifest.json (version, seed, threads,
// machine, resolved spec, status), history.csv, cracks.csv, summary.json and the failure
// analysis. The manifest is written first with status "running" and rewritten at the end, so a
// run killed on the way is visibly incomplete; an interrupted run (Ctrl-C, SIGTERM) keeps its
// tables, says "interrupted" and leaves a checkpoint (checkpoint.bin) that `resume_run`
// continues exactly. A sweep runs one experiment at several confining stresses, strain rates or
// values of a key, and resume_sweep finishes one that stopped.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "breccia/spec/experiment.hpp"

namespace breccia {

// Where a run stands, for a progress callback (the Python package's, for one).
struct RunProgress {
  double fraction = 0.0;  // axial strain over the test's strain limit (0-1)
  double axial_strain = 0.0;
  double deviatoric_stress = 0.0;  // Pa
  std::size_t cracks = 0;
  std::uint64_t steps = 0;
  double elapsed_seconds = 0.0;  // wall time of this run, earlier sessions included
};

struct RunOptions {
  std::string command_line;
  const std::atomic<bool>* interrupt = nullptr;  // set from a signal handler to stop cleanly
  bool show_progress = false;                    // progress bar on stderr
  // Called at the progress bar's pace (every 250 ms of wall time), bar or not, and once when
  // the test ends; it may set `interrupt` to stop the run cleanly.
  std::function<void(const RunProgress&)> progress;
  std::function<void(const std::string&)> log;  // human-readable messages
  // Stop cleanly, with a checkpoint, once the engine has taken this many steps in all (0 = no
  // limit): for splitting a long test into jobs, and for the restart tests.
  std::uint64_t stop_at_step = 0;
  // Sweeps: the runs at once as child processes of `executable` (the breccia command), each
  // with its share of the cores (0: as many as cores allow; 1: one after another, in this
  // process). Without an executable a sweep runs in this process.
  int jobs = 0;
  std::string executable;
  // Under mpirun: one sample split over the ranks of the launch (`breccia run`), with the results
  // of one process to the bit. Root writes the run folder; each other rank runs the same loop
  // beside it, writing what it records into a scratch folder of its own that it removes.
  bool split_over_ranks = false;
  // Sweeps under mpirun: the ranks in groups of this many consecutive ranks, each group running
  // one run at a time split over its ranks (1: every rank runs whole runs alone). It divides the
  // rank count.
  int ranks_per_run = 1;
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
  std::uint64_t loop_steps = 0;  // this sitting's loading loop (summary.json "loading_loop")
  double loop_seconds = 0.0;
  double energy_residual_relative = 0.0;
};

RunResult run_experiment(const ExperimentSpec& spec, const RunOptions& options);
// Continues an interrupted run from its checkpoint.bin, in the same folder: the tables are cut
// back to the checkpoint and continued, and the result is the one the uninterrupted run gives.
RunResult resume_run(const std::string& folder, const ResumeOptions& resume,
                     const RunOptions& options);

// Runs the experiment once per confining stress on copies of one sample; writes a sweep folder
// with the run folders, sweep.json and the Mohr-Coulomb and Hoek-Brown fits. Returns its path.
struct SweepResult {
  std::string folder;
  std::vector<RunResult> runs;
  std::string status;
};
SweepResult run_sweep(const ExperimentSpec& spec, const std::vector<double>& confining_stresses,
                      const RunOptions& options);

// Runs the experiment's compression test once per strain rate (1/s) on copies of one sample, the
// platens' speed set from the sample's length (rate = 2 v / L); writes a sweep folder with the
// runs, their failure planes and damage ratios, and the fit of UCS(rate) (docs/analysis.md §11).
// Refuses density scaling: a rate study measures the inertia it would scale.
SweepResult run_rate_sweep(const ExperimentSpec& spec, const std::vector<double>& strain_rates,
                           const RunOptions& options);

// Runs the experiment once per value of one key (section.key, e.g. sample.slab_thickness): any
// test, each run on its own sample when the key changes it. sweep.json lists each run's cracks
// (and their share of the most any run had, as seed 001 scales them), its fragments and the
// test's own sweep metrics. Every value is checked like an override before any run starts.
SweepResult run_parameter_sweep(const ExperimentSpec& spec, const std::string& key,
                                const std::vector<std::string>& values, const RunOptions& options);

// Finishes a sweep that stopped (Ctrl-C, SIGTERM, a time limit, --stop-at-step), from the plan
// every sweep writes first (sweep-plan.json: the resolved experiment and what varies over which
// values): runs that completed are kept, those with a checkpoint continue from it (the result is
// that of the uninterrupted run), the others start anew; then sweep.json, fits and report are
// written again. options.jobs and options.stop_at_step apply as for a new sweep.
SweepResult resume_sweep(const std::string& folder, const RunOptions& options);
// Checks a sweep plan's text (sweep-plan.json) as resume does before anything runs: the
// format, the kind, the resolved experiment and the values; throws InputError naming `where`.
void check_sweep_plan(const std::string& text, const std::string& where);

}  // namespace breccia
