#pragma once
// The files of a run folder that are not the run itself: the folder's name, atomic JSON writes,
// the headline summaries of run and sweep folders, the plotting and report scripts, and the
// machine description the manifests carry.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "breccia/spec/experiment.hpp"

namespace breccia {

// Writes JSON atomically (temporary file, then rename): a reader never sees half a manifest.
void write_json(const std::filesystem::path& path, const nlohmann::json& j);
// Creates <output.directory>/<timestamp>-<name>[-k], a new folder for one run or sweep.
std::filesystem::path make_folder(const ExperimentSpec& spec, const std::string& suffix = "");
// A run's name as its folder spells it (after the time stamp): letters, digits and '-' kept,
// anything else '_'.
std::string folder_safe_name(const std::string& name);
// stress_strain.png and report.html of a run folder; a warning through `log` if either fails.
void make_plot(const std::filesystem::path& folder,
               const std::function<void(const std::string&)>& log);

// Human-readable headline results of a run folder (summary.json) or sweep folder (sweep.json).
std::string summarise_folder(const std::string& folder);
// Draws stress_strain.png in a run folder (breccia.plots); false with a message if not.
bool plot_run(const std::string& folder);
// Writes report.html and report/*.png of a run or sweep folder (breccia.report); false with the
// module's messages in report.log if not.
bool write_report(const std::string& folder);

// Runs `python3 -m breccia.<module> <folder>` with Debian's Python; its output goes to
// <folder>/<log_name>, removed when it succeeds. False if it failed.
// Runs `python3 -m breccia.<module> <args>...` with Debian's Python, its output on this
// process's; returns its exit status.
int run_python_command(const std::string& module, const std::vector<std::string>& args);
bool run_python_module(const std::string& module, const std::string& folder,
                       const std::string& log_name);

// A description of this machine for manifests and benchmark records.
std::string machine_description();

}  // namespace breccia
