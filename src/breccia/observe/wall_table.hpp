#pragma once
// walls.csv: one row per history row with every wall of the test (platens, side walls, the
// cylinder, a projectile, a loading nose): where it is (its point; the cylinder's radius), the
// force it exerts on the grains, its contacts and the work it has done. A lab's load-frame log:
// the platen forces and displacements that history.csv reduces to one stress and strain.
#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "breccia/observe/recorder.hpp"
#include "breccia/observe/recorders.hpp"

namespace breccia {

class WallTable : public Recorder {
 public:
  static constexpr std::string_view kind = "wall table";
  static std::unique_ptr<Recorder> create(const RecorderSetup& setup) {
    return std::make_unique<WallTable>(setup, columns(setup.sim.walls()));
  }
  static std::unique_ptr<Recorder> restore(const RecorderSetup& setup, ArchiveReader& a) {
    a.label("wall table");
    return std::make_unique<WallTable>(setup, a.get<std::uint64_t>());
  }

  // A new table (`header`) or one continued from a checkpoint (its length in bytes).
  template <class Start>
  WallTable(const RecorderSetup& setup, const Start& start)
      : csv_((setup.folder / "walls.csv").string(), start) {}

  std::string_view name() const noexcept override { return kind; }
  void at_row(const Simulation& sim, const Protocol&, const RecordedRow&) override {
    std::string line = fmt::format("{},{:.9g}", sim.step_count(), sim.time());
    for (const Wall& w : sim.walls())
      line += fmt::format(",{:.12g},{:.12g},{:.12g},{:.12g},{:.9g},{:.9g},{:.9g},{},{:.9g}",
                          w.point.x, w.point.y, w.point.z, w.radius, w.force.x, w.force.y,
                          w.force.z, w.contacts, w.work);
    csv_.write_line(line);
    csv_.flush();
  }
  void finish(const Simulation&) override { csv_.flush(); }
  void save_state(ArchiveWriter& a) const override {
    a.label("wall table");
    a.value(csv_.bytes());
  }
  std::vector<std::string> files() const override { return {"walls.csv"}; }

 private:
  // Per wall (named by its position in the test and its name): point, radius, force, contacts,
  // work; SI units in the names.
  static std::vector<std::string> columns(const std::vector<Wall>& walls) {
    std::vector<std::string> c{"step", "time_s"};
    for (std::size_t k = 0; k < walls.size(); ++k) {
      const std::string w = fmt::format("wall{}_{}_", k, walls[k].name);
      for (const char* f :
           {"x_m", "y_m", "z_m", "radius_m", "fx_n", "fy_n", "fz_n", "contacts", "work_j"})
        c.push_back(w + f);
    }
    return c;
  }

  CsvFile csv_;
};

}  // namespace breccia
