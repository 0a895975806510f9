#include <fcntl.h>
#include <fmt/chrono.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

#include "breccia/analysis/compression.hpp"
#include "breccia/analysis/rate_dependence.hpp"
#include "breccia/analysis/stress_strain.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/io/json_view.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/run/run.hpp"
#include "breccia/run/sample_build.hpp"
#include "breccia/version.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

json nan_null(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}

json sweep_entry(double sigma3, const RunResult& r) {
  return {{"confining_stress_pa", sigma3},
          {"folder", fs::path(r.folder).filename().string()},
          {"status", r.status},
          {"peak_deviatoric_stress_pa", r.peak_stress},
          {"sigma1_at_peak_pa", r.sigma1_at_peak},
          {"youngs_modulus_pa", nan_null(r.youngs_modulus)},
          {"poisson_ratio", nan_null(r.poisson)},
          {"cracks", r.cracks},
          {"bonds_initial", r.bonds},
          {"wall_seconds", r.wall_seconds}};
}

// The headline results of a run folder written by a child process (its summary, or its manifest
// when the run stopped before one was written).
RunResult result_of_folder(const fs::path& folder) {
  RunResult r;
  r.folder = folder.string();
  r.status = "failed";
  const fs::path summary = folder / "summary.json", manifest = folder / "manifest.json";
  if (fs::exists(summary)) {
    const json j = read_json_object(summary.string());
    const JsonView v(j, summary.string());
    r.status = v.text("status", "failed");
    r.stop_reason = v.text("stop_reason", "");
    r.peak_stress = v.maybe_number("peak_deviatoric_stress_pa").value_or(0.0);
    r.sigma1_at_peak = v.maybe_number("sigma1_at_peak_pa").value_or(0.0);
    r.strain_at_peak = v.maybe_number("axial_strain_at_peak").value_or(0.0);
    r.youngs_modulus =
        v.maybe_number("youngs_modulus_pa").value_or(std::numeric_limits<double>::quiet_NaN());
    r.poisson = v.maybe_number("poisson_ratio").value_or(std::numeric_limits<double>::quiet_NaN());
    r.confining_stress = v.maybe_number("confining_stress_pa").value_or(0.0);
    r.particles = static_cast<std::size_t>(v.maybe_number("particles").value_or(0.0));
    r.bonds = static_cast<std::size_t>(v.maybe_number("bonds_initial").value_or(0.0));
    r.steps = static_cast<std::uint64_t>(v.maybe_number("steps").value_or(0.0));
    r.cracks = static_cast<std::size_t>(v.maybe_number("bonds_broken").value_or(0.0));
    r.tensile = static_cast<std::size_t>(v.maybe_number("cracks_tensile").value_or(0.0));
    r.shear = static_cast<std::size_t>(v.maybe_number("cracks_shear").value_or(0.0));
    r.wall_seconds = v.maybe_number("wall_seconds").value_or(0.0);
  } else if (fs::exists(manifest)) {
    const json j = read_json_object(manifest.string());
    const JsonView v(j, manifest.string());
    r.status = v.text("status", "failed");
    r.stop_reason = v.text("stop_reason", "the run wrote no summary");
  }
  return r;
}

// Starts `exe args...` with stdout to `out` and stderr to `err`; the child's pid.
pid_t spawn_child(const std::string& exe, std::vector<std::string> args, const fs::path& out,
                  const fs::path& err) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  args.insert(args.begin(), exe);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0)
    throw std::runtime_error(fmt::format("sweep: cannot start {}: {}", exe, std::strerror(rc)));
  return pid;
}

// The folder a child's `breccia run` printed as its last line of output.
fs::path printed_folder(const fs::path& out) {
  std::ifstream in(out);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

// Where a run of a sweep being resumed stands: its newest folder in the sweep folder (named
// <stamp>-<run name>, see make_folder), if any.
struct EarlierRun {
  fs::path folder;  // empty: never started
  RunResult result;
  bool complete() const { return result.status == "complete"; }
  bool resumable() const {
    return !folder.empty() && !complete() && fs::exists(folder / "checkpoint.bin");
  }
};

EarlierRun earlier_run(const fs::path& sweep_folder, const std::string& name) {
  const std::string safe = folder_safe_name(name);
  constexpr std::size_t kStamp = 16;  // "YYYYmmdd-HHMMSS-"
  EarlierRun e;
  for (const fs::directory_entry& d : fs::directory_iterator(sweep_folder)) {
    const std::string f = d.path().filename().string();
    if (!d.is_directory() || f.size() <= kStamp ||
        f.compare(kStamp, std::string::npos, safe) != 0 || !fs::exists(d.path() / "manifest.json"))
      continue;
    if (e.folder.empty() || f > e.folder.filename().string()) e.folder = d.path();
  }
  if (!e.folder.empty()) e.result = result_of_folder(e.folder);
  return e;
}

using Children = std::vector<std::pair<pid_t, std::size_t>>;  // pid, index of the run

// Waits for one of the running children to end and returns its pid (-1: none left). A stop asked
// of the sweep alone (SIGTERM from a job scheduler, kill from another terminal) is passed on to
// its runs, which stop with a checkpoint, so that the sweep can be resumed; Ctrl-C in the
// terminal reaches them already, and a second signal changes nothing.
pid_t wait_for_a_child(const Children& running, const RunOptions& opt, bool& passed_on) {
  int status = 0;
  pid_t pid = 0;
  while ((pid = waitpid(-1, &status, WNOHANG)) == 0) {
    if (!passed_on && opt.interrupt && opt.interrupt->load()) {
      for (const auto& [child, index] : running) kill(child, SIGINT);
      passed_on = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return pid;
}

// What a child wrote: its run folder's results, or a failure pointing at its log.
RunResult result_of_child(const fs::path& stem) {
  const fs::path run = printed_folder(stem.string() + ".out");
  if (!run.empty() && fs::exists(run)) return result_of_folder(run);
  RunResult r;
  r.status = "failed";
  r.stop_reason = "no run folder: see " + stem.string() + ".log";
  return r;
}

// The command line of a child: `resume` of a run with a checkpoint, else `run` of the
// experiment written beside `stem`.
std::vector<std::string> child_arguments(const ExperimentSpec& one, const EarlierRun& earlier,
                                         int threads, const fs::path& stem,
                                         std::uint64_t stop_at_step) {
  std::vector<std::string> args{"resume", earlier.folder.string(), "--threads",
                                std::to_string(threads)};
  if (!earlier.resumable()) {
    write_file_atomically(stem.string() + ".toml", to_toml(one));
    args = {"run", stem.string() + ".toml"};
  }
  if (stop_at_step > 0) args.insert(args.end(), {"--stop-at-step", std::to_string(stop_at_step)});
  return args;
}

// The sweep's runs as child processes, `jobs` at a time, each with `threads` OpenMP threads. A
// generated sample is packed first, once, into the cache the children read. Resuming, a run
// that completed is kept, one with a checkpoint continues from it, and the others start anew.
std::vector<RunResult> sweep_in_processes(std::vector<ExperimentSpec> specs, int jobs, int threads,
                                          const fs::path& folder, const RunOptions& opt,
                                          bool resuming) {
  const ExperimentSpec& first = specs.front();
  if (first.sample_source == "generate" && first.cache) {
    json report;
    SampleInfo info;
    load_sample(first, report, info, opt.log);
  }
  const fs::path dir = folder / "experiments";
  fs::create_directories(dir);
  std::vector<RunResult> results(specs.size());
  Children running;
  std::size_t next = 0;
  bool passed_on = false;
  auto reap_one = [&] {
    const pid_t pid = wait_for_a_child(running, opt, passed_on);
    const auto done = std::find_if(running.begin(), running.end(),
                                   [pid](const auto& c) { return c.first == pid; });
    if (done == running.end()) return;
    const std::size_t i = done->second;
    results[i] = result_of_child(dir / specs[i].name);
    if (opt.log)
      opt.log(fmt::format("sweep: {} {} ({})", specs[i].name, results[i].status,
                          results[i].status == "complete"
                              ? fmt::format("peak q {:.2f} MPa", results[i].peak_stress * 1e-6)
                              : results[i].stop_reason));
    running.erase(done);
  };
  while (next < specs.size() || !running.empty()) {
    const bool stopping = opt.interrupt && opt.interrupt->load();
    if (!stopping && next < specs.size() && running.size() < static_cast<std::size_t>(jobs)) {
      ExperimentSpec& one = specs[next];
      one.threads = threads;
      one.progress = false;
      const fs::path stem = dir / one.name;
      const EarlierRun earlier = resuming ? earlier_run(folder, one.name) : EarlierRun{};
      if (earlier.complete()) {
        results[next++] = earlier.result;
        continue;
      }
      if (opt.log)
        opt.log(fmt::format("sweep: {} {} ({} thread{})",
                            earlier.resumable() ? "resumed" : "started", one.name, threads,
                            threads == 1 ? "" : "s"));
      running.emplace_back(
          spawn_child(opt.executable,
                      child_arguments(one, earlier, threads, stem, opt.stop_at_step),
                      stem.string() + ".out", stem.string() + ".log"),
          next);
      ++next;
      continue;
    }
    if (running.empty()) break;  // interrupted before every run started
    reap_one();
  }
  for (std::size_t i = next; i < specs.size(); ++i) {
    results[i].status = "interrupted";
    results[i].stop_reason = "not started: the sweep was interrupted";
  }
  return results;
}

// One run of a sweep on this rank's group of ranks (see sweep_over_ranks), split over them when
// there are several: its messages go to experiments/<name>.log (as a child process's do), written
// by the group's first rank, and what it throws becomes its status, so that every rank reaches
// the gather that follows. A failure that the group's ranks did not all meet (one rank ran out
// of memory) would leave the others waiting for it: it ends the launch instead.
RunResult run_on_this_rank(ExperimentSpec one, const EarlierRun& earlier, int threads,
                           const fs::path& stem, const RunOptions& opt) {
  one.threads = threads;
  one.progress = false;
  const bool speaks = ranks::root();
  if (speaks && !earlier.resumable()) write_file_atomically(stem.string() + ".toml", to_toml(one));
  auto log = speaks ? std::make_shared<std::ofstream>(stem.string() + ".log") : nullptr;
  RunOptions mine = opt;
  mine.show_progress = false;
  mine.progress = nullptr;
  mine.jobs = 1;
  mine.log = [log](const std::string& m) {
    if (log) *log << m << std::endl;
  };
  mine.split_over_ranks = ranks::size() > 1;
  RunResult r;
  try {
    return earlier.resumable() ? resume_run(earlier.folder.string(), ResumeOptions{threads}, mine)
                               : run_experiment(one, mine);
  } catch (const Interrupted& e) {
    r.status = "interrupted";
    r.stop_reason = std::string(e.what()) + " (not started: resume runs it)";
  } catch (const std::exception& e) {
    r.status = "failed";
    r.stop_reason = fmt::format("rank {}: {}", ranks::launch_rank(), e.what());
    ranks::abort_unless_shared(dynamic_cast<const InputError*>(&e) != nullptr,
                               one.name + ": " + r.stop_reason);
  }
  if (log) *log << "error: " << r.stop_reason << std::endl;
  return r;
}

// "rank 3", or "ranks 4-7" for a run split over a group.
std::string ranks_named(int first, int count) {
  return count == 1 ? fmt::format("rank {}", first)
                    : fmt::format("ranks {}-{}", first, first + count - 1);
}

// What root must know of the sweep's runs before they start: where each stands (resuming), the
// generated sample packed once into the cache every rank reads.
std::vector<EarlierRun> runs_before_start(const std::vector<ExperimentSpec>& specs,
                                          const fs::path& folder, bool resuming,
                                          const RunOptions& opt) {
  const json seen = json::parse(ranks::on_root([&] {
    const ExperimentSpec& first = specs.front();
    if (first.sample_source == "generate" && first.cache) {
      json report;
      SampleInfo info;
      load_sample(first, report, info, opt.log);
    }
    json folders = json::array();
    for (const ExperimentSpec& one : specs)
      folders.push_back(resuming ? earlier_run(folder, one.name).folder.string() : "");
    return folders.dump();
  }));
  std::vector<EarlierRun> earlier(specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i) {
    earlier[i].folder = seen[i].get<std::string>();
    if (!earlier[i].folder.empty()) earlier[i].result = result_of_folder(earlier[i].folder);
  }
  return earlier;
}

// This group's share of the sweep's runs: the k-th run still to do goes to group k mod G. Every
// rank of the group takes the same runs, and starts each only when none of them has been
// interrupted. The group's first rank reports the outcomes (as JSON; the others report none).
json runs_of_this_group(const std::vector<ExperimentSpec>& specs,
                        const std::vector<EarlierRun>& earlier, ranks::Group& group, int threads,
                        const fs::path& dir, const RunOptions& opt) {
  json mine = json::array();
  std::size_t k = 0;  // runs still to do, so far
  for (std::size_t i = 0; i < specs.size(); ++i) {
    if (earlier[i].complete() ||
        k++ % static_cast<std::size_t>(group.count()) != static_cast<std::size_t>(group.index()))
      continue;
    RunResult r;
    if (ranks::any_flags(opt.interrupt && opt.interrupt->load() ? 1u : 0u) != 0) {
      r.status = "interrupted";
      r.stop_reason = "not started: the sweep was interrupted";
    } else {
      group.begin_task();
      r = run_on_this_rank(specs[i], earlier[i], threads, dir / specs[i].name, opt);
    }
    if (ranks::root())
      mine.push_back({{"index", i},
                      {"folder", r.folder},
                      {"status", r.status},
                      {"stop_reason", r.stop_reason},
                      {"rank", group.first_rank()},
                      {"ranks", ranks::size()}});
  }
  return mine;
}

// The sweep's runs shared out over the ranks of an MPI launch, in groups of
// `opt.ranks_per_run` consecutive ranks: each group runs its runs one after another, each split
// over the group's ranks (or whole on one rank, in groups of one), with the group's share of its
// machine's cores. Runs do not depend on where they ran nor on how many ranks ran them, so the
// folders are those of a sweep in one process. Root gathers every group's outcomes and reads
// each run's folder, as it does a child process's.
std::vector<RunResult> sweep_over_ranks(const std::vector<ExperimentSpec>& specs,
                                        const fs::path& folder, const RunOptions& opt,
                                        bool resuming) {
  const std::vector<EarlierRun> earlier = runs_before_start(specs, folder, resuming, opt);
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int threads = specs.front().threads > 0 ? static_cast<int>(specs.front().threads)
                                                : std::max(1, cores / ranks::local_size());
  const int each = std::max(1, opt.ranks_per_run);
  if (opt.log)
    opt.log(fmt::format("sweep: {} runs over {} ranks, {} ({} thread{} a rank)", specs.size(),
                        ranks::size(),
                        each == 1 ? std::string("one run a rank")
                                  : fmt::format("each run split over {} ranks", each),
                        threads, threads == 1 ? "" : "s"));
  const fs::path dir = folder / "experiments";
  fs::create_directories(dir);
  json mine;
  {
    ranks::Group group(each);
    mine = runs_of_this_group(specs, earlier, group, threads, dir, opt);
  }
  std::vector<RunResult> results(specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (earlier[i].complete()) results[i] = earlier[i].result;
  for (const std::string& text : ranks::gather(mine.dump())) {
    for (const json& o : json::parse(text)) {
      const std::size_t i = o.at("index").get<std::size_t>();
      const std::string run = o.at("folder").get<std::string>();
      if (!run.empty() && fs::exists(run)) {
        results[i] = result_of_folder(run);
      } else {
        results[i].status = o.at("status").get<std::string>();
        results[i].stop_reason = o.at("stop_reason").get<std::string>();
      }
      if (opt.log)
        opt.log(fmt::format("sweep: {} {} on {} ({})", specs[i].name, results[i].status,
                            ranks_named(o.at("rank").get<int>(), o.at("ranks").get<int>()),
                            results[i].status == "complete"
                                ? fmt::format("peak q {:.2f} MPa", results[i].peak_stress * 1e-6)
                                : results[i].stop_reason));
    }
  }
  return results;
}

}  // namespace

namespace {

// A new sweep folder, <output.directory>/<stamp>-<name>-sweep.
// Under mpirun root makes it and names it to the other ranks.
fs::path make_sweep_folder(const ExperimentSpec& spec) {
  return ranks::on_root([&] { return make_folder(spec, "-sweep").string(); });
}

// Runs the sweep's experiments: as parallel processes when cores allow (each with its share of
// the cores, or the threads the experiment asks for), else one after another in this process,
// stopping at the first that does not complete. `describe` names a run in the log.
std::vector<RunResult> run_all(const ExperimentSpec& spec, const std::vector<ExperimentSpec>& specs,
                               const fs::path& folder, const RunOptions& opt,
                               const std::function<std::string(const ExperimentSpec&)>& describe,
                               bool resuming) {
  if (ranks::size() > 1) return sweep_over_ranks(specs, folder, opt, resuming);
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int per_run = spec.threads > 0 ? static_cast<int>(spec.threads) : 1;
  const int jobs = opt.jobs > 0
                       ? opt.jobs
                       : std::min(static_cast<int>(specs.size()), std::max(1, cores / per_run));
  if (jobs > 1 && !opt.executable.empty()) {
    const int threads = spec.threads > 0 ? per_run : std::max(1, cores / jobs);
    if (opt.log)
      opt.log(fmt::format("sweep: {} runs, {} at a time ({} thread{} each)", specs.size(), jobs,
                          threads, threads == 1 ? "" : "s"));
    return sweep_in_processes(specs, jobs, threads, folder, opt, resuming);
  }
  // Copies of one sample: a generated sample is packed once and cached in the sweep folder.
  std::vector<RunResult> runs;
  for (const ExperimentSpec& one : specs) {
    const EarlierRun earlier = resuming ? earlier_run(folder, one.name) : EarlierRun{};
    if (earlier.complete()) {
      runs.push_back(earlier.result);
      continue;
    }
    if (opt.log) opt.log("sweep: " + describe(one) + (earlier.resumable() ? " (resumed)" : ""));
    try {
      runs.push_back(earlier.resumable()
                         ? resume_run(earlier.folder.string(),
                                      ResumeOptions{static_cast<int>(spec.threads)}, opt)
                         : run_experiment(one, opt));
    } catch (const Interrupted& e) {
      // Stopped before the run had a folder (packing its sample, say): the sweep stops as
      // interrupted, and resume starts this run anew.
      RunResult stopped;
      stopped.status = "interrupted";
      stopped.stop_reason = std::string(e.what()) + " (not started: resume runs it)";
      runs.push_back(stopped);
    }
    if (runs.back().status != "complete") break;
  }
  return runs;
}

// The sweep's status: that of its first run that did not complete.
std::string sweep_status(const std::vector<RunResult>& runs, std::size_t planned) {
  for (const RunResult& r : runs)
    if (r.status != "complete") return r.status;
  return runs.size() == planned ? "complete" : "interrupted";
}

void finish_sweep(const ExperimentSpec& spec, const SweepResult& out, const json& sweep,
                  const RunOptions& opt) {
  write_json(fs::path(out.folder) / "sweep.json", sweep);
  if (spec.plot && !write_report(out.folder) && opt.log)
    opt.log("warning: no report.html (see " + out.folder + "/report.log)");
}

json mohr_coulomb_json(const analysis::MohrCoulombFit& mc) {
  return {{"valid", mc.valid},
          {"method", "least squares of sigma_1 on sigma_3 (principal-stress form)"},
          {"k", mc.k},
          {"friction_angle_deg", mc.friction_angle_deg},
          {"cohesion_pa", mc.cohesion},
          {"ucs_intercept_pa", mc.ucs},
          {"implied_tensile_strength_pa", mc.tensile},
          {"r2", nan_null(mc.r2)},
          {"flag", mc.flag}};
}

json hoek_brown_json(const analysis::HoekBrownFit& hb) {
  return {{"valid", hb.valid},
          {"sigma_ci_pa", hb.sigma_ci},
          {"m_i", hb.m_i},
          {"sigma_ci_linearised_pa", hb.sigma_ci_linear},
          {"m_i_linearised", hb.m_i_linear},
          {"rms_residual_pa", hb.rms},
          {"flag", hb.flag}};
}

json rate_fit_json(const analysis::ExponentialRateFit& f) {
  return {{"valid", f.valid},
          {"flag", f.flag},
          {"points", f.points},
          {"method",
           "UCS = a exp(b rate): least squares of ln UCS on the rate (start), then "
           "Levenberg-Marquardt on the untransformed residuals (docs/analysis.md §11); a is the "
           "quasi-static strength"},
          {"a_pa", nan_null(f.valid ? f.a : std::nan(""))},
          {"b_s", nan_null(f.valid ? f.b : std::nan(""))},
          {"a_standard_error_pa", nan_null(f.valid ? f.a_se : std::nan(""))},
          {"b_standard_error_s", nan_null(f.valid ? f.b_se : std::nan(""))},
          {"rms_residual_pa", nan_null(f.valid ? f.rms : std::nan(""))},
          {"log_linear", {{"a_pa", nan_null(f.a_log)}, {"b_s", nan_null(f.b_log)}}},
          {"dynamic_increase_factor", f.dynamic_increase},
          {"three_parameter",
           {{"valid", f.three_valid},
            {"form", "UCS = c + a exp(b rate), from c = 0.9 min UCS (4 rates or more)"},
            {"c_pa", nan_null(f.three_valid ? f.c3 : std::nan(""))},
            {"a_pa", nan_null(f.three_valid ? f.a3 : std::nan(""))},
            {"b_s", nan_null(f.three_valid ? f.b3 : std::nan(""))},
            {"quasi_static_pa", nan_null(f.three_valid ? f.c3 + f.a3 : std::nan(""))},
            {"rms_residual_pa", nan_null(f.three_valid ? f.rms3 : std::nan(""))}}}};
}

// The sample's length along the load (z in 3D, y in 2D), from the sample itself: the platen
// speed of a strain rate needs it before the test is built.
double sample_length(const ExperimentSpec& spec, const RunOptions& opt) {
  json report;
  SampleInfo info;
  const GeometryData g = load_sample(spec, report, info, opt.log);
  const int axis = spec.dimension == 2 ? 1 : 2;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& p : g.particles) {
    lo = std::min(lo, p.position[axis] - p.radius);
    hi = std::max(hi, p.position[axis] + p.radius);
  }
  return hi - lo;
}

// One run of a parameter sweep in sweep.json: what every test reports, then the test's own
// sweep metrics (summary.<kind>.sweep_metrics) or, for stress-strain tests, the usual entry.
json parameter_entry(const std::string& value, const RunResult& r) {
  json e{{"value", value},           {"folder", fs::path(r.folder).filename().string()},
         {"status", r.status},       {"cracks", r.cracks},
         {"bonds_initial", r.bonds}, {"wall_seconds", r.wall_seconds}};
  const fs::path file = fs::path(r.folder) / "summary.json";
  if (r.status != "complete" || !fs::exists(file)) return e;
  const json summary = read_json_object(file.string());
  const json fragments = summary.value("fragments", json::object());
  e["fragments"] = fragments.value("count", 0);
  e["largest_fragment_fraction"] = fragments.value("largest_fraction_of_total", 0.0);
  const json own = summary.value(summary.value("test_kind", std::string()), json::object());
  if (own.contains("sweep_metrics")) {
    e["metrics"] = own["sweep_metrics"];
  } else {
    e["metrics"] = {{"peak_deviatoric_stress_pa", r.peak_stress},
                    {"youngs_modulus_pa", nan_null(r.youngs_modulus)}};
  }
  return e;
}

// One sweep's experiments, how the log names each, and sweep.json's body from their results.
struct SweepJob {
  std::vector<ExperimentSpec> specs;
  std::function<std::string(const ExperimentSpec&)> describe;
  std::function<json(const std::vector<RunResult>&)> assemble;
};

// Where a sweep's values came from, for its errors: the command line's option (with the unit
// the user gave) or the plan file of a sweep being resumed.
struct ValuesOrigin {
  std::string where, key;
  double scale = 1.0;  // the value as given = value / scale
  std::string unit;    // of the value as given, when it is not the SI unit
};

std::string shown(const ValuesOrigin& o, double v) {
  return num(v / o.scale) + o.unit;
}

// A sweep runs each value once: a repeated value would run twice and weigh twice in the fits.
void check_distinct(const std::vector<double>& values, const ValuesOrigin& o) {
  for (std::size_t i = 0; i < values.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (values[i] == values[j])
        throw InputError(
            o.where, o.key, shown(o, values[i]),
            fmt::format("given twice (values {} and {}): each value once", j + 1, i + 1));
}

void check_confining(const std::vector<double>& confining, const ExperimentSpec& spec,
                     const ValuesOrigin& o) {
  if (confining.empty()) throw InputError(o.where, o.key, "(none)", "give at least one value");
  for (double c : confining)
    if (!(c >= 0.0) || !std::isfinite(c))
      throw InputError(o.where, o.key, shown(o, c),
                       "each confining stress must be finite and >= 0");
  check_distinct(confining, o);
  for (double c : confining) {  // a test that cannot be swept fails before any folder exists
    ExperimentSpec probe = spec;
    try {
      set_confining_stress(probe, c, o.where);
      (void)parse_experiment(to_toml(probe), spec.source, {});  // the key's own range
    } catch (const InputError& e) {
      // The key of the experiment that refuses it (the test in use, a range) stays named.
      throw InputError(
          o.where, o.key, shown(o, c),
          e.key().empty() || e.key() == "confining_stress"
              ? e.allowed()
              : fmt::format("the experiment's {} = {}: {}", e.key(), e.value(), e.allowed()));
    }
  }
}

SweepJob confining_job(const ExperimentSpec& spec, const std::vector<double>& confining,
                       const fs::path& folder) {
  SweepJob job;
  for (double c : confining) {
    ExperimentSpec one = spec;
    one.output_directory = folder.string();
    set_confining_stress(one, c, "sweep");
    one.name = fmt::format("{}-confining-{}MPa", spec.name, c * 1e-6);
    job.specs.push_back(one);
  }
  job.describe = [](const ExperimentSpec& one) {
    return fmt::format("confining stress {} MPa", confining_stress(one) * 1e-6);
  };
  job.assemble = [spec, confining](const std::vector<RunResult>& done) {
    json runs = json::array();
    std::vector<double> s3, s1;
    for (std::size_t i = 0; i < done.size(); ++i) {
      const RunResult& r = done[i];
      runs.push_back(sweep_entry(confining[i], r));
      if (r.status != "complete") continue;
      s3.push_back(confining[i]);
      s1.push_back(r.sigma1_at_peak);
    }
    return json{{"experiment", spec.name},
                {"variable", "confining_stress"},
                {"runs", runs},
                {"mohr_coulomb", mohr_coulomb_json(analysis::fit_mohr_coulomb(s3, s1))},
                {"hoek_brown", hoek_brown_json(analysis::fit_hoek_brown(s3, s1))}};
  };
  return job;
}

void check_rates(const std::vector<double>& rates, const ExperimentSpec& spec,
                 const ValuesOrigin& o) {
  if (rates.empty()) throw InputError(o.where, o.key, "(none)", "give at least one strain rate");
  for (double r : rates)
    if (!(r > 0.0) || !std::isfinite(r))
      throw InputError(o.where, o.key, shown(o, r), "each strain rate must be finite and > 0 1/s");
  check_distinct(rates, o);
  if (spec.density_scaling != 1.0)
    throw InputError(spec.source, "engine.density_scaling", num(spec.density_scaling),
                     "a strain-rate study measures the sample's inertia, which density scaling "
                     "multiplies: set engine.density_scaling = 1");
  ExperimentSpec probe = spec;
  set_platen_speed(probe, 1.0, o.where);
}

// One run of a strain-rate sweep in sweep.json: the usual entry, the rate asked for and measured,
// the damage ratio, the failure plane and the quasi-static check.
json rate_entry(const ExperimentSpec& spec, double rate, double length, const RunResult& r) {
  json e = sweep_entry(confining_stress(spec), r);
  e["strain_rate_target_per_s"] = rate;
  e["platen_speed_m_per_s"] = 0.5 * rate * length;
  e["damage_ratio_percent"] =
      r.bonds > 0 ? 100.0 * static_cast<double>(r.cracks) / static_cast<double>(r.bonds) : 0.0;
  if (r.status == "complete") {
    const json summary = read_json_object((fs::path(r.folder) / "summary.json").string());
    e["strain_rate_per_s"] = summary.value("strain_rate_per_s", rate);
    e["failure_plane"] =
        summary.value("crack_pattern", json::object()).value("failure_plane", json::object());
    e["quasi_static"] = summary.value("quasi_static", json::object()).value("ok", false);
  }
  return e;
}

SweepJob rate_job(const ExperimentSpec& spec, const std::vector<double>& rates,
                  const fs::path& folder, const RunOptions& opt) {
  ExperimentSpec base = spec;
  base.output_directory = folder.string();
  // The platens close at 2 v: v = rate L / 2 for the sample's length L.
  const double length = sample_length(base, opt);
  SweepJob job;
  for (double rate : rates) {
    ExperimentSpec one = base;
    set_platen_speed(one, 0.5 * rate * length, "sweep");
    one.name = fmt::format("{}-rate-{}-per-s", spec.name, rate);
    job.specs.push_back(one);
  }
  job.describe = [length](const ExperimentSpec& one) {
    double v = 0.0;
    std::visit(
        [&](const auto& p) {
          if constexpr (requires { p.platen_speed; }) v = p.platen_speed;
        },
        one.test);
    return fmt::format("strain rate {:.3g} /s (platens at {:.4g} m/s)", 2.0 * v / length, v);
  };
  job.assemble = [spec, rates, length](const std::vector<RunResult>& done) {
    json runs = json::array();
    std::vector<double> measured, ucs;
    for (std::size_t i = 0; i < done.size(); ++i) {
      json e = rate_entry(spec, rates[i], length, done[i]);
      if (done[i].status == "complete") {
        measured.push_back(e["strain_rate_per_s"].get<double>());
        ucs.push_back(done[i].peak_stress);
      }
      runs.push_back(e);
    }
    return json{{"experiment", spec.name},
                {"variable", "strain_rate"},
                {"sample_length_m", length},
                {"runs", runs},
                {"rate_dependence", rate_fit_json(analysis::fit_rate_dependence(measured, ucs))}};
  };
  return job;
}

// Each value read as an override of the resolved experiment: a bad key or value fails here,
// named as the sweep gave it (`--over KEY VALUE`, or the plan file), and two values that make
// the same experiment are refused.
std::vector<ExperimentSpec> parameter_specs(const ExperimentSpec& spec, const std::string& key,
                                            const std::vector<std::string>& values,
                                            const ValuesOrigin& o) {
  if (values.empty())
    throw InputError(o.where, o.key, "(no values)", "give the key, then its values");
  const std::string text = to_toml(spec);
  std::vector<ExperimentSpec> specs;
  std::vector<std::string> resolved;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string& v = values[i];
    ExperimentSpec one;
    try {
      one = parse_experiment(text, spec.source, {key + "=" + v});
    } catch (const InputError& e) {
      // The override's own name (--set KEY=VALUE) is not what the user typed.
      const bool from_value = e.where().rfind("--set ", 0) == 0;
      throw InputError(o.where, from_value ? o.key : e.key(),
                       from_value ? key + " " + v : e.value(), from_value ? e.allowed() : e.what());
    }
    one.name = fmt::format("{}-{}-{}", spec.name, key.substr(key.find('.') + 1), v);
    ExperimentSpec same = one;
    same.name = spec.name;
    resolved.push_back(to_toml(same));
    for (std::size_t j = 0; j < i; ++j)
      if (resolved[j] == resolved[i])
        throw InputError(o.where, o.key, key + " " + v,
                         fmt::format("values {} ({}) and {} ({}) give the same experiment: each "
                                     "value once",
                                     j + 1, values[j], i + 1, v));
    specs.push_back(std::move(one));
  }
  return specs;
}

SweepJob parameter_job(const ExperimentSpec& spec, const std::string& key,
                       const std::vector<std::string>& values, const fs::path& folder) {
  SweepJob job;
  job.specs = parameter_specs(spec, key, values, {"sweep", "--over"});
  for (ExperimentSpec& one : job.specs) one.output_directory = folder.string();
  job.describe = [key](const ExperimentSpec& one) { return fmt::format("{} ({})", one.name, key); };
  job.assemble = [spec, key, values](const std::vector<RunResult>& done) {
    json runs = json::array();
    std::size_t most = 0;
    for (const RunResult& r : done) most = std::max(most, r.cracks);
    for (std::size_t i = 0; i < done.size(); ++i) {
      json e = parameter_entry(values[i], done[i]);
      e["cracks_scaled"] =
          most > 0 ? static_cast<double>(done[i].cracks) / static_cast<double>(most) : 0.0;
      runs.push_back(e);
    }
    return json{{"experiment", spec.name},
                {"variable", key},
                {"test_kind", spec.test_kind()},
                {"cracks_scaled_note",
                 "cracks over the most any run of the sweep had (seed 001, "
                 "figure 16: N_frac / N_frac,max)"},
                {"runs", runs}};
  };
  return job;
}

constexpr const char* kPlanFile = "sweep-plan.json";
constexpr const char* kPlanFormat = "breccia-sweep-plan 1";

// A plan's values as numbers; an error names the plan file `where`.
std::vector<double> plan_numbers(const std::vector<std::string>& values, const std::string& where) {
  std::vector<double> v;
  for (const std::string& t : values) {
    char* end = nullptr;
    v.push_back(std::strtod(t.c_str(), &end));
    if (t.empty() || *end != '\0') throw InputError(where, "values", t, "finite numbers");
  }
  return v;
}

// The job a plan describes, its runs writing into `folder`.
SweepJob job_of_plan(const ExperimentSpec& spec, const json& plan, const fs::path& folder,
                     const RunOptions& opt) {
  const std::string kind = plan.at("kind").get<std::string>();
  const auto values = plan.at("values").get<std::vector<std::string>>();
  const std::string where = (folder / kPlanFile).string();
  if (kind == "confining_stress") return confining_job(spec, plan_numbers(values, where), folder);
  if (kind == "strain_rate") return rate_job(spec, plan_numbers(values, where), folder, opt);
  return parameter_job(spec, plan.at("key").get<std::string>(), values, folder);
}

// Runs a plan's experiments (resuming: what an earlier pass left) and writes sweep.json.
// Under mpirun every rank runs its share, and root alone writes sweep.json and the report; the
// other ranks learn the sweep's status from root. Root builds the job first: a strain-rate
// sweep measures the sample, packing and caching it for the other ranks.
SweepResult execute_plan(const ExperimentSpec& spec, json plan, const fs::path& folder,
                         const RunOptions& opt, bool resuming) {
  SweepJob job;
  ranks::on_root([&] {
    job = job_of_plan(spec, plan, folder, opt);
    return std::string();
  });
  if (!ranks::root()) job = job_of_plan(spec, plan, folder, opt);
  SweepResult out;
  out.folder = folder.string();
  out.runs = run_all(spec, job.specs, folder, opt, job.describe, resuming);
  out.status = ranks::on_root([&] {
    const std::string status = sweep_status(out.runs, job.specs.size());
    json sweep = job.assemble(out.runs);
    sweep["status"] = status;
    if (ranks::size() > 1) sweep["ranks"] = ranks::size();
    if (opt.ranks_per_run > 1) sweep["ranks_per_run"] = opt.ranks_per_run;
    if (plan.contains("resumed")) sweep["resumed"] = plan["resumed"];
    SweepResult written = out;
    written.status = status;
    finish_sweep(spec, written, sweep, opt);
    return status;
  });
  return out;
}

// A new sweep: its folder, its plan (the resolved experiment and what varies over which values,
// so that resume_sweep can finish it), then its runs.
SweepResult start_sweep(const ExperimentSpec& spec, const std::string& kind, const std::string& key,
                        const std::vector<std::string>& values, const RunOptions& opt) {
  const fs::path folder = make_sweep_folder(spec);
  const json plan{{"format", kPlanFormat},
                  {"kind", kind},
                  {"key", key},
                  {"values", values},
                  {"experiment_source", spec.source},
                  {"experiment", to_toml(spec)},
                  {"program", fmt::format("breccia {} ({})", kVersion, kCommit)}};
  if (ranks::root()) write_json(folder / kPlanFile, plan);
  return execute_plan(spec, plan, folder, opt, false);
}

std::vector<std::string> exact_text(const std::vector<double>& values) {
  std::vector<std::string> out;
  for (double v : values) out.push_back(fmt::format("{}", v));  // shortest exact form
  return out;
}

}  // namespace

SweepResult run_sweep(const ExperimentSpec& spec, const std::vector<double>& confining,
                      const RunOptions& opt) {
  check_confining(confining, spec, {"sweep", "--confining-mpa", 1e6, " MPa"});
  return start_sweep(spec, "confining_stress", "", exact_text(confining), opt);
}

SweepResult run_rate_sweep(const ExperimentSpec& spec, const std::vector<double>& rates,
                           const RunOptions& opt) {
  check_rates(rates, spec, {"sweep", "--strain-rates"});
  return start_sweep(spec, "strain_rate", "", exact_text(rates), opt);
}

SweepResult run_parameter_sweep(const ExperimentSpec& spec, const std::string& key,
                                const std::vector<std::string>& values, const RunOptions& opt) {
  // Every value checked before any folder exists.
  parameter_specs(spec, key, values, {"sweep", "--over"});
  return start_sweep(spec, "parameter", key, values, opt);
}

namespace {

// The experiment of a plan, checked with its values as a new sweep checks them. Every error
// names the plan file and its key: the plan is what `breccia sweep` resolved, not the user's
// file or options.
ExperimentSpec checked_plan(const fs::path& path, const json& plan) {
  const std::string where = path.string();
  const JsonView v(plan, where);
  if (v.text("format", "") != kPlanFormat)
    throw InputError(where, "format", v.text("format", "(missing)"),
                     std::string("\"") + kPlanFormat + "\"");
  const std::string kind = v.text("kind", "");
  if (kind != "confining_stress" && kind != "strain_rate" && kind != "parameter")
    throw InputError(where, "kind", kind, "confining_stress, strain_rate or parameter");
  const std::string text = v.text("experiment", "");
  if (text.empty())
    throw InputError(where, "experiment", v.has("experiment") ? "\"\"" : "(missing)",
                     "the resolved experiment (TOML) that `breccia sweep` wrote; without it the "
                     "sweep cannot be resumed");
  ExperimentSpec spec;
  try {
    spec = parse_experiment(text, v.text("experiment_source", where), {});
  } catch (const InputError& e) {
    throw InputError(where, "experiment" + (e.key().empty() ? "" : "." + e.key()), e.value(),
                     e.allowed() + " (the plan's experiment does not check out)");
  }
  std::vector<std::string> values;
  for (const JsonView& x : v.elements("values")) values.push_back(x.as_text());
  if (values.empty()) throw InputError(where, "values", "[]", "one value or more");
  const ValuesOrigin origin{where, "values"};
  try {
    if (kind == "parameter") {
      if (v.text("key", "").empty())
        throw InputError(where, "key", "\"\"", "the key the sweep varies");
      parameter_specs(spec, v.text("key", ""), values, origin);
    } else {
      const std::vector<double> numbers = plan_numbers(values, where);
      if (kind == "confining_stress") check_confining(numbers, spec, origin);
      if (kind == "strain_rate") check_rates(numbers, spec, origin);
    }
  } catch (const InputError& e) {
    if (e.where() == where) throw;
    throw InputError(where, "experiment" + (e.key().empty() ? "" : "." + e.key()), e.value(),
                     e.allowed() + " (the plan's experiment does not check out)");
  }
  return spec;
}

}  // namespace

void check_sweep_plan(const std::string& text, const std::string& where) {
  const json plan = json::parse(text, nullptr, false);
  if (plan.is_discarded() || !plan.is_object())
    throw InputError(where, "", "", "not a JSON object (damaged or truncated?)");
  (void)checked_plan(where, plan);
}

SweepResult resume_sweep(const std::string& folder_name, const RunOptions& opt) {
  const fs::path folder(folder_name), path = folder / kPlanFile;
  if (!fs::exists(path))
    throw InputError(folder_name, kPlanFile, "(missing)",
                     "a sweep folder written by `breccia sweep` (sweeps from before version "
                     "0.1.0's sweep plans cannot be resumed: resume their runs one by one)");
  // Root reads and extends the plan; every rank gets root's copy.
  const json plan = json::parse(ranks::on_root([&] {
    json read = read_json_object(path.string());
    (void)checked_plan(path, read);
    if (!read.contains("resumed")) read["resumed"] = json::array();
    json entry{{"when", fmt::format("{:%Y-%m-%dT%H:%M:%S}", fmt::localtime(std::time(nullptr)))},
               {"program", fmt::format("breccia {} ({})", kVersion, kCommit)},
               {"command", opt.command_line}};
    if (ranks::size() > 1) entry["ranks"] = ranks::size();
    if (opt.ranks_per_run > 1) entry["ranks_per_run"] = opt.ranks_per_run;
    read["resumed"].push_back(entry);
    write_json(path, read);
    return read.dump();
  }));
  const ExperimentSpec spec = checked_plan(path, plan);
  if (opt.log) opt.log("resuming the sweep in " + folder_name);
  return execute_plan(spec, plan, folder, opt, true);
}

}  // namespace breccia
