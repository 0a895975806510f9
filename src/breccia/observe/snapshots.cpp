#include "breccia/observe/snapshots.hpp"

#include <fmt/format.h>
#include <fmt/os.h>

#include <cmath>
#include <filesystem>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/spec/experiment.hpp"

namespace breccia {

namespace fs = std::filesystem;

namespace {

// Writes `text` to path atomically (temporary file, then rename).
void put(const fs::path& path, const std::string& text) {
  write_file_atomically(path, text);
}

std::string header(std::size_t points, std::size_t cells) {
  return fmt::format(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
      "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"{}\" "
      "NumberOfCells=\"{}\">\n",
      points, cells);
}
const char* kFooter = "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";

void points_block(std::string& s, const std::vector<Vec3>& x) {
  s += "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const Vec3& p : x) s += fmt::format("{:.9g} {:.9g} {:.9g}\n", p.x, p.y, p.z);
  s += "</DataArray>\n</Points>\n";
}

// Vertex cells (one per point) or line cells (pairs of points).
void cells_block(std::string& s, std::size_t cells, int per_cell) {
  s += "<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < cells * static_cast<std::size_t>(per_cell); ++c)
    s += fmt::format("{}\n", c);
  s += "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t c = 1; c <= cells; ++c) s += fmt::format("{}\n", c * per_cell);
  s += "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < cells; ++c) s += per_cell == 1 ? "1\n" : "3\n";
  s += "</DataArray>\n</Cells>\n";
}

template <class F>
void scalar(std::string& s, const char* name, const char* type, std::size_t n, F&& f) {
  s += fmt::format("<DataArray type=\"{}\" Name=\"{}\" format=\"ascii\">\n", type, name);
  for (std::size_t i = 0; i < n; ++i) s += fmt::format("{}\n", f(i));
  s += "</DataArray>\n";
}
// A symmetric 3x3 tensor per point, row-major (ParaView reads 9 components as a tensor).
template <class F>
void tensor(std::string& s, const char* name, std::size_t n, F&& f) {
  s += fmt::format(
      "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"9\" format=\"ascii\">\n", name);
  for (std::size_t i = 0; i < n; ++i) {
    const std::array<double, 9> t = f(i);
    s += fmt::format("{:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g}\n", t[0], t[1],
                     t[2], t[3], t[4], t[5], t[6], t[7], t[8]);
  }
  s += "</DataArray>\n";
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
void vector(std::string& s, const char* name, std::size_t n, F&& f) {
  s += fmt::format(
      "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\" format=\"ascii\">\n", name);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 v = f(i);
    s += fmt::format("{:.9g} {:.9g} {:.9g}\n", v.x, v.y, v.z);
  }
  s += "</DataArray>\n";
}

}  // namespace

std::unique_ptr<Recorder> SnapshotWriter::create(const RecorderSetup& setup) {
  auto w = std::make_unique<SnapshotWriter>((setup.folder / "snapshots").string(),
                                            setup.spec.snapshot_strain_interval);
  w->write(setup.sim);  // the sample as loading begins
  return w;
}

std::unique_ptr<Recorder> SnapshotWriter::restore(const RecorderSetup& setup, ArchiveReader& a) {
  return std::make_unique<SnapshotWriter>((setup.folder / "snapshots").string(),
                                          setup.spec.snapshot_strain_interval, a, setup.sim);
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
  for (; cracks_seen_ < seen; ++cracks_seen_) {
    ++broken_per_tag_[sim.cracks()[cracks_seen_].id1];
    ++broken_per_tag_[sim.cracks()[cracks_seen_].id2];
  }
  write_collections();
}

void SnapshotWriter::save_state(ArchiveWriter& a) const {
  a.label("snapshots");
  a.value(next_strain_);
  a.vector(times_);
  for (const std::string& n : names_) a.string(n);
  a.value(static_cast<std::uint64_t>(cracks_seen_));
}

void SnapshotWriter::at_row(const Simulation& sim, const Protocol&, const RecordedRow& row) {
  const double strain = row.axial.strain;
  if (interval_ <= 0.0 || strain < next_strain_) return;
  write(sim);
  // The next multiple of the interval above this strain (one snapshot per row at most).
  next_strain_ = interval_ * (std::floor(strain / interval_) + 1.0);
}

void SnapshotWriter::write(const Simulation& sim) {
  const auto& cracks = sim.cracks();
  for (; cracks_seen_ < cracks.size(); ++cracks_seen_) {
    ++broken_per_tag_[cracks[cracks_seen_].id1];
    ++broken_per_tag_[cracks[cracks_seen_].id2];
  }
  const std::string name = fmt::format("{:05d}", times_.size());
  write_particles(sim, fs::path(folder_) / ("particles_" + name + ".vtu"));
  write_bonds(sim, fs::path(folder_) / ("bonds_" + name + ".vtu"));
  write_cracks(sim, fs::path(folder_) / ("cracks_" + name + ".vtu"));
  times_.push_back(sim.time());
  names_.push_back(name);
  write_collections();
}

// Grains as points: radius, tag, broken bonds so far, velocity, displacement since loading
// began, angular velocity, rotation (axis times angle, rad) and stress (docs/physics.md §6.5).
void SnapshotWriter::write_particles(const Simulation& sim, const fs::path& path) const {
  const ParticleStore& p = sim.particles();
  const std::size_t n = p.size();
  std::string s = header(n, n);
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = p.pos_rad[i].x;
  points_block(s, x);
  cells_block(s, n, 1);
  s += "<PointData Scalars=\"radius\" Vectors=\"velocity\" Tensors=\"stress_pa\">\n";
  scalar(s, "radius", "Float64", n, [&](std::size_t i) { return p.pos_rad[i].r; });
  scalar(s, "tag", "Int64", n, [&](std::size_t i) { return p.tag[i]; });
  scalar(s, "broken_bonds", "Int32", n, [&](std::size_t i) {
    const auto it = broken_per_tag_.find(p.tag[i]);
    return it == broken_per_tag_.end() ? 0 : it->second;
  });
  vector(s, "velocity", n, [&](std::size_t i) { return p.vel[i]; });
  vector(s, "displacement", n, [&](std::size_t i) { return p.displacement[i]; });
  vector(s, "angular_velocity", n, [&](std::size_t i) { return p.angvel[i]; });
  vector(s, "rotation", n, [&](std::size_t i) {
    return p.planar() ? Vec3{0.0, 0.0, p.angle[i]} : rotation_vector(p.orientation[i]);
  });
  const std::vector<std::array<double, 9>> stress = sim.particle_stress();
  tensor(s, "stress_pa", n, [&](std::size_t i) { return stress[i]; });
  s += "</PointData>\n";
  s += kFooter;
  put(path, s);
}

// Intact bonds as lines between the grain centres, each with its loads and how close they are
// to its strength as its law judges them (the law's assess(): docs/physics.md §4.5).
void SnapshotWriter::write_bonds(const Simulation& sim, const fs::path& path) const {
  const ParticleStore& p = sim.particles();
  std::vector<Vec3> x;
  std::vector<int> law;
  std::vector<BondFailure> loads;
  int law_index = 0;
  auto add_set = [&]<class Law>(const BondSet<Law>& b) {
    for (std::size_t k = 0; k < b.size(); ++k) {
      if (!b.intact[k]) continue;
      x.push_back(p.pos_rad[b.pairs.first[k]].x);
      x.push_back(p.pos_rad[b.pairs.second[k]].x);
      law.push_back(law_index);
      loads.push_back(Law::assess(b.params, b.state[k]));
    }
    ++law_index;
  };
  std::apply([&](const auto&... set) { (add_set(set), ...); }, sim.bonds());
  const std::size_t m = loads.size();
  std::string s = header(x.size(), m);
  points_block(s, x);
  cells_block(s, m, 2);
  s += "<CellData Scalars=\"breakage_index\">\n";
  scalar(s, "law", "Int32", m, [&](std::size_t k) { return law[k]; });
  scalar(s, "normal_force_n", "Float64", m, [&](std::size_t k) { return loads[k].Fn; });
  scalar(s, "shear_force_n", "Float64", m, [&](std::size_t k) { return loads[k].Fs; });
  scalar(s, "twisting_moment_nm", "Float64", m, [&](std::size_t k) { return loads[k].Mt; });
  scalar(s, "bending_moment_nm", "Float64", m, [&](std::size_t k) { return loads[k].Mb; });
  scalar(s, "sigma_pa", "Float64", m, [&](std::size_t k) { return loads[k].sigma; });
  scalar(s, "tau_pa", "Float64", m, [&](std::size_t k) { return loads[k].tau; });
  scalar(s, "breakage_index", "Float64", m, [&](std::size_t k) { return loads[k].index; });
  s += "</CellData>\n";
  s += kFooter;
  put(path, s);
}

// The cracks so far as points at their positions, with the crack plane's normal and radius (a
// disc glyph oriented by `normal` and scaled by `radius_m` draws each crack).
void SnapshotWriter::write_cracks(const Simulation& sim, const fs::path& path) const {
  const auto& cracks = sim.cracks();
  const std::size_t m = cracks.size();
  std::vector<Vec3> x(m);
  for (std::size_t k = 0; k < m; ++k) x[k] = cracks[k].position;
  std::string s = header(m, m);
  points_block(s, x);
  cells_block(s, m, 1);
  s += "<PointData Scalars=\"mode\" Vectors=\"normal\">\n";
  scalar(s, "mode", "Int32", m,
         [&](std::size_t k) { return cracks[k].mode == CrackMode::Tensile ? 0 : 1; });
  scalar(s, "time_s", "Float64", m, [&](std::size_t k) { return cracks[k].time; });
  scalar(s, "step", "Int64", m, [&](std::size_t k) { return cracks[k].step; });
  scalar(s, "energy_j", "Float64", m, [&](std::size_t k) { return cracks[k].energy.total(); });
  scalar(s, "radius_m", "Float64", m, [&](std::size_t k) { return cracks[k].bond_radius; });
  vector(s, "normal", m, [&](std::size_t k) { return cracks[k].normal; });
  s += "</PointData>\n";
  s += kFooter;
  put(path, s);
}

void SnapshotWriter::write_collections() const {
  for (const char* set : {"particles", "bonds", "cracks"}) {
    std::string s =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
    for (std::size_t k = 0; k < times_.size(); ++k)
      s += fmt::format("<DataSet timestep=\"{:.9g}\" file=\"{}_{}.vtu\"/>\n", times_[k], set,
                       names_[k]);
    s += "</Collection>\n</VTKFile>\n";
    put(fs::path(folder_) / (std::string(set) + ".pvd"), s);
  }
}

}  // namespace breccia
