#include "breccia/observe/recorders.hpp"

#include <fmt/format.h>

#include <filesystem>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/text_file.hpp"

namespace breccia {

CsvFile::CsvFile(const std::string& path, const std::vector<std::string>& columns) : path_(path) {
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) throw InputError(path, "", "", "cannot create the output file");
  std::string header;
  for (const auto& c : columns) header += (header.empty() ? "" : ",") + c;
  write_line(header);
  flush();
}

CsvFile::CsvFile(const std::string& path, std::uint64_t bytes) : path_(path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec || size < bytes)
    throw InputError(path, "size", ec ? "missing" : std::to_string(size),
                     "the checkpoint needs the first " + std::to_string(bytes) +
                         " bytes of this file as the run wrote them");
  std::filesystem::resize_file(path, bytes);
  f_ = std::fopen(path.c_str(), "a");
  if (!f_) throw InputError(path, "", "", "cannot append to the output file");
}

std::uint64_t CsvFile::bytes() const {
  flush();
  const long pos = f_ ? std::ftell(f_) : -1;
  if (pos < 0) throw InputError(path_, "", "", "cannot tell the position in the output file");
  return static_cast<std::uint64_t>(pos);
}

CsvFile::~CsvFile() {
  if (f_) std::fclose(f_);
}

void CsvFile::write_line(const std::string& line) {
  errno = 0;
  if (std::fputs(line.c_str(), f_) < 0 || std::fputc('\n', f_) == EOF)
    throw InputError(path_, "", "", "cannot write the table: " + write_failure(errno));
}

void CsvFile::flush() const {
  errno = 0;
  if (f_ && std::fflush(f_) != 0)
    throw InputError(path_, "", "", "cannot write the table: " + write_failure(errno));
}

namespace {

// The columns every test writes, then the test's own (Protocol::history_columns).
std::vector<std::string> history_header(const std::vector<std::string>& extra) {
  std::vector<std::string> c{"step",
                             "time_s",
                             "axial_strain",
                             "axial_stress_pa",
                             "axial_stress_nominal_pa",
                             "deviatoric_stress_pa",
                             "confining_stress_pa",
                             "lateral_strain",
                             "volumetric_strain",
                             "gauge_axial_strain",
                             "gauge_lateral_strain",
                             "platen_force_bottom_n",
                             "platen_force_top_n",
                             "broken_bonds",
                             "tensile_cracks",
                             "shear_cracks",
                             "intact_bonds",
                             "contacts",
                             "kinetic_j",
                             "bond_tension_j",
                             "bond_compression_j",
                             "bond_shear_j",
                             "bond_bending_j",
                             "bond_twisting_j",
                             "contact_strain_j",
                             "boundary_work_j",
                             "external_load_work_j",
                             "friction_j",
                             "local_damping_j",
                             "viscous_damping_j",
                             "deleted_springs_j",
                             "released_by_breaks_j",
                             "energy_residual_j",
                             "energy_residual_relative"};
  c.insert(c.end(), extra.begin(), extra.end());
  return c;
}

}  // namespace

std::unique_ptr<Recorder> HistoryRecorder::create(const RecorderSetup& setup) {
  return std::make_unique<HistoryRecorder>((setup.folder / "history.csv").string(),
                                           setup.test.history_columns());
}

std::unique_ptr<Recorder> HistoryRecorder::restore(const RecorderSetup& setup, ArchiveReader& a) {
  return std::make_unique<HistoryRecorder>((setup.folder / "history.csv").string(), a);
}

HistoryRecorder::HistoryRecorder(const std::string& path, const std::vector<std::string>& extra)
    : csv_(path, history_header(extra)) {}

HistoryRecorder::HistoryRecorder(const std::string& path, ArchiveReader& a)
    : csv_(path, (a.label("history"), a.get<std::uint64_t>())) {
  a.value(cracks_seen_);
  a.value(tensile_);
}

void HistoryRecorder::save_state(ArchiveWriter& a) const {
  a.label("history");
  a.value(csv_.bytes());
  a.value(cracks_seen_);
  a.value(tensile_);
}

void HistoryRecorder::record(const Simulation& sim, const AxialState& a,
                             const std::vector<double>& extra) {
  auto cracks = sim.cracks().reader();
  for (; cracks_seen_ < cracks.size(); ++cracks_seen_)
    tensile_ += cracks[cracks_seen_].mode == CrackMode::Tensile ? 1 : 0;
  const std::size_t tensile = tensile_;
  const EnergyLedger& L = sim.ledger();
  const Simulation::SampleCounts counts = sim.sample_counts();
  std::string line = fmt::format(
      "{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},"
      "{},{},{},{},{},"
      "{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},"
      "{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g}",
      sim.step_count(), sim.time(), a.strain, a.stress, a.stress_nominal, a.deviatoric,
      a.confining_stress, a.lateral_strain, a.volumetric_strain, a.gauge_strain,
      a.gauge_lateral_strain, a.force_bottom, a.force_top, sim.cracks().size(), tensile,
      sim.cracks().size() - tensile, counts.intact_bonds, counts.active_contacts, L.kinetic(),
      L.bond.tension, L.bond.compression, L.bond.shear, L.bond.bending, L.bond.twisting, L.contact,
      L.boundary_work, L.external_work, L.friction, L.local_damping, L.viscous_damping, L.deleted,
      L.released.total(), L.residual, L.residual_relative);
  for (double v : extra) line += fmt::format(",{:.9g}", v);
  csv_.write_line(line);
}

std::string crack_row(const CrackRecord& c) {
  return fmt::format(
      "{},{:.12g},{},{},{},{},{:.9g},{:.9g},{:.12g},{:.12g},{:.12g},{:.9g},{:.9g},{:.9g},{},"
      "{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{:.9g},{:.9g},{:.9g},"
      "{:.9g},{:.9g}",
      c.step, c.time, c.law, c.bond_tag, c.id1, c.id2, c.R1, c.R2, c.position.x, c.position.y,
      c.position.z, c.normal.x, c.normal.y, c.normal.z, to_string(c.mode), c.bond_radius, c.Fn,
      c.Fs, c.Mt, c.Mb, c.sigma, c.tau, c.ratio_t, c.ratio_s, c.energy.total(),
      c.energy.tension + c.energy.compression, c.energy.shear, c.energy.bending, c.energy.twisting);
}

std::vector<std::string> crack_columns() {
  return {"step",
          "time_s",
          "law",
          "bond_tag",
          "id1",
          "id2",
          "r1_m",
          "r2_m",
          "x_m",
          "y_m",
          "z_m",
          "nx",
          "ny",
          "nz",
          "mode",
          "bond_radius_m",
          "fn_n",
          "fs_n",
          "mt_nm",
          "mb_nm",
          "sigma_pa",
          "tau_pa",
          "ratio_t",
          "ratio_s",
          "energy_j",
          "energy_normal_j",
          "energy_shear_j",
          "energy_bending_j",
          "energy_twisting_j"};
}

std::unique_ptr<Recorder> CrackRecorder::create(const RecorderSetup& setup) {
  return std::make_unique<CrackRecorder>((setup.folder / "cracks.csv").string());
}

std::unique_ptr<Recorder> CrackRecorder::restore(const RecorderSetup& setup, ArchiveReader& a) {
  return std::make_unique<CrackRecorder>((setup.folder / "cracks.csv").string(), a);
}

CrackRecorder::CrackRecorder(const std::string& path) : csv_(path, crack_columns()) {}

CrackRecorder::CrackRecorder(const std::string& path, ArchiveReader& a)
    : csv_(path, (a.label("crack table"), a.get<std::uint64_t>())) {
  a.value(written_);
}

void CrackRecorder::save_state(ArchiveWriter& a) const {
  a.label("crack table");
  a.value(csv_.bytes());
  a.value(written_);
}

void CrackRecorder::record(const Simulation& sim) {
  auto cracks = sim.cracks().reader();
  for (; written_ < cracks.size(); ++written_) {
    csv_.write_line(crack_row(cracks[written_]));
  }
}

}  // namespace breccia
