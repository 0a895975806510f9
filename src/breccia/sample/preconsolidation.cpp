// 2D preconsolidation between particle rows (physics.md §7.3; RICEBAL practice as in seed 002,
// where the rows are pushed in until the sample carries 10 MPa). The disks, drawn for the target
// porosity of the width x height box, are placed shrunk between four rows of fixed disks and
// grown to size, frictionless, as in the expansion method; then the two side rows are driven by
// a servo (physics.md §6.2) until they carry the preconsolidation stress, the end rows held. The
// rows are rough walls: the grains against them stay as disordered as the bulk. The sample is
// bonded in this compacted state; when the test starts it unloads to its test stress and the
// bonds take up the difference, the locked-in stress of a cemented rock (§7.3 step 7). Floaters
// are then placed snug in their cages as in the expansion method.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "breccia/core/error.hpp"
#include "breccia/sample/packing_methods.hpp"

namespace breccia::packing {

namespace {

constexpr std::uint64_t kCheck = 20;
constexpr double kLooseFraction = 0.45;  // solid fraction of the placement (2D RSA jams at 0.55)
constexpr double kGrowthRate = 4e-3;     // radius growth per check while growing
constexpr std::uint64_t kSettleSteps = 1500;
constexpr double kServoRelaxation = 0.2;   // alpha_s of §6.2 for the side rows
constexpr double kStressTolerance = 0.02;  // as the expansion servo: within 2 % for 10 checks
constexpr int kChecksHeld = 10;

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
          // The slot holds the force on the second particle; sample disks come first.
          if (i < n_sample && j >= lo && j <= hi) f -= dot(c.slot[k].force, inward);
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
          if (i < n_sample && j < n_sample) lf += (p[j].x.x - p[i].x.x) * c.slot[k].force.x;
        }
      },
      sim.contact_model());
  return lf;
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
  Rows rows;
  // Rows of the smallest grains: a grain of radius r nests in the cusp between two touching row
  // disks of radius R_w to R_w + r - sqrt(r^2 + 2 R_w r) below the row's face: 0.27 r_min when
  // R_w = r = r_min.
  rows.radius = s.radii.kind == RadiusDistribution::Kind::Classes
                    ? *std::min_element(s.radii.class_radius.begin(), s.radii.class_radius.end())
                    : s.radii.r_min;
  const double rw = rows.radius, h = target.ly, w0 = target.lx;
  add_row(all, rows.bottom, {-3 * rw, -rw, 0}, {w0 + 3 * rw, -rw, 0}, rw);
  add_row(all, rows.top, {-3 * rw, h + rw, 0}, {w0 + 3 * rw, h + rw, 0}, rw);
  // The side rows reach into the end rows, so the corners are closed.
  add_row(all, rows.left, {-rw, -rw, 0}, {-rw, h + rw, 0}, rw);
  add_row(all, rows.right, {w0 + rw, -rw, 0}, {w0 + rw, h + rw, 0}, rw);
  log(
      fmt::format("packing: {} disks placed at {:.0f} % of their radii in a {:.4g} x {:.4g} m box "
                  "between rows of {} disks; compacting to {:.4g} MPa",
                  n, 100 * shrink, w0, h, all.size() - n, s.preconsolidation_stress * 1e-6));

  // Cycling with the rows driven: the ends held, the sides servoed (physics.md §6.2).
  Region box = target;
  box.lx = w0 + 8 * rw;  // the rows are the walls: the vessel planes stay clear of everything
  box.ly = h + 4 * rw;
  std::vector<PosRad> shifted = all;
  for (PosRad& q : shifted) q.x += Vec3{4 * rw, 2 * rw, 0};
  PackingSettings plain = s;
  Simulation sim = vessel_simulation(shifted, box, plain);
  ParticleStore& P = sim.particles_mut();
  for (std::size_t i = n; i < all.size(); ++i) P.motion[i] = Motion::Driven;
  // Servo gain from the stiffness of one contact of a row disk at a small overlap (§6.2).
  double kn = 0.0;
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        PairGeometry g =
            pair_geometry({}, rw, {2 * rw, 0, 0}, rw, {}, {}, {}, {}, 1, 1, true, box.thickness);
        g.delta = 1e-4 * rw;
        double ks = 0.0;
        CL::timestep_stiffness(c.params, g, kn, ks);
      },
      sim.contact_model());
  const double area = h * box.thickness;
  const double target_stress = s.preconsolidation_stress;
  StageClock clock(&sim);
  // Growth to size between the fixed rows, then settling.
  for (double applied = 1.0;
       applied < (1.0 / shrink) * (1 - 1e-12) && sim.step_count() < s.max_steps;) {
    const double f = std::min(1.0 + kGrowthRate, 1.0 / shrink / applied);
    for (std::size_t i = 0; i < n; ++i) sim.set_radius(i, P.pos_rad[i].r * f);
    applied *= f;
    sim.run(kCheck);
  }
  sim.refresh_time_step();
  sim.run(std::min(kSettleSteps, s.max_steps - std::min(s.max_steps, sim.step_count())));
  st.report.stages.push_back(clock.done("growth", fmt::format("radii x {:.4f}", 1.0 / shrink)));
  // The side rows move at most 1 % of the width per 1000 steps.
  const double v_max = 0.01 * w0 / (1000.0 * sim.time_step());
  int held = 0;
  double sxx = 0.0;
  while (sim.step_count() < s.max_steps) {
    sim.run(kCheck);
    const double f_left = row_load(sim, rows.left, n, {1, 0, 0});
    const double f_right = row_load(sim, rows.right, n, {-1, 0, 0});
    sxx = 0.5 * (f_left + f_right) / area;
    // At the target on the rows, and the sample's own contacts in equilibrium with them (their
    // mean sigma_xx within 5 %): the rows alone pass through the band while the sample moves.
    const double width =
        P.pos_rad[rows.right.front()].x.x - P.pos_rad[rows.left.front()].x.x - 2.0 * rw;
    const double inner = internal_sxx(sim, n) / (width * area);
    held = std::abs(sxx - target_stress) <= kStressTolerance * target_stress &&
                   std::abs(inner - sxx) <= 0.05 * sxx
               ? held + 1
               : 0;
    if (held >= kChecksHeld) break;
    // Contacts on each row: at least one, as §6.2 asks when a wall touches nothing yet.
    auto drive = [&](const std::vector<std::size_t>& row, double force, double sign) {
      const std::size_t touching = row.size() / 2;
      const double gain =
          kServoRelaxation * area /
          (kn * static_cast<double>(std::max<std::size_t>(1, touching)) * sim.time_step());
      const double v = std::clamp(gain * (target_stress - force / area), -v_max, v_max);
      for (std::size_t i : row) P.drive_vel[i] = Vec3{sign * v, 0, 0};
    };
    drive(rows.left, f_left, 1.0);
    drive(rows.right, f_right, -1.0);
  }
  for (std::size_t i = n; i < all.size(); ++i) P.drive_vel[i] = {};
  const double x_left = P.pos_rad[rows.left.front()].x.x + rw;
  const double x_right = P.pos_rad[rows.right.front()].x.x - rw;
  const double f_ends =
      row_load(sim, rows.bottom, n, {0, 1, 0}) + row_load(sim, rows.top, n, {0, -1, 0});
  const double syy = 0.5 * f_ends / ((x_right - x_left) * box.thickness);
  st.report.converged = held >= kChecksHeld;
  st.report.preconsolidation_stress_reached = sxx;
  st.report.stages.push_back(clock.done(
      "preconsolidation", fmt::format("sigma_xx = {:.4g} MPa (rows), sigma_yy = {:.4g} MPa "
                                      "(ends), width {:.4g} m",
                                      sxx * 1e-6, syy * 1e-6, x_right - x_left)));
  if (!st.report.converged)
    st.report.warnings.push_back(fmt::format(
        "preconsolidation did not hold {} MPa within {} steps (sample.max_steps); reached {:.4g} "
        "MPa",
        target_stress * 1e-6, s.max_steps, sxx * 1e-6));

  // The compacted sample in its own frame: x from the left row's face, y from the bottom row's.
  st.region = target;
  st.region.lx = x_right - x_left;
  const Vec3 origin{x_left, 2 * rw, 0};
  std::vector<double> nominal;
  for (const PosRad& q : P.pos_rad) nominal.push_back(q.r);
  const FloaterFix fix = fit_floaters(sim, box, s.bond_gap_tolerance, s.floater_contacts,
                                      s.floater_max_growth, nominal, n);
  st.report.floaters_grown = fix.fitted;
  st.report.largest_floater_growth = fix.largest_growth;
  st.report.stages.push_back(clock.done(
      "floaters", fmt::format("{} found, {} placed snug in their cages", fix.found, fix.fitted)));
  for (std::size_t i = 0; i < n; ++i)
    st.particles.push_back({P.pos_rad[i].x - origin, P.pos_rad[i].r});
  st.report.steps = sim.step_count();
  return st;
}

}  // namespace breccia::packing
