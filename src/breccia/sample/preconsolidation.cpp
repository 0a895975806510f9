// 2D preconsolidation between particle rows (docs/physics.md §7.3; RICEBAL practice as in seed 002,
// where the rows are pushed in until the sample carries 10 MPa). The disks, drawn for the target
// porosity of the width x height box, are placed shrunk between four rows of fixed disks and
// grown to size, frictionless, as in the expansion method; then the side rows are pushed in by a
// servo (docs/physics.md §6.2), or the sample and its side rows are compacted together by a
// homogeneous strain across the width (sample.compaction), until the side rows carry the
// preconsolidation stress, the end rows held.
// The rows are rough walls: the grains against them stay as disordered as the bulk. The sample is
// bonded in this compacted state; when the test starts it unloads to its test stress and the
// bonds take up the difference, the locked-in stress of a cemented rock (§7.3 step 7). Floaters
// are then placed snug in their cages as in the expansion method.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "breccia/core/error.hpp"
#include "breccia/sample/packing_methods.hpp"

namespace breccia::packing {

namespace {

constexpr std::uint64_t kCheck = 20;
constexpr double kLooseFraction = 0.45;  // solid fraction of the placement (2D RSA jams at 0.55)
constexpr double kGrowthRate = 4e-3;     // radius growth per check while growing
constexpr std::uint64_t kSettleSteps = 1500;
constexpr double kServoRelaxation = 0.2;   // alpha_s of §6.2 for the pushed side rows
constexpr double kStressTolerance = 0.02;  // as the expansion servo: within 2 % for 10 checks
constexpr int kChecksHeld = 10;
constexpr double kIntegralShare = 0.1;  // of the rows' proportional speed, added per check
constexpr double kServoCap = 5e-5;      // largest strain per check of the compaction

// The four rows of disks around the sample: indices into the simulation's particles.
struct Rows {
  std::vector<std::size_t> left, right, bottom, top;
  double radius = 0.0;
};

void add_row(std::vector<PosRad>& all, std::vector<std::size_t>& row, Vec3 from, Vec3 to,
             double r) {
  const double length = norm(to - from);
  const int n = std::max(2, static_cast<int>(std::ceil(length / (2.0 * r))) + 1);
  for (int k = 0; k < n; ++k) {
    row.push_back(all.size());
    all.push_back({from + (to - from) * (static_cast<double>(k) / (n - 1)), r});
  }
}

// Force the sample's disks exert on a row, along the row's inward normal (compression-positive);
// contacts between rows (the side rows slide along the end rows) do not count.
double row_load(const Simulation& sim, const std::vector<std::size_t>& row, std::size_t n_sample,
                const Vec3& inward) {
  if (row.empty()) return 0.0;
  const std::size_t lo = row.front(), hi = row.back();  // a row's disks are consecutive
  double f = 0.0;
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const std::size_t i = c.pairs.first[k], j = c.pairs.second[k];
          // A pair keeps the force on its second particle; sample disks come first.
          if (i < n_sample && j >= lo && j <= hi) f -= dot(sim.pair_force(c, k), inward);
        }
      },
      sim.contact_model());
  return f;
}

// Sum of l_x F_x over the contacts between sample disks (rows excluded), N m (§6.5).
double internal_sxx(const Simulation& sim, std::size_t n_sample) {
  double lf = 0.0;
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        const auto& p = sim.particles().pos_rad;
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const std::uint32_t i = c.pairs.first[k], j = c.pairs.second[k];
          if (i < n_sample && j < n_sample) lf += (p[j].x.x - p[i].x.x) * sim.pair_force(c, k).x;
        }
      },
      sim.contact_model());
  return lf;
}

// The four rows around the sample, appended to `all` (the sample's disks stay first). Rows of
// the smallest grains: a grain of radius r nests in the cusp between two touching row disks of
// radius R_w to R_w + r - sqrt(r^2 + 2 R_w r) below the row's face, 0.27 r_min when
// R_w = r = r_min.
Rows surround_with_rows(std::vector<PosRad>& all, const PackingSettings& s, const Region& box) {
  Rows rows;
  rows.radius = s.radii.kind == RadiusDistribution::Kind::Classes
                    ? *std::min_element(s.radii.class_radius.begin(), s.radii.class_radius.end())
                    : s.radii.r_min;
  const double rw = rows.radius, h = box.ly, w = box.lx;
  add_row(all, rows.bottom, {-3 * rw, -rw, 0}, {w + 3 * rw, -rw, 0}, rw);
  add_row(all, rows.top, {-3 * rw, h + rw, 0}, {w + 3 * rw, h + rw, 0}, rw);
  // The side rows reach into the end rows, so the corners are closed.
  add_row(all, rows.left, {-rw, -rw, 0}, {-rw, h + rw, 0}, rw);
  add_row(all, rows.right, {w + rw, -rw, 0}, {w + rw, h + rw, 0}, rw);
  return rows;
}

// Normal tangent stiffness of one contact of a row disk when it carries `force`: the servo's
// gain (§6.2). A linear law has one stiffness; a Hertz contact stiffens with its load, and its
// stiffness at first touch (near zero) would make the gain, and the rows, race.
double row_contact_stiffness(const Simulation& sim, double rw, double thickness, double force) {
  double kn = 0.0;
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        PairGeometry g =
            pair_geometry({}, rw, {2 * rw, 0, 0}, rw, {}, {}, {}, {}, 1, 1, true, thickness);
        auto normal_force = [&](double delta) {
          g.delta = delta;
          typename CL::State st{};
          PairDissipation dis;
          return dot(CL::compute(c.params, st, g, 0.0, dis).force, g.n);
        };
        // Bisection on the overlap (the force grows with it), to 1e-6 of the radius at most.
        double lo = 0.0, hi = 0.5 * rw;
        for (int k = 0; k < 60 && normal_force(hi) < force; ++k) lo = hi, hi *= 2.0;
        for (int k = 0; k < 60; ++k) {
          const double mid = 0.5 * (lo + hi);
          (normal_force(mid) < force ? lo : hi) = mid;
        }
        g.delta = std::max(hi, 1e-4 * rw);
        double ks = 0.0;
        CL::timestep_stiffness(c.params, g, kn, ks);
      },
      sim.contact_model());
  return kn;
}

// The sample's first n disks grow by `factor` between the fixed rows, then settle.
void grow_between_rows(Simulation& sim, std::size_t n, double factor, std::uint64_t max_steps) {
  for (double applied = 1.0; applied < factor * (1 - 1e-12) && sim.step_count() < max_steps;) {
    const double f = std::min(1.0 + kGrowthRate, factor / applied);
    for (std::size_t i = 0; i < n; ++i) sim.set_radius(i, sim.particles().pos_rad[i].r * f);
    applied *= f;
    sim.run(kCheck);
  }
  sim.refresh_time_step();
  sim.run(std::min(kSettleSteps, max_steps - std::min(max_steps, sim.step_count())));
}

struct RowServo {
  double sxx = 0.0;  // Pa, on the side rows
  bool held = false;
};

// Drives the side rows (the end rows held) until they carry `target` and the sample's own
// contacts balance them. The rows move at most 1 % of the width per 1000 steps.
RowServo servo_side_rows(Simulation& sim, const Rows& rows, std::size_t n, double target,
                         double thickness, std::uint64_t max_steps) {
  ParticleStore& P = sim.particles_mut();
  const double rw = rows.radius;
  const double area =
      (P.pos_rad[rows.left.back()].x.y - P.pos_rad[rows.left.front()].x.y - 2.0 * rw) * thickness;
  // Half the row's disks taken as its contacts (docs/physics.md §6.2 needs their number).
  const double contacts = static_cast<double>(std::max<std::size_t>(1, rows.left.size() / 2));
  const double kn = row_contact_stiffness(sim, rw, thickness, target * area / contacts);
  auto width = [&] {
    return P.pos_rad[rows.right.front()].x.x - P.pos_rad[rows.left.front()].x.x - 2.0 * rw;
  };
  const double v_max = 0.01 * width() / (1000.0 * sim.time_step());
  RowServo out;
  int held = 0;
  std::array<double, 2> integral{};  // m/s, left and right rows
  while (sim.step_count() < max_steps) {
    sim.run(kCheck);
    const double f_left = row_load(sim, rows.left, n, {1, 0, 0});
    const double f_right = row_load(sim, rows.right, n, {-1, 0, 0});
    out.sxx = 0.5 * (f_left + f_right) / area;
    // At the target on the rows, and the sample's own contacts in equilibrium with them (their
    // mean sigma_xx within 5 %): the rows alone pass through the band while the sample moves.
    const double inner = internal_sxx(sim, n) / (width() * area);
    held = std::abs(out.sxx - target) <= kStressTolerance * target &&
                   std::abs(inner - out.sxx) <= 0.05 * out.sxx
               ? held + 1
               : 0;
    if (held >= kChecksHeld) break;
    // Half the row's disks taken as its contacts (docs/physics.md §6.2 needs their number).
    // Proportional-integral: a packing that creeps under load (frictionless grains rearranging)
    // leaves a proportional servo short of its target for good (Hertz grains: 9.25 of 10 MPa
    // after 400,000 steps); each check adds kIntegralShare of the correction to the integral.
    auto drive = [&](const std::vector<std::size_t>& row, double force, double sign,
                     double& i_term) {
      // The speed holds for the kCheck steps to the next check: the gain corrects alpha_s of
      // the error over them.
      const double gain = kServoRelaxation * area /
                          (kn * static_cast<double>(std::max<std::size_t>(1, row.size() / 2)) *
                           static_cast<double>(kCheck) * sim.time_step());
      const double p = std::clamp(gain * (target - force / area), -v_max, v_max);
      i_term = std::clamp(i_term + kIntegralShare * p, -v_max, v_max);
      const double v = std::clamp(p + i_term, -v_max, v_max);
      for (std::size_t i : row) P.drive_vel[i] = Vec3{sign * v, 0, 0};
    };
    drive(rows.left, f_left, 1.0, integral[0]);
    drive(rows.right, f_right, -1.0, integral[1]);
  }
  for (const auto* row : {&rows.left, &rows.right})
    for (std::size_t i : *row) P.drive_vel[i] = {};
  out.held = held >= kChecksHeld;
  return out;
}

// Compacts the sample and its side rows together by a homogeneous strain along x about the
// sample's centre, the end rows held, until the side rows carry `target` and the sample's own
// contacts balance them. Every grain moves at once, so no check waits for a stress wave to cross
// the sample from the rows, as it did when the rows pushed alone (151,100 steps for 59,817
// disks, growing with the width; docs/physics.md §7.3). The strain increment of a check is
// g (target - sigma_xx) / S, sigma_xx the sample's own mean stress and S the affine stiffness of
// the contacts (PairStress::axial_stiffness), capped at kServoCap; the gain g adapts as the
// expansion servo's does (AdaptiveServo).
RowServo compact_affinely(Simulation& sim, const Rows& rows, std::size_t n, double target,
                          double thickness, std::uint64_t max_steps) {
  const ParticleStore& P = sim.particles();
  const double rw = rows.radius;
  const double area =
      (P.pos_rad[rows.left.back()].x.y - P.pos_rad[rows.left.front()].x.y - 2.0 * rw) * thickness;
  auto width = [&] {
    return P.pos_rad[rows.right.front()].x.x - P.pos_rad[rows.left.front()].x.x - 2.0 * rw;
  };
  // The grains that move: the sample's and the side rows'.
  std::vector<std::size_t> moving(n);
  std::iota(moving.begin(), moving.end(), std::size_t{0});
  moving.insert(moving.end(), rows.left.begin(), rows.left.end());
  moving.insert(moving.end(), rows.right.begin(), rows.right.end());
  RowServo out;
  int held = 0;
  AdaptiveServo servo(kServoCap);
  while (sim.step_count() < max_steps) {
    sim.run(kCheck);
    const double f_left = row_load(sim, rows.left, n, {1, 0, 0});
    const double f_right = row_load(sim, rows.right, n, {-1, 0, 0});
    out.sxx = 0.5 * (f_left + f_right) / area;
    const double volume = width() * area;
    const double inner = internal_sxx(sim, n) / volume;
    // At the target on the rows, and the sample's own contacts in equilibrium with them (their
    // mean sigma_xx within 5 %).
    held = std::abs(out.sxx - target) <= kStressTolerance * target &&
                   std::abs(inner - out.sxx) <= 0.05 * out.sxx
               ? held + 1
               : 0;
    if (held >= kChecksHeld) break;
    const double stiffness = sim.pair_stress().axial_stiffness[0] / volume;
    const double strain = servo.increment(target - inner, stiffness);
    const double centre =
        0.5 * (P.pos_rad[rows.left.front()].x.x + P.pos_rad[rows.right.front()].x.x);
    for (std::size_t i : moving)
      sim.displace_particle(i, {-strain * (P.pos_rad[i].x.x - centre), 0, 0});
  }
  out.held = held >= kChecksHeld;
  return out;
}

}  // namespace

PackedState pack_by_preconsolidation(const PackingSettings& s, const Log& log) {
  PackedState st;
  const Region target = packing_region(s);
  const std::vector<double> radii = draw_radii(s, target);
  const double shrink = std::min(1.0, std::sqrt(kLooseFraction / (1.0 - s.porosity)));
  std::vector<PosRad> all = place_at_random(radii, shrink, target, s.seed, 16);
  sort_spatially(all, target);
  const std::size_t n = all.size();
  const Rows rows = surround_with_rows(all, s, target);
  const double rw = rows.radius;
  log(fmt::format(
      "packing: {} disks placed at {:.0f} % of their radii in a {:.4g} x {:.4g} m box "
      "between rows of {} disks; compacting to {:.4g} MPa",
      n, 100 * shrink, target.lx, target.ly, all.size() - n, s.preconsolidation_stress * 1e-6));
  // The rows are the walls: the vessel's planes stay clear of everything.
  Region box = target;
  box.lx = target.lx + 8 * rw;
  box.ly = target.ly + 4 * rw;
  for (PosRad& q : all) q.x += Vec3{4 * rw, 2 * rw, 0};
  Simulation sim = vessel_simulation(all, box, s);
  ParticleStore& P = sim.particles_mut();
  for (std::size_t i = n; i < all.size(); ++i) P.set_motion(i, Motion::Driven);
  StageClock clock(&sim);
  grow_between_rows(sim, n, 1.0 / shrink, s.max_steps);
  st.report.stages.push_back(clock.done("growth", fmt::format("radii x {:.4f}", 1.0 / shrink)));
  const RowServo servo =
      s.homogeneous_compaction
          ? compact_affinely(sim, rows, n, s.preconsolidation_stress, box.thickness, s.max_steps)
          : servo_side_rows(sim, rows, n, s.preconsolidation_stress, box.thickness, s.max_steps);
  const double x_left = P.pos_rad[rows.left.front()].x.x + rw;
  const double x_right = P.pos_rad[rows.right.front()].x.x - rw;
  const double f_ends =
      row_load(sim, rows.bottom, n, {0, 1, 0}) + row_load(sim, rows.top, n, {0, -1, 0});
  const double syy = 0.5 * f_ends / ((x_right - x_left) * box.thickness);
  st.report.converged = servo.held;
  st.report.preconsolidation_stress_reached = servo.sxx;
  st.report.stages.push_back(clock.done(
      "preconsolidation", fmt::format("sigma_xx = {:.4g} MPa (rows), sigma_yy = {:.4g} MPa "
                                      "(ends), width {:.4g} m",
                                      servo.sxx * 1e-6, syy * 1e-6, x_right - x_left)));
  if (!servo.held)
    st.report.warnings.push_back(fmt::format(
        "preconsolidation did not hold {} MPa (sample.preconsolidation_stress) within the "
        "packing's limit of {} steps; reached {:.4g} MPa",
        s.preconsolidation_stress * 1e-6, s.max_steps, servo.sxx * 1e-6));
  // Floaters may grow 20 % beyond the size they have now (rows are neighbours, not candidates).
  std::vector<double> nominal;
  for (const PosRad& q : P.pos_rad) nominal.push_back(q.r);
  const FloaterFix fix = fit_floaters(sim, box, s.bond_gap_tolerance, s.floater_contacts,
                                      s.floater_max_growth, nominal, n);
  st.report.floaters_grown = fix.fitted;
  st.report.largest_floater_growth = fix.largest_growth;
  st.report.stages.push_back(clock.done(
      "floaters", fmt::format("{} found, {} placed snug in their cages", fix.found, fix.fitted)));
  // The compacted sample in its own frame: x from the left row's face, y from the bottom row's.
  st.region = target;
  st.region.lx = x_right - x_left;
  const Vec3 origin{x_left, 2 * rw, 0};
  for (std::size_t i = 0; i < n; ++i)
    st.particles.push_back({P.pos_rad[i].x - origin, P.pos_rad[i].r});
  st.report.steps = sim.step_count();
  return st;
}

}  // namespace breccia::packing
