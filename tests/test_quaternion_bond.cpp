// The quaternion bond (physics.md §4.3, LAMMPS bpm/rotational) against numbers worked by hand,
// for the pair of tests/test_brittle_beam.cpp: R = 0.5 mm touching along x (d0 = 1 mm,
// R_b = 0.5 mm), E_b = 10 GPa, nu_b = 0.25 (G_b = 4 GPa), sigma_t,b = c_b = 20 MPa:
//   K_r = E A / d0 = 7.854e6 N/m, K_s = G A / d0 = 3.1416e6 N/m, K_b = E I / d0 = 0.4909 N m,
//   K_t = G J / d0 = 0.3927 N m; the index B = <-F_n> / (sigma A) + F_s / (c A) +
//   M_b R_b / (sigma I) + M_t R_b / (c J).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <tuple>
#include <type_traits>

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
  EXPECT_EQ(q.state.kr, b.state.kr);
  EXPECT_EQ(q.state.kb, b.state.kb);
  EXPECT_NEAR(q.state.ks, kKs, 1e-12 * kKs);
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
    EXPECT_NEAR(s.failure.energy.total(), QuaternionBond::energy(s.state).total(), 1e-30);
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
