// Two bonded particles driven through the whole engine, against the hand numbers of docs/physics.md
// §8: R = 0.5 mm, E_bar = 10 GPa, kappa = 2.5, sigma_c = c = 20 MPa, lambda = 1.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "breccia/engine/simulation.hpp"

using namespace breccia;

namespace {

constexpr double kR = 0.5e-3;
constexpr double kKn = 7.853981633974483e6;  // E A / L
constexpr double kKs = kKn / 2.5;
constexpr double kKb = 0.4908738521234052;   // E I / L
constexpr double kKt = 0.39269908169872414;  // (E / 2.5) J / L

struct Pair {
  Simulation sim;
  std::size_t i1, i2;
};

Pair make_pair(bool planar, double thickness = 1.0) {
  ParticleStore ps(planar ? Dimension::Two : Dimension::Three, thickness);
  ParticleSpec a{.tag = 1, .position = {0, 0, 0}, .radius = kR, .density = 2650};
  ParticleSpec b{.tag = 2, .position = {2 * kR, 0, 0}, .radius = kR, .density = 2650};
  a.motion = Motion::Driven;
  b.motion = Motion::Driven;
  ps.add(a);
  ps.add(b);
  EngineConfig cfg;
  cfg.energy_interval = 0;
  Pair p{Simulation(std::move(ps), cfg, make_contact_model<LinearContact>({}, {})), 0, 1};
  ParallelBond::Params bp;  // defaults are the §8 values
  p.sim.set_bond_params<ParallelBond>(bp);
  p.sim.add_bond<ParallelBond>(1, 2);
  p.sim.initialise();
  return p;
}

// Force on particle 2 from the bond, read back from the particle (particle 1 gets the opposite).
Vec3 force_on_2(const Simulation& s) {
  return s.particles().force[1];
}

// The bond's section and stiffnesses as the engine's parameters give them (its dimension and
// thickness included).
ParallelBond::Section section_of(const Simulation& s) {
  const auto& set = std::get<BondSet<ParallelBond>>(s.bonds());
  return ParallelBond::section(set.params, s.bond_radii(set.pairs.first[0], set.pairs.second[0]));
}

}  // namespace

TEST(TwoParticle, HandStiffnessesOfPhysicsSection8) {
  Pair p = make_pair(false);
  const ParallelBond::Section st = section_of(p.sim);
  EXPECT_NEAR(st.kn, kKn, 1e-9 * kKn);
  EXPECT_NEAR(st.ks, kKs, 1e-9 * kKs);
  EXPECT_NEAR(st.kb, kKb, 1e-9 * kKb);
  EXPECT_NEAR(st.kt, kKt, 1e-9 * kKt);
}

TEST(TwoParticle, PullBreaksInTensionAtTwoMicrometres) {
  Pair p = make_pair(false);
  const double V = 1e-3;
  p.sim.particles_mut().drive_vel[1] = {V, 0, 0};
  const double dt = p.sim.time_step();
  double f_prev = 0.0;
  while (p.sim.cracks().empty() && p.sim.step_count() < 2000000) {
    const double stretch = p.sim.particles().pos_rad[1].x.x - 2 * kR;
    p.sim.step();
    if (p.sim.cracks().empty()) {
      // F_n = -K_n (d - d0), tension on particle 2 points back to particle 1.
      ASSERT_NEAR(force_on_2(p.sim).x, -kKn * stretch, 1e-9 * kKn * 2e-6) << p.sim.step_count();
      f_prev = force_on_2(p.sim).x;
    }
  }
  ASSERT_EQ(p.sim.cracks().size(), 1u);
  const CrackRecord& c = p.sim.cracks()[0];
  EXPECT_EQ(c.mode, CrackMode::Tensile);
  EXPECT_EQ(c.id1, 1u);
  EXPECT_EQ(c.id2, 2u);
  // sigma_c A / K_n = 2.0 um, reached within one step's displacement V dt.
  const double stretch_at_break = -c.Fn / kKn;
  EXPECT_GE(stretch_at_break, 2.0e-6 - 1e-15);
  EXPECT_LE(stretch_at_break, 2.0e-6 + V * dt);
  EXPECT_NEAR(-c.Fn, 15.70796, 15.70796 * V * dt / 2e-6 + 1e-5);
  EXPECT_NEAR(c.energy.total(), c.Fn * c.Fn / (2 * kKn), 1e-12);
  EXPECT_NEAR(c.energy.total(), 1.5708e-5, 1.5708e-5 * 2 * V * dt / 2e-6 + 1e-9);
  EXPECT_NEAR(c.position.x, kR + 0.5 * stretch_at_break, 1e-12);
  EXPECT_LT(f_prev, 0.0);
  // The force of the breaking step is not applied (§4.0): the pair is now force-free.
  EXPECT_EQ(force_on_2(p.sim).x, 0.0);
  EXPECT_EQ(p.sim.intact_bonds(), 0u);
}

namespace {

// Drives particle 2 along the circle of radius d0 about particle 1 (rotations held at zero) until
// the bond breaks; checks |F_s| = K_s * arc on the way and returns the crack.
CrackRecord shear_along_arc(bool planar, double thickness) {
  Pair p = make_pair(planar, thickness);
  const ParallelBond::Section st = section_of(p.sim);
  const double ks = st.ks, kn = st.kn;
  const double V = 1e-2, d0 = 2 * kR;
  const double dt = p.sim.time_step();
  double arc = 0.0;
  while (p.sim.cracks().empty() && p.sim.step_count() < 2000000) {
    const Vec3 x = p.sim.particles().pos_rad[1].x;
    const double phi = std::atan2(x.y, x.x);
    p.sim.particles_mut().drive_vel[1] = Vec3{-std::sin(phi), std::cos(phi), 0} * V;
    p.sim.step();
    if (p.sim.cracks().empty()) {
      arc += V * dt;
      const Vec3 f = force_on_2(p.sim);
      const Vec3 n = unit(x);  // normal of the configuration the force belongs to
      const double fs = norm(f - n * dot(f, n));
      EXPECT_NEAR(fs, ks * (arc - V * dt), 1e-6 * ks * 5e-6) << p.sim.step_count();
      if (std::abs(fs - ks * (arc - V * dt)) > 1e-6 * ks * 5e-6) break;
    }
  }
  EXPECT_EQ(p.sim.cracks().size(), 1u);
  CrackRecord c = p.sim.cracks().empty() ? CrackRecord{} : p.sim.cracks()[0];
  EXPECT_EQ(c.mode, CrackMode::Shear);
  // tau_c A / K_s = c L / (E_bar / kappa) = 5.0 um of arc in 3D and 2D alike.
  EXPECT_GE(c.Fs / ks, 5.0e-6 - 1e-12);
  EXPECT_LE(c.Fs / ks, 5.0e-6 + V * dt);
  EXPECT_NEAR(c.energy.shear, c.Fs * c.Fs / (2 * ks), 1e-12 * c.energy.shear + 1e-30);
  // Each chord of the polygonal path lengthens the bond by (V dt)^2 / (2 d0).
  const double chord_stretch =
      static_cast<double>(p.sim.step_count()) * std::pow(V * dt, 2) / (2 * d0);
  EXPECT_LE(std::abs(c.Fn), 2 * kn * chord_stretch) << "an arc keeps d = d0";
  return c;
}

}  // namespace

TEST(TwoParticle, ShearAlongArcBreaksInShearAtFiveMicrometres) {
  const CrackRecord c = shear_along_arc(false, 1.0);
  EXPECT_NEAR(c.Fs, kKs * 5e-6, kKs * 1e-8);
}

TEST(TwoDisk, ShearAlongArcBreaksInShearAtFiveMicrometres) {
  const CrackRecord c = shear_along_arc(true, 1e-3);
  // Slab: K_s = E_bar t / kappa; the shear stress at failure is the cohesion, 20 MPa.
  EXPECT_NEAR(c.tau, 20e6, 20e6 * 1e-3);
}

TEST(TwoParticle, PureBendingBreaksInTensionAtFourMilliradians) {
  Pair p = make_pair(false);
  // Opposite rotations about y: no slip at the contact point, pure bending (§8 cross-check 2).
  const double W = 2.0;
  p.sim.particles_mut().drive_angvel[0] = {0, -0.5 * W, 0};
  p.sim.particles_mut().drive_angvel[1] = {0, 0.5 * W, 0};
  const double dt = p.sim.time_step();
  double theta = 0.0;
  while (p.sim.cracks().empty() && p.sim.step_count() < 2000000) {
    p.sim.step();
    if (p.sim.cracks().empty()) {
      // Bond couple on 2 is -K_b theta about y; the torque on particle 2 is exactly that couple.
      ASSERT_NEAR(p.sim.particles().torque[1].y, -kKb * theta, 1e-6 * kKb * 4e-3);
      ASSERT_NEAR(norm(force_on_2(p.sim)), 0.0, 1e-9);
      theta += W * dt;
    }
  }
  ASSERT_EQ(p.sim.cracks().size(), 1u);
  const CrackRecord& c = p.sim.cracks()[0];
  EXPECT_EQ(c.mode, CrackMode::Tensile);
  EXPECT_GE(c.Mb, 1.963495e-3 * (1 - 1e-6));
  EXPECT_LE(c.Mb / kKb, 4.0e-3 + W * dt);
  EXPECT_NEAR(c.energy.bending, c.Mb * c.Mb / (2 * kKb), 1e-15);
}

TEST(TwoParticle, TwistBreaksInShear) {
  Pair p = make_pair(false);
  const double W = 5.0;
  p.sim.particles_mut().drive_angvel[1] = {W, 0, 0};  // about the bond axis
  const double dt = p.sim.time_step();
  double psi = 0.0;
  while (p.sim.cracks().empty() && p.sim.step_count() < 2000000) {
    p.sim.step();
    if (p.sim.cracks().empty()) {
      ASSERT_NEAR(p.sim.particles().torque[1].x, -kKt * psi, 1e-6 * kKt * 1e-2);
      psi += W * dt;
    }
  }
  ASSERT_EQ(p.sim.cracks().size(), 1u);
  const CrackRecord& c = p.sim.cracks()[0];
  EXPECT_EQ(c.mode, CrackMode::Shear);
  // tau = |M_t| R / J = c at psi = c J / (R K_t) = 0.01 rad.
  EXPECT_GE(std::abs(c.Mt) / kKt, 1e-2 * (1 - 1e-9));
  EXPECT_LE(std::abs(c.Mt) / kKt, 1e-2 + W * dt);
  EXPECT_NEAR(c.energy.twisting, c.Mt * c.Mt / (2 * kKt), 1e-15);
}

// --- 2D planar mode: disks with a slab bond, A = 2 R t, I = 2/3 R^3 t (§4.1) ---

TEST(TwoDisk, SlabStiffnessAndPullBreakIndependentOfThickness) {
  for (const double t : {1.0, 1e-3}) {
    Pair p = make_pair(true, t);
    const ParallelBond::Section st = section_of(p.sim);
    // K_n = E_bar (2 R t) / (2 R) = E_bar t: 1e10 N/m at t = 1 m, 1e7 N/m at t = 1 mm (§8.4).
    EXPECT_NEAR(st.kn, 10e9 * t, 1e-6 * 10e9 * t);
    EXPECT_NEAR(st.kb, 10e9 / (2 * kR) * (2.0 / 3.0) * kR * kR * kR * t, 1e-12 * t);
    const double V = 1e-3;
    p.sim.particles_mut().drive_vel[1] = {V, 0, 0};
    while (p.sim.cracks().empty() && p.sim.step_count() < 2000000) p.sim.step();
    ASSERT_EQ(p.sim.cracks().size(), 1u);
    const CrackRecord& c = p.sim.cracks()[0];
    EXPECT_EQ(c.mode, CrackMode::Tensile);
    // Same strength, same strain: break at 2 um whatever the thickness; stress -Fn/A = 20 MPa.
    EXPECT_NEAR(-c.Fn / st.kn, 2e-6, V * p.sim.time_step());
    EXPECT_NEAR(-c.Fn / (2 * kR * t), 20e6, 20e6 * V * p.sim.time_step() / 2e-6 + 1);
  }
}

TEST(TwoDisk, BendingAboutZBreaksInTension) {
  Pair p = make_pair(true, 1.0);
  const double W = 2.0;
  p.sim.particles_mut().drive_angvel[0] = {0, 0, -0.5 * W};
  p.sim.particles_mut().drive_angvel[1] = {0, 0, 0.5 * W};
  const double kb = section_of(p.sim).kb;
  while (p.sim.cracks().empty() && p.sim.step_count() < 2000000) p.sim.step();
  ASSERT_EQ(p.sim.cracks().size(), 1u);
  const CrackRecord& c = p.sim.cracks()[0];
  EXPECT_EQ(c.mode, CrackMode::Tensile);
  // sigma = M R / I = sigma_c with I = 2/3 R^3 t: M = 20e6 * (2/3) R^2 t, theta = M / K_b.
  const double m_break = 20e6 * (2.0 / 3.0) * kR * kR;
  EXPECT_GE(c.Mb, m_break * (1 - 1e-9));
  EXPECT_LE(c.Mb, m_break + kb * W * p.sim.time_step());
  EXPECT_EQ(c.Mt, 0.0);
  EXPECT_EQ(c.energy.twisting, 0.0);
}

TEST(TwoDisk, MotionStaysInThePlane) {
  // A free disk pushed by a bond with out-of-plane-looking inputs stays in the plane.
  ParticleStore ps(Dimension::Two, 1e-3);
  ps.add({.tag = 1, .position = {0, 0, 0}, .radius = kR, .density = 2650, .motion = Motion::Fixed});
  ps.add({.tag = 2,
          .position = {2 * kR, 0, 0},
          .radius = kR,
          .density = 2650,
          .velocity = {0.01, 0.02, 0},
          .angular_velocity = {0, 0, 30}});
  EngineConfig cfg;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.add_bond<ParallelBond>(1, 2);
  sim.run(5000);
  EXPECT_EQ(sim.particles().pos_rad[1].x.z, 0.0);
  EXPECT_EQ(sim.particles().angvel[1].x, 0.0);
  EXPECT_EQ(sim.particles().angvel[1].y, 0.0);
  EXPECT_NE(sim.particles().angle[1], 0.0);
}

// The parallel bond derives its section at every step from its grains' radii (R_bar = lambda
// min(R1, R2), k_n = E_bar / (R1 + R2)) with one more division (ParallelBond::section): 1 / A,
// R_bar / I and R_bar / J must be those of the disc (3D) or the slab (2D, no twist), within 8
// epsilon (at most six roundings of 0.5 ulp after the division; k_n's sum and division, and the
// test's own 10 GPa / 1.1 mm, add three more to the stiffnesses).
TEST(ParallelBondSection, StressCoefficientsAreThoseOfTheSection) {
  const double tol = 8 * std::numeric_limits<double>::epsilon();
  ParallelBond::Params p = ParallelBond::example_params();
  p.stiffness_ratio = 1.7;
  ParallelBond::prepare(p);
  // R_bar = min(R1, R2) = 0.43 mm (lambda = 1) and k_n = E_bar / (R1 + R2) = 10 GPa / 1.1 mm.
  const BondRadii radii{0.67e-3, 0.43e-3};
  for (const bool planar : {false, true}) {
    p.run = {.planar = planar, .thickness = 2.5e-3};
    const ParallelBond::Section c = ParallelBond::section(p, radii);
    const double r = 0.43e-3, t = p.run.thickness;
    const double area = planar ? 2 * r * t : std::numbers::pi * r * r;
    const double inertia =
        planar ? 2.0 / 3.0 * r * r * r * t : std::numbers::pi / 4 * r * r * r * r;
    const double polar = planar ? 0.0 : 2 * inertia;
    const double kn_area = 10e9 / 1.1e-3, kn = kn_area * area;
    EXPECT_NEAR(c.kn, kn, tol * kn);
    EXPECT_NEAR(c.ks, kn / 1.7, tol * kn / 1.7);
    EXPECT_NEAR(c.kb, kn_area * inertia, tol * kn_area * inertia);
    EXPECT_NEAR(c.kt, kn_area / 1.7 * polar, tol * kn_area * polar);
    EXPECT_NEAR(c.inv_area, 1 / area, tol / area);
    EXPECT_NEAR(c.bend_coeff, r / inertia, tol * r / inertia);
    if (planar)
      EXPECT_EQ(c.twist_coeff, 0.0);
    else
      EXPECT_NEAR(c.twist_coeff, r / polar, tol * r / polar);
  }
}

namespace {

// Two bonded spheres 10 um apart (no contact while they ring), free, with bond dashpots of ratios
// beta_n and beta_s; particle 2 starts with velocity v2, particle 1 at rest.
Simulation damped_bonded_pair(double beta_n, double beta_s, Vec3 v2, bool driven,
                              double time_step = 0.0) {
  ParticleStore ps(Dimension::Three, 1.0);
  ParticleSpec a{.tag = 1, .position = {0, 0, 0}, .radius = kR, .density = 2650};
  ParticleSpec b{
      .tag = 2, .position = {2 * kR + 1e-5, 0, 0}, .radius = kR, .density = 2650, .velocity = v2};
  if (driven) a.motion = b.motion = Motion::Driven;
  ps.add(a);
  ps.add(b);
  EngineConfig cfg;
  cfg.energy_interval = 0;
  cfg.bond_normal_damping_ratio = beta_n;
  cfg.bond_shear_damping_ratio = beta_s;
  cfg.time_step = time_step;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.set_bond_params<ParallelBond>({});
  sim.add_bond<ParallelBond>(1, 2);
  sim.initialise();
  if (driven) sim.particles_mut().drive_vel[1] = v2;
  return sim;
}

}  // namespace

// A bond's section follows from its grains' radii and its law's parameters at every step, so
// the parameters cannot change under installed bonds: the engine refuses, naming the law.
TEST(ParallelBondSection, ParametersCannotChangeOnceBondsAreInstalled) {
  Simulation sim = damped_bonded_pair(0.0, 0.0, {}, false);
  ParallelBond::Params stiffer;
  stiffer.modulus = 2 * stiffer.modulus;
  try {
    sim.set_bond_params<ParallelBond>(stiffer);
    FAIL() << "new parameters were accepted under an installed bond";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("parallel_bond"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1 intact bonds"), std::string::npos) << e.what();
  }
  const auto& set = std::get<BondSet<ParallelBond>>(sim.bonds());
  EXPECT_EQ(set.params.modulus, ParallelBond::Params{}.modulus);
}

TEST(BondDashpot, AddsMinusCTimesTheRelativeVelocity) {
  // Driven grains, so the two runs see the same motion: the forces differ by the dashpot alone,
  // -c_n v_n n - c_s v_t with c = 2 beta sqrt(m* k), m* = m / 2.
  const Vec3 v2{2e-3, -1e-3, 0.5e-3};
  Simulation plain = damped_bonded_pair(0.0, 0.0, v2, true);
  Simulation damped = damped_bonded_pair(0.2, 0.1, v2, true);
  const auto& set = std::get<BondSet<ParallelBond>>(damped.bonds());
  const BondRadii radii = damped.bond_radii(set.pairs.first[0], set.pairs.second[0]);
  const double kn = ParallelBond::normal_stiffness(set.params, set.state[0], radii);
  const double ks = ParallelBond::shear_stiffness(set.params, set.state[0], radii);
  const double m = damped.particles().mass[1], ms = 0.5 * m;
  const double cn = 2 * 0.2 * std::sqrt(ms * kn), cs = 2 * 0.1 * std::sqrt(ms * ks);
  for (int k = 0; k < 3; ++k) {
    // The normal of the step: the branch at its start (it tilts as particle 2 moves sideways).
    const Vec3 n = unit(damped.particles().pos_rad[1].x - damped.particles().pos_rad[0].x);
    const Vec3 vn = n * dot(v2, n), vt = v2 - vn;
    plain.step();
    damped.step();
    const Vec3 d = damped.particles().force[1] - plain.particles().force[1];
    const Vec3 expected = vn * -cn - vt * cs;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(d[c], expected[c], 1e-12 * cn * norm(v2)) << k;
  }
}

TEST(BondDashpot, AxialRingingDecaysAtTheCriticalDampingRatio) {
  // Free ringing along the bond: successive maxima of the stretch fall by
  // exp(-2 pi beta / sqrt(1 - beta^2)), and the ledger books the kinetic energy lost as viscous.
  // k_n = 7.854e6 N/m and m* = m / 2 ring with a period of 1.87 us: 200 steps per period.
  const double beta = 0.05, m = 2650 * 4.0 / 3.0 * std::numbers::pi * kR * kR * kR;
  const double period = 2 * std::numbers::pi * std::sqrt(0.5 * m / kKn);
  Simulation sim = damped_bonded_pair(beta, 0.0, {1e-3, 0, 0}, false, period / 200);
  sim.request_energy_sample();
  sim.step();
  const double e0 = sim.ledger().stored();
  const double d0 = 2 * kR + 1e-5;
  std::vector<double> peaks;
  double before = 0.0, now = 0.0;
  for (int k = 0; k < 200000 && peaks.size() < 4; ++k) {
    sim.step();
    const double after = sim.particles().pos_rad[1].x.x - sim.particles().pos_rad[0].x.x - d0;
    if (k > 1 && now > before && now >= after && now > 0.0) peaks.push_back(now);
    before = now;
    now = after;
  }
  ASSERT_EQ(peaks.size(), 4u);
  const double expected = 2 * std::numbers::pi * beta / std::sqrt(1 - beta * beta);
  // A peak read at a step lies within (w dt)^2 / 8 = 1.2e-4 of the true one; the dashpot reads
  // the velocity half a step old, an error of order w dt in the decrement (7e-4 of it at
  // w dt = 0.031, halving with dt): within 2e-3.
  const double measured = std::log(peaks[0] / peaks[3]) / 3;
  EXPECT_NEAR(measured, expected, 2e-3 * expected) << "measured " << measured;
  sim.request_energy_sample();
  sim.step();
  const EnergyLedger& L = sim.ledger();
  // Half of e0 is the centre of mass's, which no force inside the pair removes; of the relative
  // motion's half, three and a half periods at this ratio leave about a tenth.
  EXPECT_GT(L.viscous_damping, 0.4 * e0);
  EXPECT_LT(L.viscous_damping, 0.5 * e0);
  // The same half-step lag between the booked loss c v^2 dt and the dashpot's work: O(w dt).
  EXPECT_LT(std::abs(L.residual), 2e-3 * e0) << "relative residual " << L.residual / e0;
}

TEST(BondDashpot, RatiosOutsideZeroToOneAreRefused) {
  EngineConfig cfg;
  cfg.bond_shear_damping_ratio = 1.5;
  ParticleStore ps(Dimension::Three, 1.0);
  EXPECT_THROW(Simulation(std::move(ps), cfg, make_contact_model<LinearContact>({}, {})),
               InputError);
}
