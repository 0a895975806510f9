#include "breccia/sample/packing.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/sample/packing_methods.hpp"
#include "breccia/sample/sphere_grid.hpp"

namespace breccia {

const char* shape_name(SampleShape s) {
  switch (s) {
    case SampleShape::Prism:
      return "prism";
    case SampleShape::Cylinder:
      return "cylinder";
    case SampleShape::Rectangle:
      return "rectangle";
    case SampleShape::Disk:
      return "disk";
  }
  return "?";
}

const char* method_name(PackingMethod m) {
  switch (m) {
    case PackingMethod::Expansion:
      return "expansion";
    case PackingMethod::Insertion:
      return "insertion";
    case PackingMethod::Preconsolidation:
      return "preconsolidation";
  }
  return "?";
}

Region packing_region(const PackingSettings& s) {
  Region r;
  r.shape = s.shape;
  r.thickness = r.planar() ? s.thickness : 1.0;
  switch (s.shape) {
    case SampleShape::Prism:
      r.lx = s.width;
      r.ly = s.depth;
      r.lz = s.height;
      break;
    case SampleShape::Cylinder:
      r.radius = 0.5 * s.diameter;
      r.lz = s.height;
      break;
    case SampleShape::Rectangle:
      r.lx = s.width;
      r.ly = s.height;
      break;
    case SampleShape::Disk:
      r.radius = 0.5 * s.diameter;
      break;
  }
  return r;
}

namespace packing {

namespace {
constexpr std::uint64_t kPlaceStream = 0x706c616365000000ull;  // "place"
}

std::vector<double> draw_radii(const PackingSettings& s, const Region& region) {
  RadiusDistribution dist = s.radii;
  dist.planar = region.planar();
  std::vector<double> radii =
      draw_radii_for_volume(dist, s.seed, (1.0 - s.porosity) * region.volume(), region.planar(),
                            region.thickness, s.max_particles);
  std::sort(radii.begin(), radii.end(), std::greater<>());
  return radii;
}

std::vector<PosRad> place_at_random(const std::vector<double>& radii, double shrink,
                                    const Region& region, std::uint64_t seed, int strata) {
  std::vector<PosRad> placed;
  placed.reserve(radii.size());
  SphereGrid grid(region.lower(), region.upper(), 2.0 * radii.front() * shrink, region.planar());
  std::uint64_t counter = 0;
  const double band = 1.0 / std::max(1, strata);
  for (std::size_t i = 0; i < radii.size(); ++i) {
    const double r = radii[i] * shrink;
    const double lo = static_cast<double>(i % static_cast<std::size_t>(std::max(1, strata))) * band;
    bool ok = false;
    for (int attempt = 0; attempt < 20000 && !ok; ++attempt) {
      // After many misses in its stratum a particle may go anywhere (never happens at the
      // solid fractions used, but placement must not fail for it).
      const Vec3 x = attempt < 1000 ? region.draw(r, seed, kPlaceStream, counter, lo, lo + band)
                                    : region.draw(r, seed, kPlaceStream, counter);
      if (grid.overlaps(x, r, placed)) continue;
      grid.insert(static_cast<std::uint32_t>(placed.size()), x);
      placed.push_back({x, r});
      ok = true;
    }
    if (!ok)
      throw InputError("sample generation", "sample.porosity", "",
                       fmt::format("could not place particle {} of {} without overlap; the "
                                   "vessel is too small for the size distribution",
                                   i + 1, radii.size()));
  }
  return placed;
}

void sort_spatially(std::vector<PosRad>& p, const Region& region) {
  double r_max = 0.0;
  for (const PosRad& q : p) r_max = std::max(r_max, q.r);
  const double cell = 4.0 * r_max;
  const Vec3 lo = region.lower();
  const int axis = region.axis();
  auto key = [&](const PosRad& q) {
    return std::array<long, 3>{static_cast<long>(std::floor((q.x[axis] - lo[axis]) / cell)),
                               static_cast<long>(std::floor((q.x.y - lo.y) / cell)),
                               static_cast<long>(std::floor((q.x.x - lo.x) / cell))};
  };
  std::stable_sort(p.begin(), p.end(),
                   [&](const PosRad& a, const PosRad& b) { return key(a) < key(b); });
}

ContactModel frictionless(const ContactModel& m) {
  ContactModel out = m;
  std::visit(
      [](auto& c) {
        c.params.friction = 0.0;
        c.wall_params.friction = 0.0;
      },
      out);
  return out;
}

const char* contact_law_name(const ContactModel& m) {
  return std::visit([]<class CL>(const ContactSet<CL>&) { return CL::name.data(); }, m);
}

Simulation vessel_simulation(const std::vector<PosRad>& particles, const Region& region,
                             const PackingSettings& s) {
  const bool planar = region.planar();
  ParticleStore store(planar ? Dimension::Two : Dimension::Three, region.thickness, s.planar_body);
  store.reserve(particles.size());
  for (std::size_t i = 0; i < particles.size(); ++i)
    store.add(
        {.tag = i + 1, .position = particles[i].x, .radius = particles[i].r, .density = s.density});
  EngineConfig cfg;
  cfg.local_damping = 0.7;
  cfg.energy_interval = 0;
  cfg.seed = s.seed;
  cfg.instruction_set = s.instruction_set;
  double rsum = 0.0;
  for (const PosRad& q : particles) rsum += q.r;
  cfg.skin = 0.4 * rsum / static_cast<double>(particles.size());
  Simulation sim(std::move(store), cfg, frictionless(s.contact));
  const Vec3 lo = region.lower(), hi = region.upper();
  if (region.round()) {
    sim.add_wall(Wall::cylinder("vessel_side", {}, {0, 0, 1}, region.radius));
  } else {
    sim.add_wall(Wall::plane("vessel_x0", lo, {1, 0, 0}));
    sim.add_wall(Wall::plane("vessel_x1", hi, {-1, 0, 0}));
    sim.add_wall(Wall::plane("vessel_y0", lo, {0, 1, 0}));
    sim.add_wall(Wall::plane("vessel_y1", hi, {0, -1, 0}));
  }
  if (!planar) {
    sim.add_wall(Wall::plane("vessel_z0", lo, {0, 0, 1}));
    sim.add_wall(Wall::plane("vessel_z1", hi, {0, 0, -1}));
  }
  sim.initialise();
  return sim;
}

double kinetic_energy(const Simulation& sim) {
  const ParticleStore& p = sim.particles();
  double e = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    e += 0.5 * (p.mass[i] * norm2(p.vel[i]) + p.inertia[i] * norm2(p.angvel[i]));
  return e;
}

StageClock::StageClock(const Simulation* sim)
    : sim_(sim),
      step0_(sim ? sim->step_count() : 0),
      t0_(std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
              .count()) {}

PackingStage StageClock::done(std::string name, std::string note) {
  const double now =
      std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  PackingStage st{std::move(name), sim_ ? sim_->step_count() - step0_ : 0, now - t0_,
                  std::move(note)};
  step0_ = sim_ ? sim_->step_count() : 0;
  t0_ = now;
  return st;
}

}  // namespace packing

namespace {

void check_settings(const PackingSettings& s) {
  const std::string w = "sample generation";
  auto positive = [&](double v, const char* key) {
    if (!(v > 0.0) || !std::isfinite(v)) throw InputError(w, key, num(v), "must be > 0 m");
  };
  switch (s.shape) {
    case SampleShape::Prism:
      positive(s.width, "sample.width");
      positive(s.depth, "sample.depth");
      positive(s.height, "sample.height");
      break;
    case SampleShape::Cylinder:
      positive(s.diameter, "sample.diameter");
      positive(s.height, "sample.height");
      break;
    case SampleShape::Rectangle:
      positive(s.width, "sample.width");
      positive(s.height, "sample.height");
      positive(s.thickness, "sample.thickness");
      break;
    case SampleShape::Disk:
      positive(s.diameter, "sample.diameter");
      positive(s.thickness, "sample.thickness");
      break;
  }
  s.radii.validate(w);
  if (!(s.porosity > 0.0 && s.porosity < 1.0))
    throw InputError(w, "sample.porosity", num(s.porosity), "allowed: 0 < value < 1");
  if (s.method == PackingMethod::Expansion && s.servo_to_stress && !(s.isotropic_stress > 0.0))
    throw InputError(w, "sample.isotropic_stress", num(s.isotropic_stress), "must be > 0 Pa");
  if (s.method == PackingMethod::Preconsolidation && s.shape != SampleShape::Rectangle)
    throw InputError(w, "sample.packing", "\"preconsolidation\"",
                     "preconsolidation between particle rows is a 2D procedure (seed 002): use "
                     "shape = \"rectangle\" with engine.dimension = 2");
  if (s.method == PackingMethod::Preconsolidation && !(s.preconsolidation_stress > 0.0))
    throw InputError(w, "sample.preconsolidation_stress", num(s.preconsolidation_stress),
                     "must be > 0 Pa");
  const double rmax =
      s.radii.kind == RadiusDistribution::Kind::Classes
          ? *std::max_element(s.radii.class_radius.begin(), s.radii.class_radius.end())
          : s.radii.r_max;
  const double smallest = packing_region(s).smallest_extent();
  if (smallest < 4.0 * rmax)
    throw InputError(w,
                     s.radii.kind == RadiusDistribution::Kind::Classes ? "sample.class_radii"
                                                                       : "sample.radius_max",
                     num(rmax) + " m",
                     "the sample (" + num(smallest) +
                         " m across at its narrowest) must be at least 4 largest radii across; "
                         "docs/physics.md §7.1 recommends 20-30 particles across");
}

// Radius moments of the packed particles.
void radius_moments(const std::vector<PosRad>& p, PackingReport& rep) {
  double rs = 0.0, rs2 = 0.0;
  rep.radius_min = p.front().r;
  rep.radius_max = 0.0;
  for (const PosRad& q : p) {
    rs += q.r;
    rs2 += q.r * q.r;
    rep.radius_min = std::min(rep.radius_min, q.r);
    rep.radius_max = std::max(rep.radius_max, q.r);
  }
  const double n = static_cast<double>(p.size());
  rep.radius_mean = rs / n;
  rep.radius_sd = std::sqrt(std::max(0.0, rs2 / n - rep.radius_mean * rep.radius_mean));
}

// Bonds every pair with a gap within the tolerance (§7.6); index pairs, sorted.
std::vector<std::pair<std::uint32_t, std::uint32_t>> bond_pairs(const std::vector<PosRad>& p,
                                                                bool planar, double tol) {
  PairList near;
  build_neighbour_pairs(p, tol * 1.0001 + 1e-300, planar, near);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  for (std::size_t k = 0; k < near.size(); ++k) {
    const PosRad& a = p[near.first[k]];
    const PosRad& b = p[near.second[k]];
    if (norm(b.x - a.x) - a.r - b.r <= tol) out.emplace_back(near.first[k], near.second[k]);
  }
  return out;
}

// Sum of l (x) F over the contacts of the packed grains with the test's contact law, computed
// from the positions as they are written (the forces of the first step of a simulation built from
// them; nothing moves before they are computed): the stress the test starts from (§6.5).
std::array<double, 9> contact_stress_sum(const std::vector<PosRad>& p, const Region& region,
                                         const PackingSettings& s) {
  ParticleStore store(region.planar() ? Dimension::Two : Dimension::Three, region.thickness,
                      s.planar_body);
  store.reserve(p.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    store.add({.tag = i + 1, .position = p[i].x, .radius = p[i].r, .density = s.density});
  EngineConfig cfg;
  cfg.energy_interval = 0;
  cfg.instruction_set = s.instruction_set;
  Simulation sim(std::move(store), cfg, packing::frictionless(s.contact));
  sim.initialise();
  sim.step();
  return sim.pair_stress().lf;
}

}  // namespace

PackedSample pack_sample(const PackingSettings& s,
                         const std::function<void(const std::string&)>& log_fn) {
  auto log = [&](const std::string& m) {
    if (log_fn) log_fn(m);
  };
  check_settings(s);
  const auto t0 = std::chrono::steady_clock::now();
  packing::PackedState st;
  switch (s.method) {
    case PackingMethod::Expansion:
      st = packing::pack_by_expansion(s, log);
      break;
    case PackingMethod::Insertion:
      st = packing::pack_by_insertion(s, log);
      break;
    case PackingMethod::Preconsolidation:
      st = packing::pack_by_preconsolidation(s, log);
      break;
  }
  // The sample, stored in spatial order (tags follow it), with its bonds.
  packing::StageClock clock;
  packing::sort_spatially(st.particles, st.region);
  const bool planar = st.region.planar();
  PackedSample out;
  GeometryData& g = out.geometry;
  g.dimension = planar ? Dimension::Two : Dimension::Three;
  g.thickness = planar ? s.thickness : 1.0;
  for (std::size_t k = 0; k < st.particles.size(); ++k)
    g.particles.push_back({.tag = k + 1,
                           .position = st.particles[k].x,
                           .radius = st.particles[k].r,
                           .density = s.density});
  const auto bonds = bond_pairs(st.particles, planar, s.bond_gap_tolerance);
  for (auto [i, j] : bonds) g.bonds.emplace_back(i + 1, j + 1);

  PackingReport& rep = st.report;
  rep.method = method_name(s.method);
  rep.contact_law = packing::contact_law_name(s.contact);
  rep.structure =
      describe_structure(st.particles, bonds, st.region, s.bond_gap_tolerance, s.floater_contacts);
  radius_moments(st.particles, rep);
  rep.volume = st.region.volume();
  rep.width = st.region.round() ? 2 * st.region.radius : st.region.lx;
  rep.depth = planar ? 0.0 : (st.region.round() ? 2 * st.region.radius : st.region.ly);
  rep.height = st.region.height();
  const int dim = st.region.dimension();
  const std::array<double, 9> lf = contact_stress_sum(st.particles, st.region, s);
  rep.locked_in_xx = lf[0] / rep.volume;
  rep.locked_in_yy = lf[4] / rep.volume;
  rep.locked_in_zz = lf[8] / rep.volume;
  rep.locked_in_mean_stress =
      (rep.locked_in_xx + rep.locked_in_yy + (dim == 3 ? rep.locked_in_zz : 0.0)) / dim;
  rep.stages.push_back(clock.done("bond and report"));
  rep.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const SampleStructure& ss = rep.structure;
  log(fmt::format(
      "packing ({}): {} particles, {} steps, porosity {:.4f}, locked-in mean stress {:.4g} MPa "
      "({}), contact coordination {:.2f}, {} bonds ({:.2f} per interior grain), {} floaters "
      "({:.2f} %), homogeneity {} (eighths along {}), {:.1f} s",
      rep.method, ss.particles, rep.steps, ss.porosity, rep.locked_in_mean_stress * 1e-6,
      rep.contact_law, ss.contact_coordination, ss.bonds, ss.bonds_per_interior_particle,
      ss.floaters, 100.0 * static_cast<double>(ss.floaters) / static_cast<double>(ss.particles),
      ss.homogeneity.passes() ? "passes" : "FAILS", "xyz"[ss.profile_axis], rep.wall_seconds));
  for (const std::string& w : rep.warnings) log("warning: " + w);
  out.report = std::move(rep);
  return out;
}

}  // namespace breccia
