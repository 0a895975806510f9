#include "breccia/io/run_folder.hpp"

#include <fcntl.h>
#include <fmt/chrono.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <thread>

#include "breccia/analysis/compression.hpp"
#include "breccia/analysis/crack_pattern.hpp"
#include "breccia/analysis/stress_strain.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/core/checksum.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/io/failure_analysis.hpp"
#include "breccia/io/geometry_checks.hpp"
#include "breccia/io/geometry_file.hpp"
#include "breccia/io/json_view.hpp"
#include "breccia/io/sample_import.hpp"
#include "breccia/observe/ae_monitor.hpp"
#include "breccia/observe/recorders.hpp"
#include "breccia/observe/snapshots.hpp"
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
  // The threads this process runs on (engine.threads, --threads or OMP_NUM_THREADS) and the
  // machine's: a timing means little without both.
  return fmt::format("{}; {} threads used of {} hardware threads; host {}", cpu, max_threads(),
                     std::thread::hardware_concurrency(), host);
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
  std::unique_ptr<Protocol> protocol;
  double bar_wave_speed = 0.0;
  json sample_report;
  std::uint64_t consolidation_steps = 0;
};

std::string resolve(const ExperimentSpec& s, const std::string& file) {
  fs::path p = file;
  if (p.is_relative() && s.source != "built-in default") p = fs::path(s.source).parent_path() / p;
  return p.string();
}

json packing_json(const PackingReport& r) {
  const SampleStructure& ss = r.structure;
  json profile = json::array();
  for (const ProfileSlice& sl : ss.profile)
    profile.push_back({{"from_m", sl.lo},
                       {"to_m", sl.hi},
                       {"grains", sl.grains},
                       {"bonds_per_grain", sl.bonds_per_grain},
                       {"solid_fraction", sl.solid_fraction}});
  const HomogeneityCheck& h = ss.homogeneity;
  json stages = json::array();
  for (const PackingStage& st : r.stages)
    stages.push_back(
        {{"stage", st.name}, {"steps", st.steps}, {"seconds", st.seconds}, {"note", st.note}});
  const double n = static_cast<double>(std::max<std::size_t>(ss.particles, 1));
  return json{
      {"method", r.method},
      {"particles", ss.particles},
      {"bonds", ss.bonds},
      {"porosity", ss.porosity},
      {"contact_coordination", ss.contact_coordination},
      {"bond_coordination", ss.bond_coordination},
      {"bonds_per_interior_particle", ss.bonds_per_interior_particle},
      {"floaters",
       {{"definition",
         fmt::format("grains with fewer than {} contacts: bonded neighbours plus vessel walls "
                     "within the bond gap tolerance (Potyondy & Cundall 2004)",
                     ss.floater_contacts)},
        {"count", ss.floaters},
        {"fraction", static_cast<double>(ss.floaters) / n},
        {"grains_with_fewer_bonds", ss.few_bonds},
        {"grains_with_fewer_bonds_fraction", static_cast<double>(ss.few_bonds) / n},
        {"unbonded_grains", ss.unbonded},
        {"grown", r.floaters_grown},
        {"largest_growth", r.largest_floater_growth}}},
      {"locked_in_stress",
       {{"contact_law", r.contact_law},
        {"mean_pa", r.locked_in_mean_stress},
        {"diagonal_pa", {r.locked_in_xx, r.locked_in_yy, r.locked_in_zz}}}},
      {"profile_along_axis", profile},
      {"homogeneity",
       {{"passes", h.passes()},
        {"bars",
         "interior eighths within 3 % of their mean; end eighths within 3 % of each other "
         "and 8 % of the interior mean (bonds per grain and solid fraction)"},
        {"interior_bonds_spread", h.interior_bonds_spread},
        {"interior_solid_spread", h.interior_solid_spread},
        {"end_bonds_difference", h.end_bonds_difference},
        {"end_solid_difference", h.end_solid_difference},
        {"end_bonds_deficit", h.end_bonds_deficit},
        {"end_solid_deficit", h.end_solid_deficit}}},
      {"preconsolidation_stress_reached_pa", r.preconsolidation_stress_reached},
      {"radius_mean_m", r.radius_mean},
      {"radius_sd_m", r.radius_sd},
      {"radius_min_m", r.radius_min},
      {"radius_max_m", r.radius_max},
      {"packing_steps", r.steps},
      {"converged", r.converged},
      {"size_m", {r.width, r.depth, r.height}},
      {"stages", stages},
      {"warnings", r.warnings},
      {"packing_seconds", r.wall_seconds}};
}

// A short stable hash of the settings that define a generated sample (the cache key).
std::string sample_key(const ExperimentSpec& s) {
  const std::string text = to_toml(s);
  std::string sample_part;
  bool in = false;
  for (std::size_t pos = 0; pos < text.size();) {
    const std::size_t e = text.find('\n', pos);
    const std::string line = text.substr(pos, e - pos);
    pos = e == std::string::npos ? text.size() : e + 1;
    if (!line.empty() && line[0] == '[') in = line == "[sample]";
    if (in || line.rfind("seed", 0) == 0 || line.rfind("dimension", 0) == 0) sample_part += line;
  }
  // The packing revision: a change of the algorithm must not reuse samples packed before it.
  // The packing cycles with the test's contact law: its parameters define the sample too.
  const std::size_t c0 = text.find("\n[contact]"), c1 = text.find("\n[bond]");
  if (c0 != std::string::npos && c1 != std::string::npos) sample_part += text.substr(c0, c1 - c0);
  sample_part += "|packing-7";
  return fmt::format("{:016x}", fnv1a64(sample_part));
}

}  // namespace

ContactModel contact_model(const ExperimentSpec& s) {
  // Every contact law has a friction coefficient: walls use the contact law with wall_friction.
  return visit_params<ContactLaws>(s.contact, [&]<class Law>(const typename Law::Params& p) {
    typename Law::Params wall = p;
    wall.friction = s.wall_friction;
    return make_contact_model<Law>(p, wall);
  });
}

PackingSettings packing_settings(const ExperimentSpec& s) {
  PackingSettings p;
  p.shape = s.shape == "cylinder"    ? SampleShape::Cylinder
            : s.shape == "rectangle" ? SampleShape::Rectangle
            : s.shape == "disk"      ? SampleShape::Disk
                                     : SampleShape::Prism;
  p.width = s.width;
  p.depth = s.depth;
  p.height = s.height;
  p.diameter = s.diameter;
  p.thickness = s.thickness;
  p.planar_body = s.grain_body();
  p.radii = radius_distribution(s);
  p.density = s.density;
  p.method = s.packing == "insertion"          ? PackingMethod::Insertion
             : s.packing == "preconsolidation" ? PackingMethod::Preconsolidation
                                               : PackingMethod::Expansion;
  p.porosity = s.porosity;
  p.servo_to_stress = s.packing_target == "stress";
  p.isotropic_stress = s.isotropic_stress;
  p.preconsolidation_stress = s.preconsolidation_stress;
  p.contact = contact_model(s);
  p.bond_gap_tolerance = s.bond_gap_tolerance;
  p.floater_contacts = static_cast<int>(s.floater_contacts);
  p.floater_max_growth = s.floater_max_growth;
  p.insertion_failures = static_cast<std::uint64_t>(s.insertion_failures);
  p.seed = s.engine.seed;
  p.max_particles = static_cast<std::size_t>(s.max_particles);
  return p;
}

GeneratedSample generate_sample(const ExperimentSpec& s, const std::string& path,
                                const std::function<void(const std::string&)>& log) {
  PackedSample packed = pack_sample(packing_settings(s), log);
  GeneratedSample out{std::move(packed.geometry), packing_json(packed.report)};
  out.report["generator"] = fmt::format("breccia {}", kVersion);
  out.report["settings"] = to_toml(s);
  if (!path.empty()) {
    const fs::path p(path);
    if (p.has_parent_path()) fs::create_directories(p.parent_path());
    write_geometry(p.string() + ".tmp", out.geometry);
    fs::rename(p.string() + ".tmp", p);
    write_json(p.string() + ".json", out.report);
  }
  return out;
}

namespace {

GeometryData load_sample(const ExperimentSpec& s, json& report, SampleInfo& info,
                         const std::function<void(const std::string&)>& log) {
  const Dimension want = s.dimension == 2 ? Dimension::Two : Dimension::Three;
  info = sample_info(s);
  const auto max_n = static_cast<std::uint64_t>(s.max_particles);
  GeometryData g;
  if (s.sample_source == "generate") {
    const fs::path cache = fs::path(s.output_directory) / "samples" /
                           fmt::format("{}-{}.geom", s.shape, sample_key(s));
    if (s.cache && fs::exists(cache) && fs::exists(cache.string() + ".json")) {
      log("sample: reusing " + cache.string());
      g = read_geometry(cache.string(), max_n);
      report = read_json_object(cache.string() + ".json");
      report["cached_file"] = cache.string();
    } else {
      log("sample: generating (cached afterwards in " + cache.string() + ")");
      GeneratedSample gs = generate_sample(s, s.cache ? cache.string() : std::string(), log);
      g = std::move(gs.geometry);
      report = gs.report;
      if (s.cache) report["cached_file"] = cache.string();
    }
  } else if (s.sample_source == "file") {
    const std::string p = resolve(s, s.geometry_file);
    g = read_geometry(p, max_n);
    if (fs::exists(p + ".json")) {
      report = read_json_object(p + ".json");
      // A sample written by `breccia generate` says its shape in its settings.
      if (report.contains("settings") && report["settings"].is_string())
        for (const char* shape : {"prism", "cylinder", "rectangle", "disk"})
          if (report["settings"].get<std::string>().find(fmt::format("shape = \"{}\"", shape)) !=
              std::string::npos)
            info.shape = shape;
    }
    report["file"] = p;
  } else if (s.sample_source == "table") {
    g = read_xyzr_table(resolve(s, s.geometry_file), want, s.density, s.thickness, max_n);
    report["file"] = resolve(s, s.geometry_file);
  } else if (s.sample_source == "gengeo") {
    g = read_gengeo(resolve(s, s.geometry_file), s.density, s.thickness, max_n);
    report["file"] = resolve(s, s.geometry_file);
  } else {
    const ParticleStore ps =
        s.dimension == 2 ? hex_block(static_cast<int>(s.cells[0]), static_cast<int>(s.cells[1]),
                                     s.radius, s.density, s.thickness)
                         : fcc_block(static_cast<int>(s.cells[0]), static_cast<int>(s.cells[1]),
                                     static_cast<int>(s.cells[2]), s.radius, s.density);
    g.dimension = ps.dimension();
    g.thickness = ps.thickness();
    for (std::size_t i = 0; i < ps.size(); ++i)
      g.particles.push_back({.tag = ps.tag[i],
                             .position = ps.pos_rad[i].x,
                             .radius = ps.pos_rad[i].r,
                             .density = ps.density[i]});
    report["lattice"] = s.dimension == 2 ? "hexagonal" : "fcc";
    check_geometry(g, s.source + " (sample.source = \"lattice\")", max_n);
  }
  if (g.dimension != want)
    throw InputError(s.source, "engine.dimension", std::to_string(s.dimension),
                     std::string("the sample is ") + (g.dimension == Dimension::Two ? "2D" : "3D"));
  return g;
}

// Limits on what a run may ask for, checked before the test starts and before the run folder
// exists: beyond them a run cannot finish in any reasonable time (or memory), and the cause is
// almost always a typo or a unit error in a key the message names.
constexpr double kMaxRunSteps = 1e9;        // about a month for a small sample on 2 cores
constexpr double kMaxParticleSteps = 1e13;  // about a month on 2 cores (bench/RESULTS.md)
constexpr double kMaxStrainBins = 1e6;      // indicator series and their windows
constexpr double kMaxSnapshotsPerRun = 1e5;
// Platen travel per step relative to the smallest radius: the contact search (skin 0.4 x mean
// radius) and the explicit integration both assume far smaller moves per step.
constexpr double kMaxPlatenTravelPerStep = 0.05;

// The steps the test needs at most: its ramp plus the platen travel to max_strain at the platen
// speed (each platen moves, so the sample shortens at twice that speed).
void check_run_budget(const ExperimentSpec& s, const Simulation& sim, double length, double v_bar) {
  const double dt = sim.time_step();
  if (!(std::isfinite(dt) && dt > 0.0))
    throw InputError(s.source, "engine.time_step", num(dt),
                     "the time step must be finite and > 0; check the grain radii, densities and "
                     "stiffnesses");
  double ramp = 0.0, speed = 0.0, max_strain = 0.0;
  visit_lab_test(s.test, [&]<class T>(const typename T::Params& p) {
    ramp = p.ramp_time > 0.0 ? p.ramp_time : 10.0 * length / v_bar;
    speed = p.platen_speed;
    max_strain = p.max_strain;
  });
  const double steps = (ramp + max_strain * length / (2.0 * speed)) / dt;
  const double n = static_cast<double>(sim.particles().size());
  const std::string what = fmt::format(
      "ramp {} s + max_strain {} x sample length {} m / (2 x platen_speed {} m/s), at a time step "
      "of {} s",
      num(ramp), num(max_strain), num(length), num(speed), num(dt));
  if (!(steps <= kMaxRunSteps) || !(steps * n <= kMaxParticleSteps))
    throw InputError(s.source, "test.platen_speed / test.max_strain / test.ramp_time",
                     fmt::format("{:.3g} steps of {} particles", steps, sim.particles().size()),
                     fmt::format("a test may take at most {:.0e} steps and {:.0e} particle-steps; "
                                 "this one needs {}: raise the platen speed, lower the strain or "
                                 "the ramp, or check engine.time_step and the grain radii",
                                 kMaxRunSteps, kMaxParticleSteps, what));
  double r_min = std::numeric_limits<double>::infinity();
  for (const PosRad& q : sim.particles().pos_rad) r_min = std::min(r_min, q.r);
  if (!(speed * dt <= kMaxPlatenTravelPerStep * r_min))
    throw InputError(s.source, "test.platen_speed", num(speed) + " m/s",
                     fmt::format("a platen may move at most {} of the smallest grain radius ({} "
                                 "m) per time step ({} s), i.e. at most {} m/s: faster, contacts "
                                 "are crossed within a step and the test is no longer quasi-static "
                                 "(use a few cm/s or less)",
                                 kMaxPlatenTravelPerStep, num(r_min), num(dt),
                                 num(kMaxPlatenTravelPerStep * r_min / dt)));
  if (max_strain / s.ae_bin_width > kMaxStrainBins)
    throw InputError(
        s.source, "ae.bin_width", num(s.ae_bin_width),
        fmt::format("at most {:.0e} bins up to test.max_strain = {}: use a bin of at "
                    "least {}",
                    kMaxStrainBins, num(max_strain), num(max_strain / kMaxStrainBins)));
  if (s.snapshot_strain_interval > 0.0 &&
      max_strain / s.snapshot_strain_interval > kMaxSnapshotsPerRun)
    throw InputError(
        s.source, "output.snapshot_strain_interval", num(s.snapshot_strain_interval),
        fmt::format("at most {:.0e} snapshots up to test.max_strain = {}; use 0 for "
                    "none or an interval of at least {}",
                    kMaxSnapshotsPerRun, num(max_strain), num(max_strain / kMaxSnapshotsPerRun)));
}

// The experiment's joint planes, placed about the centre of the sample's bounding box, with the
// joint law's parameters.
void add_joints(const ExperimentSpec& s, Simulation& sim) {
  if (s.joint_planes.empty()) return;
  visit_params<JointLaws>(
      s.joint, [&]<class Law>(const typename Law::Params& p) { sim.set_joint_params<Law>(p); });
  Vec3 lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  for (const PosRad& q : sim.particles().pos_rad)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], q.x[k] - q.r);
      hi[k] = std::max(hi[k], q.x[k] + q.r);
    }
  Vec3 centre = (lo + hi) * 0.5;
  if (s.dimension == 2) centre.z = 0.0;
  for (const JointPlaneSpec& j : s.joint_planes) {
    JointPlane plane;
    plane.point = centre + Vec3{j.centre[0], j.centre[1], j.centre[2]};
    plane.normal = joint_normal(j, static_cast<int>(s.dimension));
    plane.radius = j.radius > 0.0 ? j.radius : kInf;
    plane.spacing = j.spacing;
    sim.add_joint_plane(plane);
  }
}

Built build(const ExperimentSpec& s, const std::function<void(const std::string&)>& log) {
  json report;
  SampleInfo info;
  GeometryData g = load_sample(s, report, info, log);
  // Density scaling (physics.md §1.5): masses and inertias grow, so does the stable time step.
  for (ParticleSpec& q : g.particles) q.density *= s.density_scaling;
  ParticleStore ps = g.make_store(s.grain_body());
  EngineConfig cfg = s.engine;
  cfg.gravity = s.dimension == 2 ? Vec3{0, -s.gravity, 0} : Vec3{0, 0, -s.gravity};
  Simulation sim(std::move(ps), cfg, contact_model(s));
  visit_params<BondLaws>(s.bond, [&]<class Law>(const typename Law::Params& p) {
    sim.set_bond_params<Law>(p);
    if (!g.bonds.empty())
      for (auto [a, b] : g.bonds) sim.add_bond<Law>(a, b);
    else
      sim.bond_touching_pairs<Law>(s.bond_gap_tolerance);
  });
  add_joints(s, sim);
  std::unique_ptr<Protocol> protocol;
  visit_lab_test(s.test, [&]<class T>(const typename T::Params& p) {
    T::check(p, info, s.source);
    protocol = T::create(sim, p, info);
  });
  sim.initialise();
  // Bar-wave speed for the ramp (§2.3, §6.1): E estimated by the bond modulus, bulk density from
  // the (scaled) particle mass in the sample's bounding box.
  double mass = 0.0;
  for (double m : sim.particles().mass) mass += m;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const int axis = s.dimension == 2 ? 1 : 2;
  double footprint_lo[2] = {lo, lo}, footprint_hi[2] = {hi, hi};
  for (const PosRad& q : sim.particles().pos_rad) {
    lo = std::min(lo, q.x[axis] - q.r);
    hi = std::max(hi, q.x[axis] + q.r);
    for (int k = 0; k < 2; ++k) {
      footprint_lo[k] = std::min(footprint_lo[k], q.x[k] - q.r);
      footprint_hi[k] = std::max(footprint_hi[k], q.x[k] + q.r);
    }
  }
  const double volume = (hi - lo) * (footprint_hi[0] - footprint_lo[0]) *
                        (s.dimension == 2 ? s.thickness : footprint_hi[1] - footprint_lo[1]);
  const double v_bar = std::sqrt(bond_moduli(s).young / (mass / volume));
  check_run_budget(s, sim, hi - lo, v_bar);
  const std::uint64_t consolidation = protocol->start(sim, v_bar);
  return Built{std::move(sim), std::move(protocol), v_bar, report, consolidation};
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
              {"joint_slip_j", L.joint_slip},
              {"joint_dilation_work_j", L.joint_dilation},
              {"local_damping_j", L.local_damping},
              {"viscous_damping_j", L.viscous_damping},
              {"deleted_springs_j", L.deleted},
              {"released_by_breaks_j", L.released.total()},
              {"residual_j", L.residual},
              {"residual_relative", L.residual_relative}};
}

}  // namespace

namespace {

json nan_null(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}

void make_plot(const fs::path& folder, const std::function<void(const std::string&)>& log) {
  if (!plot_run(folder.string()))
    log("warning: no stress_strain.png (see " + (folder / "plot.log").string() + ")");
  if (!write_report(folder.string()))
    log("warning: no report.html (see " + (folder / "report.log").string() + ")");
}

std::string mpa(const JsonView& j, const char* key) {
  const auto v = j.maybe_number(key);
  return v ? fmt::format("{:.2f} MPa", *v * 1e-6) : "n/a";
}
std::string gpa(const JsonView& j, const char* key) {
  const auto v = j.maybe_number(key);
  return v ? fmt::format("{:.2f} GPa", *v * 1e-9) : "n/a";
}
std::string plain(const JsonView& j, const char* key, const char* f = "{:.3g}") {
  const auto v = j.maybe_number(key);
  return v ? fmt::format(fmt::runtime(f), *v) : "n/a";
}
// A two-number range ("a to b"), n/a when absent.
std::string range(const JsonView& j, const char* key) {
  const auto r = j.elements(key);
  if (r.size() != 2 || r[0].raw().is_null() || r[1].raw().is_null()) return "n/a";
  return fmt::format("{:.2f} to {:.2f}", r[0].as_number(), r[1].as_number());
}

std::string summarise_sweep(const fs::path& file) {
  const json doc = read_json_object(file.string());
  const JsonView j(doc, file.string());
  std::string s = fmt::format("sweep {} ({})\n", j.text("experiment", ""), j.text("status", ""));
  s += "  sigma3 (MPa)   peak q (MPa)   sigma1 (MPa)   E_t50 (GPa)   cracks\n";
  for (const JsonView& r : j.elements("runs"))
    s += fmt::format("  {:>12.2f}   {:>12.2f}   {:>12.2f}   {:>11}   {:>6}\n",
                     r.number("confining_stress_pa") * 1e-6,
                     r.maybe_number("peak_deviatoric_stress_pa").value_or(0.0) * 1e-6,
                     r.maybe_number("sigma1_at_peak_pa").value_or(0.0) * 1e-6,
                     gpa(r, "youngs_modulus_pa"), r.maybe_number("cracks").value_or(0.0));
  if (const auto mc = j.find("mohr_coulomb"))
    s += mc->flag("valid", false)
             ? fmt::format("Mohr-Coulomb: cohesion {}, friction angle {} deg, UCS {} (R^2 {})\n",
                           mpa(*mc, "cohesion_pa"), plain(*mc, "friction_angle_deg", "{:.1f}"),
                           mpa(*mc, "ucs_intercept_pa"), plain(*mc, "r2"))
             : "Mohr-Coulomb: no fit (" + mc->text("flag", "") + ")\n";
  if (const auto hb = j.find("hoek_brown"))
    s += hb->flag("valid", false)
             ? fmt::format("Hoek-Brown: sigma_ci {}, m_i {} (rms {})\n", mpa(*hb, "sigma_ci_pa"),
                           plain(*hb, "m_i"), mpa(*hb, "rms_residual_pa"))
             : "Hoek-Brown: no fit (" + hb->text("flag", "") + ")\n";
  return s;
}

std::string summarise_acoustic_emission(const JsonView& ae) {
  std::string b_text = "n/a";
  if (const auto b = ae.find("b_value"))
    b_text = b->has("b") ? fmt::format("{:.2f} +- {:.2f}", b->number("b"),
                                       b->maybe_number("sigma").value_or(0.0))
                         : "n/a (" + b->text("flag", "") + ")";
  std::string d2 = "n/a";
  if (const auto d = ae.find("d2")) d2 = plain(*d, "d2", "{:.2f}");
  return fmt::format(
      "\n  AE: {} events (largest {} cracks), M_w {}, b = {} (windows {}), D2 = {} (windows "
      "{}); shear fraction {}",
      plain(ae, "events", "{:.0f}"), plain(ae, "largest_event_cracks", "{:.0f}"),
      range(ae, "magnitude_range"), b_text, range(ae, "b_value_window_range"), d2,
      range(ae, "d2_window_range"), plain(ae, "shear_fraction", "{:.3f}"));
}

std::string summarise_run(const fs::path& file) {
  const json doc = read_json_object(file.string());
  const JsonView j(doc, file.string());
  std::string s =
      fmt::format("{}: {}, sigma3 = {} ({}; {})\n", j.text("experiment", ""), j.text("test", ""),
                  mpa(j, "confining_stress_pa"), j.text("status", ""), j.text("stop_reason", ""));
  if (j.has("tensile_strength_pa"))
    s += fmt::format("  tensile strength sigma_t = 2F/(pi D t) {} (peak force {} N) at strain {}\n",
                     mpa(j, "tensile_strength_pa"), plain(j, "peak_force_n", "{:.4g}"),
                     plain(j, "axial_strain_at_peak", "{:.5f}"));
  else
    s +=
        fmt::format("  peak q {} at axial strain {}; E_t50 {}; Poisson {}\n",
                    mpa(j, "peak_deviatoric_stress_pa"), plain(j, "axial_strain_at_peak", "{:.5f}"),
                    gpa(j, "youngs_modulus_pa"), plain(j, "poisson_ratio"));
  s += fmt::format("  crack initiation {}, crack damage {}, residual {}\n",
                   mpa(j, "crack_initiation_stress_pa"), mpa(j, "crack_damage_stress_pa"),
                   mpa(j, "residual_strength_pa"));
  s += fmt::format("  {} particles, {} bonds; {} cracks ({} tensile, {} shear)\n",
                   plain(j, "particles", "{:.0f}"), plain(j, "bonds_initial", "{:.0f}"),
                   plain(j, "bonds_broken", "{:.0f}"), plain(j, "cracks_tensile", "{:.0f}"),
                   plain(j, "cracks_shear", "{:.0f}"));
  if (const auto cp = j.find("crack_pattern")) {
    const auto q = cp->elements("quarter_shares_along_axis");
    if (q.size() == 4)
      s += fmt::format("  cracks per quarter along the axis: {:.2f} {:.2f} {:.2f} {:.2f}\n",
                       q[0].as_number(), q[1].as_number(), q[2].as_number(), q[3].as_number());
  }
  if (const auto qs = j.find("quasi_static"))
    s += fmt::format("  quasi-static: {} (platen imbalance {}, kinetic/strain {})",
                     qs->flag("ok", false) ? "yes" : "NO",
                     plain(*qs, "max_platen_force_imbalance_before_peak"),
                     plain(*qs, "max_kinetic_to_strain_energy_before_peak"));
  if (j.maybe_number("confining_stress_pa").value_or(0.0) > 0.0)
    if (const auto ce = j.find("confining_stress_error"))
      s += fmt::format("; confining error before peak {:.2f} %",
                       100 * ce->maybe_number("max_relative_before_peak").value_or(0.0));
  if (const auto ae = j.find("acoustic_emission")) s += summarise_acoustic_emission(*ae);
  if (const auto eb = j.find("energy_budget"))
    s += fmt::format("\n  energy balance: {} (largest relative residual {})",
                     eb->text("classification", "n/a"),
                     plain(*eb, "residual_relative_max_after_1pct_work", "{:.2e}"));
  s += fmt::format("\n  {} steps in {} s ({} particle-steps/s)\n", plain(j, "steps", "{:.0f}"),
                   plain(j, "wall_seconds", "{:.1f}"), plain(j, "particle_steps_per_second"));
  for (const JsonView& w : j.elements("warnings")) s += "  warning: " + w.as_text() + "\n";
  return s;
}

}  // namespace

namespace {
// The plotting scripts ship beside the sources and are installed nowhere: run them from the
// source tree with Debian's interpreter; their output goes to `log_name` in the folder, which is
// removed when they succeed.
bool run_script(const char* script_name, const std::string& folder, const char* log_name) {
  const fs::path script = fs::path(BRECCIA_SOURCE_DIR) / "scripts" / script_name;
  const fs::path logf = fs::path(folder) / log_name;
  const std::string cmd =
      fmt::format("/usr/bin/python3 '{}' '{}' > '{}' 2>&1", script.string(), folder, logf.string());
  if (std::system(cmd.c_str()) != 0) return false;
  fs::remove(logf);
  return true;
}
}  // namespace

bool run_python_script(const std::string& script, const std::string& folder,
                       const std::string& log_name) {
  return run_script(script.c_str(), folder, log_name.c_str());
}

bool plot_run(const std::string& folder) {
  return run_script("plot_run.py", folder, "plot.log");
}

bool write_report(const std::string& folder) {
  return run_script("report.py", folder, "report.log");
}

std::string summarise_folder(const std::string& folder) {
  const fs::path f(folder);
  if (!fs::is_directory(f)) throw InputError(folder, "", "", "not a folder");
  if (fs::exists(f / "sweep.json")) return summarise_sweep(f / "sweep.json");
  if (!fs::exists(f / "summary.json")) {
    std::string status = "unknown";
    if (fs::exists(f / "manifest.json")) {
      const json m = read_json_object((f / "manifest.json").string());
      status = JsonView(m, (f / "manifest.json").string()).text("status", "unknown");
    }
    throw InputError(folder, "summary.json", "(missing)",
                     "not a finished run folder (manifest status: " + status + ")");
  }
  return summarise_run(f / "summary.json");
}

namespace {

constexpr const char* kCheckpointMagic = "breccia-checkpoint";
// 2: commit and trailing hash; 3: strain gauges; 4, 5: brittle-beam and quaternion bond sets;
// 6: smooth joints; 7: the 2D side-wall servo's integral terms; 8: RICEBAL bond set
constexpr std::uint32_t kCheckpointFormat = 9;
constexpr const char* kCheckpointFile = "checkpoint.bin";

// What the loading loop carries from one row to the next besides the engine, the protocol and
// the recorders: the analysed series, the quality monitors and the run's bookkeeping.
struct LoopState {
  analysis::CompressionSeries series;
  std::vector<double> imbalance, ke_ratio, confine_err;
  double next_snapshot = 0.0;
  double wall_seconds = 0.0;  // spent in earlier sessions of this run (updated when saved)
  std::uint64_t consolidation_steps = 0;
  std::uint64_t bonds_initial = 0;
  std::vector<std::string> warnings;  // those of the set-up
  // Reference state of the loading stage for the failure analysis.
  double volume0 = 0.0, porosity0 = 0.0, length_min = 0.0;
  std::string wave_speed_method;

  template <class Archive>
  void transfer(Archive& a) {
    a.label("loop");
    a.vector(series.axial_strain);
    a.vector(series.deviatoric);
    a.vector(series.lateral_strain);
    a.vector(series.volumetric_strain);
    a.vector(series.gauge_axial_strain);
    a.vector(series.gauge_lateral_strain);
    a.vector(series.broken_bonds);
    a.value(series.confining_stress);
    a.vector(imbalance);
    a.vector(ke_ratio);
    a.vector(confine_err);
    a.value(next_snapshot);
    a.value(wall_seconds);
    a.value(consolidation_steps);
    a.value(bonds_initial);
    a.sized(warnings, 8);
    for (std::string& w : warnings) a.string(w);
    a.value(volume0);
    a.value(porosity0);
    a.value(length_min);
    a.string(wave_speed_method);
  }
  void save(ArchiveWriter& a) const { const_cast<LoopState*>(this)->transfer(a); }
  void load(ArchiveReader& a) {
    transfer(a);
    const std::size_t rows = series.axial_strain.size();
    for (std::size_t m :
         {series.deviatoric.size(), series.lateral_strain.size(), series.volumetric_strain.size(),
          series.gauge_axial_strain.size(), series.gauge_lateral_strain.size(),
          series.broken_bonds.size(), imbalance.size(), ke_ratio.size()})
      if (m != rows)
        throw InputError(a.where(), "series", std::to_string(m),
                         "series lengths differ: the checkpoint is corrupt");
  }
};

// One run in progress: everything a checkpoint holds.
struct Session {
  Simulation sim;
  std::unique_ptr<Protocol> test;
  HistoryRecorder history;
  CrackRecorder cracks;
  SnapshotWriter snaps;
  LoopState loop;
  AeMonitor ae;
};

// Writes checkpoint.bin atomically (temporary file, then rename): a crash while writing leaves the
// previous checkpoint intact. Layout: magic, format, version, commit, the resolved experiment,
// the state of every part, and last the FNV-1a hash of all bytes before it, so that a damaged
// file is refused before any of it is trusted.
void write_checkpoint(const fs::path& folder, const ExperimentSpec& spec, Session& s) {
  const fs::path path = folder / kCheckpointFile, tmp = folder / "checkpoint.bin.tmp";
  std::ostringstream body(std::ios::binary);
  {
    ArchiveWriter a(body);
    a.string(kCheckpointMagic);
    a.value(kCheckpointFormat);
    a.string(kVersion);
    a.string(kCommit);
    a.string(to_toml(spec));
    s.loop.save(a);
    s.sim.save_state(a);
    s.test->save_state(a);
    s.history.save_state(a);
    s.cracks.save_state(a);
    s.snaps.save_state(a);
    s.ae.save(a);
    a.label("end of checkpoint");
  }
  const std::string bytes = std::move(body).str();
  const std::uint64_t hash = fnv1a64(bytes);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(tmp.string(), "", "", "cannot write the checkpoint");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.write(reinterpret_cast<const char*>(&hash), sizeof hash);
    out.flush();
    if (!out) throw InputError(tmp.string(), "", "", "cannot write the checkpoint (disk full?)");
  }
  fs::rename(tmp, path);
}

// Reads checkpoint.bin whole and checks its header and hash; returns the bytes before the hash.
std::string read_checkpoint_bytes(const fs::path& cpath) {
  std::ifstream in(cpath, std::ios::binary);
  if (!in) throw InputError(cpath.string(), "", "", "cannot read the checkpoint");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  {
    std::istringstream head(bytes, std::ios::binary);
    ArchiveReader a(head, cpath.string());
    if (a.string() != kCheckpointMagic)
      throw InputError(cpath.string(), "header", "", "not a Breccia checkpoint");
    const auto format = a.get<std::uint32_t>();
    const std::string version = a.string();
    if (format != kCheckpointFormat || version != kVersion)
      throw InputError(cpath.string(), "version",
                       version + " (format " + std::to_string(format) + ")",
                       std::string("this is breccia ") + kVersion + " (format " +
                           std::to_string(kCheckpointFormat) +
                           "): resume with the version that wrote the checkpoint");
  }
  std::uint64_t stored = 0;
  if (bytes.size() < sizeof stored)
    throw InputError(cpath.string(), "length", std::to_string(bytes.size()) + " bytes",
                     "the checkpoint is truncated");
  std::memcpy(&stored, bytes.data() + bytes.size() - sizeof stored, sizeof stored);
  bytes.resize(bytes.size() - sizeof stored);
  if (fnv1a64(bytes) != stored)
    throw InputError(cpath.string(), "checksum", fmt::format("{:016x}", stored),
                     fmt::format("the file's bytes hash to {:016x}: the checkpoint is damaged "
                                 "or truncated and cannot be resumed",
                                 fnv1a64(bytes)));
  return bytes;
}

// v_S for the event duration (analysis.md §4.1), fixed at the first crack: sqrt(G / rho) with E and
// nu fitted over the rows recorded so far above 20 % of the current peak (the sample is still
// intact), and rho the (scaled) grain density times (1 - n0).
void configure_ae(const ExperimentSpec& spec, LoopState& L, AeMonitor& ae) {
  const auto& s = L.series;
  double qmax = 0.0;
  for (double q : s.deviatoric) qmax = std::max(qmax, q);
  // The sample gauges where the test has them (they leave out the platen contacts).
  const bool gauges = analysis::has_gauges(s);
  std::vector<double> x, y, lat;
  for (std::size_t k = 0; k < s.deviatoric.size(); ++k)
    if (s.deviatoric[k] >= 0.2 * qmax && qmax > 0.0) {
      x.push_back(gauges ? s.gauge_axial_strain[k] : s.axial_strain[k]);
      y.push_back(s.deviatoric[k]);
      lat.push_back(gauges ? s.gauge_lateral_strain[k] : s.lateral_strain[k]);
    }
  const analysis::LinearFit fe = analysis::fit_line(x, y, 3);
  const analysis::LinearFit fn = analysis::fit_line(x, lat, 3);
  const bool e_ok = fe.valid && fe.slope > 0.0;
  const double E = e_ok ? fe.slope : bond_moduli(spec).young;
  double nu = fn.valid ? -fn.slope : -1.0;
  const bool nu_ok = nu > 0.0 && nu < 0.5;
  if (!nu_ok) nu = 0.25;
  const double rho = spec.density * spec.density_scaling * (1.0 - L.porosity0);
  const double vs = analysis::shear_wave_speed(E, nu, rho);
  L.wave_speed_method = fmt::format(
      "sqrt(G / rho) fixed at the first crack: E = {:.4g} Pa ({}), nu = {:.3g} ({}), rho = {:.5g} "
      "kg/m^3 (simulated grain density x (1 - n0))",
      E, e_ok ? "slope of q over the rows so far" : "bond modulus: too few rows", nu,
      nu_ok ? "lateral/axial strain slope" : "default 0.25", rho);
  ae.configure(vs);
}

// Where the cracks are: shares per quarter along the loading axis (between the platens as they
// stood when loading began) and, for a Brazilian disc, how close they lie to the loaded diameter.
json crack_pattern_json(const Protocol& test, const Simulation& sim) {
  std::vector<double> axial, offset;
  std::vector<bool> tensile;
  for (const CrackRecord& c : sim.cracks()) {
    axial.push_back(c.position[test.axis()]);
    tensile.push_back(c.mode == CrackMode::Tensile);
  }
  const auto q = analysis::quarter_shares(axial, test.origin0(), test.origin0() + test.length0());
  json j{{"quarter_shares_along_axis", {q[0], q[1], q[2], q[3]}},
         {"largest_end_quarter_share", std::max(q[0], q[3])},
         {"quarters",
          "cracks per quarter of the initial length along the loading axis, from the "
          "bottom platen; a test that fails through its body has no end quarter "
          "above 0.40"}};
  if (const auto* b = dynamic_cast<const BrazilianTest*>(&test)) {
    for (const CrackRecord& c : sim.cracks()) offset.push_back(c.position.x - b->centre().x);
    const analysis::SplitPattern sp = analysis::split_pattern(offset, tensile, 0.5 * b->diameter());
    j["brazilian"] = {
        {"band_half_width_fraction_of_radius", sp.band},
        {"early_cracks", sp.early},
        {"early_tensile_share", sp.early_tensile_share},
        {"early_in_band_share", sp.early_in_band},
        {"all_in_band_share", sp.all_in_band},
        {"early_mean_offset_fraction_of_radius", sp.early_mean_offset},
        {"note",
         "cracks within +-band x R of the loaded diameter (x = disc centre); the first 20 % "
         "by time are the early ones; a uniform scatter would put 31 % in the band"}};
  }
  return j;
}

// NaN or inf in the state: the run cannot recover and everything after would be garbage, so it
// stops at once, failed, naming the step and the first particle affected. Checked at every history
// row (one pass over the particles every history_interval steps).
void check_finite_state(const Simulation& sim, const AxialState& a) {
  const ParticleStore& p = sim.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3& x = p.pos_rad[i].x;
    const Vec3& v = p.vel[i];
    const Vec3& f = p.force[i];
    if (std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z + f.x + f.y + f.z)) continue;
    throw std::runtime_error(fmt::format(
        "non-finite state at step {}: particle {} (tag {}) has position ({}, {}, {}), velocity "
        "({}, {}, {}), force ({}, {}, {}); the run stops here. Usual causes: a time step above "
        "the critical one (engine.time_step, engine.safety_factor), grains that overlap deeply "
        "in the sample, or stiffnesses or loads far outside the physical range",
        sim.step_count(), i, p.tag[i], x.x, x.y, x.z, v.x, v.y, v.z, f.x, f.y, f.z));
  }
  for (const double q : {a.strain, a.stress, a.deviatoric, a.force_bottom, a.force_top,
                         a.lateral_strain, a.volumetric_strain, a.confining_stress})
    if (!std::isfinite(q))
      throw std::runtime_error(fmt::format(
          "non-finite test state at step {} (strain {}, stress {} Pa, forces {} / {} N): the run "
          "stops here; check the platen speed, the confining stress and the time step",
          sim.step_count(), a.strain, a.stress, a.force_bottom, a.force_top));
}

// Steps between history rows: output.history_interval, or the steps in which the platens, at
// full speed, strain the sample by output.history_strain_interval.
std::uint64_t history_step_interval(const ExperimentSpec& spec, const Protocol& test,
                                    const Simulation& sim) {
  const double strain_rate = 2.0 * test.platen_speed() / test.length0();
  if (spec.history_strain_interval <= 0.0 || !(strain_rate > 0.0))
    return static_cast<std::uint64_t>(spec.history_interval);
  const double steps = spec.history_strain_interval / (strain_rate * sim.time_step());
  return static_cast<std::uint64_t>(std::clamp(std::round(steps), 1.0, 1e9));
}

// How the loading loop ended.
struct LoopEnd {
  std::string status = "complete";  // complete | interrupted
  std::string reason;
};

// One history row: the tables (flushed, so an interrupted run keeps them), the analysed series,
// the quality monitors (physics.md §6.1) and the snapshot when its strain is due.
void record_row(const ExperimentSpec& spec, Session& ss, const AxialState& a) {
  const Simulation& sim = ss.sim;
  LoopState& L = ss.loop;
  ss.history.record(sim, a);
  ss.cracks.record(sim);
  ss.history.flush();
  ss.cracks.flush();
  analysis::CompressionSeries& series = L.series;
  series.axial_strain.push_back(a.strain);
  series.deviatoric.push_back(a.deviatoric);
  series.lateral_strain.push_back(a.lateral_strain);
  series.volumetric_strain.push_back(a.volumetric_strain);
  series.gauge_axial_strain.push_back(a.gauge_strain);
  series.gauge_lateral_strain.push_back(a.gauge_lateral_strain);
  series.broken_bonds.push_back(static_cast<double>(sim.cracks().size()));
  const double fbar = 0.5 * (a.force_bottom + a.force_top);
  const double stored = sim.ledger().bond.total() + sim.ledger().contact;
  L.imbalance.push_back(fbar > 0.0 ? std::abs(a.force_top - a.force_bottom) / fbar : 0.0);
  L.ke_ratio.push_back(stored > 0.0 ? sim.ledger().kinetic() / stored : 0.0);
  const double sigma3 = ss.test->confining_stress();
  if (sigma3 > 0.0) L.confine_err.push_back(std::abs(a.confining_stress - sigma3) / sigma3);
  if (spec.snapshot_strain_interval > 0.0 && a.strain >= L.next_snapshot) {
    ss.snaps.write(sim);
    // The next multiple of the interval above this strain (one snapshot per row at most).
    L.next_snapshot = spec.snapshot_strain_interval *
                      (std::floor(a.strain / spec.snapshot_strain_interval) + 1.0);
  }
}

void print_progress_bar(const Session& ss, const AxialState& a, double elapsed) {
  const double frac = std::clamp(a.strain / ss.test->max_strain(), 1e-9, 1.0);
  const int width = 30, fill = static_cast<int>(frac * width);
  std::fprintf(stderr,
               "\r[%s%s] strain %.4f  q %.2f MPa  cracks %zu  %.0fs elapsed, <= %.0fs left ",
               std::string(static_cast<std::size_t>(fill), '#').c_str(),
               std::string(static_cast<std::size_t>(width - fill), '.').c_str(), a.strain,
               a.deviatoric * 1e-6, ss.sim.cracks().size(), elapsed, elapsed * (1 - frac) / frac);
  std::fflush(stderr);
}

// Steps the test until it stops, the run is interrupted (a signal or --stop-at-step: then it
// saves a checkpoint first) or it fails. `wall` gives the run's wall time so far.
LoopEnd run_loading_loop(const ExperimentSpec& spec, Session& ss, const RunOptions& opt,
                         const std::function<void()>& checkpoint,
                         const std::function<double()>& wall,
                         const std::function<void(const std::string&)>& log,
                         const fs::path& folder) {
  Simulation& sim = ss.sim;
  Protocol& test = *ss.test;
  const std::uint64_t interval = history_step_interval(spec, test, sim);
  auto last_bar = std::chrono::steady_clock::now(), last_checkpoint = last_bar;
  for (;;) {
    const bool stop_step = opt.stop_at_step > 0 && sim.step_count() >= opt.stop_at_step;
    if ((opt.interrupt && opt.interrupt->load()) || stop_step) {
      // Between two steps: the checkpoint continues exactly from here.
      checkpoint();
      log(fmt::format("checkpoint at step {}: continue with `breccia resume {}`", sim.step_count(),
                      folder.string()));
      return {"interrupted",
              stop_step ? fmt::format("stopped at step {} (--stop-at-step)", sim.step_count())
                        : "interrupted by a signal"};
    }
    if (sim.step_count() % interval == 0) sim.request_energy_sample();
    test.control(sim);
    sim.step();
    // Acoustic emission: cheap unless bonds broke in this step or an event is open.
    if (sim.cracks().size() > ss.ae.cracks_seen() || ss.ae.has_open_events()) {
      const AxialState now = test.measure(sim);
      if (!ss.ae.configured()) configure_ae(spec, ss.loop, ss.ae);
      ss.ae.after_step(sim, now.strain, now.deviatoric);
    }
    if ((sim.step_count() - 1) % interval != 0) continue;
    const AxialState a = test.measure(sim);
    check_finite_state(sim, a);
    record_row(spec, ss, a);
    if (test.finished(a, sim.cracks().size())) return {"complete", test.stop_reason()};
    const auto now = std::chrono::steady_clock::now();
    if (spec.checkpoint_interval > 0.0 &&
        std::chrono::duration<double>(now - last_checkpoint).count() >= spec.checkpoint_interval) {
      checkpoint();
      last_checkpoint = std::chrono::steady_clock::now();
    }
    if (opt.show_progress && now - last_bar > std::chrono::milliseconds(250)) {
      last_bar = now;
      print_progress_bar(ss, a, wall());
    }
  }
}

// The quality monitors over the pre-peak rows once the load exceeds 10 % of the peak (the
// ramp-up start is excluded), judged against physics.md §6.1's limits.
struct QualityVerdict {
  double imbalance_pre = 0.0, ke_ratio_pre = 0.0, confine_err_pre = 0.0, confine_err_all = 0.0;
  // Before the first crack, kinetic energy comes from the loading alone; after, breaking bonds
  // release it too (dynamic crack release that a lower platen speed does not remove).
  double ke_ratio_intact = 0.0, imbalance_intact = 0.0;
  bool quasi_static() const { return imbalance_pre <= 0.05 && ke_ratio_pre <= 1e-3; }
  bool quasi_static_until_cracking() const {
    return imbalance_intact <= 0.05 && ke_ratio_intact <= 1e-3;
  }
};

QualityVerdict judge_quality(const LoopState& L, const analysis::CompressionResult& an) {
  const analysis::CompressionSeries& series = L.series;
  QualityVerdict q;
  for (std::size_t k = 0; k < series.deviatoric.size(); ++k) {
    if (k < L.confine_err.size()) q.confine_err_all = std::max(q.confine_err_all, L.confine_err[k]);
    const bool pre = series.axial_strain[k] <= an.strain_at_peak &&
                     series.deviatoric[k] >= 0.1 * an.peak_deviatoric;
    if (!pre) continue;
    q.imbalance_pre = std::max(q.imbalance_pre, L.imbalance[k]);
    q.ke_ratio_pre = std::max(q.ke_ratio_pre, L.ke_ratio[k]);
    if (series.broken_bonds[k] == 0.0) {
      q.ke_ratio_intact = std::max(q.ke_ratio_intact, L.ke_ratio[k]);
      q.imbalance_intact = std::max(q.imbalance_intact, L.imbalance[k]);
    }
    if (k < L.confine_err.size()) q.confine_err_pre = std::max(q.confine_err_pre, L.confine_err[k]);
  }
  return q;
}

std::vector<std::string> quality_warnings(const QualityVerdict& q, const Protocol& test) {
  std::vector<std::string> w;
  if (!q.quasi_static())
    w.push_back(fmt::format(
        "the test was not quasi-static before the peak: platen force imbalance {:.3g} (limit "
        "0.05; {:.3g} before the first crack), kinetic/strain energy {:.3g} (limit 1e-3; {:.3g} "
        "before the first crack); {}",
        q.imbalance_pre, q.imbalance_intact, q.ke_ratio_pre, q.ke_ratio_intact,
        q.quasi_static_until_cracking()
            ? "the loading was quasi-static until bonds broke: the excess comes from bursts of "
              "breaking bonds near the peak, which a lower platen speed does not remove"
            : "lower test.platen_speed"));
  if (test.confining_stress() > 0.0 && q.confine_err_pre > 0.02)
    w.push_back(fmt::format(
        "the confining stress left its 2 % band before the peak (largest error {:.3g} %)",
        100 * q.confine_err_pre));
  return w;
}

// The headline numbers of a finished (or interrupted) run, for the caller.
RunResult run_result(const fs::path& folder, const Session& ss, const LoopEnd& end,
                     const analysis::CompressionResult& an, double wall_seconds) {
  const Simulation& sim = ss.sim;
  RunResult r;
  r.folder = folder.string();
  r.status = end.status;
  r.stop_reason = end.reason;
  r.particles = sim.particles().size();
  r.bonds = ss.loop.bonds_initial;
  r.confining_stress = ss.test->confining_stress();
  r.wall_seconds = wall_seconds;
  r.steps = sim.step_count();
  r.peak_stress = an.peak_deviatoric;
  r.sigma1_at_peak = an.sigma1_at_peak;
  r.strain_at_peak = an.strain_at_peak;
  r.youngs_modulus = an.e_t50.valid ? an.e_t50.slope : std::nan("");
  r.poisson = an.poisson;
  r.cracks = sim.cracks().size();
  for (const auto& c : sim.cracks()) (c.mode == CrackMode::Tensile ? r.tensile : r.shear)++;
  r.energy_residual_relative = sim.ledger().residual_relative;
  return r;
}

// The compression analysis's moduli, strengths and thresholds, with how each was read.
json compression_fields(const analysis::CompressionResult& an) {
  const char* strain_read = an.moduli_from_gauges
                                ? "the axial strain of the sample gauge (grain layers at 1/4 and "
                                  "3/4 of the height, clear of the platen contacts)"
                                : "the platen approach strain";
  return {
      {"peak_reached", an.peak_reached},
      {"peak_deviatoric_stress_pa", an.peak_deviatoric},
      {"peak_deviatoric_stress_mpa", an.peak_deviatoric * 1e-6},
      {"sigma1_at_peak_pa", an.sigma1_at_peak},
      {"axial_strain_at_peak", an.strain_at_peak},
      {"youngs_modulus_pa", an.e_t50.valid ? json(an.e_t50.slope) : json(nullptr)},
      {"youngs_modulus_method",
       fmt::format("ISRM tangent E_t50: least-squares slope of q = sigma_1 - sigma_3 against {} "
                   "over pre-peak samples at {:.0f}-{:.0f} % of the peak",
                   strain_read, 100 * an.e_t50_lo, 100 * an.e_t50_hi)},
      {"youngs_modulus_fit",
       {{"points", an.e_t50.points},
        {"r2", an.e_t50.r2},
        {"strain_column", an.moduli_from_gauges ? "gauge_axial_strain" : "axial_strain"},
        {"window_fraction_of_peak", {an.e_t50_lo, an.e_t50_hi}}}},
      {"youngs_modulus_platen_pa",
       an.e_t50_platen.valid ? json(an.e_t50_platen.slope) : json(nullptr)},
      {"youngs_modulus_average_pa", an.e_av.valid ? json(an.e_av.slope) : json(nullptr)},
      {"youngs_modulus_secant50_pa", nan_null(an.e_s50)},
      {"poisson_ratio", nan_null(an.poisson)},
      {"poisson_ratio_method",
       an.moduli_from_gauges ? "-slope of the gauge lateral strain (lateral-face grains of the "
                               "middle half) against the gauge axial strain, E_t50 window"
                             : "-slope of the lateral strain against the platen approach "
                               "strain, E_t50 window"},
      {"crack_initiation_stress_pa", nan_null(an.crack_initiation)},
      {"crack_initiation_method", "q when the broken bonds reach 5 % of those at the peak"},
      {"crack_damage_stress_pa", nan_null(an.crack_damage)},
      {"residual_strength_pa", nan_null(an.residual)},
      {"brittleness_index", nan_null(an.brittleness)},
      {"analysis_flags", an.flags}};
}

json quality_fields(const QualityVerdict& q) {
  return {{"quasi_static",
           {{"ok", q.quasi_static()},
            {"max_platen_force_imbalance_before_peak", q.imbalance_pre},
            {"max_kinetic_to_strain_energy_before_peak", q.ke_ratio_pre},
            {"max_kinetic_to_strain_energy_before_first_crack", q.ke_ratio_intact},
            {"max_platen_force_imbalance_before_first_crack", q.imbalance_intact}}},
          {"confining_stress_error",
           {{"max_relative_before_peak", q.confine_err_pre},
            {"max_relative_overall", q.confine_err_all}}}};
}

// The Brazilian test reads its peak as the tensile strength.
void add_brazilian_fields(json& summary, const Protocol& test,
                          const analysis::CompressionResult& an) {
  const auto* b = dynamic_cast<const BrazilianTest*>(&test);
  if (!b) return;
  summary["tensile_strength_pa"] = an.peak_deviatoric;
  summary["tensile_strength_mpa"] = an.peak_deviatoric * 1e-6;
  summary["tensile_strength_method"] =
      "sigma_t = 2 F / (pi D t) at the largest mean platen force F (ISRM Brazilian test)";
  summary["peak_force_n"] =
      0.5 * an.peak_deviatoric * std::numbers::pi * b->diameter() * b->thickness();
  summary["disc_diameter_m"] = b->diameter();
  summary["disc_thickness_m"] = b->thickness();
}

// summary.json: the run, the test, the analysis, the quality verdict and the warnings.
json run_summary(const ExperimentSpec& spec, const Session& ss, const RunResult& r,
                 const analysis::CompressionResult& an, const QualityVerdict& q,
                 const std::vector<std::string>& warnings, const json& manifest) {
  const Simulation& sim = ss.sim;
  const Protocol& test = *ss.test;
  json summary{{"status", r.status},
               {"stop_reason", r.stop_reason},
               {"experiment", spec.name},
               {"test", test.label()},
               {"test_kind", test.kind()},
               {"confining_stress_pa", test.confining_stress()},
               {"lateral_boundary", test.lateral_boundary()},
               {"particles", r.particles},
               {"bonds_initial", r.bonds},
               {"bonds_broken", r.cracks},
               {"cracks_tensile", r.tensile},
               {"cracks_shear", r.shear},
               {"steps", r.steps},
               {"consolidation_steps", ss.loop.consolidation_steps},
               {"simulated_time_s", sim.time()},
               {"time_step_s", sim.time_step()},
               {"density_scaling", spec.density_scaling},
               {"wall_seconds", r.wall_seconds},
               {"particle_steps_per_second",
                static_cast<double>(r.particles) * static_cast<double>(r.steps) / r.wall_seconds}};
  summary.update(compression_fields(an));
  summary.update(quality_fields(q));
  summary.update(json{{"platen_speed_m_per_s", test.platen_speed()},
                      {"strain_rate_per_s", 2.0 * test.platen_speed() / test.length0()},
                      {"sample_height_m", test.length0()},
                      {"sample_area_m2", test.area0()},
                      {"sample", manifest.value("sample", json::object())},
                      {"energy", ledger_json(sim.ledger())},
                      {"snapshots", ss.snaps.count()},
                      {"warnings", warnings}});
  if (manifest.contains("resumed")) summary["resumed"] = manifest["resumed"];
  if (!spec.joint_planes.empty())
    summary["joints"] = {{"law", spec.joint_law()},
                         {"planes", spec.joint_planes.size()},
                         {"elements", sim.joint_count()},
                         {"bonded_at_end", sim.bonded_joints()}};
  summary["crack_pattern"] = crack_pattern_json(test, sim);
  add_brazilian_fields(summary, test, an);
  return summary;
}

// The run folder's files in the manifest; a finished run drops its checkpoint, an interrupted
// one keeps it for `breccia resume`. Plots and the report are made here when asked for.
void list_run_files(const ExperimentSpec& spec, const fs::path& folder, const LoopEnd& end,
                    json& manifest, const std::function<void(const std::string&)>& log) {
  manifest["files"] = {"experiment.toml",     "history.csv",
                       "cracks.csv",          "events.csv",
                       "indicators.csv",      "b_value_windows.csv",
                       "d2_windows.csv",      "fragments.csv",
                       "summary.json",        "snapshots/particles.pvd",
                       "snapshots/bonds.pvd", "snapshots/cracks.pvd"};
  if (end.status == "complete") {
    fs::remove(folder / kCheckpointFile);
    manifest.erase("checkpoint");
  } else {
    manifest["files"].push_back(kCheckpointFile);
  }
  if (!spec.plot) return;
  make_plot(folder, log);
  if (fs::exists(folder / "stress_strain.png")) manifest["files"].push_back("stress_strain.png");
  if (fs::exists(folder / "report.html")) {
    manifest["files"].push_back("report.html");
    manifest["files"].push_back("report/");
  }
}

// After the loop: the recorders' last rows, the analysis, summary.json and the manifest.
RunResult conclude_run(const ExperimentSpec& spec, const fs::path& folder, json& manifest,
                       Session& ss, const LoopEnd& end, const std::function<double()>& wall,
                       const std::function<void(const std::string&)>& log) {
  Simulation& sim = ss.sim;
  ss.ae.finish();
  ss.cracks.record(sim);
  ss.cracks.flush();
  ss.history.flush();
  ss.snaps.write(sim);
  const analysis::CompressionResult an = analysis::analyse_compression(ss.loop.series);
  const RunResult result = run_result(folder, ss, end, an, wall());
  const QualityVerdict q = judge_quality(ss.loop, an);
  std::vector<std::string> warnings = ss.loop.warnings;  // those of the set-up, logged already
  for (const std::string& w : quality_warnings(q, *ss.test)) {
    log("warning: " + w);
    warnings.push_back(w);
  }
  json summary = run_summary(spec, ss, result, an, q, warnings, manifest);
  // Failure analysis: events, indicators, stages, fragments, energy budget (analysis.md §2-§9).
  const json failure = write_failure_analysis(
      folder, FailureInputs{spec, sim, ss.ae, ss.loop.series, an, ss.loop.volume0,
                            ss.loop.porosity0, ss.loop.length_min, ss.loop.wave_speed_method});
  for (const auto& [key, value] : failure.items()) summary[key] = value;
  write_json(folder / "summary.json", summary);
  list_run_files(spec, folder, end, manifest, log);
  return result;
}

// Loads the loop, runs it to its end (or the next interruption), and writes the summary and the
// final manifest. `t_start` is when this session began.
RunResult execute(const ExperimentSpec& spec, const fs::path& folder, json& manifest, Session& ss,
                  const RunOptions& opt, std::chrono::steady_clock::time_point t_start) {
  auto log = [&](const std::string& m) {
    if (opt.log) opt.log(m);
  };
  auto wall = [&] {
    return ss.loop.wall_seconds +
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  };
  auto finish = [&](const std::string& status, const std::string& reason, double seconds) {
    manifest["status"] = status;
    manifest["stop_reason"] = reason;
    manifest["wall_seconds"] = seconds;
    write_json(folder / "manifest.json", manifest);
  };
  auto checkpoint = [&] {
    const double before = ss.loop.wall_seconds;
    ss.loop.wall_seconds = wall();
    write_checkpoint(folder, spec, ss);
    ss.loop.wall_seconds = before;
    manifest["checkpoint"] = {{"file", kCheckpointFile},
                              {"step", ss.sim.step_count()},
                              {"time_s", ss.sim.time()},
                              {"resume_command", "breccia resume " + folder.string()}};
    write_json(folder / "manifest.json", manifest);
  };
  try {
    const LoopEnd end = run_loading_loop(spec, ss, opt, checkpoint, wall, log, folder);
    if (opt.show_progress) std::fprintf(stderr, "\n");
    const RunResult result = conclude_run(spec, folder, manifest, ss, end, wall, log);
    finish(result.status, result.stop_reason, result.wall_seconds);
    return result;
  } catch (const std::exception& e) {
    finish("failed", e.what(), wall());
    throw;
  }
}

}  // namespace

RunResult run_experiment(const ExperimentSpec& spec, const RunOptions& opt) {
  auto log = [&](const std::string& m) {
    if (opt.log) opt.log(m);
  };
  if (spec.threads > 0) set_threads(static_cast<int>(spec.threads));
  const auto t_start = std::chrono::steady_clock::now();
  // Build first: a bad sample (geometry file, bond list) fails before any file is written.
  Built b = build(spec, log);
  const fs::path folder = make_folder(spec);
  json manifest{
      {"program", "breccia"},
      {"version", kVersion},
      {"commit", kCommit},
      {"created", fmt::format("{:%Y-%m-%dT%H:%M:%S}", fmt::localtime(std::time(nullptr)))},
      {"command", opt.command_line},
      {"experiment_source", spec.source},
      {"seed", spec.engine.seed},
      {"threads", max_threads()},
      {"machine", machine_description()},
      {"status", "running"},
      {"density_scaling", spec.density_scaling},
      {"grain_density_kg_m3", spec.density},
      {"simulated_density_kg_m3", spec.density * spec.density_scaling},
      {"bar_wave_speed_m_s", b.bar_wave_speed},
      {"sample", b.sample_report},
      {"resolved_experiment", to_toml(spec)}};
  { std::ofstream(folder / "experiment.toml") << to_toml(spec); }
  write_json(folder / "manifest.json", manifest);

  Simulation& sim = b.sim;
  Protocol& test = *b.protocol;
  LoopState loop;
  AeSettings ae_settings;
  loop.warnings = sim.warnings();
  loop.consolidation_steps = b.consolidation_steps;
  loop.bonds_initial = sim.intact_bonds();
  loop.series.confining_stress = test.confining_stress();
  loop.next_snapshot = spec.snapshot_strain_interval;
  if (test.confining_stress() > 0.0 && !test.consolidated())
    loop.warnings.push_back(fmt::format(
        "consolidation to {} MPa did not settle within {} steps; loading started anyway",
        test.confining_stress() * 1e-6, b.consolidation_steps));
  for (const std::string& w : loop.warnings) log("warning: " + w);
  manifest["time_step_s"] = sim.time_step();
  manifest["critical_time_step_s"] = sim.critical_time_step();
  manifest["particles"] = sim.particles().size();
  manifest["bonds"] = sim.intact_bonds();
  manifest["consolidation_steps"] = b.consolidation_steps;
  manifest["strain_rate_per_s"] = 2.0 * test.platen_speed() / test.length0();
  write_json(folder / "manifest.json", manifest);
  log(fmt::format("sample: {} particles, {} bonds; time step {:.3g} s (critical {:.3g} s){}",
                  sim.particles().size(), sim.intact_bonds(), sim.time_step(),
                  sim.critical_time_step(),
                  test.confining_stress() > 0.0
                      ? fmt::format("; consolidated to {:.3g} MPa in {} steps",
                                    test.confining_stress() * 1e-6, b.consolidation_steps)
                      : ""));
  // Reference state for porosity and D2, and the acoustic-emission monitor.
  {
    const ParticleStore& p = sim.particles();
    double solid = 0.0, r_max = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      solid += p.mass[i] / p.density[i];
      r_max = std::max(r_max, p.pos_rad[i].r);
    }
    loop.volume0 = test.length0() * test.area0();
    loop.porosity0 = 1.0 - solid / loop.volume0;
    loop.length_min = spec.dimension == 2
                          ? std::min(test.length0(), test.width0())
                          : std::min({test.length0(), test.width0(), test.depth0()});
    ae_settings.source_radius =
        spec.ae_source_radius > 0.0 ? spec.ae_source_radius : 3.0 * (2.0 * r_max);
  }
  ae_settings.shear_wave_speed = spec.ae_shear_wave_speed;
  ae_settings.moment_tensors = spec.ae_moment_tensors;
  ae_settings.moment_interval = static_cast<std::uint64_t>(spec.ae_moment_interval);
  ae_settings.linkage =
      spec.ae_clustering == "grain" ? analysis::Linkage::Grain : analysis::Linkage::SourceRadius;
  std::unique_ptr<Session> ss;
  try {
    ss.reset(new Session{
        std::move(b.sim), std::move(b.protocol), HistoryRecorder((folder / "history.csv").string()),
        CrackRecorder((folder / "cracks.csv").string()),
        SnapshotWriter((folder / "snapshots").string()), std::move(loop), AeMonitor(ae_settings)});
    if (spec.ae_shear_wave_speed > 0.0) {
      ss->ae.configure(spec.ae_shear_wave_speed);
      ss->loop.wave_speed_method = "given in the experiment file (ae.shear_wave_speed)";
    }
    ss->snaps.write(ss->sim);
  } catch (const std::exception& e) {
    manifest["status"] = "failed";
    manifest["stop_reason"] = e.what();
    write_json(folder / "manifest.json", manifest);
    throw;
  }
  return execute(spec, folder, manifest, *ss, opt, t_start);
}

RunResult resume_run(const std::string& folder_name, const ResumeOptions& ro,
                     const RunOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  const fs::path folder(folder_name);
  const fs::path mpath = folder / "manifest.json", cpath = folder / kCheckpointFile;
  if (!fs::exists(mpath))
    throw InputError(folder_name, "manifest.json", "(missing)", "not a Breccia run folder");
  json manifest = read_json_object(mpath.string());
  const std::string status = JsonView(manifest, mpath.string()).text("status", "unknown");
  if (status == "complete")
    throw InputError(mpath.string(), "status", status, "the run is complete: nothing to resume");
  if (!fs::exists(cpath))
    throw InputError(cpath.string(), "", "(missing)",
                     "the run (status '" + status +
                         "') has no checkpoint: it stopped before writing one "
                         "(see output.checkpoint_interval_s)");
  std::istringstream in(read_checkpoint_bytes(cpath), std::ios::binary);
  ArchiveReader a(in, cpath.string());
  a.string();  // magic, format and version: checked with the hash
  a.get<std::uint32_t>();
  a.string();
  const std::string commit = a.string();
  // The resolved experiment travels in the checkpoint; only run-time options may change.
  std::vector<std::string> overrides;
  if (ro.threads >= 0) overrides.push_back("engine.threads=" + std::to_string(ro.threads));
  const ExperimentSpec spec = parse_experiment(a.string(), cpath.string(), overrides);
  if (spec.threads > 0) set_threads(static_cast<int>(spec.threads));

  LoopState loop;
  loop.load(a);
  Simulation sim = Simulation::restore(a);
  std::unique_ptr<Protocol> test;
  if (!with_lab_test(spec.test_kind, [&]<class T>() { test = T::restore(a); }))
    throw InputError(cpath.string(), "test.kind", spec.test_kind, "not a registered test");
  test->check_restored(sim, cpath.string());
  HistoryRecorder history((folder / "history.csv").string(), a);
  CrackRecorder cracks((folder / "cracks.csv").string(), a);
  SnapshotWriter snaps((folder / "snapshots").string(), a, sim);
  AeMonitor ae;
  ae.load(a);
  a.label("end of checkpoint");
  if (loop.imbalance.size() != loop.series.axial_strain.size())
    throw InputError(cpath.string(), "loop", "", "inconsistent series: the checkpoint is corrupt");

  if (opt.log)
    opt.log(fmt::format("resuming {} at step {} (simulated time {:.6g} s)", folder_name,
                        sim.step_count(), sim.time()));
  json entry{{"at_step", sim.step_count()},
             {"at_time_s", sim.time()},
             {"previous_status", status},
             {"checkpoint_written_by", std::string(kVersion) + " (" + commit + ")"},
             {"when", fmt::format("{:%Y-%m-%dT%H:%M:%S}", fmt::localtime(std::time(nullptr)))},
             {"command", opt.command_line},
             {"threads", max_threads()},
             {"machine", machine_description()}};
  if (!manifest.contains("resumed")) manifest["resumed"] = json::array();
  manifest["resumed"].push_back(entry);
  manifest["status"] = "running";
  manifest.erase("stop_reason");
  write_json(mpath, manifest);
  Session ss{std::move(sim),   std::move(test), std::move(history), std::move(cracks),
             std::move(snaps), std::move(loop), std::move(ae)};
  return execute(spec, folder, manifest, ss, opt, t_start);
}

namespace {

json sweep_entry(double sigma3, const RunResult& r) {
  return {{"confining_stress_pa", sigma3},
          {"folder", fs::path(r.folder).filename().string()},
          {"status", r.status},
          {"peak_deviatoric_stress_pa", r.peak_stress},
          {"sigma1_at_peak_pa", r.sigma1_at_peak},
          {"youngs_modulus_pa", nan_null(r.youngs_modulus)},
          {"poisson_ratio", nan_null(r.poisson)},
          {"cracks", r.cracks},
          {"wall_seconds", r.wall_seconds}};
}

// The headline results of a run folder written by a child process (its summary, or its manifest
// when the run stopped before one was written).
RunResult result_of_folder(const fs::path& folder) {
  RunResult r;
  r.folder = folder.string();
  r.status = "failed";
  const fs::path summary = folder / "summary.json", manifest = folder / "manifest.json";
  if (fs::exists(summary)) {
    const json j = read_json_object(summary.string());
    const JsonView v(j, summary.string());
    r.status = v.text("status", "failed");
    r.stop_reason = v.text("stop_reason", "");
    r.peak_stress = v.maybe_number("peak_deviatoric_stress_pa").value_or(0.0);
    r.sigma1_at_peak = v.maybe_number("sigma1_at_peak_pa").value_or(0.0);
    r.strain_at_peak = v.maybe_number("axial_strain_at_peak").value_or(0.0);
    r.youngs_modulus =
        v.maybe_number("youngs_modulus_pa").value_or(std::numeric_limits<double>::quiet_NaN());
    r.poisson = v.maybe_number("poisson_ratio").value_or(std::numeric_limits<double>::quiet_NaN());
    r.confining_stress = v.maybe_number("confining_stress_pa").value_or(0.0);
    r.particles = static_cast<std::size_t>(v.maybe_number("particles").value_or(0.0));
    r.cracks = static_cast<std::size_t>(v.maybe_number("bonds_broken").value_or(0.0));
    r.tensile = static_cast<std::size_t>(v.maybe_number("cracks_tensile").value_or(0.0));
    r.shear = static_cast<std::size_t>(v.maybe_number("cracks_shear").value_or(0.0));
    r.wall_seconds = v.maybe_number("wall_seconds").value_or(0.0);
  } else if (fs::exists(manifest)) {
    const json j = read_json_object(manifest.string());
    const JsonView v(j, manifest.string());
    r.status = v.text("status", "failed");
    r.stop_reason = v.text("stop_reason", "the run wrote no summary");
  }
  return r;
}

// Starts `exe run file` with stdout to `out` and stderr to `err`; the child's pid.
pid_t spawn_run(const std::string& exe, const fs::path& file, const fs::path& out,
                const fs::path& err) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> args{exe, "run", file.string()};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0)
    throw std::runtime_error(fmt::format("sweep: cannot start {}: {}", exe, std::strerror(rc)));
  return pid;
}

// The folder a child's `breccia run` printed as its last line of output.
fs::path printed_folder(const fs::path& out) {
  std::ifstream in(out);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

// The sweep's runs as child processes, `jobs` at a time, each with `threads` OpenMP threads. A
// generated sample is packed first, once, into the cache the children read.
std::vector<RunResult> sweep_in_processes(std::vector<ExperimentSpec> specs, int jobs, int threads,
                                          const fs::path& folder, const RunOptions& opt) {
  const ExperimentSpec& first = specs.front();
  if (first.sample_source == "generate" && first.cache) {
    json report;
    SampleInfo info;
    load_sample(first, report, info, opt.log);
  }
  const fs::path dir = folder / "experiments";
  fs::create_directories(dir);
  std::vector<RunResult> results(specs.size());
  std::vector<std::pair<pid_t, std::size_t>> running;
  std::size_t next = 0;
  auto reap_one = [&] {
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid <= 0) return;
    for (std::size_t k = 0; k < running.size(); ++k) {
      if (running[k].first != pid) continue;
      const std::size_t i = running[k].second;
      const fs::path stem = dir / specs[i].name;
      const fs::path run = printed_folder(stem.string() + ".out");
      results[i] = run.empty() || !fs::exists(run) ? RunResult{} : result_of_folder(run);
      if (run.empty() || !fs::exists(run)) {
        results[i].status = "failed";
        results[i].stop_reason = "no run folder: see " + stem.string() + ".log";
      }
      if (opt.log)
        opt.log(fmt::format("sweep: {} {} ({})", specs[i].name, results[i].status,
                            results[i].status == "complete"
                                ? fmt::format("peak q {:.2f} MPa", results[i].peak_stress * 1e-6)
                                : results[i].stop_reason));
      running.erase(running.begin() + static_cast<std::ptrdiff_t>(k));
      return;
    }
  };
  while (next < specs.size() || !running.empty()) {
    const bool stopping = opt.interrupt && opt.interrupt->load();
    if (!stopping && next < specs.size() && running.size() < static_cast<std::size_t>(jobs)) {
      ExperimentSpec& one = specs[next];
      one.threads = threads;
      one.progress = false;
      const fs::path stem = dir / one.name;
      { std::ofstream(stem.string() + ".toml") << to_toml(one); }
      if (opt.log)
        opt.log(fmt::format("sweep: started {} ({} thread{})", one.name, threads,
                            threads == 1 ? "" : "s"));
      running.emplace_back(spawn_run(opt.executable, stem.string() + ".toml",
                                     stem.string() + ".out", stem.string() + ".log"),
                           next);
      ++next;
      continue;
    }
    if (running.empty()) break;  // interrupted before every run started
    reap_one();
  }
  for (std::size_t i = next; i < specs.size(); ++i) {
    results[i].status = "interrupted";
    results[i].stop_reason = "not started: the sweep was interrupted";
  }
  return results;
}

}  // namespace

SweepResult run_sweep(const ExperimentSpec& spec, const std::vector<double>& confining,
                      const RunOptions& opt) {
  if (confining.empty())
    throw InputError("sweep", "--confining", "(none)", "give at least one confining stress");
  for (double c : confining)
    if (!(c >= 0.0))
      throw InputError("sweep", "--confining", num(c), "each confining stress must be >= 0 Pa");
  ExperimentSpec base = spec;
  {
    ExperimentSpec probe = spec;  // a test that cannot be swept fails before any folder exists
    set_confining_stress(probe, confining.front(), "sweep");
  }
  const fs::path folder = make_folder(spec);
  fs::rename(folder, folder.string() + "-sweep");
  SweepResult out;
  out.folder = folder.string() + "-sweep";
  base.output_directory = out.folder;
  std::vector<ExperimentSpec> specs;
  for (double c : confining) {
    ExperimentSpec one = base;
    set_confining_stress(one, c, "sweep");
    one.name = fmt::format("{}-confining-{}MPa", spec.name, c * 1e-6);
    specs.push_back(one);
  }
  // Parallel processes when cores allow: each run gets its share of the cores (or the threads
  // the experiment asks for).
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int per_run = spec.threads > 0 ? static_cast<int>(spec.threads) : 1;
  const int jobs = opt.jobs > 0
                       ? opt.jobs
                       : std::min(static_cast<int>(specs.size()), std::max(1, cores / per_run));
  json runs = json::array();
  std::vector<double> s3, s1;
  out.status = "complete";
  if (jobs > 1 && !opt.executable.empty()) {
    const int threads = spec.threads > 0 ? per_run : std::max(1, cores / jobs);
    if (opt.log)
      opt.log(fmt::format("sweep: {} runs, {} at a time ({} thread{} each)", specs.size(), jobs,
                          threads, threads == 1 ? "" : "s"));
    out.runs = sweep_in_processes(specs, jobs, threads, out.folder, opt);
  } else {
    // Copies of one sample: a generated sample is packed once and cached in the sweep folder.
    for (const ExperimentSpec& one : specs) {
      if (opt.log)
        opt.log(fmt::format("sweep: confining stress {} MPa", confining_stress(one) * 1e-6));
      out.runs.push_back(run_experiment(one, opt));
      if (out.runs.back().status != "complete") break;
    }
  }
  for (std::size_t i = 0; i < out.runs.size(); ++i) {
    const RunResult& r = out.runs[i];
    runs.push_back(sweep_entry(confining[i], r));
    if (r.status != "complete") {
      if (out.status == "complete") out.status = r.status;
      continue;
    }
    s3.push_back(confining[i]);
    s1.push_back(r.sigma1_at_peak);
  }
  const auto mc = analysis::fit_mohr_coulomb(s3, s1);
  const auto hb = analysis::fit_hoek_brown(s3, s1);
  json sweep{{"status", out.status},
             {"experiment", spec.name},
             {"runs", runs},
             {"mohr_coulomb",
              {{"valid", mc.valid},
               {"method", "least squares of sigma_1 on sigma_3 (principal-stress form)"},
               {"k", mc.k},
               {"friction_angle_deg", mc.friction_angle_deg},
               {"cohesion_pa", mc.cohesion},
               {"ucs_intercept_pa", mc.ucs},
               {"implied_tensile_strength_pa", mc.tensile},
               {"r2", nan_null(mc.r2)},
               {"flag", mc.flag}}},
             {"hoek_brown",
              {{"valid", hb.valid},
               {"sigma_ci_pa", hb.sigma_ci},
               {"m_i", hb.m_i},
               {"sigma_ci_linearised_pa", hb.sigma_ci_linear},
               {"m_i_linearised", hb.m_i_linear},
               {"rms_residual_pa", hb.rms},
               {"flag", hb.flag}}}};
  write_json(fs::path(out.folder) / "sweep.json", sweep);
  if (spec.plot && !write_report(out.folder) && opt.log)
    opt.log("warning: no report.html (see " + out.folder + "/report.log)");
  return out;
}

}  // namespace breccia
