// The quaternion bond (docs/physics.md §4.3, LAMMPS bpm/rotational) against numbers worked by hand,
// for the pair of tests/test_brittle_beam.cpp: R = 0.5 mm touching along x (d0 = 1 mm,
// R_b = 0.5 mm), E_b = 10 GPa, nu_b = 0.25 (G_b = 4 GPa), sigma_t,b = c_b = 20 MPa:
//   K_r = E A / d0 = 7.854e6 N/m, K_s = G A / d0 = 3.1416e6 N/m, K_b = E I / d0 = 0.4909 N m,
//   K_t = G J / d0 = 0.3927 N m; the index B = <-F_n> / (sigma A) + F_s / (c A) +
//   M_b R_b / (sigma I) + M_t R_b / (c J).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>
#include <type_traits>
#include <utility>

#include "breccia/engine/simulation.hpp"
#include "breccia/law/brittle_beam.hpp"
#include "breccia/law/quaternion_bond.hpp"
#include "pair_harness.hpp"

using namespace breccia;
using namespace breccia::test;

namespace {

constexpr double kR = 0.5e-3, kL = 1e-3, kE = 10e9, kG = 4e9, kStrength = 20e6;
constexpr double kPi = std::numbers::pi;
constexpr double kA = kPi * kR * kR;
constexpr double kKr = kE * kA / kL, kKs = kG * kA / kL;

template <class Law = QuaternionBond>
PairStepper<Law> touching_pair(double strength = kStrength) {
  PairStepper<Law> s;
  s.params.modulus = kE;
  s.params.poisson_ratio = 0.25;
  if constexpr (std::is_same_v<Law, QuaternionBond>) {
    s.params.tensile_strength = strength;
    s.params.shear_strength = strength;
  } else {
    s.params.cohesion = 1e12;  // elastic
  }
  s.a.R = s.b.R = kR;
  s.b.x = {kL, 0, 0};
  s.install();
  return s;
}

// Particle 2 at distance d from particle 1, at angle alpha from the x axis in the xy plane.
void place(Body& b, double d, double alpha) {
  b.x = {d * std::cos(alpha), d * std::sin(alpha), 0};
}

}  // namespace

TEST(QuaternionBond, ShearArmsAreThePresentLength) {
  // Stretched by 1 % and turned by gamma: the quaternion bond's shear is K_s d gamma, the
  // brittle beam's K_s d0 gamma (ESyS); their ratio is d / d0 exactly. Stiffnesses agree.
  auto q = touching_pair(1e12);  // elastic
  auto b = touching_pair<BrittleBeam>();
  const beam::BeamSection qs = QuaternionBond::section(q.params, q.state, q.radii());
  const beam::BeamSection bs = BrittleBeam::section(b.params, b.state, b.radii());
  EXPECT_EQ(qs.kr, bs.kr);
  EXPECT_EQ(qs.kb, bs.kb);
  EXPECT_NEAR(qs.ks, kKs, 1e-12 * kKs);
  const double d = 1.01 * kL, gamma = 1e-6;
  place(q.b, d, gamma);
  place(b.b, d, gamma);
  q.evaluate();
  b.evaluate();
  ASSERT_FALSE(q.failure.broken || b.failure.broken);
  EXPECT_NEAR(q.state.shear_force, kKs * d * gamma, 1e-6 * kKs * d * gamma);
  EXPECT_NEAR(q.state.shear_force / b.state.shear_force, 1.01, 1e-9);
  // The rotation-induced shear: K_s d theta / 2, against K_s d0 theta / 2 for the beam.
  auto qr = touching_pair(1e12);
  place(qr.b, d, 0.0);
  qr.b.q = from_axis_angle({0, 0, 1}, 1e-6);
  const PairResult r = qr.evaluate();
  EXPECT_NEAR(r.f2.y, 0.5 * kKs * d * 1e-6, 1e-6 * kKs * d * 1e-6);
}

TEST(QuaternionBond, EachLoadAloneBreaksAtIndexOne) {
  // Tension: B = E u / (d0 sigma) -> u_c = 2 um, tensile.
  const double uc = kStrength * kL / kE;
  // Shear on the arc: B = G gamma / c -> gamma_c = 5e-3 rad, shear.
  const double gc = kStrength / kG;
  // Bending by theta: M_b R_b / (sigma I) = E R_b theta / (d0 sigma) = 250 theta, plus the
  // rotation-induced shear K_s d0 theta / 2 / (c A) = G theta / (2 c) = 100 theta:
  // theta_c = 1 / 350, tensile (250 > 100).
  const double tc = 1.0 / (kE * kR / (kL * kStrength) + kG / (2 * kStrength));
  // Twist: M_t R_b / (c J) = G R_b psi / (d0 c) = 100 psi -> psi_c = 0.01, shear.
  const double pc = kStrength * kL / (kG * kR);
  struct Case {
    const char* what;
    double critical;
    CrackMode mode;
    void (*apply)(PairStepper<QuaternionBond>&, double);
  };
  const Case cases[] = {
      {"tension", uc, CrackMode::Tensile,
       [](PairStepper<QuaternionBond>& s, double v) { s.b.x.x += v; }},
      {"shear", gc, CrackMode::Shear,
       [](PairStepper<QuaternionBond>& s, double v) { place(s.b, kL, v); }},
      {"bending", tc, CrackMode::Tensile,
       [](PairStepper<QuaternionBond>& s, double v) {
         s.b.q = from_axis_angle({0, 0, 1}, v);
       }},
      {"twist", pc, CrackMode::Shear,
       [](PairStepper<QuaternionBond>& s, double v) {
         s.b.q = from_axis_angle({1, 0, 0}, v);
       }},
  };
  for (const Case& c : cases) {
    auto hold = touching_pair();
    c.apply(hold, 0.99 * c.critical);
    hold.evaluate();
    EXPECT_FALSE(hold.failure.broken) << c.what;
    auto s = touching_pair();
    c.apply(s, 1.01 * c.critical);
    s.evaluate();
    ASSERT_TRUE(s.failure.broken) << c.what;
    EXPECT_EQ(s.failure.mode, c.mode) << c.what;
    EXPECT_NEAR(s.failure.ratio_t + s.failure.ratio_s, 1.01, 2e-4) << c.what;
    EXPECT_NEAR(s.failure.energy.total(),
                QuaternionBond::energy(s.params, s.state, s.radii()).total(), 1e-30);
  }
  // The stored energy at the tensile break is K_r u^2 / 2.
  auto t = touching_pair();
  t.b.x.x += 1.01 * uc;
  t.evaluate();
  EXPECT_NEAR(t.failure.energy.tension, 0.5 * kKr * 1.0201 * uc * uc, 1e-6 * kKr * uc * uc);
}

TEST(QuaternionBond, LoadsAddUpInTheIndex) {
  // Six tenths of the tensile strength and half the shear strength: B = 1.1, breaks; 0.45 and
  // 0.5: B = 0.95, holds (the stretch lengthens the shear arm by 1e-6, far inside the margins).
  const double uc = kStrength * kL / kE, gc = kStrength / kG;
  for (const auto& [u, g, breaks] : {std::tuple{0.6, 0.5, true}, std::tuple{0.45, 0.5, false}}) {
    auto s = touching_pair();
    place(s.b, kL + u * uc, g * gc);
    s.evaluate();
    EXPECT_EQ(s.failure.broken, breaks) << u;
  }
  // Compression: by default it does not count; as in LAMMPS (signed) it lowers the index.
  for (const bool signed_normal : {false, true}) {
    auto s = touching_pair();
    s.params.signed_normal = signed_normal;
    place(s.b, kL - 0.5 * uc, 1.2 * gc);
    s.evaluate();
    EXPECT_EQ(s.failure.broken, !signed_normal) << signed_normal;
  }
}

// ---- planar spheres (§4.3: a 2D run of them must be a 3D run confined to the plane) ----

namespace {

Simulation bent_chain(Dimension dim) {
  // Three spheres 20 um apart (no contact ever forms), bonded 1-2 and 2-3 at an angle, moving
  // and spinning in the xy plane.
  ParticleStore ps(dim, 1e-3, PlanarBody::PlanarSphere);
  const double R = 0.5e-3, gap = 20e-6;
  const Vec3 x2{2 * R + gap, 0, 0};
  const Vec3 x3 = x2 + Vec3{0.8, 0.6, 0} * (2 * R + gap);
  ps.add({.tag = 1, .position = {}, .radius = R, .density = 2650, .velocity = {1e-3, -2e-3, 0}});
  ps.add({.tag = 2,
          .position = x2,
          .radius = R,
          .density = 2650,
          .velocity = {-1e-3, 1e-3, 0},
          .angular_velocity = {0, 0, 4.0}});
  ps.add({.tag = 3,
          .position = x3,
          .radius = R,
          .density = 2650,
          .velocity = {0, 2e-3, 0},
          .angular_velocity = {0, 0, -3.0}});
  EngineConfig cfg;
  cfg.time_step = 2e-8;
  cfg.energy_interval = 0;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  QuaternionBond::Params p;
  p.modulus = kE;
  p.tensile_strength = p.shear_strength = 1e12;  // elastic
  sim.set_bond_params<QuaternionBond>(p);
  sim.add_bond<QuaternionBond>(1, 2);
  sim.add_bond<QuaternionBond>(2, 3);
  sim.initialise();
  return sim;
}

}  // namespace

TEST(QuaternionBond, PlanarSpheresIn2DMoveAsIn3D) {
  Simulation flat = bent_chain(Dimension::Two), solid = bent_chain(Dimension::Three);
  for (Simulation* s : {&flat, &solid}) {
    s->run(3000);
    s->request_energy_sample();
    s->step();
  }
  const ParticleStore &a = flat.particles(), &b = solid.particles();
  // The 2D run turns its grains by summed angles, the 3D run by quaternion products: their
  // orientations part by up to an ulp a step, 3000 x 2.2e-16 = 7e-13 rad, against relative
  // rotations of the bonded grains of about 1e-5 rad here, so the runs agree to ~1e-7 of the
  // motion, not to the last digit (measured: 2e-9).
  double v_scale = 0.0, x_scale = 0.0, w_scale = 0.0;
  for (std::size_t i = 0; i < 3; ++i) {
    v_scale = std::max(v_scale, norm(b.vel[i]));
    x_scale = std::max(x_scale, norm(b.displacement[i]));
    w_scale = std::max(w_scale, std::abs(b.angvel[i].z));
  }
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_LT(norm(a.displacement[i] - b.displacement[i]), 1e-7 * x_scale) << i;
    EXPECT_LT(norm(a.vel[i] - b.vel[i]), 1e-7 * v_scale) << i;
    EXPECT_NEAR(a.angvel[i].z, b.angvel[i].z, 1e-7 * w_scale) << i;
    EXPECT_LT(std::abs(b.pos_rad[i].x.z), 1e-20) << i;
  }
  EXPECT_GT(x_scale, 1e-8);
  // The bonds carried load and the two runs stored the same energy in them: the planar
  // spheres' bonds have the 3D disc section, not the disks' slab.
  const double e3 = solid.ledger().bond.total();
  EXPECT_GT(e3, 0.01 * solid.ledger().kinetic());
  EXPECT_NEAR(flat.ledger().bond.total(), e3, 1e-6 * e3);
}

TEST(QuaternionBond, ThreeGrainsShareATurnedGrainAsTheFormulasSay) {
  // An L of three held grains: 2 at +x and 3 at +y of grain 1, each touching it and bonded to
  // it. Grain 1 turns about x by theta (driven spin, one step): bond 1-2 is twisted by theta,
  // bond 1-3 is bent by theta, and grain 1's rim at +y moves along +z by R theta. By hand
  // (d = d0 = 2R, quaternion-bond shear arm d):
  //   M_1x = -(K_t + K_b + R K_s d / 2) theta,  M_2x = K_t theta,
  //   M_3x = (K_b - R K_s d / 2) theta,         F_3z = -F_1z = K_s d theta / 2,  F_2 = 0.
  // Terms of order theta^2 are 1e-6 of these at theta = 1e-6, hence the tolerance 1e-5.
  ParticleStore ps(Dimension::Three, 1e-3);
  const double dt = 1e-8, omega = 100.0, theta = omega * dt;
  ps.add({.tag = 1,
          .position = {},
          .radius = kR,
          .density = 2650,
          .angular_velocity = {omega, 0, 0},
          .motion = Motion::Driven});
  ps.add(
      {.tag = 2, .position = {kL, 0, 0}, .radius = kR, .density = 2650, .motion = Motion::Driven});
  ps.add(
      {.tag = 3, .position = {0, kL, 0}, .radius = kR, .density = 2650, .motion = Motion::Driven});
  EngineConfig cfg;
  cfg.time_step = dt;
  cfg.energy_interval = 0;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  QuaternionBond::Params p;
  p.modulus = kE;
  p.poisson_ratio = 0.25;
  p.tensile_strength = p.shear_strength = 1e12;  // elastic
  p.contact_while_bonded = false;
  sim.set_bond_params<QuaternionBond>(p);
  sim.add_bond<QuaternionBond>(1, 2);
  sim.add_bond<QuaternionBond>(1, 3);
  sim.initialise();
  sim.step();  // forces at the installed state (zero), then grain 1 turns by theta
  sim.step();  // forces at the turned state
  const double J = 0.5 * kPi * std::pow(kR, 4), I = 0.5 * J;
  const double Kt = kG * J / kL, Kb = kE * I / kL;
  const double shear = 0.5 * kKs * kL * theta, shear_moment = kR * shear;
  const ParticleStore& s = sim.particles();
  const double m1 = (Kt + Kb) * theta + shear_moment;
  EXPECT_NEAR(s.torque[0].x, -m1, 1e-5 * m1);
  EXPECT_NEAR(s.torque[1].x, Kt * theta, 1e-5 * Kt * theta);
  EXPECT_NEAR(s.torque[2].x, Kb * theta - shear_moment, 1e-5 * m1);
  EXPECT_NEAR(s.force[2].z, shear, 1e-5 * shear);
  EXPECT_NEAR(s.force[0].z, -shear, 1e-5 * shear);
  EXPECT_LT(norm(s.force[1]), 1e-5 * shear);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_LT(std::abs(s.torque[i].y) + std::abs(s.torque[i].z), 1e-5 * m1) << i;
    EXPECT_LT(std::abs(s.force[i].x) + std::abs(s.force[i].y), 1e-5 * shear) << i;
  }
}

namespace {

// Distance in units in the last place between two doubles of the same sign.
double ulps(double a, double b) {
  if (a == b) return 0.0;
  return std::abs(a - b) / std::abs(std::nextafter(b, 2.0 * b) - b);
}

}  // namespace

// The beam angles' atan2: the series on |y| <= x / 16 (bond rotations before breaking) and
// std::atan2 elsewhere. The series to t^13 truncates at t^15 / 15 < 1e-18 t; its division and
// six Horner steps round to about 1 ulp, so 2 ulp is the bound, over four decades of angle,
// both signs, the edge of the series' range and beyond it.
TEST(BeamAngle, AgreesWithAtan2WithinTwoUlp) {
  double worst = 0.0;
  for (double x : {1.0, 0.5, 1e-3, 3.7}) {
    for (int k = 0; k <= 4000; ++k) {
      const double t = std::pow(10.0, -8.0 + 7.0 * k / 4000.0);  // 1e-8 .. 0.1
      for (double sign : {1.0, -1.0}) {
        const double y = sign * t * x;
        const double exact = std::atan2(y, x);
        worst = std::max(worst, ulps(beam::bond_angle(y, x), exact));
      }
    }
    const double edge = 0.0625 * x;
    for (double y : {edge, std::nextafter(edge, 1.0), -edge, 0.0})
      worst = std::max(worst, ulps(beam::bond_angle(y, x), std::atan2(y, x)));
  }
  EXPECT_LE(worst, 2.0);
  // Outside the series' range it is std::atan2 itself: the far side and the axes.
  for (auto [y, x] : {std::pair{1.0, -1.0}, {0.3, 0.0}, {-0.2, -3.0}, {0.0, -1.0}, {2.0, 1.0}})
    EXPECT_EQ(beam::bond_angle(y, x), std::atan2(y, x)) << y << " " << x;
  // A series that dropped a term would miss by far more than 2 ulp at the edge.
  const double t = 0.0625, z = t * t;
  const double short_series = t * (1.0 - z / 3.0 + z * z / 5.0 - z * z * z / 7.0);
  EXPECT_GT(ulps(short_series, std::atan(t)), 2.0);
}

// The beam laws declare that they read the pair's shape, never its motion, so the pair pass
// hands them a geometry without velocities or masses. The same bent, twisted and stretched bond
// with and without its (large) motion must give the same loads to the bit.
template <class Law>
void expect_loads_ignore_motion() {
  static_assert(!law_needs_motion<Law>);
  const Vec3 x1{0, 0, 0}, x2{1.0002e-3, 0.0001e-3, -0.00005e-3};  // loads well below strength
  const BodyFrames installed{{1, 0, 0, 0}, {1, 0, 0, 0}};
  const typename Law::Params p = Law::example_params();
  typename Law::State with_motion =
      Law::install(p, pair_shape(x1, kR, {kL, 0, 0}, kR, false, 1.0), installed, 1, 1);
  typename Law::State shape_only = with_motion;
  const BodyFrames turned{normalized(Quat{1, 0.0001, -0.00005, 0.00015}),
                          normalized(Quat{1, -0.00005, 0.0002, 0})};
  const PairGeometry shape = pair_shape(x1, kR, x2, kR, false, 1.0);
  PairGeometry moving = shape;
  add_pair_motion(moving, {3, -1, 2}, {400, 50, -90}, {-2, 5, 1}, {-30, 800, 60}, 1e-6, 2e-6);
  BondFailure f1, f2;
  const PairForce a = Law::compute(p, with_motion, moving, turned, 1e-8, f1);
  const PairForce b = Law::compute(p, shape_only, shape, turned, 1e-8, f2);
  ASSERT_FALSE(f1.broken);
  EXPECT_NE(norm(a.force), 0.0);
  EXPECT_NE(norm(a.couple), 0.0);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(a.force[c], b.force[c]) << c;
    EXPECT_EQ(a.couple[c], b.couple[c]) << c;
  }
  EXPECT_EQ(f1.broken, f2.broken);
}

TEST(BeamLaws, LoadsDoNotReadThePairsMotion) {
  expect_loads_ignore_motion<QuaternionBond>();
  expect_loads_ignore_motion<BrittleBeam>();
}
