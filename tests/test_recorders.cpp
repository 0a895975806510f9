// The recorder registry (observe/registry.hpp): every registered recorder is made for a run,
// saves its state and is restored from it, so a new recorder is checked here without further
// work.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <sstream>
#include <string>

#include "breccia/observe/registry.hpp"
#include "breccia/run/sample_build.hpp"
#include "breccia/spec/experiment.hpp"

namespace fs = std::filesystem;
using namespace breccia;

namespace {

// A bonded FCC block under a UCS test, built as a run builds it (without loading). Its bonds are
// weak and a snapshot every few rows, so that a few steps give every recorder some state.
ExperimentSpec tiny_spec() {
  return parse_experiment(
      "[sample]\nsource = \"lattice\"\ncells = [2, 2, 4]\nradius = 5e-4\n"
      "[bond]\ntensile_strength = 2e4\ncohesion = 2e4\n"
      "[test]\nkind = \"ucs\"\nmax_strain = 0.01\nplaten_speed = 1.0\n"
      "[output]\nsnapshot_strain_interval = 0.02\n",
      "tiny.toml", {});
}

}  // namespace

TEST(Recorders, EveryRegisteredKindIsMadeOnceWithItsOwnName) {
  const fs::path dir = fs::temp_directory_path() / "breccia_recorders_kinds";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const ExperimentSpec spec = tiny_spec();
  Built b = build(spec, [](const std::string&) {});
  const RecorderList list = make_recorders({dir, spec, b.sim, *b.protocol});
  ASSERT_EQ(list.size(), RecorderTypes::size);
  std::set<std::string> names;
  for (const auto& r : list) {
    EXPECT_TRUE(names.insert(std::string(r->name())).second) << "two recorders named " << r->name();
    for (const std::string& f : r->files()) EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
  for_each_type<RecorderTypes>(
      [&]<class R>() { EXPECT_EQ(find_recorder<R>(list).name(), R::kind); });
  fs::remove_all(dir);
}

// Loading steps and rows as the run drives them: every recorder after every step and at every
// row.
void load(Simulation& sim, Protocol& test, const RecorderList& list, int rows) {
  std::vector<double> extra;
  for (int row = 0; row < rows; ++row) {
    for (int s = 0; s < 100; ++s) {
      test.control(sim);
      sim.step();
      for (const auto& r : list) r->after_step(sim, test);
    }
    const AxialState a = test.measure(sim);
    extra.clear();
    test.history_values(sim, extra);
    for (const auto& r : list) r->at_row(sim, test, {a, extra});
  }
}

std::string saved_state(const RecorderList& list) {
  std::ostringstream out(std::ios::binary);
  ArchiveWriter w(out);
  save_recorders(list, w);
  return out.str();
}

// Every recorder restored from a checkpoint goes on exactly as the one that was saved: after the
// same further loading both save the same bytes. A part of a recorder's state left out of its
// checkpoint (a counter, the strain of the next snapshot) shows up here.
TEST(Recorders, EveryRegisteredKindContinuesExactlyFromItsCheckpoint) {
  const fs::path dir = fs::temp_directory_path() / "breccia_recorders_round_trip";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const ExperimentSpec spec = tiny_spec();
  Built b = build(spec, [](const std::string&) {});
  Simulation& sim = b.sim;
  Protocol& test = *b.protocol;
  const auto wave_speed = [] { return 2000.0; };
  RecorderList list = make_recorders({dir, spec, sim, test});
  find_recorder<AeMonitor>(list).set_wave_speed_source(wave_speed);
  load(sim, test, list, 40);
  ASSERT_GT(sim.cracks().size(), 0u) << "the test needs cracks";
  ASSERT_GT(find_recorder<SnapshotWriter>(list).count(), 2u) << "the test needs snapshots";
  std::ostringstream checkpoint(std::ios::binary);
  {
    ArchiveWriter w(checkpoint);
    sim.save_state(w);
    test.save_state(w);
    save_recorders(list, w);
  }
  load(sim, test, list, 10);
  const std::string continued = saved_state(list);

  std::istringstream in(checkpoint.str(), std::ios::binary);
  ArchiveReader reader(in, "checkpoint");
  Simulation sim2 = Simulation::restore(reader);
  std::unique_ptr<Protocol> test2;
  ASSERT_TRUE(with_lab_test(spec.test_kind(), [&]<class T>() { test2 = T::restore(reader); }));
  const RecorderList restored = restore_recorders({dir, spec, sim2, *test2}, reader);
  ASSERT_EQ(restored.size(), list.size());
  find_recorder<AeMonitor>(restored).set_wave_speed_source(wave_speed);
  load(sim2, *test2, restored, 10);
  EXPECT_EQ(saved_state(restored), continued);
  fs::remove_all(dir);
}
