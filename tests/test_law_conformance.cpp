// Conformance suite run over every law in the registry (law/registry.hpp): a law added there is
// checked here without further work. Each check is physics any pair law must obey (docs/physics.md
// §0.3).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "breccia/core/quat.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/spec/experiment.hpp"
#include "pair_harness.hpp"

using namespace breccia;
using namespace breccia::test;

namespace {

// A loaded pair: touching spheres of §8 (R = 0.5 mm), with a slight overlap for contact laws so
// that they carry force; random but reproducible small velocities.
template <class Law>
PairStepper<Law> loaded_pair(std::uint64_t seed, double speed = 1e-3, double spin = 1.0) {
  PairStepper<Law> s;
  const double R = 0.5e-3;
  s.a.x = {0, 0, 0};
  const Vec3 dir = unit(in_plane<Law>({0.8, 0.35, -0.2}));
  const double overlap = is_bond_law<Law> || is_joint_law<Law> ? 0.0 : 2e-6;
  s.b.x = dir * (2 * R - overlap);
  s.a.R = s.b.R = R;
  for (int k = 0; k < 3; ++k) {
    s.a.v[k] = speed * standard_normal(seed, 1, k);
    s.b.v[k] = speed * standard_normal(seed, 2, k);
    s.a.w[k] = spin * standard_normal(seed, 3, k);
    s.b.w[k] = spin * standard_normal(seed, 4, k);
  }
  for (Body* b : {&s.a, &s.b}) {
    b->v = in_plane<Law>(b->v);
    b->w = about_z<Law>(b->w);
  }
  s.install(seed);
  return s;
}

// Turns on a contact law's rolling and twisting resistance (docs/physics.md §3.5): with
// `elastic`, limits so high that the springs never slip and no dashpot, so that the pair stays a
// potential.
template <class Law>
void with_rolling(PairStepper<Law>& s, bool elastic = false) {
  if constexpr (requires { s.state.rolling; }) {
    s.params.rolling_friction = elastic ? 1e6 : 0.3;
    s.params.twisting_friction = elastic ? 1e6 : 0.2;
    s.params.rolling_damping_ratio = elastic ? 0.0 : 0.3;
  }
}

double scale_of(const PairResult& r) {
  return norm(r.f2) + 1e-300;
}

}  // namespace

template <class Law>
class BondLawConformance : public ::testing::Test {};
TYPED_TEST_SUITE(BondLawConformance, GTypes<BondLaws>::type);

template <class Law>
class ContactLawConformance : public ::testing::Test {};
// Every contact law in both state layouts: the one with the rolling moments runs the checks with
// rolling and twisting resistance on where a check says so (with_rolling).
TYPED_TEST_SUITE(ContactLawConformance, GTypes<EngineContactLaws>::type);

// Joint laws (docs/physics.md §5) with their example parameters (a bonded joint, so that tension
// and compression both load it), on a plane tilted from the branch.
template <class Law>
class JointLawConformance : public ::testing::Test {};
TYPED_TEST_SUITE(JointLawConformance, GTypes<JointLaws>::type);

template <class Law>
void check_zero_force_at_install() {
  auto s = loaded_pair<Law>(3, 0.0, 0.0);
  for (int k = 0; k < 10; ++k) {
    const PairResult r = s.evaluate();
    EXPECT_EQ(norm(r.f2), 0.0);
    EXPECT_EQ(norm(r.couple), 0.0);
    s.move();
  }
  EXPECT_EQ(s.energy(), 0.0);
}
TYPED_TEST(BondLawConformance, ZeroForceAtInstalledGeometry) {
  check_zero_force_at_install<TypeParam>();
}
TYPED_TEST(JointLawConformance, ZeroForceAtInstalledGeometry) {
  check_zero_force_at_install<TypeParam>();
}

TYPED_TEST(ContactLawConformance, ZeroForceWhenNotOverlapping) {
  PairStepper<TypeParam> s;
  s.b.x = {1e-3, 0, 0};  // exactly touching
  s.b.v = {1e-3, 0, 0};  // separating
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(norm(s.evaluate().f2), 0.0);
    s.move();
  }
}

template <class Law>
void check_newton_third_law(bool rolling = false) {
  auto s = loaded_pair<Law>(11);
  if (rolling) with_rolling(s);
  for (int k = 0; k < 200; ++k) {
    const PairResult r = s.evaluate();
    const double f = scale_of(r);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(r.f1[c], -r.f2[c]);
    // Angular momentum about the origin: sum of torques plus moments of the forces vanishes.
    const Vec3 L = r.t1 + r.t2 + cross(s.a.x, r.f1) + cross(s.b.x, r.f2);
    EXPECT_LE(norm(L), 1e-13 * f * 1e-3 + 1e-25) << "step " << k;
    s.move();
  }
}
TYPED_TEST(BondLawConformance, NewtonsThirdLawForForcesAndMoments) {
  check_newton_third_law<TypeParam>();
}
TYPED_TEST(JointLawConformance, NewtonsThirdLawForForcesAndMoments) {
  check_newton_third_law<TypeParam>();
}
TYPED_TEST(ContactLawConformance, NewtonsThirdLawForForcesAndMoments) {
  check_newton_third_law<TypeParam>();
  check_newton_third_law<TypeParam>(true);
}

// A contact law that reads only the pair's shape for some parameters (`needs_motion_with` false:
// frictionless, without dashpots) must give through `compute`, whose engine call then carries no
// velocities, exactly what its general law gives with them: the same forces, stored energy and
// dissipation, bit for bit, while the pair approaches, slides and spins, unloads, separates and
// touches again. The motion handed to `compute` is NaN, so a shortcut that read it would show.
TYPED_TEST(ContactLawConformance, ShapeOnlyShortcutAgreesWithTheGeneralLaw) {
  using Law = TypeParam;
  if constexpr (requires(const typename Law::Params& p) { Law::needs_motion_with(p); }) {
    EXPECT_TRUE(Law::needs_motion_with(Law::example_params()));  // with friction: the motion
    typename Law::Params p = Law::example_params();
    p.friction = 0.0;
    p.normal_damping_ratio = 0.0;
    p.shear_damping_ratio = 0.0;
    ASSERT_FALSE(Law::needs_motion_with(p));
    auto s = loaded_pair<Law>(17, 0.0, 0.0);
    const Vec3 n = unit(s.b.x - s.a.x);
    const Vec3 slide = in_plane<Law>(unit(cross(n, Vec3{0, 0, 1}))) * 0.7;
    s.a.w = about_z<Law>({3e3, -1e3, 2e3});
    typename Law::State ref{};
    PairDissipation dis_fast, dis_ref;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    int touching = 0, apart = 0;
    for (int k = 0; k < 600; ++k) {
      // Along the normal: in by 1 um, out by 6 um (apart from about step 250), in again.
      s.b.v = n * (k < 100 ? -1.0 : k < 400 ? 2.0 : -2.0) + slide;
      const PairGeometry g = make_geometry(s.a, s.b, s.planar, s.thickness, s.planar_sphere);
      (g.delta > 0.0 ? touching : apart) += 1;
      const PairForce r = Law::compute_with_motion(p, ref, g, s.dt, dis_ref);
      PairGeometry blind = g;
      blind.vc = blind.w1 = blind.w2 = {nan, nan, nan};
      blind.m1 = blind.m2 = nan;
      const PairForce f = Law::compute(p, s.state, blind, s.dt, dis_fast);
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(f.force[c], r.force[c]) << "step " << k;
        EXPECT_EQ(f.couple[c], r.couple[c]) << "step " << k;
      }
      EXPECT_EQ(Law::stored_energy(p, s.state), Law::stored_energy(p, ref)) << "step " << k;
      s.move();
    }
    EXPECT_GT(touching, 280);  // the walk did load, part and reload the contact
    EXPECT_GT(apart, 50);
    EXPECT_EQ(dis_fast.slip, dis_ref.slip);
    EXPECT_EQ(dis_fast.viscous, dis_ref.viscous);
    EXPECT_EQ(dis_fast.deleted, dis_ref.deleted);
  }
}

template <class Law>
void check_rigid_motion_invariance(bool rolling = false) {
  // The same motion seen in a rotated and translated frame gives the rotated forces.
  auto s = loaded_pair<Law>(5);
  if (rolling) with_rolling(s);
  // 2D laws: a turn about z and a shift in the plane.
  const Quat q = planar_only_law<Law> ? normalized(Quat{0.7, 0.0, 0.0, 0.3})
                                      : normalized(Quat{0.7, 0.1, -0.4, 0.3});
  const Vec3 shift = in_plane<Law>({3.1e-3, -2.0e-3, 7.5e-3});
  PairStepper<Law> t = s;
  for (Body* b : {&t.a, &t.b}) {
    b->x = rot(q, b->x) + shift;
    b->v = rot(q, b->v);
    b->w = rot(q, b->w);
    b->q = q * b->q;
  }
  t.joint_normal = rot(q, t.joint_normal);
  t.install(5);
  // A total formulation (one that reads orientations, hence positions against a reference)
  // carries the round-off of the shifted positions and rotated orientations into its forces:
  // 16 ulp of the largest coordinate (about 1e-2 m) at installation, and each step's x += v dt
  // rounds every coordinate of both bodies in both frames (at most 2 ulp of the relative
  // position per step), times the stiffness; for couples the same in orientation units times
  // the moment stiffness, plus the force error times the radius. Incremental laws work from
  // velocities and are held to 1e-9 of the force alone.
  // RICEBAL's normal spring is total too: -K_n (d - d0) from the positions.
  double f_ulp = 0.0, m_ulp = 0.0;
  if constexpr (is_bond_law<Law>) {
    if constexpr (Law::needs_frames || requires { &Law::State::d0; }) {
      const double eps = std::numeric_limits<double>::epsilon();
      f_ulp = eps * 1e-2 * Law::max_stiffness(s.params, s.state, s.radii());
      m_ulp = eps * Law::max_moment_stiffness(s.params, s.state, s.radii()) + f_ulp * s.a.R;
    }
  }
  for (int k = 0; k < 300; ++k) {
    const double f_floor = (16.0 + 2.0 * k) * f_ulp, m_floor = (16.0 + 2.0 * k) * m_ulp;
    const PairResult r = s.evaluate(), u = t.evaluate();
    const Vec3 fr = rot(q, r.f2), mr = rot(q, r.couple);
    const double f = scale_of(r), m = norm(r.couple) + f * 1e-3;
    // The shift costs digits of the positions (|shift| / delta ~ 4e3 ulp of the overlap).
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(u.f2[c], fr[c], 1e-9 * f + f_floor) << "step " << k;
      EXPECT_NEAR(u.couple[c], mr[c], 1e-9 * m + m_floor) << "step " << k;
    }
    s.move();
    t.move();
  }
}
TYPED_TEST(BondLawConformance, InvariantUnderRigidRotationAndTranslation) {
  check_rigid_motion_invariance<TypeParam>();
}
TYPED_TEST(JointLawConformance, InvariantUnderRigidRotationAndTranslation) {
  check_rigid_motion_invariance<TypeParam>();
}
TYPED_TEST(ContactLawConformance, InvariantUnderRigidRotationAndTranslation) {
  check_rigid_motion_invariance<TypeParam>();
  check_rigid_motion_invariance<TypeParam>(true);
}

template <class Law>
void check_force_is_energy_gradient(double speed, double spin, int steps, bool rolling = false) {
  // The work the interaction does on the two particles along a smooth elastic path equals minus
  // the change of its stored energy, plus what the law books as lost without work (the Hertz
  // shear spring whose stiffness follows the overlap, docs/physics.md §2.4). Trapezoidal work over
  // 1e-8 s steps: error O(dt^2), far below the tolerance; a wrong sign or factor in any
  // stiffness, or an unbooked loss, fails it.
  auto s = loaded_pair<Law>(7, speed, spin);
  if constexpr (requires { s.params.friction; }) s.params.friction = 1e6;  // no Coulomb slip
  if (rolling) with_rolling(s, true);
  PairResult r0 = s.evaluate();
  const double e0 = s.energy();
  double work = 0.0, e_scale = std::abs(e0);
  // Total beam formulations (§4.2, §4.3) are a potential to first order in the deformation
  // only (arms fixed at d0, forces in the deformed frame): work and energy change differ by a
  // fraction of the order of the largest deformation on the path (strain, branch rotation, body
  // rotations). A wrong sign or factor in any stiffness still gives an O(1) difference.
  const double d0 = norm(s.b.x - s.a.x);
  const Vec3 n0 = unit(s.b.x - s.a.x);
  double deformation = 0.0;
  for (int k = 0; k < steps; ++k) {
    // Velocities change smoothly along the path (a curved, non-proportional load path).
    const double phase = 0.01 * k;
    (planar_only_law<Law> ? s.b.w.z : s.b.w.x) += 1e-3 * std::cos(phase) * spin;
    s.b.v.y += 1e-3 * std::sin(phase) * speed;
    const Body a0 = s.a, b0 = s.b;
    s.move();
    const PairResult r1 = s.evaluate();
    const Vec3 dxa = s.a.x - a0.x, dxb = s.b.x - b0.x;
    const Vec3 dra = a0.w * s.dt, drb = b0.w * s.dt;
    work += 0.5 * (dot(r0.f1 + r1.f1, dxa) + dot(r0.f2 + r1.f2, dxb) + dot(r0.t1 + r1.t1, dra) +
                   dot(r0.t2 + r1.t2, drb));
    r0 = r1;
    e_scale = std::max(e_scale, std::abs(s.energy()));
    const Vec3 d = s.b.x - s.a.x;
    const auto angle = [](const Quat& q) { return 2.0 * std::acos(std::min(1.0, std::abs(q.w))); };
    deformation =
        std::max({deformation, std::abs(norm(d) / d0 - 1.0),
                  std::acos(std::min(1.0, dot(unit(d), n0))), angle(s.a.q), angle(s.b.q)});
  }
  double tolerance = 1e-6;
  if constexpr (is_bond_law<Law>) {
    if constexpr (Law::needs_frames) tolerance += deformation;
  }
  const double de = s.energy() - e0 + s.dissipation.deleted + s.dissipation.slip;
  ASSERT_GT(std::abs(de), 0.05 * e_scale) << "the path must load the pair substantially";
  EXPECT_NEAR(work, -de, tolerance * e_scale)
      << "work " << work << " energy change " << de << " largest deformation " << deformation;
}
TYPED_TEST(BondLawConformance, ForceIsMinusEnergyGradient) {
  check_force_is_energy_gradient<TypeParam>(2e-3, 2.0, 2000);
}
TYPED_TEST(JointLawConformance, ForceIsMinusEnergyGradient) {
  check_force_is_energy_gradient<TypeParam>(2e-3, 2.0, 2000);
}
TYPED_TEST(ContactLawConformance, ForceIsMinusEnergyGradient) {
  check_force_is_energy_gradient<TypeParam>(5e-3, 10.0, 2000);
  check_force_is_energy_gradient<TypeParam>(5e-3, 10.0, 2000, true);
}

template <class Law>
void check_stretch_to_failure() {
  // Pulling apart must end in a tensile crack whose released energy is the energy stored in the
  // breaking step (§4.0), after which the bond carries nothing.
  PairStepper<Law> s;
  s.b.x = {1e-3, 0, 0};
  s.install();
  s.b.v = {1e-2, 0, 0};
  double last_energy = 0.0;
  int k = 0;
  for (; k < 1000000 && !s.failure.broken; ++k) {
    last_energy = s.energy();
    s.evaluate();
    s.move();
  }
  ASSERT_TRUE(s.failure.broken);
  EXPECT_EQ(s.failure.mode, CrackMode::Tensile);
  EXPECT_LT(s.failure.Fn, 0.0);
  EXPECT_GE(s.failure.ratio_t, 1.0);
  double released = s.failure.energy.total();
  if constexpr (is_bond_law<Law> && law_breaks_by_element<Law>) {
    // Element by element, one per step, each a tensile crack; then the parted interface is
    // released without one. Together the cracks release what the bond stored.
    int cracks = 1;
    for (int more = 0; more < 100 && s.failure.outcome != BondOutcome::Released; ++more) {
      s.move();
      s.failure = {};
      const PairResult r = s.evaluate();
      if (s.failure.outcome == BondOutcome::Released) {
        EXPECT_EQ(norm(r.f2), 0.0);
      } else if (s.failure.broken) {
        EXPECT_EQ(s.failure.mode, CrackMode::Tensile);
        released += s.failure.energy.total();
        ++cracks;
      }
    }
    EXPECT_EQ(s.failure.outcome, BondOutcome::Released);
    EXPECT_TRUE(s.failure.broken);
    EXPECT_GT(cracks, 1);
    EXPECT_NEAR(s.energy(), 0.0, 1e-12 * last_energy);
  }
  // One step adds at most 2 dV/V of stored energy; here far below 1e-3 (a flat joint takes one
  // step per element).
  EXPECT_NEAR(released, last_energy, 1e-3 * last_energy);
}
TYPED_TEST(BondLawConformance, StretchToFailureReleasesTheStoredEnergy) {
  check_stretch_to_failure<TypeParam>();
}
TYPED_TEST(JointLawConformance, StretchToFailureReleasesTheStoredEnergy) {
  check_stretch_to_failure<TypeParam>();
}

template <class Law>
void check_assess_agrees_with_the_breaking_step() {
  // assess() reads a bond's loads against its strength from its state (what snapshots show of
  // intact bonds): zero at installation, below 1 while the bond holds, and in the breaking step
  // exactly the failure the step reported.
  PairStepper<Law> s;
  s.b.x = {1e-3, 0, 0};
  s.install();
  EXPECT_EQ(Law::assess(s.params, s.state, s.radii()).index, 0.0);
  s.b.v = {1e-2, 0, 0};
  double last_index = 0.0;
  int k = 0;
  for (; k < 1000000 && !s.failure.broken; ++k) {
    s.evaluate();
    if (s.failure.broken) break;
    const BondFailure now = Law::assess(s.params, s.state, s.radii());
    ASSERT_FALSE(now.broken) << "step " << k;
    ASSERT_LT(now.index, 1.0) << "step " << k;
    EXPECT_GE(now.index, 0.0);
    last_index = now.index;
    s.move();
  }
  ASSERT_TRUE(s.failure.broken);
  EXPECT_GT(last_index, 0.9) << "a steady pull approaches the strength step by step";
  const BondFailure a = Law::assess(s.params, s.state, s.radii());
  EXPECT_TRUE(a.broken);
  EXPECT_GE(a.index, 1.0);
  EXPECT_EQ(a.mode, s.failure.mode);
  EXPECT_EQ(a.Fn, s.failure.Fn);
  EXPECT_EQ(a.Fs, s.failure.Fs);
  EXPECT_EQ(a.sigma, s.failure.sigma);
  EXPECT_EQ(a.tau, s.failure.tau);
  EXPECT_EQ(a.ratio_t, s.failure.ratio_t);
  EXPECT_EQ(a.bond_radius, s.failure.bond_radius);
}
TYPED_TEST(BondLawConformance, AssessAgreesWithTheBreakingStep) {
  check_assess_agrees_with_the_breaking_step<TypeParam>();
}

template <class Law>
void check_rigid_body_motion() {
  // The pair turns and translates as one rigid body (every velocity set from omega x r each
  // step): the bond must stay unloaded. For incremental laws the relative contact velocity is
  // exactly zero; the straight-line drift of each step moves the centres off the circle by
  // (omega dt)^2 d / 2, 5e-18 m here, so even a total law would see at most
  // 1000 x 5e-18 m x K (~1e7 N/m) = 5e-8 N. Hence 1e-6 N.
  PairStepper<Law> s;
  s.b.x = unit(in_plane<Law>({0.3, -0.8, 0.5})) * 1e-3;
  s.install();
  const Vec3 omega = about_z<Law>({4.0, -7.0, 5.0}), drift = in_plane<Law>({1e-3, 2e-3, -1e-3});
  double worst = 0.0;
  for (int k = 0; k < 1000; ++k) {
    const Vec3 c = (s.a.x + s.b.x) * 0.5;
    for (Body* b : {&s.a, &s.b}) {
      b->v = drift + cross(omega, b->x - c);
      b->w = omega;
    }
    const PairResult r = s.evaluate();
    worst = std::max({worst, norm(r.f2), norm(r.couple) / 1e-3});
    s.move();
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_FALSE(s.failure.broken);
}
TYPED_TEST(BondLawConformance, RigidBodyMotionLeavesTheBondUnloaded) {
  check_rigid_body_motion<TypeParam>();
}
TYPED_TEST(JointLawConformance, RigidBodyMotionLeavesTheBondUnloaded) {
  check_rigid_body_motion<TypeParam>();
}

// ---- the experiment file reads every law's keys from the law's own table ----

namespace {

// A value inside the field's range that differs from its default.
template <class Law>
double probe_value(const ParamField<typename Law::Params>& f) {
  const typename Law::Params d{};
  const double v = d.*std::get<double Law::Params::*>(f.member);
  // A tenth of a finite range before a fixed step keeps fractions that share a budget (the
  // flat joint's bonded and gapped fractions) within it; v + 1 reaches the next count.
  const double tenth = std::isfinite(f.max - f.min) ? v + 0.1 * (f.max - f.min) : v;
  for (const double candidate :
       {v * 1.25, v * 0.75, tenth, v + 0.5, 0.5 * (f.min + f.max), 1.0, v + 1.0})
    if (candidate != v && f.in_range(candidate)) return candidate;
  ADD_FAILURE() << "no probe value for " << f.key;
  return v;
}

// Sets every real key of `Law` in its section, reads the file, and checks the spec holds the law
// with those values, and that the resolved experiment (to_toml) reads back to the same.
template <class Law, class List, class Variant>
void check_law_keys(const char* section, Variant ExperimentSpec::*member) {
  // 2D laws are read from a 2D experiment.
  const std::string dimension =
      planar_only_law<Law> ? "[engine]\ndimension = 2\n[sample]\nshape = \"rectangle\"\n" : "";
  std::string text = dimension + fmt::format("[{}]\nlaw = \"{}\"\n", section, Law::name);
  std::vector<std::pair<double Law::Params::*, double>> set;
  for (const auto& f : Law::fields()) {
    if (f.is_flag()) continue;
    const double v = probe_value<Law>(f);
    text += fmt::format("{} = {:.17g}\n", f.key, v);
    set.emplace_back(std::get<double Law::Params::*>(f.member), v);
  }
  const ExperimentSpec spec = parse_experiment(text, "laws.toml", {});
  ASSERT_TRUE(std::holds_alternative<typename Law::Params>(spec.*member));
  EXPECT_EQ(name_of_params<List>(spec.*member), Law::name);
  const ExperimentSpec again = parse_experiment(to_toml(spec), "resolved.toml", {});
  for (const auto& [field, v] : set) {
    EXPECT_EQ(std::get<typename Law::Params>(spec.*member).*field, v);
    EXPECT_EQ(std::get<typename Law::Params>(again.*member).*field, v);
  }
  // An unknown key names the law and lists its keys.
  try {
    parse_experiment(
        dimension + fmt::format("[{}]\nlaw = \"{}\"\nno_such_key = 1\n", section, Law::name),
        "laws.toml", {});
    ADD_FAILURE() << "an unknown key was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(std::string(Law::name)), std::string::npos) << e.what();
  }
}

}  // namespace

TYPED_TEST(BondLawConformance, EveryKeyIsReadFromTheExperimentFile) {
  check_law_keys<TypeParam, BondLaws>("bond", &ExperimentSpec::bond);
}
TYPED_TEST(ContactLawConformance, EveryKeyIsReadFromTheExperimentFile) {
  check_law_keys<TypeParam, ContactLaws>("contact", &ExperimentSpec::contact);
}
TYPED_TEST(JointLawConformance, EveryKeyIsReadFromTheExperimentFile) {
  check_law_keys<TypeParam, JointLaws>("joint", &ExperimentSpec::joint);
}

TEST(LawChoice, NamingTheChosenLawKeepsItsParametersAndAnotherStartsFromDefaults) {
  // The Berea preset sets Hertz-Mindlin contacts; naming that law again keeps its values, naming
  // another law starts from that law's defaults.
  const ExperimentSpec preset = parse_experiment("[material]\npreset = \"berea\"\n", "p", {});
  ASSERT_TRUE(std::holds_alternative<HertzMindlin::Params>(preset.contact));
  const ExperimentSpec same = parse_experiment(
      "[material]\npreset = \"berea\"\n[contact]\nlaw = \"hertz_mindlin\"\n", "p", {});
  EXPECT_EQ(std::get<HertzMindlin::Params>(same.contact).shear_modulus,
            std::get<HertzMindlin::Params>(preset.contact).shear_modulus);
  const ExperimentSpec other =
      parse_experiment("[material]\npreset = \"berea\"\n", "p", {"contact.law=linear"});
  ASSERT_TRUE(std::holds_alternative<LinearContact::Params>(other.contact));
  EXPECT_EQ(std::get<LinearContact::Params>(other.contact).modulus,
            LinearContact::Params{}.modulus);
}
