// The command under mpirun (built only with MPI): a sweep's runs and a calibration's tests,
// spread over ranks, give the folders of one process, byte for byte in every table; a sweep
// stopped on some ranks resumes on others; SIGUSR1 to mpirun stops every rank with a checkpoint;
// commands that run in one process and bad input are refused once, by name.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_harness.hpp"

namespace fs = std::filesystem;
using breccia::testing::last_line;
using breccia::testing::read;
using breccia::testing::Result;
using breccia::testing::run;
using breccia::testing::run_with_prefix;

namespace {

// Open MPI as CI runs it: as root, more ranks than cores, on one machine (shared memory only, no
// network), with no cross-memory attach (containers forbid it).
std::string mpirun(int ranks) {
  return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
         "OMPI_MCA_btl=self,vader OMPI_MCA_btl_vader_single_copy_mechanism=none mpirun "
         "--oversubscribe -np " +
         std::to_string(ranks) + " ";
}

// A small UCS that breaks bonds in about a second, over three bond strengths.
const std::string kSweep =
    std::string(" --set sample.source=\"file\" --set sample.file=\"") + BRECCIA_SOURCE_DIR +
    "/tests/data/ucs-small.geom\" --set engine.density_scaling=100 --set output.plot=false"
    " --set material.preset=\"custom\" --set contact.law=\"hertz_mindlin\""
    " --set contact.shear_modulus=29e9 --set contact.poisson_ratio=0.33"
    " --set contact.friction=0.4 --set bond.modulus=8e9 --set bond.tensile_strength=30e6"
    " --set bond.cohesion=300e6 --set loading.platen_speed=0.2 --set loading.max_strain=0.006"
    " --set engine.threads=1 --over bond.tensile_strength 25e6 30e6 35e6";

// Runs a shell command line; its output and exit status.
Result shell(const std::string& command) {
  Result r{0, {}};
  FILE* p = popen(("sh -c '" + command + "' 2>&1").c_str(), "r");
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, p)) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

int count(const std::string& text, const std::string& part) {
  int n = 0;
  for (auto at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}

// The one folder a command wrote into `out` (under mpirun the ranks' output reaches the terminal
// in no fixed order, so the folder printed last may not be the last line).
fs::path only_folder(const fs::path& out) {
  EXPECT_TRUE(fs::exists(out));
  if (!fs::exists(out) || fs::is_empty(out)) return out / "(nothing written)";
  return fs::directory_iterator(out)->path();
}

// The sweep of one process, run once per test process (ctest runs the tests here in processes of
// their own, side by side: each has its own folder, removed when it ends).
const fs::path& serial_sweep() {
  struct Sweep {
    fs::path out = fs::temp_directory_path() / ("breccia_mpi_serial_" + std::to_string(getpid()));
    fs::path folder;
    Sweep() {
      fs::remove_all(out);
      const Result r = run("sweep --jobs 1 --output " + out.string() + kSweep);
      EXPECT_EQ(r.code, 0) << r.out;
      folder = last_line(r.out);
    }
    ~Sweep() { fs::remove_all(out); }
  };
  static const Sweep sweep;
  return sweep.folder;
}

// Every run of sweep `b` has the tables of the same run of the one-process sweep, byte for byte,
// and sweep.json the same results.
void expect_as_one_process(const fs::path& b, const std::string& how) {
  const fs::path a = serial_sweep();
  const auto ja = nlohmann::json::parse(read(a / "sweep.json"));
  const auto jb = nlohmann::json::parse(read(b / "sweep.json"));
  EXPECT_EQ(jb["status"], "complete") << how;
  ASSERT_EQ(ja["runs"].size(), 3u);
  ASSERT_EQ(jb["runs"].size(), 3u) << how;
  ASSERT_GT(ja["runs"][0]["cracks"].get<int>(), 10) << "the runs must break bonds";
  for (std::size_t i = 0; i < 3; ++i) {
    for (const char* key : {"status", "value", "cracks", "cracks_scaled", "fragments", "metrics"})
      EXPECT_EQ(ja["runs"][i][key], jb["runs"][i][key]) << how << ": run " << i << " " << key;
    const fs::path ra = a / ja["runs"][i]["folder"].get<std::string>();
    const fs::path rb = b / jb["runs"][i]["folder"].get<std::string>();
    for (const char* f : {"history.csv", "cracks.csv", "events.csv", "walls.csv", "fragments.csv",
                          "b_value_windows.csv"})
      EXPECT_EQ(read(ra / f), read(rb / f)) << how << ": run " << i << " " << f;
  }
}

}  // namespace

// Two ranks (one runs two of the three runs) and four (one rank has none): the folders of one
// process; root alone writes sweep.json and prints, once.
// On 2 ranks each rank runs whole runs; on 4, in groups of 2 (--ranks-per-run 2), each run is
// split over the 2 ranks of a group.
TEST(Mpi, ASweepOverRanksGivesTheFoldersOfOneProcess) {
  for (int ranks : {2, 4}) {
    const int each = ranks == 4 ? 2 : 1;
    const fs::path out = fs::temp_directory_path() / ("breccia_mpi_sweep_" + std::to_string(ranks));
    fs::remove_all(out);
    const Result r =
        run_with_prefix(mpirun(ranks), "sweep --ranks-per-run " + std::to_string(each) +
                                           " --output " + out.string() + kSweep);
    ASSERT_EQ(r.code, 0) << r.out;
    const fs::path b = only_folder(out);
    expect_as_one_process(b, std::to_string(ranks) + " ranks");
    const auto sweep = nlohmann::json::parse(read(b / "sweep.json"));
    EXPECT_EQ(sweep["ranks"], ranks);
    EXPECT_EQ(sweep.value("ranks_per_run", 1), each);
    // Each run's manifest says where it ran: on one rank of the launch, or split over a group.
    const auto first_run = sweep["runs"][0]["folder"];
    const auto manifest =
        nlohmann::json::parse(read(b / first_run.get<std::string>() / "manifest.json"));
    EXPECT_EQ(manifest["mpi"]["ranks"], each == 1 ? ranks : each);
    EXPECT_EQ(manifest["mpi"]["sample_split_over_ranks"], each > 1);
    if (each > 1) {
      EXPECT_EQ(manifest["mpi"]["launch_ranks"], ranks);
    }
    EXPECT_EQ(count(r.out, "sweep ucs-berea (complete)"), 1) << r.out;
    EXPECT_EQ(count(r.out, each == 1 ? "complete on rank " : "complete on ranks "), 3) << r.out;
    for (const char* name : {"25e6", "30e6", "35e6"})
      EXPECT_TRUE(fs::exists(b / "experiments" /
                             ("ucs-berea-tensile_strength-" + std::string(name) + ".log")));
    fs::remove_all(out);
  }
}

// Stopped at a step on three ranks, resumed on two: the stopped runs continue from their
// checkpoints on whichever rank takes them.
TEST(Mpi, ASweepStoppedOnThreeRanksResumesOnTwo) {
  const fs::path out = fs::temp_directory_path() / "breccia_mpi_resume";
  fs::remove_all(out);
  const Result cut =
      run_with_prefix(mpirun(3), "sweep --stop-at-step 1500 --output " + out.string() + kSweep);
  EXPECT_NE(cut.code, 0) << cut.out;
  EXPECT_EQ(count(cut.out, "sweep ucs-berea (interrupted)"), 1) << cut.out;
  const fs::path b = only_folder(out);
  const auto stopped = nlohmann::json::parse(read(b / "sweep.json"));
  for (const auto& run_entry : stopped["runs"]) {
    EXPECT_EQ(run_entry["status"], "interrupted");
    EXPECT_TRUE(fs::exists(b / run_entry["folder"].get<std::string>() / "checkpoint.bin"));
  }
  // Stopped whole on single ranks, the runs resume each split over both ranks.
  const Result resumed = run_with_prefix(mpirun(2), "resume --ranks-per-run 2 " + b.string());
  ASSERT_EQ(resumed.code, 0) << resumed.out;
  expect_as_one_process(b, "resumed on 2 ranks");
  const auto plan = nlohmann::json::parse(read(b / "sweep-plan.json"));
  EXPECT_EQ(plan["resumed"][0]["ranks"], 2);
  EXPECT_EQ(plan["resumed"][0]["ranks_per_run"], 2);
  fs::remove_all(out);
}

// mpirun passes SIGUSR1 on to every rank (its SIGINT and SIGTERM kill them a second later): the
// runs stop with checkpoints, the sweep says interrupted, and resume finishes it.
TEST(Mpi, Usr1ToMpirunStopsEveryRankWithACheckpoint) {
  const fs::path out = fs::temp_directory_path() / "breccia_mpi_usr1";
  fs::remove_all(out);
  // Signalled once both ranks' runs have written their first rows; the slow platen keeps them
  // running for about ten seconds more.
  const Result r =
      shell(mpirun(2) + BRECCIA_CLI + " sweep --output " + out.string() + kSweep +
            " --set loading.platen_speed=0.02 & pid=$!; until [ $(ls " + out.string() +
            "/*/2*/history.csv 2>/dev/null | wc -l) -ge 2 ]; do sleep 0.1; done; sleep 0.5; "
            "kill -USR1 $pid; wait $pid");
  const fs::path b = only_folder(out);
  ASSERT_TRUE(fs::exists(b / "sweep.json")) << r.out;
  const auto j = nlohmann::json::parse(read(b / "sweep.json"));
  EXPECT_EQ(j["status"], "interrupted") << r.out;
  int checkpoints = 0;
  for (const auto& e : j["runs"])
    if (!e["folder"].get<std::string>().empty() &&
        fs::exists(b / e["folder"].get<std::string>() / "checkpoint.bin"))
      ++checkpoints;
  EXPECT_EQ(checkpoints, 2) << r.out;
  fs::remove_all(out);
}

// A command that runs in one process is refused under mpirun, and bad input is named once.
TEST(Mpi, OneProcessCommandsAndBadInputAreRefusedOnce) {
  const Result r = run_with_prefix(mpirun(2), "generate --output x.csv");
  EXPECT_NE(r.code, 0);
  EXPECT_EQ(count(r.out, "`breccia generate` runs in one process"), 1) << r.out;
  const Result bad = run_with_prefix(mpirun(2), "sweep --set bond.no_such_key=1" + kSweep);
  EXPECT_NE(bad.code, 0);
  EXPECT_EQ(count(bad.out, "unknown key"), 1) << bad.out;
  const Result jobs = run_with_prefix(mpirun(2), "sweep --jobs 2" + kSweep);
  EXPECT_NE(jobs.code, 0);
  EXPECT_EQ(count(jobs.out, "'--jobs' = 2"), 1) << jobs.out;
  const Result groups = run_with_prefix(mpirun(2), "sweep --ranks-per-run 3" + kSweep);
  EXPECT_EQ(groups.code, 2);
  EXPECT_EQ(count(groups.out, "'--ranks-per-run' = 3"), 1) << groups.out;
  EXPECT_EQ(count(groups.out, "divide the launch's 2 ranks"), 1) << groups.out;
}

namespace {

// The small UCS of the sweep, alone (its first strength).
std::string small_ucs() {
  return kSweep.substr(0, kSweep.find(" --over"));
}

// A file's text without the lines that name the output folder (the resolved experiment's).
std::string without_output_folder(const std::string& text) {
  std::istringstream in(text);
  std::string out;
  for (std::string line; std::getline(in, line);)
    if (line.rfind("directory = ", 0) != 0) out += line + "\n";
  return out;
}

// A summary without what depends on the clock, the machine or the output folder, at any depth:
// timings, the sample cache's path, the folder in the resolved experiment's text.
nlohmann::json without_machine(const nlohmann::json& j) {
  static const std::vector<std::string> machine = {
      "wall_seconds", "loading_loop", "particle_steps_per_second", "resumed", "packing_seconds",
      "seconds",      "cached_file"};
  if (j.is_object()) {
    nlohmann::json out = nlohmann::json::object();
    for (const auto& [key, value] : j.items())
      if (std::find(machine.begin(), machine.end(), key) == machine.end())
        out[key] = without_machine(value);
    return out;
  }
  if (j.is_array()) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& value : j) out.push_back(without_machine(value));
    return out;
  }
  if (j.is_string()) return without_output_folder(j.get<std::string>());
  return j;
}

nlohmann::json results_of(const fs::path& summary) {
  return without_machine(nlohmann::json::parse(read(summary)));
}

// Every file of run folder `b` is that of `a`, byte for byte, but the manifest (the launch, the
// clock) and summary.json's timings.
void expect_same_run_files(const fs::path& a, const fs::path& b, const std::string& how) {
  std::size_t compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(a)) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), a);
    if (rel == "manifest.json") continue;
    ASSERT_TRUE(fs::exists(b / rel)) << how << ": " << rel;
    if (rel == "summary.json")
      EXPECT_TRUE(results_of(a / rel) == results_of(b / rel)) << how << ": summary.json differs";
    else if (rel == "experiment.toml")
      EXPECT_EQ(without_output_folder(read(a / rel)), without_output_folder(read(b / rel))) << how;
    else
      EXPECT_TRUE(read(a / rel) == read(b / rel)) << how << ": " << rel << " differs";
    ++compared;
  }
  EXPECT_GT(compared, 8u) << how;
}

}  // namespace

// One sample split over 2 ranks (2,266 grains: the first owns 1,024, the second the rest; the
// resumption test below splits it over 3) writes the run folder of one process, every table and
// snapshot byte for byte; root alone writes and prints, and the manifest records the split. The
// AE source radius is below a grain's radius: the grains the monitor reads around its sources
// are then those its sources touch more than those near the cracks (the ranks share only those
// between rows).
TEST(Mpi, ARunSplitOverRanksWritesTheFilesOfOneProcess) {
  const fs::path out =
      fs::temp_directory_path() / ("breccia_mpi_split_" + std::to_string(getpid()));
  fs::remove_all(out);
  const std::string args =
      small_ucs() + " --set output.snapshot_strain_interval=0.002 --set ae.source_radius=0.3e-3";
  const Result one = run("run --output " + (out / "one").string() + args);
  ASSERT_EQ(one.code, 0) << one.out;
  const fs::path a = last_line(one.out);
  ASSERT_GT(nlohmann::json::parse(read(a / "summary.json"))["bonds_broken"].get<int>(), 10)
      << "the run must break bonds";
  const fs::path dir = out / "two";
  const Result split = run_with_prefix(mpirun(2), "run --quiet --output " + dir.string() + args);
  ASSERT_EQ(split.code, 0) << split.out;
  EXPECT_EQ(count(split.out, dir.string()), 1) << split.out;  // root alone prints the folder
  const fs::path b = only_folder(dir);
  expect_same_run_files(a, b, "2 ranks");
  const auto m = nlohmann::json::parse(read(b / "manifest.json"));
  EXPECT_EQ(m["mpi"]["ranks"], 2);
  EXPECT_EQ(m["mpi"]["sample_split_over_ranks"], true);
  EXPECT_EQ(m["mpi"]["particles"], nlohmann::json::parse("[1024, 1242]"));
  // What each rank received: at least the other's grains at every row (184 B a grain in 3D).
  const auto& traffic = m["mpi"]["traffic"];
  ASSERT_EQ(traffic["received_bytes"].size(), 2u) << m["mpi"].dump();
  const auto rows = static_cast<std::uint64_t>(count(read(b / "history.csv"), "\n") - 1);
  ASSERT_GT(rows, 5u);
  EXPECT_GE(traffic["received_bytes"][0].get<std::uint64_t>(), rows * 1242u * 184u);
  EXPECT_GE(traffic["received_bytes"][1].get<std::uint64_t>(), rows * 1024u * 184u);
  EXPECT_EQ(traffic["exchange_seconds"].size(), 2u);
  // A step waits at two collectives (the ghosts with the last step's integrator partials, then
  // the loads), a third in steps with cracks or a sampled energy; the split, the rebuilds, the
  // rows and the AE monitor's reads add fewer. Five a step (a signal flag, the integrator's
  // partials alone, the loads' sizes sent first) would fail this.
  const auto steps = traffic["loop_steps"].get<std::uint64_t>();
  ASSERT_GT(steps, 1000u);
  EXPECT_LT(traffic["collectives"].get<std::uint64_t>(), 3 * steps) << traffic.dump();
  fs::remove_all(out);
}

// Small samples (about 1,100 grains or more: the second rank owns the grains past 1,024) of four
// other kinds of test: a 2D biaxial test confined by membranes (forces on the boundary grains,
// strain gauges), a 3D triaxial test in a membrane (its nodes chosen over both ranks' grains), a
// Brazilian disc, and a ball dropped on a slab (a dynamic test with a free body). Each split over
// 2 ranks writes the files of one process.
TEST(Mpi, OtherTestsSplitOverRanksWriteTheFilesOfOneProcess) {
  const fs::path out =
      fs::temp_directory_path() / ("breccia_mpi_kinds_" + std::to_string(getpid()));
  fs::remove_all(out);
  fs::create_directories(out);
  const std::vector<std::pair<std::string, std::string>> tests = {
      {"biaxial",
       "[engine]\ndimension = 2\ndensity_scaling = 100\n[material]\npreset = \"berea_2d\"\n"
       "[sample]\nshape = \"rectangle\"\nwidth = 0.002\nheight = 0.0035\nradius_min = 20e-6\n"
       "radius_max = 60e-6\nporosity = 0.176\n[test]\nkind = \"biaxial\"\n"
       "confining_stress = 15e6\nplaten_speed = 0.6\nmax_strain = 0.02\n"
       "[output]\nsnapshot_strain_interval = 0.005\n"},
      {"triaxial-membrane",
       "[material]\npreset = \"berea\"\n[sample]\nshape = \"cylinder\"\ndiameter = 0.0045\n"
       "height = 0.0055\nradius_min = 0.15e-3\nradius_max = 0.25e-3\n[test]\n"
       "kind = \"triaxial\"\nconfining_stress = 1e6\nmembrane = true\nplaten_speed = 0.8\n"
       "max_strain = 0.012\nstop_fraction = 0\n[output]\nsnapshot_strain_interval = 0.004\n"},
      // Adaptive loading: its checks read every grain, gathered from the ranks.
      {"ucs-adaptive",
       "[material]\npreset = \"berea\"\n[sample]\nwidth = 0.003\ndepth = 0.003\n"
       "height = 0.006\nradius_min = 0.13e-3\nradius_max = 0.2e-3\n[test]\nkind = \"ucs\"\n"
       "platen_speed = 0.05\nadaptive_speed_ratio = 8\nmax_strain = 0.014\n"
       "[output]\nsnapshot_strain_interval = 0.005\n"},
      {"brazilian",
       "[material]\npreset = \"berea\"\n[sample]\nshape = \"cylinder\"\ndiameter = 0.004\n"
       "height = 0.002\nradius_min = 0.12e-3\nradius_max = 0.18e-3\n[test]\n"
       "kind = \"brazilian\"\nplaten_speed = 0.4\nmax_strain = 0.05\nstop_fraction = 0.6\n"
       "[output]\nsnapshot_strain_interval = 0.01\n"},
      {"impact",
       "[engine]\ndensity_scaling = 1\nlocal_damping = 0\n[sample]\nshape = \"slab\"\n"
       "width = 0.009\ndepth = 0.009\nslab_thickness = 0.0015\nradius_min = 0.2e-3\n"
       "radius_max = 0.3e-3\n[test]\nkind = \"impact\"\nprojectile_diameter = 1e-3\n"
       "impact_speed = 60\nstandoff = 0.02e-3\nduration = 6e-6\n"
       "[output]\nsnapshot_strain_interval = 0\n"}};
  for (const auto& [kind, body] : tests) {
    const fs::path file = out / (kind + ".toml");
    std::ofstream(file) << "name = \"" << kind << "\"\n" << body;
    const std::string args = " " + file.string() + " --quiet --threads 1 --set output.plot=false";
    const Result one = run("run --output " + (out / kind / "one").string() + args);
    ASSERT_EQ(one.code, 0) << kind << ": " << one.out;
    const Result two =
        run_with_prefix(mpirun(2), "run --output " + (out / kind / "two").string() + args);
    ASSERT_EQ(two.code, 0) << kind << ": " << two.out;
    const fs::path a = last_line(one.out), b = last_line(two.out);
    const auto summary = nlohmann::json::parse(read(a / "summary.json"));
    ASSERT_GT(summary["particles"].get<int>(), 1024) << kind << ": the second rank must own grains";
    ASSERT_GT(summary["bonds_broken"].get<int>(), 10) << kind << ": the test must break bonds";
    if (kind == "ucs-adaptive") {
      ASSERT_GT(summary["adaptive_loading"]["largest_speed_m_per_s"].get<double>(), 0.1)
          << "the platens must speed up";
    }
    expect_same_run_files(a, b, kind + " on 2 ranks");
  }
  fs::remove_all(out);
}

// A split run stopped at a step writes the checkpoint of one process: stopped on 3 ranks, resumed
// and stopped again on 2, then finished in one process, it gives the files of the uninterrupted
// run.
TEST(Mpi, ASplitRunResumesAtAnotherRankCount) {
  const fs::path out = fs::temp_directory_path() / ("breccia_mpi_stop_" + std::to_string(getpid()));
  fs::remove_all(out);
  const Result one = run("run --output " + (out / "one").string() + small_ucs());
  ASSERT_EQ(one.code, 0) << one.out;
  const Result stopped = run_with_prefix(
      mpirun(3), "run --stop-at-step 300 --output " + (out / "three").string() + small_ucs());
  EXPECT_EQ(stopped.code, 130) << stopped.out;
  const fs::path b = only_folder(out / "three");
  ASSERT_TRUE(fs::exists(b / "checkpoint.bin")) << stopped.out;
  const Result again = run_with_prefix(mpirun(2), "resume --stop-at-step 600 " + b.string());
  EXPECT_EQ(again.code, 130) << again.out;
  EXPECT_EQ(count(again.out, "resuming"), 1) << again.out;
  const Result resumed = run("resume " + b.string());
  ASSERT_EQ(resumed.code, 0) << resumed.out;
  expect_same_run_files(last_line(one.out), b, "stopped on 3 ranks and on 2, finished in one");
  const auto m = nlohmann::json::parse(read(b / "manifest.json"));
  ASSERT_EQ(m["resumed"].size(), 2u);
  EXPECT_EQ(m["resumed"][0]["mpi"]["ranks"], 2);
  fs::remove_all(out);
}

namespace {

// Starts `breccia run` with `args` under mpirun on `ranks`, runs `act` (a shell command; $pid is
// mpirun's) once `ready` (a shell condition) holds, or after a minute, and waits for mpirun: what
// the ranks printed and mpirun's exit status.
Result acted_on_run(int ranks, const std::string& args, const std::string& ready,
                    const std::string& act, const fs::path& log) {
  const Result r = shell(mpirun(ranks) + BRECCIA_CLI + " run " + args + " > " + log.string() +
                         " 2>&1 & pid=$!; n=0; until " + ready +
                         " || [ $n -ge 1200 ]; do sleep 0.05; n=$((n+1)); done; " + act +
                         "; wait $pid; s=$?; cat " + log.string() + "; exit $s");
  return r;
}

// A shell condition: the run folder under `out` holds at least `rows` rows of history.csv.
std::string history_rows(const fs::path& out, int rows) {
  return "[ $(cat " + out.string() + "/*/history.csv 2>/dev/null | wc -l) -gt " +
         std::to_string(rows) + " ]";
}

// Every file under `dir` whose name ends in .tmp (a write that was never finished).
std::vector<fs::path> temporaries(const fs::path& dir) {
  std::vector<fs::path> out;
  if (!fs::exists(dir)) return out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().extension() == ".tmp") out.push_back(e.path());
  return out;
}

// The small UCS loaded slowly enough (about 7 s in one process) for a signal to arrive during
// its loading, with a checkpoint every half second of wall time.
std::string slow_small_ucs() {
  return small_ucs() +
         " --set loading.platen_speed=0.05 --set output.checkpoint_interval_s=0.5 --quiet";
}

}  // namespace

// SIGINT, SIGTERM or SIGUSR1 to mpirun while the sample is packed or consolidated (each rank
// consolidates root's packing): every rank stops there, the error is printed once, and no run
// folder is left half made (the run starts again from the sample cache, when one was written).
TEST(Mpi, ASignalWhileTheSampleIsBuiltStopsEveryRankAndLeavesNoRun) {
  const fs::path out =
      fs::temp_directory_path() / ("breccia_mpi_build_" + std::to_string(getpid()));
  const std::string sample =
      " --set sample.width=0.005 --set sample.depth=0.005 --set sample.height=0.01"
      " --set engine.threads=1 --set test.kind=\"triaxial\" --set test.confining_stress=30e6"
      " --set engine.density_scaling=1 --set output.plot=false";
  struct Case {
    int ranks;
    const char* signal;
    const char* phase;
    const char* ready;  // a line the log shows once the phase has begun
  };
  for (const Case& c : {Case{2, "INT", "preparing the sample", "packing:"},
                        Case{3, "TERM", "consolidating the sample", "packing ("},
                        Case{2, "USR1", "consolidating the sample", "packing ("}}) {
    const std::string how = std::string("SIG") + c.signal + " on " + std::to_string(c.ranks) +
                            " ranks while " + c.phase;
    fs::remove_all(out);
    const fs::path log = out.string() + ".log";
    const Result r = acted_on_run(c.ranks, "--output " + out.string() + sample,
                                  "grep -q \"" + std::string(c.ready) + "\" " + log.string(),
                                  std::string("kill -") + c.signal + " $pid", log);
    EXPECT_NE(r.code, 0) << how << "\n" << r.out;
    EXPECT_EQ(count(r.out, "error: interrupted by a signal while "), 1) << how << "\n" << r.out;
    EXPECT_EQ(count(r.out, std::string("while ") + c.phase), 1) << how << "\n" << r.out;
    if (fs::exists(out)) {
      for (const auto& e : fs::directory_iterator(out))
        EXPECT_EQ(e.path().filename(), "samples") << how << ": a run folder was left";
    }
    EXPECT_TRUE(temporaries(out).empty()) << how;
    fs::remove(log);
  }
  fs::remove_all(out);
}

// SIGINT, SIGTERM or SIGUSR1 to mpirun during the loading, on 2 or 3 ranks: every rank stops at
// the same step with one checkpoint, the manifest says interrupted, and the run resumed at
// another rank count gives the files of one uninterrupted process.
TEST(Mpi, ASignalDuringTheLoadingLeavesACheckpointThatResumesAtAnotherRankCount) {
  const fs::path out =
      fs::temp_directory_path() / ("breccia_mpi_signal_" + std::to_string(getpid()));
  fs::remove_all(out);
  const Result one = run("run --output " + (out / "one").string() + slow_small_ucs());
  ASSERT_EQ(one.code, 0) << one.out;
  struct Case {
    int ranks;
    const char* signal;
    int resume_ranks;  // 1: one process, without mpirun
  };
  for (const Case& c : {Case{2, "TERM", 1}, Case{3, "USR1", 2}, Case{3, "INT", 1}}) {
    const std::string how = std::string("SIG") + c.signal + " on " + std::to_string(c.ranks) +
                            " ranks, resumed on " + std::to_string(c.resume_ranks);
    const fs::path dir = out / c.signal;
    const Result r =
        acted_on_run(c.ranks, "--output " + dir.string() + slow_small_ucs(), history_rows(dir, 6),
                     std::string("kill -") + c.signal + " $pid", out / "log");
    EXPECT_NE(r.code, 0) << how << "\n" << r.out;
    const fs::path b = only_folder(dir);
    ASSERT_TRUE(fs::exists(b / "checkpoint.bin")) << how << "\n" << r.out;
    const auto m = nlohmann::json::parse(read(b / "manifest.json"));
    EXPECT_EQ(m["status"], "interrupted") << how;
    // The run's last word, or (mpirun's SIGKILL a second after SIGINT or SIGTERM came before it)
    // the one written with the checkpoint.
    EXPECT_EQ(m["stop_reason"].get<std::string>().rfind("interrupted by a signal", 0), 0u)
        << how << ": " << m["stop_reason"];
    EXPECT_TRUE(m["checkpoint"]["step"].is_number()) << how << ": " << m.dump();
    // mpirun's SIGKILL, a second after SIGINT or SIGTERM, may cut a write short: its temporary
    // is left until the resume clears it (one stands in here whatever the timing). SIGUSR1 kills
    // nothing.
    if (std::string(c.signal) == "USR1") {
      EXPECT_TRUE(temporaries(dir).empty()) << how;
    }
    std::ofstream(b / "events.csv.tmp") << "a write cut short";
    const Result resumed = c.resume_ranks == 1 ? run("resume --quiet " + b.string())
                                               : run_with_prefix(mpirun(c.resume_ranks),
                                                                 "resume --quiet " + b.string());
    ASSERT_EQ(resumed.code, 0) << how << "\n" << resumed.out;
    EXPECT_TRUE(temporaries(dir).empty()) << how;
    expect_same_run_files(last_line(one.out), b, how);
  }
  fs::remove_all(out);
}

// One rank killed outright (SIGKILL: mpirun then ends the others with SIGTERM, and SIGKILL a
// second later): the last complete checkpoint is intact, the manifest says interrupted and why,
// and the run resumes on 2 ranks to the files of one process.
TEST(Mpi, ARankKilledOutrightLeavesTheLastCheckpointAndAManifestThatSaysSo) {
  const fs::path out = fs::temp_directory_path() / ("breccia_mpi_kill_" + std::to_string(getpid()));
  fs::remove_all(out);
  const Result one = run("run --output " + (out / "one").string() + slow_small_ucs());
  ASSERT_EQ(one.code, 0) << one.out;
  const fs::path dir = out / "killed";
  // The rank mpirun started first (root, as Open MPI starts them).
  const Result r =
      acted_on_run(3, "--output " + dir.string() + slow_small_ucs(),
                   "[ -f " + dir.string() + "/*/checkpoint.bin ] && " + history_rows(dir, 8),
                   "kill -9 $(cut -d\" \" -f1 /proc/$pid/task/*/children | head -n1)", out / "log");
  EXPECT_NE(r.code, 0) << r.out;
  const fs::path b = only_folder(dir);
  ASSERT_TRUE(fs::exists(b / "checkpoint.bin")) << r.out;
  const auto m = nlohmann::json::parse(read(b / "manifest.json"));
  EXPECT_EQ(m["status"], "interrupted") << r.out;
  EXPECT_NE(m["stop_reason"].get<std::string>().find("SIGTERM arrived"), std::string::npos)
      << m["stop_reason"];
  const Result resumed = run_with_prefix(mpirun(2), "resume --quiet " + b.string());
  ASSERT_EQ(resumed.code, 0) << resumed.out;
  expect_same_run_files(last_line(one.out), b, "a rank killed on 3, resumed on 2");
  fs::remove_all(out);
}

namespace {

// trials.jsonl without what depends on the machine (the folder's time stamp, the wall time).
std::vector<nlohmann::json> trial_records(const fs::path& file) {
  std::vector<nlohmann::json> out;
  std::istringstream lines(read(file));
  for (std::string line; std::getline(lines, line);) {
    nlohmann::json j = nlohmann::json::parse(line);
    j.erase("folder");
    j.erase("wall_seconds");
    out.push_back(j);
  }
  return out;
}

}  // namespace

// A calibration on two ranks runs each batch of tests (here the three packings of the
// verification) at once, one process per test, and with --ranks-per-run 2 splits each test over
// both; both record what one process records: the same tests, numbered alike, measuring the
// same properties, and the same parameters.
TEST(Mpi, ACalibrationOverRanksRecordsTheTestsOfOneProcess) {
  const fs::path dir = fs::temp_directory_path() / "breccia_mpi_calibration";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "c.toml")
      << "[calibration]\nname = \"t\"\ntrials_per_stage = 1\npasses = 1\n"
         "verify_seeds = [2, 3, 4]\n[targets]\nyoungs_modulus = 8e9\n[free]\n"
         "\"bond.modulus\" = [2e9, 60e9]\n"
      << breccia::testing::kTinyCalibrationExperiment;
  const std::string args = "calibrate " + (dir / "c.toml").string() + " --output ";
  const Result one = run(args + (dir / "one").string());
  ASSERT_EQ(one.code, 0) << one.out;
  const Result two = run_with_prefix(mpirun(2), args + (dir / "two").string());
  ASSERT_EQ(two.code, 0) << two.out;
  EXPECT_EQ(count(two.out, "calibration complete"), 1) << two.out;
  // On 2 ranks as one group of 2: each test split over both (4 ranks on these 2 cores would
  // double the test's time; the sweep test shares runs out over several groups).
  const Result split =
      run_with_prefix(mpirun(2), args + (dir / "split").string() + " --ranks-per-run 2");
  ASSERT_EQ(split.code, 0) << split.out;
  const auto a = trial_records(dir / "one" / "t" / "trials.jsonl");
  ASSERT_EQ(a.size(), 4u) << "a trial and three verification tests";
  for (const char* launch : {"two", "split"}) {
    EXPECT_EQ(a, trial_records(dir / launch / "t" / "trials.jsonl")) << launch;
    EXPECT_EQ(read(dir / "one" / "t" / "material.toml"), read(dir / launch / "t" / "material.toml"))
        << launch;
  }
  fs::remove_all(dir);
}
