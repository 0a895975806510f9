#include "breccia/sample/packing.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>
#include <tuple>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

const char* shape_name(SampleShape s) {
  switch (s) {
    case SampleShape::Prism:
      return "prism";
    case SampleShape::Cylinder:
      return "cylinder";
    case SampleShape::Rectangle:
      return "rectangle";
  }
  return "?";
}

namespace {

constexpr std::uint64_t kPlaceStream = 0x706c616365000000ull;  // "place"

struct Region {
  SampleShape shape;
  double lx, ly, lz, radius;  // prism/rectangle extents; cylinder radius and height (lz)
  bool planar() const { return shape == SampleShape::Rectangle; }
  double volume(double thickness) const {
    switch (shape) {
      case SampleShape::Prism:
        return lx * ly * lz;
      case SampleShape::Cylinder:
        return std::numbers::pi * radius * radius * lz;
      case SampleShape::Rectangle:
        return lx * ly * thickness;
    }
    return 0.0;
  }
  // Random centre for a particle of radius r fully inside the region.
  Vec3 draw(double r, std::uint64_t seed, std::uint64_t& counter) const {
    auto u = [&] { return uniform01(seed, kPlaceStream, counter++); };
    switch (shape) {
      case SampleShape::Prism:
        return {r + u() * (lx - 2 * r), r + u() * (ly - 2 * r), r + u() * (lz - 2 * r)};
      case SampleShape::Cylinder: {
        const double rho = (radius - r) * std::sqrt(u());
        const double phi = 2.0 * std::numbers::pi * u();
        return {rho * std::cos(phi), rho * std::sin(phi), r + u() * (lz - 2 * r)};
      }
      case SampleShape::Rectangle:
        return {r + u() * (lx - 2 * r), r + u() * (ly - 2 * r), 0.0};
    }
    return {};
  }
  // Distance from a point to the nearest vessel wall.
  double wall_distance(const Vec3& x) const {
    switch (shape) {
      case SampleShape::Prism:
        return std::min({x.x, lx - x.x, x.y, ly - x.y, x.z, lz - x.z});
      case SampleShape::Cylinder:
        return std::min({radius - std::hypot(x.x, x.y), x.z, lz - x.z});
      case SampleShape::Rectangle:
        return std::min({x.x, lx - x.x, x.y, ly - x.y});
    }
    return 0.0;
  }
  Vec3 lower() const { return shape == SampleShape::Cylinder ? Vec3{-radius, -radius, 0} : Vec3{}; }
  Vec3 upper() const {
    if (shape == SampleShape::Cylinder) return {radius, radius, lz};
    return {lx, ly, planar() ? 0.0 : lz};
  }
};

// Uniform grid of particle indices for overlap tests during random placement.
class PlacementGrid {
 public:
  PlacementGrid(Vec3 lo, Vec3 hi, double cell, bool planar) : lo_(lo), cell_(cell) {
    for (int k = 0; k < 3; ++k)
      n_[k] = (planar && k == 2) ? 1 : std::max(1, static_cast<int>((hi[k] - lo[k]) / cell) + 1);
    head_.assign(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2], -1);
  }
  bool overlaps(const Vec3& x, double r, const std::vector<PosRad>& placed) const {
    int c[3];
    cell_of(x, c);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int a = c[0] + dx, b = c[1] + dy, d = c[2] + dz;
          if (a < 0 || b < 0 || d < 0 || a >= n_[0] || b >= n_[1] || d >= n_[2]) continue;
          for (int i = head_[index(a, b, d)]; i >= 0; i = next_[static_cast<std::size_t>(i)]) {
            const PosRad& q = placed[static_cast<std::size_t>(i)];
            const double reach = q.r + r;
            if (norm2(q.x - x) < reach * reach) return true;
          }
        }
    return false;
  }
  void insert(const Vec3& x, int id) {
    int c[3];
    cell_of(x, c);
    const std::size_t k = index(c[0], c[1], c[2]);
    if (next_.size() <= static_cast<std::size_t>(id))
      next_.resize(static_cast<std::size_t>(id) + 1);
    next_[static_cast<std::size_t>(id)] = head_[k];
    head_[k] = id;
  }

 private:
  void cell_of(const Vec3& x, int c[3]) const {
    for (int k = 0; k < 3; ++k)
      c[k] = std::clamp(static_cast<int>((x[k] - lo_[k]) / cell_), 0, n_[k] - 1);
  }
  std::size_t index(int a, int b, int d) const {
    return (static_cast<std::size_t>(d) * n_[1] + b) * n_[0] + a;
  }
  Vec3 lo_;
  double cell_;
  int n_[3];
  std::vector<int> head_, next_;
};

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
  }
  s.radii.validate(w);
  if (!(s.porosity > 0.0 && s.porosity < 1.0))
    throw InputError(w, "sample.porosity", num(s.porosity), "allowed: 0 < value < 1");
  if (s.servo_to_stress && !(s.isotropic_stress > 0.0))
    throw InputError(w, "sample.isotropic_stress", num(s.isotropic_stress), "must be > 0 Pa");
  const double rmax =
      s.radii.kind == RadiusDistribution::Kind::Classes
          ? *std::max_element(s.radii.class_radius.begin(), s.radii.class_radius.end())
          : s.radii.r_max;
  const double smallest =
      s.shape == SampleShape::Cylinder
          ? std::min(s.diameter, s.height)
          : (s.shape == SampleShape::Prism ? std::min({s.width, s.depth, s.height})
                                           : std::min(s.width, s.height));
  if (smallest < 4.0 * rmax)
    throw InputError(w, "sample size", num(smallest) + " m across",
                     "must be at least 4 maximum radii (" + num(4 * rmax) +
                         " m); physics.md §7.1 recommends 20-30 particles across");
}

// Lens volume (3D) or area times thickness (2D) shared by two overlapping particles (§7.7).
double lens(double r1, double r2, double d, bool planar, double t) {
  if (d >= r1 + r2 || d <= 0.0) return 0.0;
  if (!planar) {
    const double h = r1 + r2 - d;
    return std::numbers::pi * h * h * (d * d + 2 * d * (r1 + r2) - 3 * (r1 - r2) * (r1 - r2)) /
           (12.0 * d);
  }
  const double a =
      r1 * r1 * std::acos(std::clamp((d * d + r1 * r1 - r2 * r2) / (2 * d * r1), -1.0, 1.0)) +
      r2 * r2 * std::acos(std::clamp((d * d + r2 * r2 - r1 * r1) / (2 * d * r2), -1.0, 1.0)) -
      0.5 *
          std::sqrt(std::max(0.0, (-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2)));
  return a * t;
}

}  // namespace

PackedSample pack_sample(const PackingSettings& s,
                         const std::function<void(const std::string&)>& log_fn) {
  auto log = [&](const std::string& m) {
    if (log_fn) log_fn(m);
  };
  check_settings(s);
  const auto t0 = std::chrono::steady_clock::now();
  const bool planar = s.shape == SampleShape::Rectangle;
  const int dim = planar ? 2 : 3;
  const Region region{s.shape, s.width, planar ? s.height : s.depth, planar ? 0.0 : s.height,
                      0.5 * s.diameter};
  const double volume = region.volume(s.thickness);

  // 1. Radii for the target porosity (§7.1), largest first: big grains are placed while there is
  // still room.
  RadiusDistribution dist = s.radii;
  dist.planar = planar;
  std::vector<double> radii = draw_radii_for_volume(dist, s.seed, (1.0 - s.porosity) * volume,
                                                    planar, s.thickness, s.max_particles);
  std::sort(radii.begin(), radii.end(), std::greater<>());
  const std::size_t n = radii.size();

  // 2. Random placement without overlap at a reduced size (§7.2 step 2): random sequential
  // insertion jams near a solid fraction of 0.38 (3D) or 0.55 (2D), so start well below.
  const double start_fraction = planar ? 0.45 : 0.30;
  const double shrink = std::min(1.0, std::pow(start_fraction / (1.0 - s.porosity), 1.0 / dim));
  std::vector<PosRad> placed;
  placed.reserve(n);
  PlacementGrid grid(region.lower(), region.upper(), 2.0 * radii.front() * shrink, planar);
  std::uint64_t counter = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = radii[i] * shrink;
    bool ok = false;
    for (int attempt = 0; attempt < 20000 && !ok; ++attempt) {
      const Vec3 x = region.draw(r, s.seed, counter);
      if (grid.overlaps(x, r, placed)) continue;
      grid.insert(x, static_cast<int>(placed.size()));
      placed.push_back({x, r});
      ok = true;
    }
    if (!ok)
      throw InputError("sample generation", "sample.porosity", num(s.porosity),
                       fmt::format("could not place particle {} of {} without overlap; the "
                                   "vessel is too small for the size distribution",
                                   i + 1, n));
  }
  log(fmt::format("packing: {} particles placed at {:.0f} % of their radii in a {} of {:.4g} m^3",
                  n, 100 * shrink, shape_name(s.shape), volume));

  // 3. Cycling in a rigid frictionless vessel with strong local damping.
  ParticleStore store(planar ? Dimension::Two : Dimension::Three, s.thickness);
  LinearContact::Params cp;
  cp.modulus = s.contact_modulus;
  cp.stiffness_ratio = s.contact_stiffness_ratio;
  cp.friction = 0.0;
  EngineConfig cfg;
  cfg.local_damping = 0.7;
  cfg.energy_interval = 0;
  cfg.seed = s.seed;
  double rsum = 0.0;
  for (double r : radii) rsum += r;
  const double r_mean = rsum / static_cast<double>(n);
  cfg.skin = 0.4 * r_mean;
  // Particles are placed shrunk in the vessel of the requested size, then grown to full size.
  for (std::size_t i = 0; i < n; ++i)
    store.add({.tag = i + 1, .position = placed[i].x, .radius = placed[i].r, .density = s.density});
  Simulation sim(std::move(store), cfg, make_contact_model<LinearContact>(cp, cp));
  // The vessel stays where it is: the servo acts on the radii (§7.2), not on the walls.
  const Vec3 lo = region.lower(), hi = region.upper();
  if (s.shape == SampleShape::Cylinder) {
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

  // 4. Grow the radii to size, 0.1 % per 20 steps, then relax until the mean stress is steady
  // (the 200-step mean changes by less than 0.5 % from one window to the next).
  PackingReport rep;
  const std::uint64_t check_every = 20;
  auto mean_stress = [&] { return sim.pair_stress().mean(dim, volume); };
  double applied = 1.0;
  while (applied < 1.0 / shrink && sim.step_count() < s.max_steps) {
    const double f = std::min(1.001, 1.0 / shrink / applied);
    sim.scale_radii(f);
    applied *= f;
    sim.run(check_every);
  }
  auto relax = [&](std::uint64_t max_steps) {
    double prev = -1.0;
    const std::uint64_t stop = std::min(s.max_steps, sim.step_count() + max_steps);
    while (sim.step_count() < stop) {
      double sum = 0.0;
      for (int k = 0; k < 10; ++k) {
        sim.run(check_every);
        sum += mean_stress();
      }
      const double avg = 0.1 * sum;
      if (prev >= 0.0 && std::abs(avg - prev) <= 0.005 * std::abs(prev))
        return std::pair{avg, true};
      prev = avg;
    }
    return std::pair{prev, false};
  };
  auto [p, steady] = relax(s.max_steps);
  rep.converged = steady;

  // 5. Stress mode: bring the relaxed mean stress to p0 by scaling all radii (physics.md §7.2
  // step 4), one relaxed step at a time. The first step uses the affine stiffness S, which
  // overstates the response of a packing that rearranges, so it approaches p0 from above without
  // unjamming; later steps use the secant stiffness measured between relaxed states.
  // Friction is switched on for this stage: a frictionless packing near p0 creeps for a very
  // long time (its relaxation time diverges near jamming), a frictional one settles.
  if (s.servo_to_stress && steady && p < 0.05 * s.isotropic_stress) {
    // Grown to a porosity looser than jamming (disks jam near 0.16-0.20, so the 3D-minded
    // default of 0.37 is loose in 2D), the packing carries no stress once relaxed, and the servo
    // below has no stiffness to work with: grow on, frictionless, 1 % at a time as in step 4,
    // until the relaxed packing carries some.
    while (p < 0.05 * s.isotropic_stress && sim.step_count() < s.max_steps) {
      for (int k = 0; k < 10; ++k) {
        sim.scale_radii(1.001);
        sim.run(check_every);
      }
      p = relax(2000).first;
    }
    std::tie(p, steady) = relax(s.max_steps - std::min(s.max_steps, sim.step_count()));
  }
  if (s.servo_to_stress && steady) {
    sim.set_contact_friction(s.servo_friction);
    rep.converged = false;
    double p_last = p, eps_last = 0.0;
    for (int it = 0; it < 40 && sim.step_count() < s.max_steps; ++it) {
      if (std::abs(p - s.isotropic_stress) < 0.01 * s.isotropic_stress) {
        rep.converged = true;
        break;
      }
      double slope = sim.pair_stress().radius_stiffness / (dim * volume);
      if (eps_last != 0.0 && (p - p_last) / eps_last > 0.0) slope = (p - p_last) / eps_last;
      const double eps = std::clamp(0.8 * (s.isotropic_stress - p) / slope, -2e-3, 2e-3);
      sim.scale_radii(1.0 + eps);
      p_last = p;
      eps_last = eps;
      p = relax(5000).first;
    }
  }
  if (!rep.converged)
    log(
        fmt::format("warning: packing did not settle within {} steps (sample.max_steps); the "
                    "locked-in stress below is what it reached",
                    s.max_steps));

  // 6. Report (§7.2, §7.7) and the bonded sample (§7.6), stored in spatial order.
  const ParticleStore& P = sim.particles();
  const PairStress ps = sim.pair_stress();
  rep.particles = n;
  rep.volume = volume;
  rep.width = s.shape == SampleShape::Cylinder ? s.diameter : s.width;
  rep.depth = planar ? 0.0 : (s.shape == SampleShape::Cylinder ? s.diameter : s.depth);
  rep.height = s.height;
  rep.steps = sim.step_count();
  rep.locked_in_mean_stress = ps.mean(dim, volume);
  rep.locked_in_xx = ps.lf[0] / volume;
  rep.locked_in_yy = ps.lf[4] / volume;
  rep.locked_in_zz = ps.lf[8] / volume;
  rep.mean_coordination = 2.0 * static_cast<double>(ps.touching) / static_cast<double>(n);
  for (std::uint32_t c : ps.coordination) rep.floaters += c < 3 ? 1 : 0;
  double solid = 0.0, rs = 0.0, rs2 = 0.0;
  rep.radius_min = P.pos_rad[0].r;
  for (const PosRad& q : P.pos_rad) {
    solid += planar ? std::numbers::pi * q.r * q.r * s.thickness
                    : 4.0 / 3.0 * std::numbers::pi * q.r * q.r * q.r;
    rs += q.r;
    rs2 += q.r * q.r;
    rep.radius_min = std::min(rep.radius_min, q.r);
    rep.radius_max = std::max(rep.radius_max, q.r);
  }
  rep.radius_mean = rs / static_cast<double>(n);
  rep.radius_sd =
      std::sqrt(std::max(0.0, rs2 / static_cast<double>(n) - rep.radius_mean * rep.radius_mean));

  // Spatial order: cells of two maximum diameters, z then y then x.
  const double cell = 4.0 * rep.radius_max;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  auto key = [&](std::size_t i) {
    const Vec3& x = P.pos_rad[i].x;
    return std::array<long, 4>{static_cast<long>(std::floor((x.z - lo.z) / cell)),
                               static_cast<long>(std::floor((x.y - lo.y) / cell)),
                               static_cast<long>(std::floor((x.x - lo.x) / cell)),
                               static_cast<long>(i)};
  };
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
  PackedSample out;
  GeometryData& g = out.geometry;
  g.dimension = planar ? Dimension::Two : Dimension::Three;
  g.thickness = planar ? s.thickness : 1.0;
  std::vector<std::uint64_t> tag_of(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = order[k];
    tag_of[i] = k + 1;
    g.particles.push_back(
        {.tag = k + 1, .position = P.pos_rad[i].x, .radius = P.pos_rad[i].r, .density = s.density});
  }
  PairList near;
  build_neighbour_pairs(P.pos_rad, s.bond_gap_tolerance * 1.0001 + 1e-300, planar, near);
  std::vector<std::uint32_t> bonds_of(n, 0);
  double overlap = 0.0;
  for (std::size_t k = 0; k < near.size(); ++k) {
    const std::uint32_t i = near.first[k], j = near.second[k];
    const PosRad& a = P.pos_rad[i];
    const PosRad& b = P.pos_rad[j];
    const double d = norm(b.x - a.x);
    overlap += lens(a.r, b.r, d, planar, s.thickness);
    if (d - a.r - b.r <= s.bond_gap_tolerance) {
      g.bonds.emplace_back(std::min(tag_of[i], tag_of[j]), std::max(tag_of[i], tag_of[j]));
      ++bonds_of[i];
      ++bonds_of[j];
    }
  }
  std::sort(g.bonds.begin(), g.bonds.end());
  rep.bonds = g.bonds.size();
  rep.porosity = 1.0 - (solid - overlap) / volume;
  double interior_bonds = 0.0;
  std::size_t interior = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (region.wall_distance(P.pos_rad[i].x) > 2.0 * rep.radius_max) {
      interior_bonds += bonds_of[i];
      ++interior;
    }
  rep.bond_coordination_interior =
      interior ? interior_bonds / static_cast<double>(interior)
               : 2.0 * static_cast<double>(rep.bonds) / static_cast<double>(n);
  rep.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  log(
      fmt::format("packing: {} steps, porosity {:.4f}, locked-in mean stress {:.4g} MPa, "
                  "coordination {:.2f}, {} bonds ({:.2f} per interior particle), {} floaters, "
                  "{:.1f} s",
                  rep.steps, rep.porosity, rep.locked_in_mean_stress * 1e-6, rep.mean_coordination,
                  rep.bonds, rep.bond_coordination_interior, rep.floaters, rep.wall_seconds));
  out.report = rep;
  return out;
}

}  // namespace breccia
