#include "breccia/run/sample_build.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "breccia/analysis/ae_clustering.hpp"
#include "breccia/core/checksum.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/io/json_view.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/run/memory_budget.hpp"
#include "breccia/sample/geometry_checks.hpp"
#include "breccia/sample/geometry_file.hpp"
#include "breccia/sample/lattice.hpp"
#include "breccia/sample/sample_import.hpp"
#include "breccia/sample/spatial_order.hpp"
#include "breccia/version.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

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
      {"profile_axis", std::string(1, "xyz"[ss.profile_axis])},
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
  sample_part += "|packing-7|";
  // The fused multiply-adds of the higher instruction sets round the packing's forces otherwise.
  sample_part += instruction_set_name(instruction_set_of(s));
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

InstructionSet instruction_set_of(const ExperimentSpec& s) {
  if (s.instruction_set == "auto") return best_instruction_set();
  const std::optional<InstructionSet> set = instruction_set_from_name(s.instruction_set);
  if (!set)
    throw InputError(s.source, "engine.instruction_set", s.instruction_set,
                     "allowed: auto, baseline, x86-64-v3");
  if (!instruction_set_supported(*set)) {
    std::string runs;
    for (InstructionSet each : kInstructionSets)
      if (instruction_set_supported(each))
        runs += (runs.empty() ? "" : ", ") + std::string(instruction_set_name(each));
    throw InputError(s.source, "engine.instruction_set", s.instruction_set,
                     "this CPU (or this build) runs: auto, " + runs);
  }
  return *set;
}

PackingSettings packing_settings(const ExperimentSpec& s) {
  PackingSettings p;
  p.instruction_set = instruction_set_of(s);
  p.shape = s.shape == "cylinder"                   ? SampleShape::Cylinder
            : s.shape == "rectangle"                ? SampleShape::Rectangle
            : s.shape == "disk"                     ? SampleShape::Disk
            : s.shape == "slab" && s.dimension == 2 ? SampleShape::Rectangle
                                                    : SampleShape::Prism;
  p.width = s.width;
  p.depth = s.depth;
  // A slab is a prism (2D: rectangle) whose height is the slab's thickness.
  p.height = s.shape == "slab" ? s.slab_thickness : s.height;
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
  p.homogeneous_compaction = s.compaction == "homogeneous";
  p.contact = contact_model(s);
  p.bond_gap_tolerance = s.bond_gap_tolerance;
  p.floater_contacts = static_cast<int>(s.floater_contacts);
  p.floater_max_growth = s.floater_max_growth;
  p.insertion_failures = static_cast<std::uint64_t>(s.insertion_failures);
  p.seed = s.engine.seed;
  p.max_particles = static_cast<std::size_t>(s.max_particles);
  return p;
}

namespace {

// Writes a packed sample where other runs find it. Runs started together (a sweep's processes)
// pack the same sample at the same time and write the same file: each writes under a name of its
// own and renames it into place, the report first, so that a reader who finds the geometry finds
// its report whole.
void write_cached_sample(const fs::path& p, const GeneratedSample& out) {
  static std::atomic<unsigned> count{0};
  const std::string own = fmt::format(".{}-{}.tmp", static_cast<long>(::getpid()), count++);
  const fs::path report = p.string() + ".json", report_tmp = report.string() + own,
                 geometry_tmp = p.string() + own;
  // Both written before either is renamed: a failure (a full disk) leaves neither behind.
  try {
    write_json(report_tmp, out.report);
    write_geometry(geometry_tmp.string(), out.geometry);
  } catch (...) {
    std::error_code ec;
    fs::remove(report_tmp, ec);
    fs::remove(geometry_tmp, ec);
    throw;
  }
  fs::rename(report_tmp, report);
  fs::rename(geometry_tmp, p);
}

// Whether `a` and `b` name the same file (`b` need not exist).
bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
}

// The files `breccia generate` reads for an experiment, with what each is.
std::vector<std::pair<fs::path, std::string>> files_read(const ExperimentSpec& s) {
  std::vector<std::pair<fs::path, std::string>> in;
  if (s.source != "built-in default") in.emplace_back(s.source, "the experiment file");
  if (s.sample_source == "file" || s.sample_source == "table" || s.sample_source == "gengeo") {
    const std::string p = resolve(s, s.geometry_file);
    in.emplace_back(p, "the sample file the experiment reads (sample.file)");
    in.emplace_back(p + ".json", "the report beside the sample file the experiment reads");
  }
  return in;
}

// A file `breccia generate` may replace: a breccia-geometry sample, or a sample's report.
bool is_sample_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string head(17, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  return in && head == "breccia-geometry ";
}
bool is_sample_report(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  const json j = json::parse(in, nullptr, false);
  return j.is_object() && j.contains("generator") && j["generator"].is_string() &&
         j["generator"].get<std::string>().rfind("breccia", 0) == 0;
}

// Refuses an output path that is empty, a folder, an input of the experiment, or a file that is
// not a sample: `generate` never writes over what it did not write.
void check_sample_output(const ExperimentSpec& s, const std::string& path,
                         const std::string& option) {
  const std::string where = "breccia generate";
  if (path.empty())
    throw InputError(where, option, "''",
                     "the sample file to write (breccia-geometry), e.g. samples/berea.geom");
  const fs::path p(path);
  const fs::path name = p.filename();
  std::error_code ec;
  if (name.empty() || name == "." || name == ".." || fs::is_directory(p, ec))
    throw InputError(
        where, option, path,
        fmt::format("a file to write, not a folder (e.g. {})",
                    ((p.has_filename() ? p : p.parent_path()) / "sample.geom").string()));
  const fs::path report = path + ".json";
  for (const auto& [input, what] : files_read(s))
    for (const fs::path& out : {p, report})
      if (same_file(out, input))
        throw InputError(where, option, path,
                         fmt::format("writing {} would replace {} ({}): choose another name",
                                     out.string(), what, input.string()));
  if (fs::exists(p, ec) && !is_sample_file(p))
    throw InputError(where, option, path,
                     "the file exists and is not a breccia-geometry sample: generate replaces "
                     "only a sample (choose another name, or remove the file)");
  if (fs::exists(report, ec) && !is_sample_report(report))
    throw InputError(where, option, path,
                     fmt::format("{} exists and is not a sample's report, and generate writes "
                                 "the report there: choose another name, or remove the file",
                                 report.string()));
}

}  // namespace

GeneratedSample generate_sample(const ExperimentSpec& s, const std::string& path,
                                const std::function<void(const std::string&)>& log) {
  PackedSample packed = pack_sample(packing_settings(s), log);
  GeneratedSample out{std::move(packed.geometry), packing_json(packed.report)};
  out.report["generator"] = fmt::format("breccia {}", kVersion);
  out.report["settings"] = to_toml(s);
  if (!path.empty()) {
    const fs::path p(path);
    if (p.has_parent_path()) fs::create_directories(p.parent_path());
    write_cached_sample(p, out);
  }
  return out;
}

GeneratedSample write_sample(const ExperimentSpec& s, const std::string& path,
                             const std::string& option,
                             const std::function<void(const std::string&)>& log) {
  check_sample_output(s, path, option);
  GeneratedSample out;
  if (s.sample_source == "generate") {
    out = generate_sample(s, std::string(), log);
  } else {
    // A lattice, or a sample read (and so converted to breccia-geometry): written as a run
    // would take it, its own report kept where it has one.
    SampleInfo info;
    out.geometry = load_sample(s, out.report, info, log);
    out.report["source"] = s.sample_source;
    out.report["generator"] = fmt::format("breccia {}", kVersion);
    if (!out.report.contains("settings")) out.report["settings"] = to_toml(s);
  }
  const fs::path p(path);
  try {
    if (p.has_parent_path()) fs::create_directories(p.parent_path());
    write_cached_sample(p, out);
  } catch (const std::system_error& e) {
    throw InputError("breccia generate", option, path,
                     "cannot write the sample there: " + e.code().message());
  }
  return out;
}

GeometryData load_sample(const ExperimentSpec& s, json& report, SampleInfo& info,
                         const std::function<void(const std::string&)>& log_fn) {
  // A quiet caller passes no logger.
  auto log = [&](const std::string& m) {
    if (log_fn) log_fn(m);
  };
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
      log(s.cache ? "sample: generating (cached afterwards in " + cache.string() + ")"
                  : std::string("sample: generating (not cached: sample.cache = false)"));
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
        for (const char* shape : {"prism", "cylinder", "rectangle", "disk", "slab"})
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
    g = GeometryData::of_store(ps);  // at rest and free, as the lattice makes them
    report["lattice"] = s.dimension == 2 ? "hexagonal" : "fcc";
    check_geometry(g, s.source + " (sample.source = \"lattice\")", max_n);
  }
  if (g.dimension != want)
    throw InputError(s.source, "engine.dimension", std::to_string(s.dimension),
                     std::string("the sample is ") + (g.dimension == Dimension::Two ? "2D" : "3D"));
  // A read sample that lists no bonds is bonded by the gap tolerance: bounded by its grains.
  if (g.bonds.empty() && !g.particles.empty() &&
      (s.sample_source == "file" || s.sample_source == "table" || s.sample_source == "gengeo")) {
    double smallest = g.particles.front().radius;
    for (const ParticleSpec& p : g.particles) smallest = std::min(smallest, p.radius);
    if (s.bond_gap_tolerance > smallest)
      throw InputError(s.source, "sample.bond_gap_tolerance", num(s.bond_gap_tolerance),
                       fmt::format("at most the smallest grain radius of {} ({} m): a wider gap "
                                   "bonds grains that another grain could sit between",
                                   resolve(s, s.geometry_file), num(smallest)));
  }
  return g;
}

namespace {

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

// What a test needs at most: the simulated time (the ramp plus the platen travel to max_strain
// at the platen speed, each platen moving; or a test's own TestBudget), the fastest boundary
// speed and the strain its bins and snapshots span.
TestBudget test_budget(const ExperimentSpec& s, double length, double v_bar) {
  TestBudget b;
  visit_lab_test(s.test, [&]<class T>(const typename T::Params& p) {
    if constexpr (requires { T::budget(p, length, v_bar); }) {
      b = T::budget(p, length, v_bar);
    } else {
      const double ramp = p.ramp_time > 0.0 ? p.ramp_time : 10.0 * length / v_bar;
      b.time = ramp + p.max_strain * length / (2.0 * p.platen_speed);
      b.speed = p.platen_speed;
      b.max_strain = p.max_strain;
      b.what = fmt::format(
          "ramp {} s + max_strain {} x sample length {} m / (2 x platen_speed {} "
          "m/s)",
          num(ramp), num(p.max_strain), num(length), num(p.platen_speed));
    }
  });
  return b;
}

void check_run_budget(const ExperimentSpec& s, const Simulation& sim, double length, double v_bar) {
  const double dt = sim.time_step();
  if (!(std::isfinite(dt) && dt > 0.0))
    throw InputError(s.source, "engine.time_step", num(dt),
                     "the time step must be finite and > 0; check the grain radii, densities and "
                     "stiffnesses");
  const TestBudget budget = test_budget(s, length, v_bar);
  const double speed = budget.speed, max_strain = budget.max_strain;
  const double steps = budget.time / dt;
  const double n = static_cast<double>(sim.particles().size());
  const std::string what = fmt::format("{}, at a time step of {} s", budget.what, num(dt));
  if (!(steps <= kMaxRunSteps) || !(steps * n <= kMaxParticleSteps))
    throw InputError(s.source, budget.keys,
                     fmt::format("{:.3g} steps of {} particles", steps, sim.particles().size()),
                     fmt::format("a test may take at most {:.0e} steps and {:.0e} particle-steps; "
                                 "this one needs {}: {}, or check engine.time_step and the grain "
                                 "radii",
                                 kMaxRunSteps, kMaxParticleSteps, what, budget.remedy));
  double r_min = std::numeric_limits<double>::infinity();
  for (const PosRad& q : sim.particles().pos_rad) r_min = std::min(r_min, q.r);
  if (!(speed * dt <= kMaxPlatenTravelPerStep * r_min))
    throw InputError(s.source, budget.speed_key, num(speed) + " m/s",
                     fmt::format("a boundary may move at most {} of the smallest grain radius ({} "
                                 "m) per time step ({} s), i.e. at most {} m/s: faster, contacts "
                                 "are crossed within a step (platens: use a few cm/s or less)",
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

}  // namespace

namespace {

// Dynamic damping's region and window (docs/physics.md §2.3), each unless given: the largest
// rock grain's diameter (the broken bond's grains and those touching them), and the time a
// rupture at half the shear-wave speed takes to reach the region's edge, 2 r / v_S (seed 003's
// event duration: "twice the time for a shear wave to propagate to the edge of the source
// area"), with v_S = sqrt(G / rho) from the bond modulus, nu = 0.25 and the (scaled) bulk density
// (or ae.shear_wave_speed). The AE monitor fits v_S on the test's own modulus at the first
// crack; the engine needs its window before any crack.
void resolve_dynamic_damping(const ExperimentSpec& s, Simulation& sim, std::size_t rock,
                             double bulk_density) {
  if (!s.dynamic_damping) return;
  double r_max = 0.0;
  for (std::size_t i = 0; i < rock; ++i) r_max = std::max(r_max, sim.particles().pos_rad[i].r);
  const double radius =
      s.engine.dynamic_damping_radius > 0.0 ? s.engine.dynamic_damping_radius : 2.0 * r_max;
  const double v_s = s.ae_shear_wave_speed > 0.0
                         ? s.ae_shear_wave_speed
                         : analysis::shear_wave_speed(bond_moduli(s).young, 0.25, bulk_density);
  const double time =
      s.engine.dynamic_damping_time > 0.0 ? s.engine.dynamic_damping_time : 2.0 * radius / v_s;
  sim.set_dynamic_damping(s.engine.dynamic_damping_alpha, radius, time);
}

// Everything of `build` but the consolidation: the sample, its bonds and joints, the test and
// the checks of the run's size.
Built assemble(const ExperimentSpec& s, const std::function<void(const std::string&)>& log) {
  json report;
  SampleInfo info;
  GeometryData g = load_sample(s, report, info, log);
  const std::string memory =
      check_memory(s, g.particles.size(), g.bonds.size(), available_memory_bytes());
  if (log) log(memory);
  // Density scaling (docs/physics.md §1.5): masses and inertias grow, so does the stable time step.
  for (ParticleSpec& q : g.particles) q.density *= s.density_scaling;
  sort_spatially(g);
  ParticleStore ps = g.make_store(s.grain_body());
  decltype(g.particles)().swap(g.particles);  // the store holds them now
  EngineConfig cfg = s.engine;
  cfg.instruction_set = instruction_set_of(s);
  cfg.gravity = s.dimension == 2 ? Vec3{0, -s.gravity, 0} : Vec3{0, 0, -s.gravity};
  Simulation sim(std::move(ps), cfg, contact_model(s));
  visit_params<BondLaws>(s.bond, [&]<class Law>(const typename Law::Params& p) {
    sim.set_bond_params<Law>(p);
    if (!g.bonds.empty())
      for (auto [a, b] : g.bonds) sim.add_bond<Law>(a, b);
    else
      sim.bond_touching_pairs<Law>(s.bond_gap_tolerance);
  });
  decltype(g.bonds)().swap(g.bonds);  // the bond sets hold them now
  add_joints(s, sim);
  std::unique_ptr<Protocol> protocol;
  visit_lab_test(s.test, [&]<class T>(const typename T::Params& p) {
    T::check(p, info, s.source);
    protocol = T::create(sim, p, info);
  });
  sim.initialise();
  // Bar-wave speed for the ramp (§2.3, §6.1): E estimated by the bond modulus, bulk density from
  // the (scaled) particle mass in the sample's bounding box.
  // The rock's grains only: a test's apparatus grains (abrasion grit) follow them.
  const std::size_t rock = protocol->rock_particles(sim);
  double mass = 0.0;
  for (std::size_t i = 0; i < rock; ++i) mass += sim.particles().mass[i];
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const int axis = s.dimension == 2 ? 1 : 2;
  double footprint_lo[2] = {lo, lo}, footprint_hi[2] = {hi, hi};
  for (std::size_t i = 0; i < rock; ++i) {
    const PosRad& q = sim.particles().pos_rad[i];
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
  resolve_dynamic_damping(s, sim, rock, mass / volume);
  check_run_budget(s, sim, hi - lo, v_bar);
  return Built{std::move(sim), std::move(protocol), v_bar, report, 0};
}

}  // namespace

Built build(const ExperimentSpec& s, const std::function<void(const std::string&)>& log) {
  Built b = assemble(s, log);
  b.consolidation_steps = b.protocol->start(b.sim, b.bar_wave_speed);
  return b;
}

void check_buildable(const ExperimentSpec& s) {
  (void)assemble(s, {});
}

}  // namespace breccia
