// The `breccia` command: run an experiment into a run folder, check an experiment file, write the
// experiment reference, print the version.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <new>

#include "breccia/calibrate/calibrate.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/io/experiment.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/material/library.hpp"
#include "breccia/version.hpp"

namespace {
extern "C" void on_signal(int) {
  breccia::interrupt_flag().store(true);
}

void catch_signals() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
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
// `breccia calibrate FILE`: the calibration folder is <output>/<name>; running the same command
// again after an interruption continues it.
int calibrate_command(const std::string& file, const std::string& output, bool check_only,
                      const std::string& command_line) {
  const breccia::CalibrationSpec spec = breccia::load_calibration(file);
  if (check_only) {
    std::cout << "calibration \"" << spec.name << "\": " << spec.targets.size() << " targets, "
              << spec.free.size() << " free parameters, " << spec.tied.size()
              << " tied; file is valid\n";
    return 0;
  }
  catch_signals();
  breccia::CalibrationOptions opt;
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
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Breccia: a virtual rock-mechanics laboratory (bonded-particle DEM)"};
  app.require_subcommand(1);
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);

  auto* run = app.add_subcommand("run", "run an experiment (the built-in default without a file)");
  std::string file;
  std::vector<std::string> overrides;
  std::string output;
  int threads = -1;
  bool quiet = false;
  run->add_option("experiment", file, "experiment file (TOML); omit for the built-in default");
  run->add_option("--set", overrides, "override a key: section.key=value")->take_all();
  run->add_option("--output", output, "folder that receives the run folder (output.directory)");
  run->add_option("--threads", threads, "OpenMP threads (engine.threads; 0 = all cores)")
      ->check(CLI::Range(0, 1024));
  run->add_flag("--quiet", quiet, "no progress bar or messages; only the run folder is printed");
  std::int64_t stop_at_step = 0;
  run->add_option("--stop-at-step", stop_at_step,
                  "stop with a checkpoint once the engine has taken this many steps in all; "
                  "continue with `breccia resume`")
      ->check(CLI::Range(std::int64_t{1}, std::numeric_limits<std::int64_t>::max()));

  auto* resume = app.add_subcommand(
      "resume", "continue an interrupted run from its checkpoint, in the same run folder");
  std::string resume_dir;
  int resume_threads = -1;
  bool resume_quiet = false;
  std::int64_t resume_stop = 0;
  resume->add_option("folder", resume_dir, "run folder with a checkpoint.bin")->required();
  resume->add_option("--threads", resume_threads, "OpenMP threads (the result does not change)")
      ->check(CLI::Range(0, 1024));
  resume->add_flag("--quiet", resume_quiet, "no progress bar or messages");
  resume->add_option("--stop-at-step", resume_stop, "stop again, with a checkpoint, at this step")
      ->check(CLI::Range(std::int64_t{1}, std::numeric_limits<std::int64_t>::max()));

  auto* gen = app.add_subcommand("generate",
                                 "pack and bond a sample ([sample] keys) and save it to a file");
  std::string gen_file, gen_out;
  std::vector<std::string> gen_overrides;
  gen->add_option("experiment", gen_file, "experiment file (TOML); omit for the default");
  gen->add_option("--set", gen_overrides, "override a key: section.key=value")->take_all();
  gen->add_option("--output", gen_out, "sample file to write (breccia-geometry)")->required();

  auto* sweep = app.add_subcommand(
      "sweep", "run the experiment at several confining stresses; fit Mohr-Coulomb, Hoek-Brown");
  std::string sweep_file;
  std::vector<std::string> sweep_overrides;
  std::vector<double> sweep_mpa;
  std::string sweep_output;
  sweep->add_option("experiment", sweep_file, "experiment file (TOML); omit for the default");
  sweep->add_option("--set", sweep_overrides, "override a key: section.key=value")->take_all();
  sweep->add_option("--confining-mpa", sweep_mpa, "confining stresses in MPa, e.g. 0 5 10")
      ->required()
      ->expected(1, 100);
  sweep->add_option("--output", sweep_output, "folder that receives the sweep folder");

  auto* summ =
      app.add_subcommand("summarise", "print the headline results of a run or sweep folder");
  std::string summ_dir;
  summ->add_option("folder", summ_dir, "run folder or sweep folder")->required();

  auto* report = app.add_subcommand(
      "report", "write report.html and its figures (report/*.png) for a run or sweep folder");
  std::string report_dir;
  report->add_option("folder", report_dir, "run folder")->required();

  auto* check = app.add_subcommand("check", "validate an experiment file and print it resolved");
  std::string check_file;
  std::vector<std::string> check_overrides;
  check->add_option("experiment", check_file, "experiment file (TOML); omit for the default");
  check->add_option("--set", check_overrides, "override a key: section.key=value")->take_all();

  auto* docs = app.add_subcommand("docs", "write the experiment-file reference (Markdown)");
  std::string docs_out;
  docs->add_option("--output", docs_out, "file to write (default: standard output)");
  bool docs_calibration = false;
  docs->add_flag("--calibration", docs_calibration,
                 "the calibration-file reference instead (docs/calibration.md)");

  auto* cal = app.add_subcommand(
      "calibrate", "fit micro-parameters to lab targets (a calibration file); resumable");
  std::string cal_file, cal_output = "calibrations";
  bool cal_check = false;
  cal->add_option("calibration", cal_file, "calibration file (TOML)")->required();
  cal->add_option("--output", cal_output, "folder that receives <output>/<name>/")
      ->capture_default_str();
  cal->add_flag("--check", cal_check, "only validate the calibration file");

  auto* materials = app.add_subcommand(
      "materials", "write the material library's table and calibration records (Markdown)");
  std::string materials_out;
  materials->add_option("--output", materials_out, "file to write (default: standard output)");

  app.add_subcommand("version", "print the version");

  if (unknown_command(argc, argv, app)) return 2;
  CLI11_PARSE(app, argc, argv);

  try {
    if (*run) {
      if (!output.empty()) overrides.push_back("output.directory=\"" + output + "\"");
      if (threads >= 0) overrides.push_back("engine.threads=" + std::to_string(threads));
      const breccia::ExperimentSpec spec =
          file.empty() ? breccia::parse_experiment("", "built-in default", overrides)
                       : breccia::load_experiment(file, overrides);
      catch_signals();
      breccia::RunOptions opt;
      opt.command_line = command_line;
      opt.interrupt = &breccia::interrupt_flag();
      opt.show_progress = !quiet && spec.progress && isatty(fileno(stderr));
      if (!quiet) opt.log = [](const std::string& m) { std::cerr << m << "\n"; };
      opt.stop_at_step = static_cast<std::uint64_t>(stop_at_step);
      const breccia::RunResult r = breccia::run_experiment(spec, opt);
      if (!quiet) {
        std::cerr << "status: " << r.status << " (" << r.stop_reason << ")\n";
        std::cerr << breccia::summarise_folder(r.folder);
      }
      std::cout << r.folder << std::endl;
      return r.status == "complete" ? 0 : 130;
    }
    if (*resume) {
      catch_signals();
      breccia::RunOptions opt;
      opt.command_line = command_line;
      opt.interrupt = &breccia::interrupt_flag();
      opt.stop_at_step = static_cast<std::uint64_t>(resume_stop);
      opt.show_progress = !resume_quiet && isatty(fileno(stderr));
      if (!resume_quiet) opt.log = [](const std::string& m) { std::cerr << m << "\n"; };
      const breccia::RunResult r =
          breccia::resume_run(resume_dir, breccia::ResumeOptions{resume_threads}, opt);
      if (!resume_quiet) {
        std::cerr << "status: " << r.status << " (" << r.stop_reason << ")\n";
        std::cerr << breccia::summarise_folder(r.folder);
      }
      std::cout << r.folder << std::endl;
      return r.status == "complete" ? 0 : 130;
    }
    auto load = [](const std::string& f, const std::vector<std::string>& o) {
      return f.empty() ? breccia::parse_experiment("", "built-in default", o)
                       : breccia::load_experiment(f, o);
    };
    if (*gen) {
      const breccia::ExperimentSpec spec = load(gen_file, gen_overrides);
      catch_signals();
      breccia::generate_sample(spec, gen_out, [](const std::string& m) { std::cerr << m << "\n"; });
      std::cout << gen_out << std::endl;
      return 0;
    }
    if (*sweep) {
      if (!sweep_output.empty())
        sweep_overrides.push_back("output.directory=\"" + sweep_output + "\"");
      const breccia::ExperimentSpec spec = load(sweep_file, sweep_overrides);
      catch_signals();
      breccia::RunOptions opt;
      opt.command_line = command_line;
      opt.interrupt = &breccia::interrupt_flag();
      opt.show_progress = spec.progress && isatty(fileno(stderr));
      opt.log = [](const std::string& m) { std::cerr << m << "\n"; };
      std::vector<double> pa;
      for (double m : sweep_mpa) pa.push_back(m * 1e6);
      const breccia::SweepResult r = breccia::run_sweep(spec, pa, opt);
      std::cerr << breccia::summarise_folder(r.folder);
      std::cout << r.folder << std::endl;
      return r.status == "complete" ? 0 : 130;
    }
    if (*cal) return calibrate_command(cal_file, cal_output, cal_check, command_line);
    if (*summ) {
      std::cout << breccia::summarise_folder(summ_dir);
      return 0;
    }
    if (*report) {
      namespace fs = std::filesystem;
      if (!fs::exists(fs::path(report_dir) / "summary.json") &&
          !fs::exists(fs::path(report_dir) / "sweep.json"))
        throw breccia::InputError(report_dir, "summary.json", "(missing)",
                                  "not a finished run or sweep folder");
      const bool run_folder = fs::exists(fs::path(report_dir) / "summary.json");
      if (run_folder && !breccia::plot_run(report_dir)) {
        std::cerr << "error: stress_strain.png failed; see " << report_dir << "/plot.log\n";
        return 1;
      }
      if (!breccia::write_report(report_dir)) {
        std::cerr << "error: the report failed; see " << report_dir << "/report.log\n";
        return 1;
      }
      std::cout << report_dir << "/report.html" << std::endl;
      return 0;
    }
    if (*check) {
      const breccia::ExperimentSpec spec =
          check_file.empty() ? breccia::parse_experiment("", "built-in default", check_overrides)
                             : breccia::load_experiment(check_file, check_overrides);
      std::cout << breccia::to_toml(spec);
      return 0;
    }
    if (*docs || *materials) {
      const std::string text =
          *docs ? (docs_calibration ? breccia::calibration_docs() : breccia::experiment_docs())
                : breccia::materials_docs();
      if (*materials) docs_out = materials_out;
      if (docs_out.empty()) {
        std::cout << text;
      } else {
        std::ofstream out(docs_out);
        if (!out) throw breccia::InputError(docs_out, "", "", "cannot write the file");
        out << text;
      }
      return 0;
    }
    std::cout << "breccia " << breccia::kVersion << "\n";
    return 0;
  } catch (const breccia::Interrupted& e) {
    std::cerr << "error: " << e.what() << "; nothing was written\n";
    return 130;
  } catch (const breccia::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "error: out of memory: the sample or the run is larger than this machine can "
                 "hold (see sample.max_particles)\n";
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    std::cerr << "error: " << e.path1().string() << ": " << e.code().message() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
