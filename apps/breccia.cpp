// The `breccia` command: run an experiment into a run folder, check an experiment file, write the
// experiment reference, print the version.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>

#include "breccia/core/error.hpp"
#include "breccia/io/experiment.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/version.hpp"

namespace {
std::atomic<bool> g_interrupt{false};
extern "C" void on_signal(int) {
  g_interrupt.store(true);
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
  run->add_option("--threads", threads, "OpenMP threads (engine.threads)");
  run->add_flag("--quiet", quiet, "no progress bar or messages; only the run folder is printed");

  auto* check = app.add_subcommand("check", "validate an experiment file and print it resolved");
  std::string check_file;
  std::vector<std::string> check_overrides;
  check->add_option("experiment", check_file, "experiment file (TOML); omit for the default");
  check->add_option("--set", check_overrides, "override a key: section.key=value")->take_all();

  auto* docs = app.add_subcommand("docs", "write the experiment-file reference (Markdown)");
  std::string docs_out;
  docs->add_option("--output", docs_out, "file to write (default: standard output)");

  app.add_subcommand("version", "print the version");

  CLI11_PARSE(app, argc, argv);

  try {
    if (*run) {
      if (!output.empty()) overrides.push_back("output.directory=\"" + output + "\"");
      if (threads >= 0) overrides.push_back("engine.threads=" + std::to_string(threads));
      const breccia::ExperimentSpec spec =
          file.empty() ? breccia::parse_experiment("", "built-in default", overrides)
                       : breccia::load_experiment(file, overrides);
      std::signal(SIGINT, on_signal);
      std::signal(SIGTERM, on_signal);
      breccia::RunOptions opt;
      opt.command_line = command_line;
      opt.interrupt = &g_interrupt;
      opt.show_progress = !quiet && spec.progress && isatty(fileno(stderr));
      if (!quiet) opt.log = [](const std::string& m) { std::cerr << m << "\n"; };
      const breccia::RunResult r = breccia::run_experiment(spec, opt);
      if (!quiet) {
        std::cerr << "status: " << r.status << " (" << r.stop_reason << ")\n";
        std::fprintf(stderr,
                     "peak axial stress %.3f MPa at strain %.5f; Young's modulus %.3f GPa; "
                     "%zu cracks (%zu tensile, %zu shear); %llu steps in %.1f s; energy "
                     "residual %.2g of the work\n",
                     r.peak_stress * 1e-6, r.strain_at_peak, r.youngs_modulus * 1e-9, r.cracks,
                     r.tensile, r.shear, static_cast<unsigned long long>(r.steps), r.wall_seconds,
                     r.energy_residual_relative);
      }
      std::cout << r.folder << std::endl;
      return r.status == "complete" ? 0 : 130;
    }
    if (*check) {
      const breccia::ExperimentSpec spec =
          check_file.empty() ? breccia::parse_experiment("", "built-in default", check_overrides)
                             : breccia::load_experiment(check_file, check_overrides);
      std::cout << breccia::to_toml(spec);
      return 0;
    }
    if (*docs) {
      const std::string text = breccia::experiment_docs();
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
  } catch (const breccia::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
