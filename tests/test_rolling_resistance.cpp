// Rolling and twisting resistance of contacts (docs/physics.md §3.5) against hand numbers: the
// spring stiffness k_s R^2 and the limit moment mu R F_n, the energy an elastic-plastic cycle
// dissipates, the dashpot, and grains rolling and spinning on a floor to rest.
#include <gtest/gtest.h>

#include <cmath>
#include <type_traits>
#include <variant>

#include "breccia/engine/simulation.hpp"
#include "pair_harness.hpp"

using namespace breccia;
using namespace breccia::test;

namespace {

// The linear law in its state layout with the moments (make_contact_model picks it in a run).
using RollingLinear = LinearContactLaw<true>;

// Two spheres of R = 0.5 mm overlapping by 1 um under the linear law (E_c = 10 GPa, kappa 2.5):
// k_n = pi r^2 E_c / (2R) = 7.854e6 N/m, F_n = 7.854 N, k_s = 3.1416e6 N/m; R = 0.25 mm, so the
// rolling stiffness k_s R^2 = 0.19635 N m/rad.
PairStepper<RollingLinear> pressed_pair(double mu_r, double mu_t) {
  PairStepper<RollingLinear> s;
  s.params.modulus = 10e9;
  s.params.stiffness_ratio = 2.5;
  s.params.friction = 0.5;
  s.params.rolling_friction = mu_r;
  s.params.twisting_friction = mu_t;
  s.b.x = {1e-3 - 1e-6, 0, 0};
  s.dt = 1e-6;
  return s;
}
constexpr double kFn = 7.853981633974483;
constexpr double kKr = 7.853981633974483e6 / 2.5 * 0.25e-3 * 0.25e-3;

// Turns particle 2 at w about `axis` for `steps` steps (positions stay: only the couple is read).
Vec3 turn(PairStepper<RollingLinear>& s, const Vec3& w, int steps) {
  s.b.w = w;
  PairResult r;
  for (int k = 0; k < steps; ++k) {
    r = s.evaluate();
    s.move();
  }
  return r.couple;
}

}  // namespace

TEST(RollingResistance, SpringStiffnessAndLimitMoment) {
  auto s = pressed_pair(0.1, 0.0);
  // Below the limit mu_r R F_n = 1.9635e-4 N m (a turn of 1e-3 rad): M = -k_r theta on particle 2.
  const Vec3 m = turn(s, {0, 1, 0}, 500);  // theta = 5e-4 rad
  EXPECT_NEAR(m.y, -kKr * 5e-4, 1e-12 * kKr * 5e-4);
  EXPECT_NEAR(m.x, 0.0, 1e-18);
  EXPECT_NEAR(m.z, 0.0, 1e-18);
  EXPECT_NEAR(RollingLinear::stored_energy(s.params, s.state) -
                  0.5 * (kFn * kFn / 7.853981633974483e6 +
                         norm2(s.state.shear_force) * 2.5 / 7.853981633974483e6),
              0.5 * kKr * 25e-8, 1e-12);
  // Beyond: the moment stays on the limit, whatever the direction of rolling in the plane.
  const Vec3 m2 = turn(s, {0, 1, 0}, 1000);
  EXPECT_NEAR(m2.y, -0.1 * 0.25e-3 * kFn, 1e-12);
  const Vec3 m3 = turn(s, {0, 0.6, 0.8}, 4000);
  EXPECT_NEAR(norm(m3), 0.1 * 0.25e-3 * kFn, 1e-12);
  EXPECT_NEAR(dot(m3, Vec3{1, 0, 0}), 0.0, 1e-18) << "no twisting moment without mu_t";
  // A spin about the normal is free with mu_t = 0.
  auto free = pressed_pair(0.1, 0.0);
  EXPECT_EQ(norm(turn(free, {1, 0, 0}, 100)), 0.0);
}

TEST(RollingResistance, TwistingSpringAndLimit) {
  auto s = pressed_pair(0.0, 0.2);
  const Vec3 m = turn(s, {-1, 0, 0}, 700);  // twist -7e-4 rad about n = x
  EXPECT_NEAR(m.x, kKr * 7e-4, 1e-12 * kKr * 7e-4);
  EXPECT_NEAR(std::hypot(m.y, m.z), 0.0, 1e-18);
  const Vec3 m2 = turn(s, {-1, 0, 0}, 3000);  // past the limit 0.2 R F_n (2e-3 rad)
  EXPECT_NEAR(m2.x, 0.2 * 0.25e-3 * kFn, 1e-12);
  // Rolling is free with mu_r = 0.
  auto free = pressed_pair(0.0, 0.2);
  EXPECT_EQ(norm(turn(free, {0, 0, 1}, 100)), 0.0);
}

TEST(RollingResistance, ElasticPlasticCycleDissipatesTheHysteresisLoop) {
  // Rolled to +theta_a, then to -theta_a and back: the loop of an elastic-perfectly-plastic spring
  // encloses 4 M_y (theta_a - theta_y), M_y = mu_r R F_n, theta_y = M_y / k_r (1e-3 rad here).
  auto s = pressed_pair(0.1, 0.0);
  s.params.friction = 1e6;  // no Coulomb sliding: the slip booked is the rolling spring's
  turn(s, {0, 1, 0}, 3000);
  const double before = s.dissipation.slip;
  turn(s, {0, -1, 0}, 6000);
  turn(s, {0, 1, 0}, 6000);
  const double my = 0.1 * 0.25e-3 * kFn, theta_y = my / kKr, theta_a = 3e-3;
  EXPECT_NEAR(theta_y, 1e-3, 1e-12);
  EXPECT_NEAR(s.dissipation.slip - before, 4 * my * (theta_a - theta_y), 1e-9 * my * theta_a);
}

TEST(RollingResistance, DashpotWhileTheSpringHolds) {
  // Equal spheres: each has I + m R^2 = 7/5 m R^2 about the contact, the pair 7/10 m R^2; the
  // dashpot c = 2 eta sqrt(I k_r) adds -c w to the spring's couple and books c w^2 dt.
  auto s = pressed_pair(0.1, 0.0);
  s.params.rolling_damping_ratio = 0.3;
  const double I = 0.7 * s.b.m * 0.25e-6, c = 2 * 0.3 * std::sqrt(I * kKr);
  const Vec3 m = turn(s, {0, 2, 0}, 1);
  EXPECT_NEAR(m.y, -kKr * 2e-6 - 2 * c, 1e-12 * c);
  EXPECT_NEAR(s.dissipation.viscous, 4 * c * 1e-6, 1e-12 * c * 1e-6);
  // On the limit the dashpot is off: the couple is the limit moment alone.
  const Vec3 m2 = turn(s, {0, 2, 0}, 1000);
  EXPECT_NEAR(m2.y, -0.1 * 0.25e-3 * kFn, 1e-12);
}

TEST(RollingResistance, OpeningContactLosesItsMomentsAsDeletedEnergy) {
  auto s = pressed_pair(0.1, 0.1);
  turn(s, {0, 0.5, 0}, 400);
  turn(s, {0.5, 0, 0}, 400);
  const double stored = rolling_energy(s.state.rolling);
  EXPECT_NEAR(stored, 0.5 * kKr * 2 * 2e-4 * 2e-4, 1e-9 * stored);
  const double deleted = s.dissipation.deleted;
  const double shear = 0.5 * norm2(s.state.shear_force) * 2.5 / s.state.kn;
  s.b.x = {1.1e-3, 0, 0};
  s.evaluate();
  EXPECT_NEAR(s.dissipation.deleted - deleted, stored + shear, 1e-12 * (stored + shear));
  EXPECT_EQ(s.state.rolling.k, 0.0);
  EXPECT_EQ(norm(s.state.rolling.moment), 0.0);
}

TEST(RollingResistance, ParametersAreValidated) {
  LinearContact::Params p;
  p.rolling_friction = -0.1;
  EXPECT_THROW(validate_params<LinearContact>(p, "test"), InputError);
  HertzMindlin::Params h;
  h.rolling_damping_ratio = 1.5;
  EXPECT_THROW(validate_params<HertzMindlin>(h, "test"), InputError);
  h.rolling_damping_ratio = 0.3;
  h.twisting_friction = 0.2;
  EXPECT_NO_THROW(validate_params<HertzMindlin>(h, "test"));
}

namespace {

// One grain on a frictional floor under gravity, set rolling (or spinning) without slip from
// rest height: its contact's overlap is the static one, m g / k_n.
template <class CL>
Simulation grain_on_floor(Dimension dim, typename CL::Params p, Vec3 v0, Vec3 w0) {
  const double R = 0.5e-3;
  ParticleStore ps(dim, 1e-3);
  const Vec3 up = dim == Dimension::Two ? Vec3{0, 1, 0} : Vec3{0, 0, 1};
  ps.add({.tag = 1,
          .position = up * R,
          .radius = R,
          .density = 2650,
          .velocity = v0,
          .angular_velocity = w0});
  EngineConfig cfg;
  cfg.time_step = 2e-8;
  cfg.gravity = up * -9.81;
  cfg.energy_interval = 0;
  Simulation sim(std::move(ps), cfg, make_contact_model<CL>(p, p));
  sim.add_wall(Wall::plane("floor", {0, 0, 0}, up));
  sim.initialise();
  return sim;
}

template <class CL>
typename CL::Params floor_params() {
  typename CL::Params p;
  p.friction = 0.5;
  p.rolling_friction = 0.1;
  p.twisting_friction = 0.1;
  return p;
}

}  // namespace

// Rolling on the limit moment M = mu_r R m g: (I + m R^2) dw/dt = -M, so the centre decelerates
// at mu_r g R^2 m / (I + m R^2): 5/7 mu_r g for a sphere, 2/3 mu_r g for a disk. The floor's
// friction keeps the rolling free of slip. The first steps settle the grain onto its static
// overlap and load the spring (theta_y ~ 1e-9 rad): a transient far below the tolerance.
template <class CL>
void check_rolling_deceleration(Dimension dim, double factor) {
  const double v0 = 0.01, R = 0.5e-3, t = 4e-3;
  const bool planar = dim == Dimension::Two;
  const Vec3 w0 = planar ? Vec3{0, 0, -v0 / R} : Vec3{0, v0 / R, 0};
  Simulation sim = grain_on_floor<CL>(dim, floor_params<CL>(), {v0, 0, 0}, w0);
  sim.request_energy_sample();
  sim.step();
  const double e0 = sim.ledger().stored();
  const auto steps = static_cast<std::uint64_t>(t / 2e-8);
  sim.run(steps);
  sim.request_energy_sample();
  sim.step();
  const double a = factor * 0.1 * 9.81;
  EXPECT_NEAR(sim.particles().vel[0].x, v0 - a * t, 2e-3 * a * t);
  // Still rolling without slip.
  const double w = planar ? -sim.particles().angvel[0].z : sim.particles().angvel[0].y;
  EXPECT_NEAR(w * R, sim.particles().vel[0].x, 1e-3 * v0);
  // The ledger: the kinetic energy lost went into the rolling spring's slip (friction).
  const EnergyLedger& L = sim.ledger();
  EXPECT_GT(L.friction, 0.3 * e0);
  EXPECT_LT(std::abs(L.residual), 1e-4 * e0);
}
TEST(RollingResistance, SphereRollsToRestAtFiveSeventhsMuRG) {
  check_rolling_deceleration<LinearContact>(Dimension::Three, 5.0 / 7.0);
  check_rolling_deceleration<HertzMindlin>(Dimension::Three, 5.0 / 7.0);
}
TEST(RollingResistance, DiskRollsToRestAtTwoThirdsMuRG) {
  check_rolling_deceleration<LinearContact>(Dimension::Two, 2.0 / 3.0);
}

TEST(RollingResistance, SpinningSphereStopsAtTheTwistingLimit) {
  // Spin about the vertical under M_t = mu_t R m g: dw/dt = -mu_t R m g / (2/5 m R^2) =
  // -2.5 mu_t g / R = -4905 rad/s^2 for mu_t 0.1, R 0.5 mm.
  Simulation sim = grain_on_floor<LinearContact>(Dimension::Three, floor_params<LinearContact>(),
                                                 {}, {0, 0, 10});
  sim.run(50000);  // 1 ms
  EXPECT_NEAR(sim.particles().angvel[0].z, 10 - 4905.0 * 1e-3, 2e-3 * 4.905);
}

TEST(RollingResistance, TheEngineHoldsTheMomentsOnlyWhenRollingIsOn) {
  // Without rolling resistance a contact's state keeps its size (the moments cost nothing).
  static_assert(std::is_empty_v<RollingSlot<false>>);
  EXPECT_EQ(sizeof(RollingLinear::State), sizeof(LinearContact::State) + sizeof(RollingSpring));
  LinearContact::Params off, on;
  on.rolling_friction = 0.1;
  EXPECT_TRUE(std::holds_alternative<ContactSet<LinearContact>>(
      make_contact_model<LinearContact>(off, off)));
  EXPECT_TRUE(std::holds_alternative<ContactSet<RollingLinear>>(
      make_contact_model<LinearContact>(off, on)));
  EXPECT_TRUE(std::holds_alternative<ContactSet<HertzMindlinLaw<true>>>(
      make_contact_model<HertzMindlin>(HertzMindlin::Params{.twisting_friction = 0.1}, {})));
  // A model put together by hand with the moments dropped is refused.
  ContactSet<LinearContact> wrong;
  wrong.params = on;
  ParticleStore ps(Dimension::Three, 1.0);
  EXPECT_THROW(Simulation(std::move(ps), EngineConfig{},
                          ContactModel{std::in_place_type<ContactSet<LinearContact>>, wrong}),
               InputError);
}
