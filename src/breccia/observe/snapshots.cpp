#include "breccia/observe/snapshots.hpp"

#include <fmt/format.h>
#include <fmt/os.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <tuple>
#include <utility>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/spec/experiment.hpp"

namespace breccia {

namespace fs = std::filesystem;

namespace {

// Formats straight into the file's stream: a snapshot of a million grains is hundreds of
// megabytes of text, never held in memory whole.
template <class... Args>
void print(std::ostream& s, fmt::format_string<Args...> f, Args&&... args) {
  fmt::format_to(std::ostreambuf_iterator<char>(s), f, std::forward<Args>(args)...);
}

std::string header(std::size_t points, std::size_t cells) {
  return fmt::format(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
      "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"{}\" "
      "NumberOfCells=\"{}\">\n",
      points, cells);
}
const char* kFooter = "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";

// Points from `point(k)`, k < n.
template <class F>
void points_block(std::ostream& s, std::size_t n, F&& point) {
  s << "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3 p = point(k);
    print(s, "{:.9g} {:.9g} {:.9g}\n", p.x, p.y, p.z);
  }
  s << "</DataArray>\n</Points>\n";
}

// Vertex cells (one per point) or line cells (pairs of points).
void cells_block(std::ostream& s, std::size_t cells, int per_cell) {
  s << "<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < cells * static_cast<std::size_t>(per_cell); ++c) print(s, "{}\n", c);
  s << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t c = 1; c <= cells; ++c) print(s, "{}\n", c * per_cell);
  s << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < cells; ++c) s << (per_cell == 1 ? "1\n" : "3\n");
  s << "</DataArray>\n</Cells>\n";
}

template <class F>
void scalar(std::ostream& s, const char* name, const char* type, std::size_t n, F&& f) {
  print(s, "<DataArray type=\"{}\" Name=\"{}\" format=\"ascii\">\n", type, name);
  for (std::size_t i = 0; i < n; ++i) print(s, "{}\n", f(i));
  s << "</DataArray>\n";
}
// A symmetric 3x3 tensor per point, row-major (ParaView reads 9 components as a tensor).
template <class F>
void tensor(std::ostream& s, const char* name, std::size_t n, F&& f) {
  print(s, "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"9\" format=\"ascii\">\n",
        name);
  for (std::size_t i = 0; i < n; ++i) {
    const std::array<double, 9> t = f(i);
    print(s, "{:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g}\n", t[0], t[1], t[2],
          t[3], t[4], t[5], t[6], t[7], t[8]);
  }
  s << "</DataArray>\n";
}

// The rotation of a unit quaternion as its axis times its angle in [0, pi] (docs/physics.md §0.4:
// q and -q are one rotation, so the sign is made w >= 0 first).
Vec3 rotation_vector(const Quat& q) {
  const double sign = q.w < 0.0 ? -1.0 : 1.0;
  const Vec3 u{sign * q.x, sign * q.y, sign * q.z};
  const double s = norm(u);
  if (s == 0.0) return {};
  return u * (2.0 * std::atan2(s, sign * q.w) / s);
}

template <class F>
void vector(std::ostream& s, const char* name, std::size_t n, F&& f) {
  print(s, "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\" format=\"ascii\">\n",
        name);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 v = f(i);
    print(s, "{:.9g} {:.9g} {:.9g}\n", v.x, v.y, v.z);
  }
  s << "</DataArray>\n";
}

}  // namespace

std::unique_ptr<Recorder> SnapshotWriter::create(const RecorderSetup& setup) {
  auto w = std::make_unique<SnapshotWriter>((setup.folder / "snapshots").string(),
                                            setup.spec.snapshot_strain_interval);
  w->writes_files_ = setup.writes_files;
  w->write(setup.sim);  // the sample as loading begins
  return w;
}

std::unique_ptr<Recorder> SnapshotWriter::restore(const RecorderSetup& setup, ArchiveReader& a) {
  auto w = std::make_unique<SnapshotWriter>((setup.folder / "snapshots").string(),
                                            setup.spec.snapshot_strain_interval, a, setup.sim);
  w->writes_files_ = setup.writes_files;
  return w;
}

SnapshotWriter::SnapshotWriter(std::string folder, double interval)
    : folder_(std::move(folder)), interval_(interval), next_strain_(interval) {
  std::error_code ec;
  fs::create_directories(folder_, ec);
  if (ec) throw InputError(folder_, "", "", "cannot create the snapshot folder: " + ec.message());
}

SnapshotWriter::SnapshotWriter(std::string folder, double interval, ArchiveReader& a,
                               const Simulation& sim)
    : SnapshotWriter(std::move(folder), interval) {
  a.label("snapshots");
  a.value(next_strain_);
  a.vector(times_);
  names_.resize(times_.size());
  for (std::string& n : names_) a.string(n);
  const auto seen = a.get<std::uint64_t>();
  if (seen > sim.cracks().size())
    throw InputError(a.where(), "snapshots", std::to_string(seen),
                     "counts more cracks than the simulation holds: the checkpoint is corrupt");
  // The broken-bond counts per particle follow from the crack catalogue.
  count_broken(sim, seen);
  write_collections();
}

void SnapshotWriter::count_broken(const Simulation& sim, std::size_t up_to) {
  const ParticleStore& p = sim.particles();
  broken_per_grain_.resize(p.size(), 0);
  auto cracks = sim.cracks().reader();
  for (; cracks_seen_ < up_to; ++cracks_seen_) {
    const CrackRecord& c = cracks[cracks_seen_];
    ++broken_per_grain_[p.index_of(c.id1)];
    ++broken_per_grain_[p.index_of(c.id2)];
  }
}

void SnapshotWriter::save_state(ArchiveWriter& a) const {
  a.label("snapshots");
  a.value(next_strain_);
  a.vector(times_);
  for (const std::string& n : names_) a.string(n);
  a.value(static_cast<std::uint64_t>(cracks_seen_));
}

bool SnapshotWriter::reads_whole_sample(const RecordedRow& row) const {
  return interval_ > 0.0 && row.axial.strain >= next_strain_;
}

void SnapshotWriter::at_row(const Simulation& sim, const Protocol&, const RecordedRow& row) {
  const double strain = row.axial.strain;
  if (!reads_whole_sample(row)) return;
  write(sim);
  // The next multiple of the interval above this strain (one snapshot per row at most).
  next_strain_ = interval_ * (std::floor(strain / interval_) + 1.0);
}

void SnapshotWriter::write(const Simulation& sim) {
  count_broken(sim, sim.cracks().size());
  const std::string name = fmt::format("{:05d}", times_.size());
  times_.push_back(sim.time());
  names_.push_back(name);
  if (!writes_files_) return;
  write_particles(sim, fs::path(folder_) / ("particles_" + name + ".vtu"));
  write_bonds(sim, fs::path(folder_) / ("bonds_" + name + ".vtu"));
  write_cracks(sim, fs::path(folder_) / ("cracks_" + name + ".vtu"));
  write_collections();
}

namespace {

// The intact bonds of every law, in law and bond order, one at a time: next(f) calls
// f(law index, bond set, bond index) for the next one.
class IntactBonds {
 public:
  explicit IntactBonds(const Simulation& sim) : sim_(sim) {}
  template <class F>
  void next(F&& f) {
    bool found = false;
    while (!found && law_ < std::tuple_size_v<BondSets>) {
      std::uint32_t index = 0;
      std::apply(
          [&](const auto&... set) {
            (
                [&] {
                  if (index++ != law_) return;
                  while (bond_ < set.size() && !set.intact[bond_]) ++bond_;
                  if (bond_ < set.size()) {
                    f(law_, set, static_cast<std::uint32_t>(bond_++));
                    found = true;
                  }
                }(),
                ...);
          },
          sim_.bonds());
      if (!found) {
        ++law_;
        bond_ = 0;
      }
    }
  }

 private:
  const Simulation& sim_;
  std::uint32_t law_ = 0;
  std::size_t bond_ = 0;
};

}  // namespace

// Grains as points: radius, tag, broken bonds so far, velocity, displacement since loading
// began, angular velocity, rotation (axis times angle, rad) and stress (docs/physics.md §6.5).
void SnapshotWriter::write_particles(const Simulation& sim, const fs::path& path) const {
  const ParticleStore& p = sim.particles();
  const std::size_t n = p.size();
  AtomicFileWriter file(path);
  std::ostream& s = file.stream();
  s << header(n, n);
  points_block(s, n, [&](std::size_t i) { return p.pos_rad[i].x; });
  cells_block(s, n, 1);
  s << "<PointData Scalars=\"radius\" Vectors=\"velocity\" Tensors=\"stress_pa\">\n";
  scalar(s, "radius", "Float64", n, [&](std::size_t i) { return p.pos_rad[i].r; });
  scalar(s, "tag", "Int64", n, [&](std::size_t i) { return p.tag[i]; });
  scalar(s, "broken_bonds", "Int32", n,
         [&](std::size_t i) { return i < broken_per_grain_.size() ? broken_per_grain_[i] : 0; });
  vector(s, "velocity", n, [&](std::size_t i) { return p.vel[i]; });
  vector(s, "displacement", n, [&](std::size_t i) { return p.displacement[i]; });
  vector(s, "angular_velocity", n, [&](std::size_t i) { return p.angvel[i]; });
  vector(s, "rotation", n, [&](std::size_t i) {
    return p.planar() ? Vec3{0.0, 0.0, p.angle[i]} : rotation_vector(p.orientation[i]);
  });
  Simulation::ParticleStressStream stress(sim);
  tensor(s, "stress_pa", n, [&](std::size_t i) { return stress.at(i); });
  s << "</PointData>\n" << kFooter;
  file.commit();
}

// Intact bonds as lines between the grain centres, each with its loads and how close they are
// to its strength as its law judges them (the law's assess(): docs/physics.md §4.5).
void SnapshotWriter::write_bonds(const Simulation& sim, const fs::path& path) const {
  const ParticleStore& p = sim.particles();
  std::size_t m = 0;
  std::apply(
      [&](const auto&... set) {
        ((m += static_cast<std::size_t>(
              std::count_if(set.intact.begin(), set.intact.end(), [](auto v) { return v != 0; }))),
         ...);
      },
      sim.bonds());
  AtomicFileWriter file(path);
  std::ostream& s = file.stream();
  s << header(2 * m, m);
  // Each block walks the intact bonds afresh with its own cursor (assess() is cheap next to
  // formatting) instead of holding a list of every bond.
  {
    IntactBonds c(sim);
    Vec3 second;
    points_block(s, 2 * m, [&](std::size_t e) {
      if (e % 2 == 1) return second;
      Vec3 first;
      c.next([&](std::uint32_t, const auto& set, std::uint32_t k) {
        first = p.pos_rad[set.pairs.first[k]].x;
        second = p.pos_rad[set.pairs.second[k]].x;
      });
      return first;
    });
  }
  cells_block(s, m, 2);
  s << "<CellData Scalars=\"breakage_index\">\n";
  {
    IntactBonds c(sim);
    scalar(s, "law", "Int32", m, [&](std::size_t) {
      std::uint32_t law = 0;
      c.next([&](std::uint32_t l, const auto&, std::uint32_t) { law = l; });
      return law;
    });
  }
  auto column = [&](const char* name, double BondFailure::*value) {
    IntactBonds c(sim);
    scalar(s, name, "Float64", m, [&](std::size_t) {
      BondFailure loads;
      c.next([&]<class Law>(std::uint32_t, const BondSet<Law>& set, std::uint32_t k) {
        loads = Law::assess(set.params, set.state[k],
                            sim.bond_radii(set.pairs.first[k], set.pairs.second[k]));
      });
      return loads.*value;
    });
  };
  column("normal_force_n", &BondFailure::Fn);
  column("shear_force_n", &BondFailure::Fs);
  column("twisting_moment_nm", &BondFailure::Mt);
  column("bending_moment_nm", &BondFailure::Mb);
  column("sigma_pa", &BondFailure::sigma);
  column("tau_pa", &BondFailure::tau);
  column("breakage_index", &BondFailure::index);
  s << "</CellData>\n" << kFooter;
  file.commit();
}

// The cracks so far as points at their positions, with the crack plane's normal and radius (a
// disc glyph oriented by `normal` and scaled by `radius_m` draws each crack).
void SnapshotWriter::write_cracks(const Simulation& sim, const fs::path& path) const {
  auto cracks = sim.cracks().reader();
  const std::size_t m = cracks.size();
  AtomicFileWriter file(path);
  std::ostream& s = file.stream();
  s << header(m, m);
  points_block(s, m, [&](std::size_t k) { return cracks[k].position; });
  cells_block(s, m, 1);
  s << "<PointData Scalars=\"mode\" Vectors=\"normal\">\n";
  scalar(s, "mode", "Int32", m,
         [&](std::size_t k) { return cracks[k].mode == CrackMode::Tensile ? 0 : 1; });
  scalar(s, "time_s", "Float64", m, [&](std::size_t k) { return cracks[k].time; });
  scalar(s, "step", "Int64", m, [&](std::size_t k) { return cracks[k].step; });
  scalar(s, "energy_j", "Float64", m, [&](std::size_t k) { return cracks[k].energy.total(); });
  scalar(s, "radius_m", "Float64", m, [&](std::size_t k) { return cracks[k].bond_radius; });
  vector(s, "normal", m, [&](std::size_t k) { return cracks[k].normal; });
  s << "</PointData>\n" << kFooter;
  file.commit();
}

void SnapshotWriter::write_collections() const {
  for (const char* set : {"particles", "bonds", "cracks"}) {
    std::string s =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
    for (std::size_t k = 0; k < times_.size(); ++k)
      s += fmt::format("<DataSet timestep=\"{:.9g}\" file=\"{}_{}.vtu\"/>\n", times_[k], set,
                       names_[k]);
    s += "</Collection>\n</VTKFile>\n";
    write_file_atomically(fs::path(folder_) / (std::string(set) + ".pvd"), s);
  }
}

}  // namespace breccia
