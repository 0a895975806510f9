#pragma once
// ParaView snapshots (VTK XML, ASCII): per snapshot one .vtu of particles (radius, velocity,
// displacement, broken-bond count, tag), one of intact bonds (lines), and one of the cracks so
// far (points with mode, time, step and energy). Three .pvd collections index them by simulated
// time, so ParaView opens a whole run as a time series. Each file is written to a temporary name
// and renamed, and the collections are rewritten after every snapshot: an interrupted run leaves
// only complete files.
#include <string>
#include <unordered_map>
#include <vector>

#include "breccia/engine/simulation.hpp"

namespace breccia {

class SnapshotWriter {
 public:
  explicit SnapshotWriter(std::string folder);
  // Resumes the collections of a checkpoint; snapshots taken after it are dropped from them
  // (their files are overwritten by the next ones).
  SnapshotWriter(std::string folder, ArchiveReader& a, const Simulation& sim);
  void save_state(ArchiveWriter& a) const;
  void write(const Simulation& sim);
  std::size_t count() const noexcept { return times_.size(); }

 private:
  void write_collections() const;
  std::string folder_;
  std::vector<double> times_;
  std::vector<std::string> names_;
  std::unordered_map<std::uint64_t, int> broken_per_tag_;
  std::size_t cracks_seen_ = 0;
};

}  // namespace breccia
