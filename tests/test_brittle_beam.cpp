// The brittle beam (docs/physics.md §4.2) against numbers worked by hand: two spheres of R = 0.5 mm
// touching along x (d0 = L = 1 mm, R_b = 0.5 mm), E_b = 10 GPa, nu_b = 0.25 (G_b = 4 GPa):
//   A = pi R_b^2 = 7.854e-7 m^2, I = pi R_b^4 / 4 = 4.909e-14 m^4, J = 2 I,
//   K_r = E A / L = 7.854e6 N/m, K_s = G A / L = 3.1416e6 N/m,
//   K_b = E I / L = 0.4909 N m/rad, K_t = G J / L = 0.3927 N m/rad.
// Each mode is applied on its own, by placing and turning particle 2 (the law is total: forces
// follow from the configuration), and the failure load of each mode is predicted from
// sigma = -F_n / A + M_b R_b / I, tau = F_s / A + M_t R_b / J and the Mohr-Coulomb rule.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "breccia/engine/simulation.hpp"
#include "breccia/law/brittle_beam.hpp"
#include "pair_harness.hpp"

using namespace breccia;
using namespace breccia::test;

namespace {

constexpr double kR = 0.5e-3, kL = 1e-3, kE = 10e9, kG = 4e9;
constexpr double kPi = std::numbers::pi;
constexpr double kA = kPi * kR * kR, kI = 0.25 * kPi * kR * kR * kR * kR, kJ = 2 * kI;
constexpr double kKr = kE * kA / kL, kKs = kG * kA / kL, kKb = kE * kI / kL, kKt = kG * kJ / kL;

PairStepper<BrittleBeam> touching_beam(double cohesion = 20e6, double cutoff = 1.0) {
  PairStepper<BrittleBeam> s;
  s.params.modulus = kE;
  s.params.poisson_ratio = 0.25;
  s.params.cohesion = cohesion;
  s.params.tan_friction = 1.0;
  s.params.tensile_cutoff = cutoff;
  s.a.R = s.b.R = kR;
  s.a.x = {0, 0, 0};
  s.b.x = {kL, 0, 0};
  s.install();
  return s;
}

// Relative tolerance of the stiffness checks: the total formulation's second-order terms at the
// 1e-6 deformations used (and round-off far below that).
constexpr double kTol = 1e-5;

}  // namespace

TEST(BrittleBeam, StiffnessesAreThoseOfTheBeam) {
  auto s = touching_beam();
  EXPECT_NEAR(BrittleBeam::section(s.params, s.state, s.radii()).kr, kKr, 1e-12 * kKr);
  EXPECT_NEAR(BrittleBeam::section(s.params, s.state, s.radii()).ks, kKs, 1e-12 * kKs);
  EXPECT_NEAR(BrittleBeam::section(s.params, s.state, s.radii()).kb, kKb, 1e-12 * kKb);
  EXPECT_NEAR(BrittleBeam::section(s.params, s.state, s.radii()).kt, kKt, 1e-12 * kKt);
  EXPECT_NEAR(BrittleBeam::moduli(s.params).shear, kG, 1.0);
  // ESyS's bending factor 0.5 halves the bending stiffness, nothing else.
  auto h = touching_beam();
  h.params.bending_factor = 0.5;
  h.install();
  EXPECT_NEAR(BrittleBeam::section(h.params, h.state, h.radii()).kb, 0.5 * kKb, 1e-12 * kKb);
  EXPECT_EQ(BrittleBeam::section(h.params, h.state, h.radii()).kr,
            BrittleBeam::section(s.params, s.state, s.radii()).kr);
}

TEST(BrittleBeam, StretchPullsWithTheAxialStiffness) {
  auto s = touching_beam();
  const double u = 1e-9;
  s.b.x.x += u;
  const PairResult r = s.evaluate();
  EXPECT_NEAR(r.f2.x, -kKr * u, kTol * kKr * u);
  EXPECT_NEAR(r.f2.y, 0.0, 1e-12 * kKr * u);
  EXPECT_NEAR(norm(r.couple), 0.0, 1e-15);
  EXPECT_NEAR(s.energy(), 0.5 * kKr * u * u, kTol * 0.5 * kKr * u * u);
}

TEST(BrittleBeam, LateralOffsetShearsWithoutBending) {
  // Particle 2 moved by v along y on the arc of radius d0 (no stretch): gamma = v / d0, the
  // shear force K_s d0 gamma pushes it back, and no couple acts.
  auto s = touching_beam();
  const double v = 1e-9, alpha = v / kL;
  s.b.x = {kL * std::cos(alpha), kL * std::sin(alpha), 0};
  const PairResult r = s.evaluate();
  EXPECT_NEAR(norm(r.f2), kKs * v, kTol * kKs * v);
  EXPECT_LT(r.f2.y, 0.0);
  EXPECT_NEAR(norm(r.couple), 0.0, 1e-6 * kKs * v * kR);
  // The lever arms give particle 1 the torque of -F at the contact point, R1 along x.
  EXPECT_NEAR(r.t1.z, kR * kKs * v, kTol * kR * kKs * v);
}

TEST(BrittleBeam, RelativeRotationBendsAndShears) {
  // Particle 2 turned by theta about z: the bending couple -chi K_b theta and the
  // rotation-induced shear K_s d0 theta / 2 along +y on particle 2 (docs/physics.md §4.2, 2D form).
  for (const double chi : {1.0, 0.5}) {
    auto s = touching_beam();
    s.params.bending_factor = chi;
    s.install();
    const double theta = 1e-6;
    s.b.q = from_axis_angle({0, 0, 1}, theta);
    const PairResult r = s.evaluate();
    EXPECT_NEAR(r.couple.z, -chi * kKb * theta, kTol * kKb * theta) << chi;
    EXPECT_NEAR(r.f2.y, 0.5 * kKs * kL * theta, kTol * kKs * kL * theta) << chi;
    EXPECT_NEAR(r.f2.x, 0.0, 1e-9 * kKs * kL * theta);
    EXPECT_NEAR(s.state.bend_moment, chi * kKb * theta, kTol * kKb * theta);
  }
}

TEST(BrittleBeam, RelativeTwistTwists) {
  auto s = touching_beam();
  const double psi = 1e-6;
  s.b.q = from_axis_angle({1, 0, 0}, psi);
  const PairResult r = s.evaluate();
  EXPECT_NEAR(r.couple.x, -kKt * psi, kTol * kKt * psi);
  EXPECT_NEAR(norm(r.f2), 0.0, 1e-9 * kKs * kL * psi);
  EXPECT_NEAR(s.energy(), 0.5 * kKt * psi * psi, kTol * 0.5 * kKt * psi * psi);
}

TEST(BrittleBeam, TurningBothGrainsTogetherLoadsNothing) {
  // The same rotation of both grains about the branch's mid-point is a rigid motion.
  auto s = touching_beam();
  const Quat q = from_axis_angle(unit({0.3, -0.5, 0.8}), 0.4);
  const Vec3 mid{0.5 * kL, 0, 0};
  s.a.x = mid + rotate(q, s.a.x - mid);
  s.b.x = mid + rotate(q, s.b.x - mid);
  s.a.q = s.b.q = q;
  const PairResult r = s.evaluate();
  EXPECT_LT(norm(r.f2), 1e-15 * kKr * kL * 16);
  EXPECT_LT(norm(r.couple), 1e-12);
}

// Failure at the predicted load: just below it the beam holds, just above it breaks in the
// predicted mode, releasing the energy it stored.
TEST(BrittleBeam, BreaksInTensionWhereSigmaReachesTheCutOff) {
  // sigma = E u / L; tensile when sigma tan(phi) / c > T: u_c = T c L / (E tan(phi)) = 2 um.
  const double uc = 20e6 * kL / kE;
  auto hold = touching_beam();
  hold.b.x.x += 0.99 * uc;
  hold.evaluate();
  EXPECT_FALSE(hold.failure.broken);
  auto s = touching_beam();
  s.b.x.x += 1.01 * uc;
  s.evaluate();
  ASSERT_TRUE(s.failure.broken);
  EXPECT_EQ(s.failure.mode, CrackMode::Tensile);
  EXPECT_NEAR(s.failure.sigma, 1.01 * 20e6, 1e-6 * 20e6);
  EXPECT_NEAR(s.failure.ratio_t, 1.01, 1e-6);
  const double u = 1.01 * uc;
  EXPECT_NEAR(s.failure.energy.tension, 0.5 * kKr * u * u, 1e-6 * kKr * u * u);
  // A cut-off of 0.5 halves the tensile strength.
  auto half = touching_beam(20e6, 0.5);
  half.b.x.x += 0.51 * uc;
  half.evaluate();
  EXPECT_TRUE(half.failure.broken);
  EXPECT_EQ(half.failure.mode, CrackMode::Tensile);
}

TEST(BrittleBeam, BreaksInShearWhereTauReachesTheCohesion) {
  // On the arc (no stretch, sigma = 0): tau = K_s d0 alpha / A = G alpha; shear at alpha = c / G.
  const double ac = 20e6 / kG;
  for (const double f : {0.99, 1.01}) {
    auto s = touching_beam();
    s.b.x = {kL * std::cos(f * ac), kL * std::sin(f * ac), 0};
    s.evaluate();
    EXPECT_EQ(s.failure.broken, f > 1.0) << f;
    if (s.failure.broken) {
      EXPECT_EQ(s.failure.mode, CrackMode::Shear);
      EXPECT_NEAR(s.failure.tau, kG * f * ac, 1e-6 * kG * ac);
      const double fs = kKs * kL * f * ac;
      EXPECT_NEAR(s.failure.energy.shear, 0.5 * fs * fs / kKs, 1e-6 * fs * fs / kKs);
    }
  }
}

TEST(BrittleBeam, BendingBreaksTheRimInTension) {
  // Turning particle 2 by theta: sigma = chi E R_b theta / L (5e9 theta) and tau = G theta / 2
  // (2e9 theta). With T = 0.2 the tensile cut-off sigma > 4 MPa comes first, at
  // theta = 8e-4 rad, where tau + sigma = 5.6 MPa < c.
  const double tc = 0.2 * 20e6 * kL / (kE * kR);
  for (const double f : {0.99, 1.01}) {
    auto s = touching_beam(20e6, 0.2);
    s.b.q = from_axis_angle({0, 1, 0}, f * tc);
    s.evaluate();
    EXPECT_EQ(s.failure.broken, f > 1.0) << f;
    if (s.failure.broken) {
      EXPECT_EQ(s.failure.mode, CrackMode::Tensile);
      EXPECT_NEAR(s.failure.Mb, kKb * f * tc, 1e-6 * kKb * tc);
      EXPECT_NEAR(s.failure.energy.bending, 0.5 * kKb * f * f * tc * tc, 1e-6 * kKb * tc * tc);
    }
  }
  // With T = 1 the Coulomb line is reached first: tau > c - sigma at 7e9 theta = c.
  const double ts = 20e6 / (kE * kR / kL + 0.5 * kG);
  for (const double f : {0.99, 1.01}) {
    auto s = touching_beam();
    s.b.q = from_axis_angle({0, 1, 0}, f * ts);
    s.evaluate();
    EXPECT_EQ(s.failure.broken, f > 1.0) << f;
    if (s.failure.broken) {
      EXPECT_EQ(s.failure.mode, CrackMode::Shear);
    }
  }
}

TEST(BrittleBeam, TwistingBreaksInShear) {
  // tau = K_t psi R_b / J = G R_b psi / L (2e9 psi): shear at psi = c L / (G R_b) = 0.01 rad.
  const double pc = 20e6 * kL / (kG * kR);
  for (const double f : {0.99, 1.01}) {
    auto s = touching_beam();
    s.b.q = from_axis_angle({1, 0, 0}, f * pc);
    s.evaluate();
    EXPECT_EQ(s.failure.broken, f > 1.0) << f;
    if (s.failure.broken) {
      EXPECT_EQ(s.failure.mode, CrackMode::Shear);
      EXPECT_NEAR(s.failure.Mt, kKt * f * pc, 1e-6 * kKt * pc);
      EXPECT_NEAR(s.failure.energy.twisting, 0.5 * kKt * f * f * pc * pc, 1e-6 * kKt * pc * pc);
    }
  }
}

TEST(BrittleBeam, PlanarBeamIsASlab) {
  // 2D: A = 2 R_b t, I = 2/3 R_b^3 t, no twist; a disk turned about z bends the slab.
  PairStepper<BrittleBeam> s;
  s.params.modulus = kE;
  s.planar = true;
  s.thickness = 1e-3;
  s.a.R = s.b.R = kR;
  s.b.x = {kL, 0, 0};
  s.install();
  const double area = 2 * kR * 1e-3, inertia = 2.0 / 3.0 * kR * kR * kR * 1e-3;
  EXPECT_NEAR(BrittleBeam::section(s.params, s.state, s.radii()).kr, kE * area / kL,
              1e-12 * kE * area / kL);
  EXPECT_NEAR(BrittleBeam::section(s.params, s.state, s.radii()).kb, kE * inertia / kL,
              1e-12 * kE * inertia / kL);
  EXPECT_EQ(BrittleBeam::section(s.params, s.state, s.radii()).kt, 0.0);
  const double theta = 1e-6;
  s.b.q = from_axis_angle({0, 0, 1}, theta);
  const PairResult r = s.evaluate();
  EXPECT_NEAR(r.couple.z, -kE * inertia / kL * theta, kTol * kE * inertia / kL * theta);
}

TEST(BrittleBeam, UnequalGrainsAcrossAGapActAtTheBeamPoint) {
  // R1 = 0.3 mm, R2 = 0.7 mm, 2 um apart: the beam meets the crack plane at
  // x1 + d R1 / (R1 + R2) (§4.2 step 8), not at the middle of the gap. A lateral offset's shear
  // force F then turns particle 1 with the arm 0.3 d.
  PairStepper<BrittleBeam> s;
  s.a.R = 0.3e-3;
  s.b.R = 0.7e-3;
  const double d = 1.002e-3, alpha = 1e-6;
  s.b.x = {d, 0, 0};
  s.install();
  s.b.x = {d * std::cos(alpha), d * std::sin(alpha), 0};
  const PairResult r = s.evaluate();
  const Vec3 arm = unit(s.b.x) * (0.3 * d);
  const Vec3 expected = cross(arm, -r.f2);
  EXPECT_NEAR(r.t1.z, expected.z, 1e-9 * norm(expected));
  EXPECT_NEAR(r.t1.z + r.t2.z + cross(s.b.x, r.f2).z, 0.0, 1e-9 * norm(expected));
  // A crack there is placed at the beam point too: 0.3 d from particle 1, which lies
  // 0.3 d - (R1 + gap / 2) = -0.4 um from the middle of the gap.
  s.params.cohesion = 1.0;
  s.evaluate();
  ASSERT_TRUE(s.failure.broken);
  EXPECT_NEAR(s.failure.point_shift, 0.3 * d - (0.3e-3 + 1e-6), 1e-15);
}

// ---- in the engine ----

namespace {

Simulation beam_pair(bool planar, double overlap, bool contact_while_bonded, Vec3 v2 = {},
                     Vec3 w2 = {}, Motion motion = Motion::Driven) {
  ParticleStore ps(planar ? Dimension::Two : Dimension::Three, 1e-3);
  ps.add({.tag = 1, .position = {0, 0, 0}, .radius = kR, .density = 2650, .motion = motion});
  ps.add({.tag = 2,
          .position = {2 * kR - overlap, 0, 0},
          .radius = kR,
          .density = 2650,
          .velocity = v2,
          .angular_velocity = w2,
          .motion = motion});
  EngineConfig cfg;
  cfg.energy_interval = 10;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  BrittleBeam::Params p;
  p.modulus = kE;
  p.cohesion = 1e12;  // elastic
  p.contact_while_bonded = contact_while_bonded;
  sim.set_bond_params<BrittleBeam>(p);
  sim.add_bond<BrittleBeam>(1, 2);
  sim.initialise();
  return sim;
}

}  // namespace

TEST(BrittleBeamEngine, ContactActsBesideTheBondUnlessTheLawExcludesIt) {
  // Two held grains overlapping by 1 um, bonded stress-free: the linear contact pushes them
  // apart with k_n delta (k_n = A E_c / L, A = pi r^2, L = 2 r) unless contact_while_bonded is
  // false, as in ESyS-Particle.
  const double delta = 1e-6;
  Simulation with = beam_pair(false, delta, true);
  with.step();
  const double kn = kPi * kR * kR * LinearContact::Params{}.modulus / (2 * kR);  // A E_c / L
  EXPECT_NEAR(with.particles().force[1].x, kn * delta, 1e-6 * kn * delta);
  Simulation without = beam_pair(false, delta, false);
  without.step();
  EXPECT_EQ(norm(without.particles().force[1]), 0.0);
}

TEST(BrittleBeamEngine, FreeBondedPairKeepsItsEnergyIn3DAnd2D) {
  // Undamped free grains vibrating and spinning on an elastic beam, with no contact beside it
  // (a touching contact that opens and closes every cycle costs the leapfrog O(dt) per
  // crossing, which is the contact's, not the beam's): nothing does work or dissipates, so
  // kinetic plus stored energy stays constant. The total formulation is a potential to first
  // order in the deformation (strains near 1e-6 and bend angles below 1e-5 here), hence 1e-5.
  for (const bool planar : {false, true}) {
    Simulation sim = beam_pair(planar, 0.0, false, {1e-3, 2e-3, planar ? 0.0 : -1e-3},
                               {planar ? 0.0 : 3.0, planar ? 0.0 : -2.0, 5.0}, Motion::Free);
    sim.request_energy_sample();
    sim.step();
    const double e0 = sim.ledger().stored();
    double worst = 0.0, most_bond = 0.0;
    for (int k = 0; k < 50; ++k) {
      sim.run(100);
      sim.request_energy_sample();
      sim.step();
      worst = std::max(worst, std::abs(sim.ledger().stored() - e0));
      most_bond = std::max(most_bond, sim.ledger().bond.total());
    }
    EXPECT_GT(most_bond, 0.05 * e0) << "the beam must carry load";
    EXPECT_EQ(sim.ledger().friction + sim.ledger().deleted, 0.0);
    EXPECT_LT(worst, 1e-5 * e0) << (planar ? "2D" : "3D");
  }
}

// The section is derived at every step from the beam's radius and length through one division
// (beam::section). Its reciprocals and stiffnesses must be those of the section itself: each is
// a chain of at most six roundings (0.5 ulp each) after that division, so within 8 epsilon of
// the quotient taken directly. In 2D the slab has no polar moment: 1 / J and K_t read 0.
TEST(BeamSection, ReciprocalsAndStiffnessesAreThoseOfTheSection) {
  const double tol = 8 * std::numeric_limits<double>::epsilon();
  const double E = 12e9, G = 4.8e9, chi = 0.5;
  beam::BeamState s;
  const BondRadii radii{0.5e-3, 0.37e-3};  // R_b = min(R1, R2) = 0.37 mm
  s.d0 = 0.81e-3;
  struct Case {
    RunGeometry run;
    bool disc_for_planar_spheres;
    bool slab;
  };
  for (const Case& k :
       {Case{{.planar = false, .thickness = 1.0}, false, false},
        Case{{.planar = true, .thickness = 1e-3}, false, true},
        Case{{.planar = true, .planar_sphere = true, .thickness = 2e-3}, true, false},
        Case{{.planar = true, .planar_sphere = true, .thickness = 2e-3}, false, true}}) {
    const beam::BeamSection c =
        beam::section(s, {E, G, chi, k.disc_for_planar_spheres, true}, k.run, radii);
    const double r = 0.37e-3, t = k.run.thickness;
    EXPECT_EQ(c.radius, r);
    const double area = k.slab ? 2 * r * t : std::numbers::pi * r * r;
    const double inertia =
        k.slab ? 2.0 / 3.0 * r * r * r * t : 0.25 * std::numbers::pi * r * r * r * r;
    EXPECT_NEAR(c.area, area, tol * area);
    EXPECT_NEAR(c.inertia, inertia, tol * inertia);
    EXPECT_NEAR(c.inv_area, 1 / area, tol / area);
    EXPECT_NEAR(c.inv_inertia, 1 / inertia, tol / inertia);
    EXPECT_NEAR(c.kr, E * area / s.d0, tol * E * area / s.d0);
    EXPECT_NEAR(c.ks, G * area / s.d0, tol * G * area / s.d0);
    EXPECT_NEAR(c.kb, chi * E * inertia / s.d0, tol * chi * E * inertia / s.d0);
    if (k.slab) {
      EXPECT_EQ(c.polar, 0.0);
      EXPECT_EQ(c.inv_polar, 0.0);
      EXPECT_EQ(c.kt, 0.0);
    } else {
      EXPECT_NEAR(c.inv_polar, 1 / (2 * inertia), tol / (2 * inertia));
      EXPECT_NEAR(c.kt, G * 2 * inertia / s.d0, tol * G * 2 * inertia / s.d0);
    }
  }
}
