// Time integration (docs/physics.md §1): free rotation, energy conservation without damping, the
// analytic restitution of a damped linear contact, and local damping bookkeeping.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "breccia/core/error.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/sample/lattice.hpp"

using namespace breccia;

TEST(Integrator, FreeRotationKeepsAngularMomentumAndUnitQuaternion) {
  ParticleStore ps(Dimension::Three, 1.0);
  const Vec3 w0{3.0, -1.0, 2.0};
  ps.add({.tag = 1, .position = {}, .radius = 1e-3, .density = 2650, .angular_velocity = w0});
  EngineConfig cfg;
  cfg.time_step = 1e-4;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.run(10000);  // 1 s
  const auto& p = sim.particles();
  EXPECT_EQ(p.angvel[0], w0);  // I w conserved exactly: no torque
  const Quat q = p.orientation[0];
  EXPECT_NEAR(std::sqrt(norm2(q)), 1.0, 1e-14);
  const Quat ref = from_axis_angle(w0, norm(w0) * 1.0);
  const double sgn = q.w * ref.w >= 0 ? 1.0 : -1.0;
  EXPECT_NEAR(q.w, sgn * ref.w, 1e-10);
  EXPECT_NEAR(q.x, sgn * ref.x, 1e-10);
  EXPECT_NEAR(q.y, sgn * ref.y, 1e-10);
  EXPECT_NEAR(q.z, sgn * ref.z, 1e-10);
}

namespace {

// An FCC block of bonded spheres placed 0.1 % apart, so that contacts never engage and the
// system is purely bonded, with random velocities and spins.
Simulation bonded_block(int n, double speed, double spin) {
  const double R = 0.5e-3;
  ParticleStore ps = fcc_block(n, n, n, R * 1.001, 2650);
  for (auto& q : ps.pos_rad) q.r = R;
  for (std::size_t i = 0; i < ps.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      ps.vel[i][k] = speed * standard_normal(17, k, i);
      ps.angvel[i][k] = spin * standard_normal(18, k, i);
    }
  EngineConfig cfg;
  cfg.energy_interval = 0;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.bond_touching_pairs<ParallelBond>(2.1e-6);
  sim.initialise();
  return sim;
}

}  // namespace

TEST(Integrator, BondedLatticeConservesEnergyWithoutDamping) {
  Simulation sim = bonded_block(3, 1e-3, 1.0);
  ASSERT_GT(sim.intact_bonds(), 400u);
  double e0 = 0.0, worst = 0.0, bond_max = 0.0;
  for (int k = 0; k <= 10000; ++k) {
    if (k % 500 == 0) sim.request_energy_sample();
    sim.step();
    if (k % 500 == 0) {
      const EnergyLedger& L = sim.ledger();
      if (k == 0) e0 = L.stored();
      worst = std::max(worst, std::abs(L.stored() - e0));
      bond_max = std::max(bond_max, L.bond.total());
      EXPECT_EQ(L.contact, 0.0);
    }
  }
  EXPECT_GT(bond_max, 0.2 * e0) << "the lattice must exchange kinetic and strain energy";
  // Leapfrog conserves (1/2) m v^{n-1/2}.v^{n+1/2} + U exactly for linear springs; what remains
  // is the geometric non-linearity of the incremental bond (measured: ~3e-9). 1e-6 = 0.0001 %.
  EXPECT_LT(worst, 1e-6 * e0) << "relative drift " << worst / e0;
  EXPECT_TRUE(sim.cracks().empty());
}

TEST(Integrator, BondedChainConservesEnergyWithoutDamping) {
  ParticleStore ps(Dimension::Three, 1.0);
  const double R = 0.5e-3;
  // Spaced 0.1 % apart so that no contact engages: a purely bonded chain.
  for (int k = 0; k < 10; ++k)
    ps.add({.tag = static_cast<std::uint64_t>(k + 1),
            .position = {2.002 * R * k, 0, 0},
            .radius = R,
            .density = 2650,
            .velocity = {0, k == 9 ? 1e-3 : 0.0, k == 0 ? -1e-3 : 0.0}});
  EngineConfig cfg;
  cfg.energy_interval = 0;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  for (int k = 1; k < 10; ++k) sim.add_bond<ParallelBond>(k, k + 1);
  double e0 = 0.0, worst = 0.0;
  for (int k = 0; k <= 10000; ++k) {
    if (k % 250 == 0) sim.request_energy_sample();
    sim.step();
    if (k % 250 == 0) {
      if (k == 0) e0 = sim.ledger().stored();
      worst = std::max(worst, std::abs(sim.ledger().stored() - e0));
    }
  }
  EXPECT_LT(worst, 1e-6 * e0) << "relative drift " << worst / e0;
}

namespace {

// Exit velocity ratio of a linear spring-dashpot against a rigid wall with the no-tension rule:
// the contact ends when k x + c xdot first reaches zero (x = penetration), not when x = 0.
double analytic_restitution(double beta) {
  const double w0 = 1.0, wd = w0 * std::sqrt(1 - beta * beta);
  auto x = [&](double t) { return std::exp(-beta * w0 * t) * std::sin(wd * t) / wd; };
  auto xd = [&](double t) {
    return std::exp(-beta * w0 * t) * (std::cos(wd * t) - beta * w0 / wd * std::sin(wd * t));
  };
  auto force = [&](double t) { return w0 * w0 * x(t) + 2 * beta * w0 * xd(t); };
  if (beta == 0.0) return 1.0;
  double lo = 0.5 * std::numbers::pi / wd, hi = std::numbers::pi / wd;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (force(mid) > 0 ? lo : hi) = mid;
  }
  return -xd(0.5 * (lo + hi));
}

// Spheres of R = 0.5 mm under the linear law (E_c = 10 GPa) with a normal dashpot of ratio beta,
// 2000 steps per contact. A grain on a wall (k_n = pi R E_c, mass m) and two equal grains
// (k_n = pi R E_c / 2, reduced mass m / 2) share the contact time pi sqrt(m / (pi R E_c)).
constexpr double kCollisionR = 0.5e-3, kCollisionE = 10e9, kCollisionV = 0.1;
Simulation collision(ParticleStore ps, double beta) {
  const double R = kCollisionR;
  const double m = 2650 * 4.0 / 3.0 * std::numbers::pi * R * R * R;
  const double tc = std::numbers::pi * std::sqrt(m / (std::numbers::pi * R * kCollisionE));
  EngineConfig cfg;
  cfg.time_step = tc / 2000;
  cfg.energy_interval = 0;
  LinearContact::Params lp;
  lp.modulus = kCollisionE;
  lp.normal_damping_ratio = beta;
  return Simulation(std::move(ps), cfg, make_contact_model<LinearContact>(lp, lp));
}

double simulated_restitution(double beta) {
  const double R = kCollisionR, v0 = kCollisionV;
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1,
          .position = {0, 0, R + 1e-9},
          .radius = R,
          .density = 2650,
          .velocity = {0, 0, -v0}});
  Simulation sim = collision(std::move(ps), beta);
  sim.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}));
  sim.initialise();
  while (sim.particles().pos_rad[0].x.z < R + 2e-9 || sim.particles().vel[0].z < 0) sim.step();
  return sim.particles().vel[0].z / v0;
}

// Two equal free spheres meeting head-on at +-v0/2: their relative motion is the wall's problem
// with the reduced mass m* = m/2, so the same restitution. Returns the exit ratio and the
// ledger's relative residual after the collision.
std::pair<double, double> grain_collision(double beta) {
  const double R = kCollisionR, v0 = kCollisionV;
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1,
          .position = {-R - 1e-9, 0, 0},
          .radius = R,
          .density = 2650,
          .velocity = {0.5 * v0, 0, 0}});
  ps.add({.tag = 2,
          .position = {R + 1e-9, 0, 0},
          .radius = R,
          .density = 2650,
          .velocity = {-0.5 * v0, 0, 0}});
  Simulation sim = collision(std::move(ps), beta);
  sim.initialise();
  sim.request_energy_sample();
  sim.step();
  const double e0 = sim.ledger().stored();
  while (sim.particles().pos_rad[1].x.x - sim.particles().pos_rad[0].x.x < 2 * R + 4e-9 ||
         sim.particles().vel[1].x < 0)
    sim.step();
  sim.request_energy_sample();
  sim.step();
  const double rel = sim.particles().vel[1].x - sim.particles().vel[0].x;
  return {rel / v0, sim.ledger().residual / e0};
}

}  // namespace

TEST(Integrator, GrainGrainCollisionMatchesAnalyticRestitution) {
  for (const double beta : {0.0, 0.1, 0.3}) {
    const auto [e_sim, residual] = grain_collision(beta);
    // As against the wall: 2000 steps per contact.
    EXPECT_NEAR(e_sim, analytic_restitution(beta), 1e-3) << "beta " << beta;
    // The dashpot's loss closes the ledger: kinetic energy lost = viscous loss booked.
    EXPECT_LT(std::abs(residual), 1e-3) << "beta " << beta;
  }
}

TEST(Integrator, BounceOnWallMatchesAnalyticRestitution) {
  for (const double beta : {0.0, 0.05, 0.2, 0.5}) {
    const double e_sim = simulated_restitution(beta), e_ref = analytic_restitution(beta);
    // 2000 steps per contact: the contact's start and end fall inside a step, an O(dt / t_c)
    // = 5e-4 error in the exit speed.
    EXPECT_NEAR(e_sim, e_ref, 1e-3) << "beta " << beta;
    if (beta == 0.0) {
      EXPECT_NEAR(e_sim, 1.0, 1e-3);
    }
  }
  // Sanity of the reference itself: without the no-tension rule e = exp(-pi b / sqrt(1 - b^2));
  // the rule ends the contact early, so it bounces back a little faster.
  EXPECT_GT(analytic_restitution(0.2), std::exp(-std::numbers::pi * 0.2 / std::sqrt(1 - 0.04)));
}

TEST(Integrator, LocalDampingRemovesEnergyAndBooksIt) {
  const double R = 0.5e-3;
  ParticleStore ps = fcc_block(3, 3, 3, R * 1.001, 2650);
  for (auto& q : ps.pos_rad) q.r = R;
  for (std::size_t i = 0; i < ps.size(); ++i)
    for (int k = 0; k < 3; ++k) ps.vel[i][k] = 1e-3 * standard_normal(17, k, i);
  EngineConfig cfg;
  cfg.local_damping = 0.7;
  cfg.energy_interval = 0;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.bond_touching_pairs<ParallelBond>(2.1e-6);
  sim.request_energy_sample();
  sim.step();
  const double e0 = sim.ledger().stored();
  sim.run(3000);
  sim.request_energy_sample();
  sim.step();
  const EnergyLedger& L = sim.ledger();
  EXPECT_LT(L.stored(), 0.01 * e0) << "alpha = 0.7 removes ~97 % per cycle";
  EXPECT_GT(L.local_damping, 0.9 * e0);
  // The loss is booked as the damping force's work with the ledger's trapezoidal rule, so the
  // balance closes to the geometric non-linearity of the bonds (as without damping).
  EXPECT_LT(std::abs(L.residual), 1e-6 * e0) << "relative residual " << L.residual / e0;
}

// Dynamic damping (docs/physics.md §2.1). Grains A and B share a weak bond, pulled apart by
// constant loads F; C, beyond the radius, is pulled the same way. Each load points along its
// grain's velocity, so a step adds (1 - alpha) F dt / m to the speed. From the step the bond
// breaks, A and B (at R from the crack's contact point, inside the radius 3R) are damped with
// alpha_near for the window of 24.5 steps (25 steps), then with alpha again; C (at about 20R)
// keeps alpha throughout. Once broken, the loads are the grains' only forces.
TEST(Integrator, DynamicDampingLowersTheDampingNearAFreshCrackForItsWindow) {
  const double R = 0.5e-3, F = 1e-3, dt = 1e-7, alpha = 0.7, alpha_near = 0.1;
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1, .position = {0, 0, 0}, .radius = R, .density = 2650});
  ps.add({.tag = 2, .position = {2 * R, 0, 0}, .radius = R, .density = 2650});
  ps.add({.tag = 3, .position = {R, 20 * R, 0}, .radius = R, .density = 2650});
  EngineConfig cfg;
  cfg.time_step = dt;
  cfg.local_damping = alpha;
  cfg.energy_interval = 0;
  cfg.dynamic_damping_alpha = alpha_near;
  cfg.dynamic_damping_radius = 3 * R;
  cfg.dynamic_damping_time = 24.5 * dt;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  ParallelBond::Params bp;
  bp.tensile_strength = 1e3;  // breaks within a few steps of pulling
  bp.cohesion = 1e9;
  sim.set_bond_params<ParallelBond>(bp);
  sim.bond_touching_pairs<ParallelBond>(1e-9);
  sim.initialise();
  const Vec3 load[3] = {{-F, 0, 0}, {F, 0, 0}, {F, 0, 0}};
  auto step = [&] {
    for (std::size_t i = 0; i < 3; ++i) sim.external_force()[i] = load[i];
    sim.step();
  };
  const double m = sim.particles().mass[0];
  const double damped = (1 - alpha) * F * dt / m, near = (1 - alpha_near) * F * dt / m;
  while (sim.cracks().empty() && sim.step_count() < 10000) {
    const double vc = sim.particles().vel[2].x;
    step();
    EXPECT_NEAR(sim.particles().vel[2].x - vc, damped, 1e-9 * damped);
  }
  ASSERT_EQ(sim.cracks().size(), 1u) << "the bond must break";
  const double t_break = sim.cracks().front().time;
  EXPECT_EQ(sim.dynamically_damped_until(0), t_break + 24.5 * dt);
  EXPECT_EQ(sim.dynamically_damped_until(1), t_break + 24.5 * dt);
  EXPECT_EQ(sim.dynamically_damped_until(2), -std::numeric_limits<double>::infinity());
  // The breaking step was the window's first; 24 more, then alpha again.
  for (int k = 1; k < 40; ++k) {
    const double va = sim.particles().vel[0].x, vb = sim.particles().vel[1].x,
                 vc = sim.particles().vel[2].x;
    step();
    const double expected = k < 25 ? near : damped;
    EXPECT_NEAR(va - sim.particles().vel[0].x, expected, 1e-9 * damped) << "step " << k;
    EXPECT_NEAR(sim.particles().vel[1].x - vb, expected, 1e-9 * damped) << "step " << k;
    EXPECT_NEAR(sim.particles().vel[2].x - vc, damped, 1e-9 * damped) << "step " << k;
  }
  EXPECT_EQ(sim.cracks().size(), 1u);
  EXPECT_THROW(sim.set_dynamic_damping(1.0, R, dt), InputError);
  EXPECT_THROW(sim.set_dynamic_damping(0.0, -R, dt), InputError);
}

TEST(Integrator, GravityWorkIsBooked) {
  // A sphere falls freely for 0.01 s: the work of gravity m g h equals its kinetic energy.
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1, .position = {0, 0, 0}, .radius = 1e-3, .density = 2650});
  EngineConfig cfg;
  cfg.gravity = {0, 0, -9.81};
  cfg.time_step = 1e-5;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.run(1000);
  sim.request_energy_sample();
  sim.step();
  const EnergyLedger& L = sim.ledger();
  const double m = sim.particles().mass[0];
  EXPECT_NEAR(L.body_force_work, m * 9.81 * -sim.particles().pos_rad[0].x.z,
              m * 9.81 * 9.81 * 1e-5 * 0.02);  // the drift lags the kinetic energy by O(dt)
  EXPECT_NEAR(L.residual, 0.0, 1e-12 * L.body_force_work);
}

TEST(Integrator, UserTimeStepAboveTheEstimateWarns) {
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1, .position = {0, 0, 0}, .radius = 0.5e-3, .density = 2650});
  ps.add({.tag = 2, .position = {1e-3, 0, 0}, .radius = 0.5e-3, .density = 2650});
  EngineConfig cfg;
  Simulation probe(ps, cfg, make_contact_model<LinearContact>({}, {}));
  probe.initialise();
  EXPECT_TRUE(probe.warnings().empty());
  cfg.time_step = 2.0 * probe.time_step();
  Simulation sim(ps, cfg, make_contact_model<LinearContact>({}, {}));
  sim.initialise();
  ASSERT_EQ(sim.warnings().size(), 1u);
  EXPECT_NE(sim.warnings()[0].find("above the stable estimate"), std::string::npos);
  EXPECT_EQ(sim.time_step(), cfg.time_step);
  // Estimate for two touching spheres with one potential contact each side (§1.5):
  // k_tr = 2 k_n per particle, k_rot = 2 k_s R^2; the rotational term governs.
  const double kn = 7.853981633974483e6, ks = kn / 2.5;
  const double m = probe.particles().mass[0], I = probe.particles().inertia[0];
  const double crit = std::min(std::sqrt(m / (2 * kn)), std::sqrt(I / (2 * ks * 0.25e-6)));
  EXPECT_NEAR(probe.critical_time_step(), crit, 1e-12 * crit);
}

TEST(Integrator, ExternalForceWorkIsBooked) {
  // A constant external force of 1 mN on a free sphere for 2000 steps: its work is the kinetic
  // energy gained (the ledger's trapezoidal rule is exact for a constant force).
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1, .position = {0, 0, 0}, .radius = 1e-3, .density = 2650});
  EngineConfig cfg;
  cfg.time_step = 1e-6;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  for (int k = 0; k < 2000; ++k) {
    sim.external_force()[0] = {1e-3, 0, 0};
    if (k == 1999) sim.request_energy_sample();
    sim.step();
  }
  const EnergyLedger& L = sim.ledger();
  EXPECT_GT(L.external_work, 0.0);
  EXPECT_NEAR(L.external_work, L.kinetic(), 1e-12 * L.kinetic());
  EXPECT_NEAR(L.residual, 0.0, 1e-12 * L.kinetic());
}

// A run whose grains are all free holds no prescribed-velocity arrays (48 bytes a grain, and 48
// more of driver loads in the engine) and, in 3D, no 2D angles; a grain fixed or driven after the
// start gets them then, and moves exactly as prescribed from the next step.
TEST(Integrator, DriveArraysExistOnlyOnceAGrainIsDriven) {
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1, .position = {}, .radius = 1e-3, .density = 2650, .velocity = {0.1, 0, 0}});
  ps.add({.tag = 2, .position = {5e-3, 0, 0}, .radius = 1e-3, .density = 2650});
  EXPECT_FALSE(ps.has_drives());
  EXPECT_TRUE(ps.angle.empty());
  EngineConfig cfg;
  cfg.time_step = 1e-6;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.run(10);
  EXPECT_FALSE(sim.particles().has_drives());
  const Vec3 v{0.0, 0.2, 0.0};
  ParticleStore& p = sim.particles_mut();
  p.set_motion(1, Motion::Driven);
  ASSERT_TRUE(p.has_drives());
  ASSERT_EQ(p.drive_vel.size(), 2u);
  EXPECT_EQ(p.drive_vel[0], Vec3{});  // the free grain's entry exists and stays unused
  p.drive_vel[1] = v;
  const Vec3 x1 = p.pos_rad[1].x;
  sim.run(100);
  EXPECT_EQ(sim.particles().vel[1], v);
  EXPECT_NEAR(sim.particles().pos_rad[1].x.y - x1.y, v.y * 100 * 1e-6, 1e-15);
  EXPECT_EQ(sim.particles().vel[0], (Vec3{0.1, 0, 0}));  // untouched: the grains never meet
}

namespace {

// Overlapping frictionless Hertz spheres on a frictionless floor that push apart under local
// damping; with `far_fixed_grain` one more grain, fixed and touching nothing, which turns the
// central-force shortcut off (a driven grain does) without changing any other grain's sums.
Simulation frictionless_heap(bool far_fixed_grain) {
  const double R = 0.5e-3;
  ParticleStore ps = fcc_block(4, 4, 4, R * 0.999, 2650);
  double z_min = 1.0, x_max = -1.0;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    ps.pos_rad[i].r = R;
    z_min = std::min(z_min, ps.pos_rad[i].x.z);
    x_max = std::max(x_max, ps.pos_rad[i].x.x);
    for (int k = 0; k < 3; ++k) ps.vel[i][k] = 0.01 * standard_normal(23, k, i);
  }
  if (far_fixed_grain) {
    const Vec3 far{x_max + 10 * R, 2 * R, z_min + 3 * R};  // off the floor, off the heap
    ps.add({.tag = 100000, .position = far, .radius = R, .density = 2650});
    ps.set_motion(ps.size() - 1, Motion::Fixed);
  }
  EngineConfig cfg;
  cfg.local_damping = 0.7;
  HertzMindlin::Params hp;
  hp.friction = 0.0;
  Simulation sim(std::move(ps), cfg, make_contact_model<HertzMindlin>(hp, hp));
  sim.add_wall(Wall::plane("floor", {0, 0, z_min - 0.998 * R}, {0, 0, 1}));
  sim.initialise();
  return sim;
}

}  // namespace

// Central forces only (frictionless contacts without dashpots, no bond): the pair pass leaves out
// the torques, which are rounding, and the integrator turns no grain; every translation is the
// full computation's to the bit.
TEST(Integrator, CentralForcesMoveTheGrainsAsTheFullComputation) {
  Simulation central = frictionless_heap(false), full = frictionless_heap(true);
  EXPECT_EQ(central.time_step(), full.time_step());
  const ParticleStore start = central.particles();
  central.run(1);
  EXPECT_GT(central.walls()[0].contacts, 0u);  // the floor's torques are left out too
  central.run(399);
  full.run(400);
  const ParticleStore &a = central.particles(), &b = full.particles();
  ASSERT_EQ(b.size(), a.size() + 1);
  double moved = 0.0, v_max = 0.0, w_full = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(a.pos_rad[i].x[k], b.pos_rad[i].x[k]) << "grain " << i;
      EXPECT_EQ(a.vel[i][k], b.vel[i][k]) << "grain " << i;
    }
    EXPECT_EQ(a.angvel[i], Vec3{}) << "grain " << i;
    EXPECT_EQ(a.orientation[i], start.orientation[i]) << "grain " << i;
    moved = std::max(moved, norm(a.pos_rad[i].x - start.pos_rad[i].x));
    v_max = std::max(v_max, norm(a.vel[i]));
    w_full = std::max(w_full, norm(b.angvel[i]));
  }
  EXPECT_GT(moved, 1e-7);  // the overlaps (1 um) pushed the grains apart
  EXPECT_EQ(central.neighbour_rebuilds(), full.neighbour_rebuilds());
  // The full computation's spins are the rounding of central torques: their contact-point
  // speeds are far below the grains' speeds.
  EXPECT_GT(w_full, 0.0);  // so the zero spins above are the shortcut's
  EXPECT_LT(w_full * 0.5e-3, 1e-9 * v_max);
}
