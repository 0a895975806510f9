#pragma once
// ParaView snapshots (VTK XML, ASCII): per snapshot one .vtu of particles (radius, velocity,
// displacement, angular velocity, rotation, stress tensor, broken-bond count, tag), one of intact
// bonds (lines with their loads, peak stresses and breakage index), and one of the cracks so far
// (points with mode, time, step, energy, radius and the crack plane's normal). Three .pvd
// collections index them by simulated time, so ParaView opens a whole run as a time series. Each
// file is written to a temporary name and renamed, and the collections are rewritten after every
// snapshot: an interrupted run leaves only complete files.
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "breccia/engine/simulation.hpp"
#include "breccia/observe/recorder.hpp"

namespace breccia {

// Snapshots are taken when loading begins, each time the axial strain passes a multiple of
// `interval` (output.snapshot_strain_interval; 0 = none in between) and when loading ends.
class SnapshotWriter : public Recorder {
 public:
  static constexpr std::string_view kind = "snapshots";
  static std::unique_ptr<Recorder> create(const RecorderSetup& setup);
  static std::unique_ptr<Recorder> restore(const RecorderSetup& setup, ArchiveReader& a);

  explicit SnapshotWriter(std::string folder, double interval = 0.0);
  // Resumes the collections of a checkpoint; snapshots taken after it are dropped from them
  // (their files are overwritten by the next ones).
  SnapshotWriter(std::string folder, double interval, ArchiveReader& a, const Simulation& sim);
  void write(const Simulation& sim);
  std::size_t count() const noexcept { return times_.size(); }

  std::string_view name() const noexcept override { return kind; }
  void at_row(const Simulation& sim, const Protocol&, const RecordedRow& row) override;
  bool reads_whole_sample(const RecordedRow& row) const override;
  void finish(const Simulation& sim) override { write(sim); }
  void save_state(ArchiveWriter& a) const override;
  std::vector<std::string> files() const override {
    return {"snapshots/particles.pvd", "snapshots/bonds.pvd", "snapshots/cracks.pvd"};
  }

 private:
  void write_collections() const;
  void write_particles(const Simulation& sim, const std::filesystem::path& path) const;
  void write_bonds(const Simulation& sim, const std::filesystem::path& path) const;
  void write_cracks(const Simulation& sim, const std::filesystem::path& path) const;
  std::string folder_;
  bool writes_files_ = true;  // RecorderSetup::writes_files
  double interval_ = 0.0;     // axial strain between snapshots
  double next_strain_ = 0.0;  // the next snapshot is due when the strain reaches it
  std::vector<double> times_;
  std::vector<std::string> names_;
  // Broken bonds of each grain (by index: a run never reorders its grains), counted from the
  // crack catalogue as it grows.
  std::vector<std::uint16_t> broken_per_grain_;
  void count_broken(const Simulation& sim, std::size_t up_to);
  std::size_t cracks_seen_ = 0;
};

}  // namespace breccia
