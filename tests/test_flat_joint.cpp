// The flat joint (docs/physics.md §4.6) against hand numbers: its elements tile the interface,
// each element breaks in tension and in shear at its own strength (one crack each, at its
// centroid), a half-broken interface resists bending fully one way and half the other, a fully
// broken one still resists rolling through its closed faces, an intact pair keeps its energy
// without damping, and bad parameters are refused by name. R = 0.5 mm, E* = 10 GPa
// (k_n = E* / 2R = 1e13 Pa/m), kappa* = 2.5, sigma_b = 20 MPa, c_b = 40 MPa.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "breccia/core/error.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/spec/experiment.hpp"
#include "pair_harness.hpp"

using namespace breccia;
using namespace breccia::test;

namespace {

constexpr double kR = 0.5e-3;
constexpr double kKn = 1e13;  // Pa/m
constexpr double kPi = std::numbers::pi;

struct Pair {
  Simulation sim;
};

// Two grains of radius R touching on x, both driven (the test prescribes their motion).
Pair make_pair(const FlatJoint::Params& params, bool planar = false, bool driven = true) {
  ParticleStore ps(planar ? Dimension::Two : Dimension::Three, 1e-3);
  ParticleSpec a{.tag = 1, .position = {0, 0, 0}, .radius = kR, .density = 2650};
  ParticleSpec b{.tag = 2, .position = {2 * kR, 0, 0}, .radius = kR, .density = 2650};
  if (driven) a.motion = b.motion = Motion::Driven;
  ps.add(a);
  ps.add(b);
  EngineConfig cfg;
  cfg.energy_interval = 0;
  cfg.local_damping = 0.0;
  Pair p{Simulation(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}))};
  p.sim.set_bond_params<FlatJoint>(params);
  p.sim.add_bond<FlatJoint>(1, 2);
  p.sim.initialise();
  return p;
}

double sum(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s;
}

}  // namespace

TEST(FlatJoint, ElementsTileTheInterface) {
  // 3D: N_r x N_alpha sectors cover the disc (A = pi R^2, I = pi R^4 / 4 about any diameter, no
  // first moment); 2D: N_r segments cover [-R, R] (A = 2R, I = 2 R^3 / 3 per unit thickness).
  // The cells of each element add up to it.
  for (const auto& [nr, na, planar] : {std::tuple{1, 3, false}, std::tuple{2, 4, false},
                                       std::tuple{1, 1, false}, std::tuple{3, 1, true}}) {
    FlatJoint::Params p;
    p.radial_elements = nr;
    p.circumferential_elements = na;
    p.run.planar = planar;
    FlatJoint::prepare(p);
    ASSERT_EQ(p.elements, planar ? nr : nr * na);
    flat::Moments total;
    for (int e = 0; e < p.elements; ++e) {
      const flat::ElementShape& s = p.shapes[e];
      total.a += s.whole.a;
      total.s1 += s.whole.s1;
      total.s2 += s.whole.s2;
      total.i11 += s.whole.i11;
      total.i12 += s.whole.i12;
      total.i22 += s.whole.i22;
      flat::Moments cells;
      for (const flat::Moments& c : s.cells) {
        cells.a += c.a;
        cells.i11 += c.i11;
      }
      EXPECT_NEAR(cells.a, s.whole.a, 1e-14);
      EXPECT_NEAR(cells.i11, s.whole.i11, 1e-14);
    }
    EXPECT_NEAR(total.a, planar ? 2.0 : kPi, 1e-14);
    EXPECT_NEAR(total.s1, 0.0, 1e-14);
    EXPECT_NEAR(total.s2, 0.0, 1e-14);
    EXPECT_NEAR(total.i11, planar ? 2.0 / 3.0 : kPi / 4, 1e-14);
    EXPECT_NEAR(total.i12, 0.0, 1e-14);
    EXPECT_NEAR(total.i22, planar ? 0.0 : kPi / 4, 1e-14);
  }
}

TEST(FlatJoint, PullBreaksEveryElementInTensionAtItsStrength) {
  // Pulled apart, the three sectors break in three steps in tension at sigma_b / k_n = 2 um,
  // each carrying sigma_b A / 3 (A = pi R^2) at its centroid, 2 R sin(60 deg) / pi = 0.551 R off
  // the axis; then the parted interface is released, with no further crack.
  Pair p = make_pair(FlatJoint::example_params());
  const double V = 1e-3;
  p.sim.particles_mut().drive_vel[1] = {V, 0, 0};
  const double dt = p.sim.time_step();
  while (p.sim.intact_bonds() > 0 && p.sim.step_count() < 2000000) p.sim.step();
  ASSERT_EQ(p.sim.cracks().size(), 3u);
  const double area = kPi * kR * kR / 3.0;
  const double centroid = 2.0 * kR * std::sin(kPi / 3) / kPi;
  std::vector<double> energies;
  for (const CrackRecord& c : p.sim.cracks()) {
    EXPECT_EQ(c.mode, CrackMode::Tensile);
    EXPECT_EQ(c.law, "flat_joint");
    const double stretch = -c.Fn / (kKn * area);
    EXPECT_GE(stretch, 2e-6 - 1e-15);
    EXPECT_LE(stretch, 2e-6 + 3 * V * dt);
    EXPECT_NEAR(c.sigma, 20e6, 20e6 * 3 * V * dt / 2e-6);
    EXPECT_NEAR(c.bond_radius, std::sqrt(area / kPi), 1e-15);
    const Vec3 off = c.position - Vec3{kR + 0.5 * stretch, 0, 0};
    EXPECT_NEAR(off.x, 0.0, 1e-9);
    EXPECT_NEAR(std::hypot(off.y, off.z), centroid, 1e-12);
    // Uniform tension: the element's energy is F_n^2 / (2 k_n A_e).
    EXPECT_NEAR(c.energy.total(), c.Fn * c.Fn / (2 * kKn * area), 1e-9 * c.energy.total());
    energies.push_back(c.energy.total());
  }
  // sigma_b^2 A / (2 k_n) in all.
  const double stored = 20e6 * 20e6 * kPi * kR * kR / (2 * kKn);
  EXPECT_NEAR(sum(energies), stored, stored * 6 * V * dt / 2e-6);
  EXPECT_EQ(p.sim.cracks()[2].step - p.sim.cracks()[0].step, 2u);
}

TEST(FlatJoint, SlidingBreaksEveryElementInShearAtTheCohesion) {
  // Slid sideways (no normal load), each element reaches tau = c_b = 40 MPa at
  // c_b / k_s = 10 um (k_s = k_n / 2.5) and breaks in shear; unbonded and unloaded, it then
  // carries nothing.
  Pair p = make_pair(FlatJoint::example_params());
  const double V = 1e-2;
  const double dt = p.sim.time_step();
  while (p.sim.cracks().size() < 3 && p.sim.step_count() < 2000000) {
    const Vec3 x = p.sim.particles().pos_rad[1].x;
    const double phi = std::atan2(x.y, x.x);
    p.sim.particles_mut().drive_vel[1] = Vec3{-std::sin(phi), std::cos(phi), 0} * V;
    p.sim.step();
  }
  ASSERT_EQ(p.sim.cracks().size(), 3u);
  const double area = kPi * kR * kR / 3.0, ks = kKn / 2.5 * area;
  for (const CrackRecord& c : p.sim.cracks()) {
    EXPECT_EQ(c.mode, CrackMode::Shear);
    EXPECT_GE(c.Fs / ks, 1e-5 - 1e-12);
    EXPECT_LE(c.Fs / ks, 1e-5 + 3 * V * dt);
    EXPECT_NEAR(c.tau, 40e6, 40e6 * 3 * V * dt / 1e-5);
    EXPECT_NEAR(c.energy.shear, c.Fs * c.Fs / (2 * ks), 1e-9 * c.energy.shear);
  }
  p.sim.step();
  EXPECT_NEAR(norm(p.sim.particles().force[1]), 0.0, 1e-9);
}

namespace {

// A 2D flat joint of two segments, [-R, 0] and [0, R], bonded or not as `bonded` says, pressed by
// delta and turned by theta (grain 2 about z) over 100 steps: the loads on grain 2 at rest there.
PairResult two_segment_interface(bool first_bonded, bool second_bonded, double delta,
                                 double theta) {
  PairStepper<FlatJoint> s;
  s.planar = true;
  s.thickness = 1e-3;
  s.params.radial_elements = 2;
  s.b.x = {2 * kR, 0, 0};
  s.install();
  s.state.bond[0] = first_bonded ? flat::kBonded : flat::kUnbonded;
  s.state.bond[1] = second_bonded ? flat::kBonded : flat::kUnbonded;
  s.evaluate();
  const int steps = 100;
  s.b.v = {-delta / (steps * s.dt), 0, 0};
  s.b.w = {0, 0, theta / (steps * s.dt)};
  for (int k = 0; k < steps; ++k) {
    s.move();
    s.evaluate();
  }
  s.b.v = {};
  s.b.w = {};
  return s.evaluate();
}

// [-R, 0] bonded and [0, R] unbonded, turned by theta: the couple on grain 2 about z.
double half_broken_couple(double theta) {
  return two_segment_interface(true, false, 0.0, theta).couple.z;
}

}  // namespace

TEST(FlatJoint, HalfBrokenInterfaceResistsBendingFullyOneWayAndHalfTheOther) {
  // Turning grain 2 by theta > 0 closes the side s > 0, where the unbonded element is: both
  // halves push back, M = -k_n I theta with I = 2 R^3 t / 3 as if intact. Turning it back opens
  // that side: only the bonded half carries, M = k_n I |theta| / 2.
  const double t = 1e-3, theta = 1e-4;
  const double full = kKn * 2.0 / 3.0 * kR * kR * kR * t * theta;
  EXPECT_NEAR(half_broken_couple(theta), -full, 1e-9 * full);
  EXPECT_NEAR(half_broken_couple(-theta), 0.5 * full, 1e-9 * full);
}

namespace {

// A broken (all-unbonded) 2D interface pressed by delta and turned by theta: the normal force on
// grain 2 along n and the couple about z.
std::pair<double, double> broken_interface(double delta, double theta) {
  const PairResult r = two_segment_interface(false, false, delta, theta);
  return {r.f2.x, r.couple.z};
}

}  // namespace

TEST(FlatJoint, BrokenInterfaceStillResistsRollingThroughItsFaces) {
  // Pressed by delta, the faces carry F = k_n 2R t delta. Turned by theta < delta / R they stay
  // closed and resist like the intact interface, M = -k_n I theta. Turned further, the closed
  // part shrinks to s > s0 = -delta / theta: F = k_n t int (delta + theta s) ds and
  // M = -k_n t int (delta + theta s) s ds over [s0, R], never beyond F R (the whole force at the
  // rim). A Hertz or linear contact of two spheres resists no rolling at all. The partly closed
  // element is integrated over 16 cells of h = R / 16, each counted whole when its centre is
  // closed: errors below k_n t theta h^2 / 4 in F and that times R in M.
  const double t = 1e-3, delta = 1e-7, kn = kKn;
  {
    const double theta = 0.5 * delta / kR;
    const auto [f, m] = broken_interface(delta, theta);
    const double f_ref = kn * 2 * kR * t * delta,
                 m_ref = -kn * 2.0 / 3.0 * kR * kR * kR * t * theta;
    EXPECT_NEAR(f, f_ref, 1e-9 * f_ref);
    EXPECT_NEAR(m, m_ref, 1e-9 * std::abs(m_ref));
  }
  const double theta = 4 * delta / kR, s0 = -delta / theta;
  const auto [f, m] = broken_interface(delta, theta);
  const auto p1 = [&](double s) { return delta * s + 0.5 * theta * s * s; };
  const auto p2 = [&](double s) { return 0.5 * delta * s * s + theta * s * s * s / 3.0; };
  const double f_ref = kn * t * (p1(kR) - p1(s0)), m_ref = -kn * t * (p2(kR) - p2(s0));
  const double h = kR / 16, f_tol = kn * t * theta * h * h / 4;
  EXPECT_NEAR(f, f_ref, f_tol);
  EXPECT_NEAR(m, m_ref, f_tol * kR);
  EXPECT_LT(std::abs(m), f * kR);
  EXPECT_GT(std::abs(m), 0.5 * f * kR) << "rocking on its edge";
}

TEST(FlatJoint, IntactPairKeepsItsEnergyWithoutDamping) {
  // Two free grains joined by an intact flat joint, set vibrating (stretch, shear, spin): with no
  // damping, kinetic plus stored energy stays constant. The ledger's residual is what remains of
  // the incremental shear's geometric non-linearity (as for the parallel bond, test_integrator).
  FlatJoint::Params params = FlatJoint::example_params();
  params.radial_elements = 2;
  params.circumferential_elements = 4;
  Pair p = make_pair(params, false, false);
  auto& ps = p.sim.particles_mut();
  ps.vel[1] = {2e-3, 1e-3, -5e-4};
  ps.angvel[1] = {3.0, -2.0, 4.0};
  ps.angvel[0] = {-1.0, 2.0, 0.5};
  p.sim.request_energy_sample();
  p.sim.step();
  const double e0 = p.sim.ledger().stored() + p.sim.ledger().kinetic_translational +
                    p.sim.ledger().kinetic_rotational;
  double worst = 0.0;
  for (int k = 0; k < 40; ++k) {
    p.sim.run(99);
    p.sim.request_energy_sample();
    p.sim.step();
    worst = std::max(worst, std::abs(p.sim.ledger().residual));
  }
  EXPECT_TRUE(p.sim.cracks().empty());
  EXPECT_GT(p.sim.ledger().stored(), 0.01 * e0) << "the bond takes part";
  EXPECT_LT(worst, 1e-6 * e0) << "relative residual " << worst / e0;
}

TEST(FlatJoint, BadParametersAreRefusedByName) {
  const auto refused = [](const std::string& body, const std::string& key,
                          const std::string& needle) {
    try {
      parse_experiment("[bond]\nlaw = \"flat_joint\"\n" + body, "fj.toml", {});
      ADD_FAILURE() << "accepted: " << body;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("fj.toml"), std::string::npos) << what;
      EXPECT_NE(what.find(key), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
  };
  refused("radial_elements = 2.5\n", "radial_elements", "whole number");
  refused("radial_elements = 9\n", "radial_elements", "8");
  refused("radial_elements = 3\ncircumferential_elements = 3\n", "circumferential_elements",
          "at most 8");
  refused("bonded_fraction = 0.8\ngapped_fraction = 0.3\ninstallation_gap = 1e-6\n",
          "gapped_fraction", "at most 1");
  refused("bonded_fraction = 0.5\ngapped_fraction = 0.3\n", "installation_gap", "> 0");
  refused("friction = -0.1\n", "friction", ">= 0");
  // Parameters built in C++ meet the same check when the engine takes them.
  {
    FlatJoint::Params p;
    p.radial_elements = 3;
    p.circumferential_elements = 3;
    try {
      make_pair(p);
      ADD_FAILURE() << "a 3 x 3 interface was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("at most 8"), std::string::npos) << e.what();
    }
  }
  // In 2D only N_r counts: 8 segments are allowed whatever N_alpha says.
  EXPECT_NO_THROW(parse_experiment(
      "[engine]\ndimension = 2\n[sample]\nshape = \"rectangle\"\n[bond]\nlaw = \"flat_joint\"\n"
      "radial_elements = 8\n",
      "fj.toml", {}));
}
