// The `breccia` command: one function per subcommand (run, resume, generate, sweep, summarise,
// report, check, docs, calibrate, materials, predict, version) declares its options and what it
// does.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <new>

#include "breccia/calibrate/calibrate.hpp"
#include "breccia/core/allocator.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/float_mode.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/material/library.hpp"
#include "breccia/run/rank_pool.hpp"
#include "breccia/run/run.hpp"
#include "breccia/run/sample_build.hpp"
#include "breccia/spec/experiment.hpp"
#include "breccia/spec/spec_field.hpp"
#include "breccia/version.hpp"

namespace {

// An output path given empty (a shell variable that was never set) is refused, not read as
// "the default": nothing is written where the user did not ask.
const CLI::Validator kNonEmptyPath(
    [](const std::string& v) {
      return v.empty() ? std::string("'' is no path: give the folder or file to write to")
                       : std::string();
    },
    "PATH");

extern "C" void on_signal(int number) {
  breccia::interrupt_signal().store(number);
  breccia::interrupt_flag().store(true);
}

// SIGUSR1 asks the same stop: mpirun passes it on to every rank as it is (its SIGINT and SIGTERM
// end the ranks after a second), and batch systems send it ahead of a time limit (Slurm's
// --signal=USR1@120).
void catch_signals() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGUSR1, on_signal);
  // A file-size limit makes the write fail (EFBIG), which the run reports and marks, instead of
  // killing the process with a half-written folder.
  std::signal(SIGXFSZ, SIG_IGN);
}

// CLI11 answers an unknown first word with "A subcommand is required"; name it instead.
bool unknown_command(int argc, char** argv, const CLI::App& app) {
  if (argc < 2 || argv[1][0] == '-') return false;
  std::string allowed;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    if (sub->get_name() == argv[1]) return false;
    allowed += (allowed.empty() ? "" : ", ") + sub->get_name();
  }
  std::cerr << "error: unknown command '" << argv[1] << "'; allowed: " << allowed
            << " (breccia --help)\n";
  return true;
}

// Runs split over groups of `each` ranks (a sweep's, a calibration's): the groups must fill the
// launch.
void check_ranks_per_run(const std::string& command, int each) {
  const int n = breccia::ranks::size();
  if (n % each != 0)
    throw breccia::InputError(
        command, "--ranks-per-run", std::to_string(each),
        fmt::format("the runs are split over groups of ranks that must divide the launch's {} "
                    "rank{} (mpirun -np N, N a multiple of --ranks-per-run)",
                    n, n == 1 ? "" : "s"));
}

// `breccia calibrate FILE`: the calibration folder is <output>/<name>; running the same command
// again after an interruption continues it.
int calibrate_command(const std::string& file, const std::string& output, bool check_only,
                      int ranks_per_run, const std::string& command_line) {
  check_ranks_per_run("calibrate", ranks_per_run);
  const breccia::CalibrationSpec spec = breccia::load_calibration(file);
  if (!breccia::ranks::root()) {
    // Under mpirun the other ranks run the tests root hands out (none for --check).
    if (check_only) return 0;
    catch_signals();
    breccia::RunOptions quiet;
    quiet.interrupt = &breccia::interrupt_flag();
    breccia::RankPool::serve(quiet);
    return 0;
  }
  if (check_only) {
    catch_signals();
    breccia::check_calibration(spec, [](const std::string& m) { std::cerr << m << std::endl; });
    std::cout << "calibration \"" << spec.name << "\": " << spec.targets.size() << " targets, "
              << spec.free.size() << " free parameters, " << spec.tied.size()
              << " tied; file is valid: every test builds on every sample set\n";
    return 0;
  }
  catch_signals();
  // Under mpirun: each trial's tests at once over the ranks (or their groups).
  breccia::RankPool pool(ranks_per_run);
  breccia::CalibrationOptions opt;
  opt.pool = &pool;
  opt.output_directory = output;
  opt.command_line = command_line;
  opt.log = [](const std::string& m) { std::cerr << m << std::endl; };
  const breccia::CalibrationResult r = breccia::run_calibration(spec, opt);
  if (r.status == "complete") {
    std::cerr << "calibration complete: " << r.evaluations << " trials, " << r.test_runs
              << " test runs, " << static_cast<int>(r.wall_seconds) << " s\n"
              << breccia::verdict_table(r) << "parameters: " << r.folder << "/material.toml\n";
  } else {
    std::cerr << "calibration " << r.status << ": the finished tests are kept; run the same "
              << "command again to continue\n";
  }
  std::cout << r.folder << std::endl;
  return r.status == "complete" ? 0 : 130;
}

// One subcommand: its CLI11 node and what it does once parsed. The options live in a struct
// owned by the closure, so each subcommand is one function that declares and runs it.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

void log_to_stderr(const std::string& m) {
  std::cerr << m << "\n";
}

breccia::ExperimentSpec load_spec(const std::string& file,
                                  const std::vector<std::string>& overrides) {
  return file.empty() ? breccia::parse_experiment("", "built-in default", overrides)
                      : breccia::load_experiment(file, overrides);
}

// Prints the outcome of a run that wrote a run folder (root speaks for a split run's ranks); the
// exit status of the command.
int finish_run(const breccia::RunResult& r, bool quiet) {
  if (!breccia::ranks::root()) return r.status == "complete" ? 0 : 130;
  if (!quiet) {
    std::cerr << "status: " << r.status << " (" << r.stop_reason << ")\n";
    std::cerr << breccia::summarise_folder(r.folder);
  }
  std::cout << r.folder << std::endl;
  return r.status == "complete" ? 0 : 130;
}

Command add_run(CLI::App& app, const std::string& command_line) {
  struct Options {
    std::string file, output;
    std::vector<std::string> overrides;
    int threads = -1;
    bool quiet = false;
    std::int64_t stop_at_step = 0;
  };
  auto o = std::make_shared<Options>();
  auto* c = app.add_subcommand("run", "run an experiment (the built-in default without a file)");
  c->add_option("experiment", o->file, "experiment file (TOML); omit for the built-in default");
  c->add_option("--set", o->overrides, "override a key: section.key=value")->take_all();
  c->add_option("--output", o->output, "folder that receives the run folder (output.directory)")
      ->check(kNonEmptyPath);
  c->add_option("--threads", o->threads, "OpenMP threads (engine.threads; 0 = all cores)")
      ->check(CLI::Range(0, 1024));
  c->add_flag("--quiet", o->quiet, "no progress bar or messages; only the run folder is printed");
  c->add_option("--stop-at-step", o->stop_at_step,
                "stop with a checkpoint once the engine has taken this many steps in all; "
                "continue with `breccia resume`")
      ->check(CLI::Range(std::int64_t{1}, std::numeric_limits<std::int64_t>::max()));
  return {c, [o, command_line] {
            if (!o->output.empty())
              o->overrides.push_back("output.directory=" + breccia::toml_quoted(o->output));
            if (o->threads >= 0)
              o->overrides.push_back("engine.threads=" + std::to_string(o->threads));
            const breccia::ExperimentSpec spec = load_spec(o->file, o->overrides);
            catch_signals();
            breccia::RunOptions opt;
            opt.command_line = command_line;
            opt.interrupt = &breccia::interrupt_flag();
            // Under mpirun the ranks step one sample split between them; root speaks for them.
            opt.split_over_ranks = breccia::ranks::size() > 1;
            const bool speaks = breccia::ranks::root();
            opt.show_progress = speaks && !o->quiet && spec.progress && isatty(fileno(stderr));
            if (speaks && !o->quiet) opt.log = log_to_stderr;
            opt.stop_at_step = static_cast<std::uint64_t>(o->stop_at_step);
            return finish_run(breccia::run_experiment(spec, opt), o->quiet);
          }};
}

// The executable's own path, for a sweep's child processes.
std::string own_executable() {
  std::error_code ec;
  return std::filesystem::read_symlink("/proc/self/exe", ec).string();
}

// Prints the outcome of a sweep; the exit status of the command.
int finish_sweep(const breccia::SweepResult& r) {
  if (breccia::ranks::root()) {
    std::cerr << breccia::summarise_folder(r.folder);
    std::cout << r.folder << std::endl;
  }
  return r.status == "complete" ? 0 : 130;
}

// Under mpirun the ranks share out a sweep's runs; child processes (--jobs) would compete with
// them for the cores.
void check_jobs_on_ranks(int jobs) {
  if (breccia::ranks::size() > 1 && jobs > 1)
    throw breccia::InputError("sweep", "--jobs", std::to_string(jobs),
                              "under mpirun the ranks run the sweep's runs, one each at a time: "
                              "leave --jobs out (or give more ranks)");
}

Command add_resume(CLI::App& app, const std::string& command_line) {
  struct Options {
    std::string folder;
    int threads = -1, jobs = 0, ranks_per_run = 1;
    bool quiet = false;
    std::int64_t stop_at_step = 0;
  };
  auto o = std::make_shared<Options>();
  auto* c = app.add_subcommand("resume",
                               "continue an interrupted run from its checkpoint, in the same run "
                               "folder, or finish an interrupted sweep in its sweep folder");
  c->add_option("folder", o->folder,
                "run folder with a checkpoint.bin, or sweep folder with a sweep-plan.json")
      ->required();
  c->add_option("--threads", o->threads, "OpenMP threads (the result does not change)")
      ->check(CLI::Range(0, 1024));
  c->add_flag("--quiet", o->quiet, "no progress bar or messages");
  c->add_option("--stop-at-step", o->stop_at_step,
                "stop again, with a checkpoint, at this step (a sweep: each run)")
      ->check(CLI::Range(std::int64_t{1}, std::numeric_limits<std::int64_t>::max()));
  auto* jobs = c->add_option("--jobs", o->jobs,
                             "a sweep: runs at once, as separate processes (0: as many as the "
                             "cores allow, 1: one after another)")
                   ->check(CLI::Range(0, 1024));
  auto* ranks_per_run = c->add_option("--ranks-per-run", o->ranks_per_run,
                                      "a sweep under mpirun: split each run over this many ranks "
                                      "(default 1: each rank runs whole runs)")
                            ->check(CLI::Range(1, 1 << 20));
  return {c, [o, command_line, jobs, ranks_per_run] {
            catch_signals();
            breccia::RunOptions opt;
            opt.command_line = command_line;
            opt.interrupt = &breccia::interrupt_flag();
            opt.stop_at_step = static_cast<std::uint64_t>(o->stop_at_step);
            opt.show_progress = !o->quiet && isatty(fileno(stderr));
            if (!o->quiet && breccia::ranks::root()) opt.log = log_to_stderr;
            if (std::filesystem::exists(std::filesystem::path(o->folder) / "sweep-plan.json")) {
              if (o->threads >= 0)
                throw breccia::InputError(
                    "resume", "--threads", std::to_string(o->threads),
                    "a sweep's runs keep the threads of their experiment; give --jobs instead");
              check_jobs_on_ranks(o->jobs);
              check_ranks_per_run("resume", o->ranks_per_run);
              opt.jobs = o->jobs;
              opt.ranks_per_run = o->ranks_per_run;
              opt.executable = own_executable();
              return finish_sweep(breccia::resume_sweep(o->folder, opt));
            }
            // A run resumes split over the ranks, whatever split (or none) it stopped in.
            for (const CLI::Option* sweep_only : {jobs, ranks_per_run})
              if (sweep_only->count() > 0)
                throw breccia::InputError(
                    "resume " + o->folder, sweep_only->get_name(), sweep_only->as<std::string>(),
                    "a sweep's option, and this is a run folder (no sweep-plan.json): a run "
                    "resumes in one process, or split over every rank of `mpirun -np N breccia "
                    "resume FOLDER`");
            opt.split_over_ranks = breccia::ranks::size() > 1;
            if (!breccia::ranks::root()) {
              opt.log = nullptr;
              opt.show_progress = false;
            }
            return finish_run(
                breccia::resume_run(o->folder, breccia::ResumeOptions{o->threads}, opt), o->quiet);
          }};
}

Command add_generate(CLI::App& app) {
  struct Options {
    std::string file, output;
    std::vector<std::string> overrides;
  };
  auto o = std::make_shared<Options>();
  auto* c = app.add_subcommand(
      "generate",
      "pack and bond a sample ([sample] keys) and save it to a file (a lattice, or a table or "
      "GenGeo sample, is written as it is read)");
  c->add_option("experiment", o->file, "experiment file (TOML); omit for the default");
  c->add_option("--set", o->overrides, "override a key: section.key=value")->take_all();
  c->add_option("--output", o->output,
                "sample file to write (breccia-geometry, its report beside it in .json); never a "
                "file the experiment reads, nor one that is not a sample")
      ->required();
  return {c, [o] {
            const breccia::ExperimentSpec spec = load_spec(o->file, o->overrides);
            catch_signals();
            breccia::write_sample(spec, o->output, "--output", log_to_stderr);
            std::cout << o->output << std::endl;
            return 0;
          }};
}

Command add_sweep(CLI::App& app, const std::string& command_line) {
  struct Options {
    std::string file, output;
    std::vector<std::string> overrides;
    std::vector<double> confining_mpa, strain_rates;
    std::vector<std::string> over;
    int jobs = 0, ranks_per_run = 1;
    std::int64_t stop_at_step = 0;
  };
  auto o = std::make_shared<Options>();
  auto* c = app.add_subcommand(
      "sweep",
      "run the experiment at several confining stresses (fit Mohr-Coulomb, Hoek-Brown), "
      "strain rates (fit UCS against the rate), or values of any key (--over)");
  c->add_option("experiment", o->file, "experiment file (TOML); omit for the default");
  c->add_option("--set", o->overrides, "override a key: section.key=value")->take_all();
  auto* confining =
      c->add_option("--confining-mpa", o->confining_mpa, "confining stresses in MPa, e.g. 0 5 10")
          ->expected(1, 100);
  auto* rates = c->add_option("--strain-rates", o->strain_rates,
                              "strain rates in 1/s, e.g. 0.05 0.1 0.5 1 5 10 (needs "
                              "engine.density_scaling = 1)")
                    ->expected(1, 100);
  auto* over = c->add_option("--over", o->over,
                             "a key and its values, e.g. --over sample.slab_thickness 5e-3 6e-3 "
                             "7e-3 (any test)")
                   ->expected(2, 101);
  confining->excludes(rates);
  over->excludes(confining);
  over->excludes(rates);
  c->add_option("--output", o->output, "folder that receives the sweep folder")
      ->check(kNonEmptyPath);
  c->add_option("--jobs", o->jobs,
                "runs at once, as separate processes sharing the cores (0: as many as the cores "
                "allow, 1: one after another)")
      ->check(CLI::Range(0, 1024));
  c->add_option("--ranks-per-run", o->ranks_per_run,
                "under mpirun: split each run over this many ranks, the runs shared out over "
                "the groups (default 1: each rank runs whole runs)")
      ->check(CLI::Range(1, 1 << 20));
  c->add_option("--stop-at-step", o->stop_at_step,
                "stop each run with a checkpoint once it has taken this many steps; finish the "
                "sweep with `breccia resume SWEEP_FOLDER`")
      ->check(CLI::Range(std::int64_t{1}, std::numeric_limits<std::int64_t>::max()));
  return {c, [o, command_line] {
            if (!o->output.empty())
              o->overrides.push_back("output.directory=" + breccia::toml_quoted(o->output));
            const breccia::ExperimentSpec spec = load_spec(o->file, o->overrides);
            catch_signals();
            breccia::RunOptions opt;
            opt.command_line = command_line;
            opt.interrupt = &breccia::interrupt_flag();
            opt.show_progress = spec.progress && isatty(fileno(stderr));
            if (breccia::ranks::root()) opt.log = log_to_stderr;
            check_jobs_on_ranks(o->jobs);
            check_ranks_per_run("sweep", o->ranks_per_run);
            opt.jobs = o->jobs;
            opt.ranks_per_run = o->ranks_per_run;
            opt.stop_at_step = static_cast<std::uint64_t>(o->stop_at_step);
            opt.executable = own_executable();
            if (o->confining_mpa.empty() && o->strain_rates.empty() && o->over.empty())
              throw breccia::InputError("sweep", "--confining-mpa / --strain-rates / --over",
                                        "(none)",
                                        "give the confining stresses, the strain rates, or a key "
                                        "and its values");
            std::vector<double> pa;
            for (double m : o->confining_mpa) pa.push_back(m * 1e6);
            const breccia::SweepResult r =
                !o->over.empty()
                    ? breccia::run_parameter_sweep(
                          spec, o->over.front(),
                          std::vector<std::string>(o->over.begin() + 1, o->over.end()), opt)
                : o->strain_rates.empty() ? breccia::run_sweep(spec, pa, opt)
                                          : breccia::run_rate_sweep(spec, o->strain_rates, opt);
            return finish_sweep(r);
          }};
}

Command add_summarise(CLI::App& app) {
  auto folder = std::make_shared<std::string>();
  auto* c = app.add_subcommand("summarise", "print the headline results of a run or sweep folder");
  c->add_option("folder", *folder, "run folder or sweep folder")->required();
  return {c, [folder] {
            std::cout << breccia::summarise_folder(*folder);
            return 0;
          }};
}

// The last non-empty line of a log (a Python exception's own line), for an error message.
std::string last_line_of(const std::string& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last.empty() ? "(no message)" : last;
}

int report_command(const std::string& folder) {
  namespace fs = std::filesystem;
  const bool run_folder = fs::exists(fs::path(folder) / "summary.json");
  if (!run_folder && !fs::exists(fs::path(folder) / "sweep.json"))
    throw breccia::InputError(folder, "summary.json", "(missing)",
                              "not a finished run or sweep folder");
  // A damaged summary or sweep.json is named by its key before any figure is drawn.
  (void)breccia::summarise_folder(folder);
  if (run_folder && !breccia::plot_run(folder)) {
    std::cerr << "error: stress_strain.png failed: " << last_line_of(folder + "/plot.log")
              << " (whole message: " << folder << "/plot.log)\n";
    return 1;
  }
  if (!breccia::write_report(folder)) {
    std::cerr << "error: the report failed: " << last_line_of(folder + "/report.log")
              << " (whole message: " << folder << "/report.log)\n";
    return 1;
  }
  std::cout << folder << "/report.html" << std::endl;
  return 0;
}

Command add_report(CLI::App& app) {
  auto folder = std::make_shared<std::string>();
  auto* c = app.add_subcommand(
      "report", "write report.html and its figures (report/*.png) for a run or sweep folder");
  c->add_option("folder", *folder, "run folder")->required();
  return {c, [folder] { return report_command(*folder); }};
}

Command add_check(CLI::App& app) {
  struct Options {
    std::string file;
    std::vector<std::string> overrides;
  };
  auto o = std::make_shared<Options>();
  auto* c = app.add_subcommand("check", "validate an experiment file and print it resolved");
  c->add_option("experiment", o->file, "experiment file (TOML); omit for the default");
  c->add_option("--set", o->overrides, "override a key: section.key=value")->take_all();
  return {c, [o] {
            std::cout << breccia::to_toml(load_spec(o->file, o->overrides));
            return 0;
          }};
}

// Writes `text` to `path`, or to standard output when the path is empty.
int write_text(const std::string& text, const std::string& path) {
  if (path.empty()) {
    std::cout << text;
    return 0;
  }
  std::ofstream out(path);
  if (!out) throw breccia::InputError(path, "", "", "cannot write the file");
  out << text;
  return 0;
}

Command add_docs(CLI::App& app) {
  struct Options {
    std::string output;
    bool calibration = false;
  };
  auto o = std::make_shared<Options>();
  auto* c = app.add_subcommand("docs", "write the experiment-file reference (Markdown)");
  c->add_option("--output", o->output, "file to write (default: standard output)")
      ->check(kNonEmptyPath);
  c->add_flag("--calibration", o->calibration,
              "the calibration-file reference instead (docs/calibration.md)");
  return {c, [o] {
            return write_text(
                o->calibration ? breccia::calibration_docs() : breccia::experiment_docs(),
                o->output);
          }};
}

Command add_calibrate(CLI::App& app, const std::string& command_line) {
  struct Options {
    std::string file, output = "calibrations";
    bool check = false;
    int ranks_per_run = 1;
  };
  auto o = std::make_shared<Options>();
  auto* c = app.add_subcommand(
      "calibrate", "fit micro-parameters to lab targets (a calibration file); resumable");
  c->add_option("calibration", o->file, "calibration file (TOML)")->required();
  c->add_option("--output", o->output, "folder that receives <output>/<name>/")
      ->capture_default_str()
      ->check(kNonEmptyPath);
  c->add_flag("--check", o->check, "only validate the calibration file");
  c->add_option("--ranks-per-run", o->ranks_per_run,
                "under mpirun: split each test over this many ranks, the tests shared out over "
                "the groups (default 1: each rank runs whole tests)")
      ->check(CLI::Range(1, 1 << 20));
  return {c, [o, command_line] {
            return calibrate_command(o->file, o->output, o->check, o->ranks_per_run, command_line);
          }};
}

Command add_materials(CLI::App& app) {
  auto output = std::make_shared<std::string>();
  auto* c = app.add_subcommand(
      "materials", "write the material library's table and calibration records (Markdown)");
  c->add_option("--output", *output, "file to write (default: standard output)")
      ->check(kNonEmptyPath);
  return {c, [output] { return write_text(breccia::materials_docs(), *output); }};
}

// The failure predictor lives in the Python package (scikit-learn): its arguments go through.
Command add_predict(CLI::App& app) {
  auto args = std::make_shared<std::vector<std::string>>();
  auto* c = app.add_subcommand(
      "predict",
      "failure predictor (seed 000): `predict train SWEEP... --output MODEL` or `predict apply "
      "RUN --model MODEL`; `predict -h` for its options");
  c->prefix_command();
  c->set_help_flag();
  return {c, [c, args] {
            *args = c->remaining();
            if (args->empty()) args->push_back("--help");
            return breccia::run_python_command("predict", *args);
          }};
}

Command add_version(CLI::App& app) {
  return {app.add_subcommand("version", "print the version"), [] {
            std::cout << "breccia " << breccia::kVersion << "\n"
                      << (breccia::ranks::built_with_mpi() ? "MPI: yes (mpirun -np N breccia sweep)"
                                                           : "MPI: no")
                      << "\n";
            return 0;
          }};
}

// Runs a command, turning what it throws into a message and an exit status. Under mpirun root
// prints; another rank prints only an error of its own, named by its rank (a bad input is bad on
// every rank, and an error root passed on is root's to print). A failure the other ranks do not
// share aborts the launch, which would otherwise wait for this rank.
int guarded(const std::function<int()>& body) {
  const auto fail = [](int code, bool bad_input, const std::string& message) {
    const bool shared = breccia::ranks::failure_is_shared(bad_input);
    if (breccia::ranks::root())
      std::cerr << "error: " << message << "\n";
    else if (!shared)
      std::cerr << "error: rank " << breccia::ranks::rank() << ": " << message << "\n";
    if (!shared) breccia::ranks::abort(code);
    return code;
  };
  try {
    return body();
  } catch (const breccia::ranks::RootFailed& e) {
    return e.interrupted() ? 130 : 1;  // root prints it
  } catch (const breccia::Interrupted& e) {
    return fail(130, false, std::string(e.what()) + "; nothing was written");
  } catch (const breccia::InputError& e) {
    return fail(2, true, e.what());
  } catch (const std::bad_alloc&) {
    return fail(1, false,
                "out of memory: the sample or the run is larger than this machine can hold (see "
                "sample.max_particles)");
  } catch (const std::filesystem::filesystem_error& e) {
    return fail(1, false, e.path1().string() + ": " + e.code().message());
  } catch (const std::exception& e) {
    return fail(1, false, e.what());
  }
}

}  // namespace

// The subcommand a launch names (argv[1]), or empty.
std::string command_word(int argc, char** argv) {
  return argc >= 2 && argv[1][0] != '-' ? argv[1] : "";
}

int main(int argc, char** argv) {
  breccia::configure_allocator();
  breccia::flush_subnormals();  // before OpenMP starts the threads that inherit it
  // Refused before MPI starts: a build without MPI cannot call it, and a command that runs in
  // one process must not run once per rank.
  if (const auto refusal = breccia::ranks::launch_refusal(
          breccia::ranks::launch_from_environment(), breccia::ranks::built_with_mpi(),
          command_word(argc, argv), {"run", "sweep", "resume", "calibrate"})) {
    if (breccia::ranks::launch_from_environment().rank == 0)
      std::cerr << "error: " << *refusal << "\n";
    return 2;
  }
  const breccia::ranks::World world(argc, argv);
  CLI::App app{"Breccia: a virtual rock-mechanics laboratory (bonded-particle DEM)"};
  app.require_subcommand(1);
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
  const std::vector<Command> commands = {add_run(app, command_line),
                                         add_resume(app, command_line),
                                         add_generate(app),
                                         add_sweep(app, command_line),
                                         add_summarise(app),
                                         add_report(app),
                                         add_check(app),
                                         add_docs(app),
                                         add_calibrate(app, command_line),
                                         add_materials(app),
                                         add_predict(app),
                                         add_version(app)};
  if (unknown_command(argc, argv, app)) return 2;
  CLI11_PARSE(app, argc, argv);
  for (const Command& c : commands)
    if (*c.app) return guarded(c.run);
  return 2;  // unreachable: CLI11 requires one subcommand
}
