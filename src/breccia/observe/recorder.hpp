#pragma once
// The recorder interface: what a run's recorders (history, cracks, snapshots, acoustic emission)
// have in common. A recorder reads the simulation, never changes it, writes its own files and
// saves and restores itself in a checkpoint. The run holds them in a list made from the registry
// (observe/registry.hpp) and calls them after every step, at every history row and at the end;
// adding one is a new type here plus one line in the registry.
//
// A type in the registry provides, besides the virtual members below:
//   static constexpr std::string_view kind;   // its name, and its label in checkpoints
//   static std::unique_ptr<Recorder> create(const RecorderSetup&);
//   static std::unique_ptr<Recorder> restore(const RecorderSetup&, ArchiveReader&);
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "breccia/core/archive.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

struct ExperimentSpec;

// What a recorder is made from: the run folder, the resolved experiment, and the simulation and
// lab test as they stand when loading begins (or when a checkpoint was restored).
struct RecorderSetup {
  std::filesystem::path folder;
  const ExperimentSpec& spec;
  const Simulation& sim;
  const Protocol& test;
  // Whether this process writes the run's files: not a split sample's other ranks, whose
  // recorders run beside root's, alike, for what they share (a scratch folder takes the rest).
  bool writes_files = true;
};

// One history row as the run measured it: the test's axial state and its own columns.
struct RecordedRow {
  const AxialState& axial;
  const std::vector<double>& test_values;
};

class Recorder {
 public:
  virtual ~Recorder() = default;
  virtual std::string_view name() const noexcept = 0;  // the registry's `kind`
  // After every step of the loading. Called often: return at once when there is nothing to do.
  virtual void after_step(const Simulation&, const Protocol&) {}
  // The grains after_step will read in this step, besides the walls: on a sample split over
  // ranks the run brings them current first (at_row and finish see the whole sample). Called
  // on every rank before after_step: it may read what it needs to know them collectively.
  virtual GrainReads grains_read_after_step(const Simulation&, const Protocol&) { return {}; }
  // At every history row; what is written here is flushed, so an interrupted run keeps it.
  virtual void at_row(const Simulation&, const Protocol&, const RecordedRow&) {}
  // Whether at_row will read the whole sample's pairs and bonds at this row (a snapshot's
  // particle stresses): a sample split over ranks is then gathered whole around the row.
  virtual bool reads_whole_sample(const RecordedRow&) const { return false; }
  // When the loading ends, whether complete or interrupted: the last records, flushed.
  virtual void finish(const Simulation&) {}
  // Everything needed to continue exactly after a restore (file lengths, counters, state).
  virtual void save_state(ArchiveWriter&) const = 0;
  // The files it writes, relative to the run folder, for the manifest.
  virtual std::vector<std::string> files() const = 0;
};

}  // namespace breccia
