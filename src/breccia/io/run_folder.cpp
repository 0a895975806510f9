#include "breccia/io/run_folder.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "breccia/analysis/stress_strain.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/io/geometry_file.hpp"
#include "breccia/observe/recorders.hpp"
#include "breccia/sample/lattice.hpp"
#include "breccia/version.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string machine_description() {
  std::string cpu = "unknown CPU";
  std::ifstream info("/proc/cpuinfo");
  for (std::string line; std::getline(info, line);)
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  char host[256] = "unknown";
  gethostname(host, sizeof host - 1);
  return fmt::format("{}; {} hardware threads; host {}", cpu, std::thread::hardware_concurrency(),
                     host);
}

namespace {

void write_json(const fs::path& p, const json& j) {
  const fs::path tmp = p.string() + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw InputError(p.string(), "", "", "cannot write the file");
    out << j.dump(2) << "\n";
  }
  fs::rename(tmp, p);  // atomic: a reader never sees half a manifest
}

fs::path make_folder(const ExperimentSpec& spec) {
  const auto now = std::chrono::system_clock::now();
  const std::string stamp =
      fmt::format("{:%Y%m%d-%H%M%S}", fmt::localtime(std::chrono::system_clock::to_time_t(now)));
  std::string safe;
  for (char c : spec.name)
    safe += (std::isalnum(static_cast<unsigned char>(c)) || c == '-') ? c : '_';
  fs::path base = fs::path(spec.output_directory) / (stamp + "-" + safe);
  fs::path p = base;
  for (int k = 2; fs::exists(p); ++k) p = base.string() + "-" + std::to_string(k);
  std::error_code ec;
  fs::create_directories(p, ec);
  if (ec)
    throw InputError(p.string(), "output.directory", spec.output_directory,
                     "cannot create the run folder: " + ec.message());
  return p;
}

struct Built {
  Simulation sim;
  PlatenCompression protocol;
  double bar_wave_speed = 0.0;
};

ParticleStore make_particles(const ExperimentSpec& s,
                             std::vector<std::pair<std::uint64_t, std::uint64_t>>& bonds) {
  if (s.sample_source == "file") {
    fs::path p = s.geometry_file;
    if (p.is_relative() && s.source != "built-in default") p = fs::path(s.source).parent_path() / p;
    GeometryData g = read_geometry(p.string());
    const Dimension want = s.dimension == 2 ? Dimension::Two : Dimension::Three;
    if (g.dimension != want)
      throw InputError(p.string(), "dimension", g.dimension == Dimension::Two ? "2" : "3",
                       "must match engine.dimension = " + std::to_string(s.dimension));
    bonds = g.bonds;
    return g.make_store();
  }
  if (s.dimension == 2)
    return hex_block(static_cast<int>(s.cells[0]), static_cast<int>(s.cells[1]), s.radius,
                     s.density, s.thickness);
  return fcc_block(static_cast<int>(s.cells[0]), static_cast<int>(s.cells[1]),
                   static_cast<int>(s.cells[2]), s.radius, s.density);
}

Built build(const ExperimentSpec& s) {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> listed;
  ParticleStore ps = make_particles(s, listed);
  EngineConfig cfg = s.engine;
  cfg.gravity = s.dimension == 2 ? Vec3{0, -s.gravity, 0} : Vec3{0, 0, -s.gravity};
  ContactModel contact;
  if (s.contact_law == "linear") {
    LinearContact::Params w = s.linear;
    w.friction = s.wall_friction;
    contact = make_contact_model<LinearContact>(s.linear, w);
  } else {
    HertzMindlin::Params w = s.hertz;
    w.friction = s.wall_friction;
    contact = make_contact_model<HertzMindlin>(s.hertz, w);
  }
  Simulation sim(std::move(ps), cfg, std::move(contact));
  sim.set_bond_params<ParallelBond>(s.parallel_bond);
  if (!listed.empty())
    for (auto [a, b] : listed) sim.add_bond<ParallelBond>(a, b);
  else
    sim.bond_touching_pairs<ParallelBond>(s.bond_gap_tolerance);
  PlatenCompression protocol(sim, s.loading);
  sim.initialise();
  // Bar-wave speed for the ramp (§2.3, §6.1): E estimated by the bond modulus, bulk density from
  // the particle mass in the sample's bounding box.
  double mass = 0.0;
  for (double m : sim.particles().mass) mass += m;
  const double volume = protocol.area() * protocol.height0();
  const double e_est = s.parallel_bond.modulus;
  const double v_bar = std::sqrt(e_est / (mass / volume));
  protocol.start(sim, v_bar);
  return Built{std::move(sim), std::move(protocol), v_bar};
}

json ledger_json(const EnergyLedger& L) {
  return json{{"kinetic_j", L.kinetic()},
              {"bond_strain_j",
               {{"tension", L.bond.tension},
                {"compression", L.bond.compression},
                {"shear", L.bond.shear},
                {"bending", L.bond.bending},
                {"twisting", L.bond.twisting}}},
              {"contact_strain_j", L.contact},
              {"boundary_work_j", L.boundary_work},
              {"body_force_work_j", L.body_force_work},
              {"friction_j", L.friction},
              {"local_damping_j", L.local_damping},
              {"viscous_damping_j", L.viscous_damping},
              {"deleted_springs_j", L.deleted},
              {"released_by_breaks_j", L.released.total()},
              {"residual_j", L.residual},
              {"residual_relative", L.residual_relative}};
}

}  // namespace

RunResult run_experiment(const ExperimentSpec& spec, const RunOptions& opt) {
  auto log = [&](const std::string& m) {
    if (opt.log) opt.log(m);
  };
  if (spec.threads > 0) set_threads(static_cast<int>(spec.threads));
  const auto t_start = std::chrono::steady_clock::now();
  // Build first: a bad sample (geometry file, bond list) fails before any file is written.
  Built b = build(spec);
  const fs::path folder = make_folder(spec);
  RunResult result;
  result.folder = folder.string();
  json manifest{
      {"program", "breccia"},
      {"version", kVersion},
      {"created", fmt::format("{:%Y-%m-%dT%H:%M:%S}", fmt::localtime(std::time(nullptr)))},
      {"command", opt.command_line},
      {"experiment_source", spec.source},
      {"seed", spec.engine.seed},
      {"threads", max_threads()},
      {"machine", machine_description()},
      {"status", "running"},
      {"resolved_experiment", to_toml(spec)}};
  { std::ofstream(folder / "experiment.toml") << to_toml(spec); }
  write_json(folder / "manifest.json", manifest);

  auto finish = [&](const std::string& status, const std::string& reason) {
    result.status = status;
    result.stop_reason = reason;
    manifest["status"] = status;
    manifest["stop_reason"] = reason;
    manifest["wall_seconds"] = result.wall_seconds;
    write_json(folder / "manifest.json", manifest);
  };

  try {
    Simulation& sim = b.sim;
    for (const std::string& w : sim.warnings()) log("warning: " + w);
    manifest["time_step_s"] = sim.time_step();
    manifest["critical_time_step_s"] = sim.critical_time_step();
    manifest["particles"] = sim.particles().size();
    manifest["bonds"] = sim.intact_bonds();
    manifest["warnings"] = sim.warnings();
    write_json(folder / "manifest.json", manifest);
    result.particles = sim.particles().size();
    result.bonds = sim.intact_bonds();
    log(fmt::format("sample: {} particles, {} bonds; time step {:.3g} s (critical {:.3g} s)",
                    result.particles, result.bonds, sim.time_step(), sim.critical_time_step()));

    HistoryRecorder history((folder / "history.csv").string());
    CrackRecorder cracks((folder / "cracks.csv").string());
    std::vector<double> strain, stress;
    const auto interval = static_cast<std::uint64_t>(spec.history_interval);
    std::string stop = "";
    std::string status = "complete";
    auto last_bar = std::chrono::steady_clock::now();
    for (;;) {
      if (opt.interrupt && opt.interrupt->load()) {
        status = "interrupted";
        stop = "interrupted by a signal";
        break;
      }
      if (sim.step_count() % interval == 0) sim.request_energy_sample();
      sim.step();
      if ((sim.step_count() - 1) % interval != 0) continue;
      const AxialState a = b.protocol.measure(sim);
      history.record(sim, a);
      cracks.record(sim);
      history.flush();
      cracks.flush();
      strain.push_back(a.strain);
      stress.push_back(a.stress);
      if (b.protocol.finished(a, sim.cracks().size())) {
        stop = b.protocol.stop_reason();
        break;
      }
      const auto now = std::chrono::steady_clock::now();
      if (opt.show_progress && now - last_bar > std::chrono::milliseconds(250)) {
        last_bar = now;
        const double frac = std::clamp(a.strain / spec.loading.max_strain, 1e-9, 1.0);
        const double el = std::chrono::duration<double>(now - t_start).count();
        const int width = 30, fill = static_cast<int>(frac * width);
        std::fprintf(
            stderr,
            "\r[%s%s] strain %.4f  stress %.2f MPa  cracks %zu  %.0fs elapsed, <= %.0fs left ",
            std::string(static_cast<std::size_t>(fill), '#').c_str(),
            std::string(static_cast<std::size_t>(width - fill), '.').c_str(), a.strain,
            a.stress * 1e-6, sim.cracks().size(), el, el * (1 - frac) / frac);
        std::fflush(stderr);
      }
    }
    if (opt.show_progress) std::fprintf(stderr, "\n");
    cracks.record(sim);
    cracks.flush();
    history.flush();

    result.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    result.steps = sim.step_count();
    const auto peak = analysis::find_peak(strain, stress);
    const auto fit = analysis::tangent_modulus(strain, stress);
    result.peak_stress = peak.stress;
    result.strain_at_peak = peak.strain;
    result.youngs_modulus = fit.valid ? fit.slope : std::nan("");
    result.cracks = sim.cracks().size();
    for (const auto& c : sim.cracks())
      (c.mode == CrackMode::Tensile ? result.tensile : result.shear)++;
    result.energy_residual_relative = sim.ledger().residual_relative;
    json summary{
        {"status", status},
        {"stop_reason", stop},
        {"experiment", spec.name},
        {"particles", result.particles},
        {"bonds_initial", result.bonds},
        {"bonds_broken", result.cracks},
        {"cracks_tensile", result.tensile},
        {"cracks_shear", result.shear},
        {"steps", result.steps},
        {"simulated_time_s", sim.time()},
        {"time_step_s", sim.time_step()},
        {"wall_seconds", result.wall_seconds},
        {"particle_steps_per_second", static_cast<double>(result.particles) *
                                          static_cast<double>(result.steps) / result.wall_seconds},
        {"peak_axial_stress_pa", peak.stress},
        {"peak_axial_stress_mpa", peak.stress * 1e-6},
        {"axial_strain_at_peak", peak.strain},
        {"youngs_modulus_pa", fit.valid ? json(fit.slope) : json(nullptr)},
        {"youngs_modulus_method",
         "least-squares slope of axial stress vs axial strain, pre-peak points at 40-60 % of peak "
         "(ISRM tangent E_t50)"},
        {"youngs_modulus_fit", {{"points", fit.points}, {"r2", fit.r2}}},
        {"platen_speed_m_per_s", spec.loading.platen_speed},
        {"sample_height_m", b.protocol.height0()},
        {"sample_area_m2", b.protocol.area()},
        {"energy", ledger_json(sim.ledger())},
        {"warnings", sim.warnings()}};
    write_json(folder / "summary.json", summary);
    manifest["files"] = {"experiment.toml", "history.csv", "cracks.csv", "summary.json"};
    finish(status, stop);
  } catch (const std::exception& e) {
    result.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    finish("failed", e.what());
    throw;
  }
  return result;
}

}  // namespace breccia
