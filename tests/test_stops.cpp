// Runs that stop where they should not go on: a signal during the failure analysis after the
// loading, and writes that fail (a full disk, stood in for by a file-size limit). Each leaves its
// folder marked for what happened, with nothing half-written that looks whole.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "breccia/core/interrupt.hpp"
#include "breccia/run/run.hpp"
#include "breccia/spec/experiment.hpp"
#include "cli_harness.hpp"

namespace fs = std::filesystem;
using namespace breccia;
using breccia::testing::read;

namespace {

// A tiny FCC block (64 grains) loaded to failure: seconds.
ExperimentSpec tiny_run(const fs::path& dir) {
  return parse_experiment(
      "[sample]\nsource = \"lattice\"\ncells = [2, 2, 4]\n[engine]\nthreads = 1\n"
      "[output]\nplot = false\nsnapshot_strain_interval = 0\ndirectory = \"" +
          dir.string() + "\"\n",
      "stops-test", {});
}

// A signal that arrives once the loading has ended stops the failure analysis: the run is marked
// interrupted with the reason, its tables stay, and no summary.json is written. The signal is
// stood in for by the process-wide flag set from the progress callback's last call (the loop
// itself polls the run's own flag, left unset, so the loading ends as it would).
TEST(Stops, ASignalDuringTheFailureAnalysisStopsIt) {
  const fs::path dir = fs::temp_directory_path() / "breccia_stop_analysis";
  fs::remove_all(dir);
  std::atomic<bool> loop_flag{false};
  RunOptions opt;
  opt.interrupt = &loop_flag;
  opt.progress = [](const RunProgress&) { interrupt_flag().store(true); };
  const RunResult r = run_experiment(tiny_run(dir), opt);
  interrupt_flag().store(false);
  EXPECT_EQ(r.status, "interrupted");
  EXPECT_NE(r.stop_reason.find("analysing the failure"), std::string::npos) << r.stop_reason;
  EXPECT_NE(r.stop_reason.find("the loading had ended"), std::string::npos) << r.stop_reason;
  const fs::path folder(r.folder);
  EXPECT_FALSE(fs::exists(folder / "summary.json"));
  EXPECT_TRUE(fs::exists(folder / "history.csv"));
  const auto manifest = nlohmann::json::parse(read(folder / "manifest.json"));
  EXPECT_EQ(manifest.value("status", ""), "interrupted");
  // Without the signal the same run completes (the test above stopped for the signal alone).
  RunOptions plain;
  EXPECT_EQ(run_experiment(tiny_run(dir), plain).status, "complete");
  fs::remove_all(dir);
}

// The run folder under `root` (the one folder there).
fs::path only_folder(const fs::path& root) {
  for (const auto& e : fs::directory_iterator(root))
    if (e.is_directory() && e.path().filename() != "samples") return e.path();
  return {};
}

// Writes that fail, as on a full disk: a file-size limit in the child (the command ignores
// SIGXFSZ, so the write returns EFBIG instead of the signal killing it). At 40 KB the tables fail
// during the loading; at 72 KB they are written and the failure analysis's indicator table
// (81 KB for this run) fails. Either way the run stops with an error naming the file, its
// manifest says failed, and no summary.json is left (whole or not).
TEST(Stops, AFullDiskStopsTheRunWithAnErrorAndAFailedManifest) {
  for (const int kb : {40, 72}) {
    const fs::path dir = fs::temp_directory_path() / ("breccia_full_disk_" + std::to_string(kb));
    fs::remove_all(dir);
    // ulimit -f counts 512-byte blocks in Debian's sh (dash).
    const auto r = breccia::testing::run_with_prefix(
        "trap '' XFSZ; ulimit -f " + std::to_string(kb * 2) + "; ",
        "run --quiet --threads 1 --output " + dir.string() +
            " --set sample.source=\"lattice\" --set sample.cells=[2,2,4] --set output.plot=false "
            "--set output.snapshot_strain_interval=0");
    EXPECT_TRUE(r.code == 1 || r.code == 2) << kb << " KB: " << r.out;  // an error, no signal
    EXPECT_NE(r.out.find("cannot write"), std::string::npos) << kb << " KB: " << r.out;
    EXPECT_NE(r.out.find("file-size"), std::string::npos) << kb << " KB: " << r.out;
    const fs::path folder = only_folder(dir);
    ASSERT_FALSE(folder.empty()) << r.out;
    EXPECT_NE(r.out.find(folder.string()), std::string::npos) << "names a file of the run folder";
    const auto manifest = nlohmann::json::parse(read(folder / "manifest.json"), nullptr, false);
    ASSERT_FALSE(manifest.is_discarded()) << kb << " KB";
    EXPECT_EQ(manifest.value("status", ""), "failed") << kb << " KB";
    EXPECT_NE(manifest.value("stop_reason", "").find("cannot write"), std::string::npos);
    EXPECT_FALSE(fs::exists(folder / "summary.json")) << kb << " KB";
    for (const auto& e : fs::directory_iterator(folder))
      EXPECT_NE(e.path().extension(), ".tmp") << e.path() << " left behind";
    fs::remove_all(dir);
  }
}

// A calibration whose trial cannot write its tables stops with the error and says failed in its
// own manifest (it said "running" before).
TEST(Stops, AFullDiskStopsACalibrationWithAFailedManifest) {
  const fs::path dir = fs::temp_directory_path() / "breccia_full_disk_calibration";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "c.toml")
      << "[calibration]\nname = \"t\"\ntrials_per_stage = 1\npasses = 1\nverify_seeds = []\n"
         "[targets]\nyoungs_modulus = 8e9\n[free]\n\"bond.modulus\" = [2e9, 60e9]\n"
      << breccia::testing::kTinyCalibrationExperiment;
  const auto r = breccia::testing::run_with_prefix(
      "trap '' XFSZ; ulimit -f 160; ",
      "calibrate " + (dir / "c.toml").string() + " --output " + (dir / "out").string());
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("cannot write"), std::string::npos) << r.out;
  const auto manifest =
      nlohmann::json::parse(read(dir / "out" / "t" / "manifest.json"), nullptr, false);
  ASSERT_FALSE(manifest.is_discarded()) << r.out;
  EXPECT_EQ(manifest.value("status", ""), "failed") << r.out;
  EXPECT_NE(manifest.value("error", "").find("cannot write"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "out" / "t" / "record.json"));
  fs::remove_all(dir);
}

}  // namespace

namespace {

// A sweep stopped by Ctrl-C while its second run packs its own sample (each seed packs anew)
// exits 130 and leaves a folder that `breccia resume` finishes: the first run is kept, the
// second runs from the start. (The signal is sent once the second packing has begun; should the
// packing be done by then, the run stops with a checkpoint instead, and the same holds.)
TEST(Stops, ASweepStoppedWhileARunPacksResumesToTheEnd) {
  const fs::path dir = fs::temp_directory_path() / "breccia_stop_packing";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string sweep =
      std::string(BRECCIA_CLI) + " sweep --jobs 1 --output " + dir.string() +
      " --set engine.threads=1 --set output.plot=false --set output.snapshot_strain_interval=0"
      " --set sample.width=3e-3 --set sample.depth=3e-3 --set sample.height=6e-3"
      " --set test.max_strain=0.004 --over engine.seed 1 2";
  const std::string log = (dir / "sweep.log").string();
  // The log exists before the sweep starts: the loop below must not read a missing file (grep
  // would print nothing, the test would fail and the signal would come at once).
  const std::string script = ": > " + log + "; " + sweep + " > " + log + ".out 2> " + log +
                             " & pid=$!; n=0; while [ $n -lt 600 ] && [ "
                             "\"$(grep -c 'sample: generating' " +
                             log +
                             ")\" -lt 2 ]; do sleep 0.02; n=$((n+1)); done; "
                             "kill -INT $pid; wait $pid; echo \"exit $?\"";
  const auto stopped = breccia::testing::run_with_prefix("", "version >/dev/null; " + script);
  EXPECT_NE(stopped.out.find("exit 130"), std::string::npos) << stopped.out << read(log);
  fs::path folder;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory() && e.path().string().ends_with("-sweep")) folder = e.path();
  ASSERT_FALSE(folder.empty()) << read(log);
  // The sweep says where it stopped (its last line is the folder, to resume).
  const auto stopped_json = nlohmann::json::parse(read(folder / "sweep.json"), nullptr, false);
  ASSERT_FALSE(stopped_json.is_discarded()) << read(log);
  EXPECT_EQ(stopped_json.value("status", ""), "interrupted");
  EXPECT_NE(read(log + ".out").find(folder.string()), std::string::npos);
  const auto resumed = breccia::testing::run("resume --quiet " + folder.string());
  EXPECT_EQ(resumed.code, 0) << resumed.out;
  const auto sweep_json = nlohmann::json::parse(read(folder / "sweep.json"), nullptr, false);
  ASSERT_FALSE(sweep_json.is_discarded()) << resumed.out;
  EXPECT_EQ(sweep_json.value("status", ""), "complete");
  ASSERT_EQ(sweep_json["runs"].size(), 2u);
  for (const auto& r : sweep_json["runs"]) EXPECT_EQ(r.value("status", ""), "complete");
  fs::remove_all(dir);
}

}  // namespace
