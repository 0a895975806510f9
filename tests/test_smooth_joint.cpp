// The smooth joint (docs/physics.md §5) against numbers worked by hand: two spheres of R = 0.5 mm
// touching along x, a joint plane tilted 30 degrees from the branch, k_n = 2e13 Pa/m and
// k_s = 8e12 Pa/m per unit area:
//   A = pi R^2 = 7.854e-7 m^2, K_n = k_n A = 1.5708e7 N/m, K_s = k_s A = 6.2832e6 N/m.
// Particle 2 is moved by one step of a chosen velocity (no spin), so the relative motion of the
// contact point is the prescribed displacement; the forces must follow the joint's normal n_j and
// its plane, not the branch.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "block_fixture.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/law/smooth_joint.hpp"
#include "breccia/spec/experiment.hpp"
#include "pair_harness.hpp"

using namespace breccia;
using namespace breccia::test;

namespace {

constexpr double kR = 0.5e-3, kKnA = 2e13, kKsA = 8e12;
constexpr double kPi = std::numbers::pi;
constexpr double kA = kPi * kR * kR, kKn = kKnA * kA, kKs = kKsA * kA;
const Vec3 kNormal{std::cos(kPi / 6), std::sin(kPi / 6), 0};    // n_j
const Vec3 kTangent{-std::sin(kPi / 6), std::cos(kPi / 6), 0};  // in the joint plane

SmoothJoint::Params joint_params(bool bonded, double friction = 1e6, double dilation_deg = 0) {
  SmoothJoint::Params p;
  p.normal_stiffness = kKnA;
  p.shear_stiffness = kKsA;
  p.friction = friction;
  p.dilation_angle_deg = dilation_deg;
  p.bonded = bonded;
  p.tensile_strength = 5e6;
  p.cohesion = 10e6;
  p.friction_angle_deg = 20;
  SmoothJoint::prepare(p);
  return p;
}

PairStepper<SmoothJoint> touching_joint(const SmoothJoint::Params& p) {
  PairStepper<SmoothJoint> s;
  s.params = p;
  s.a.R = s.b.R = kR;
  s.a.x = {0, 0, 0};
  s.b.x = {2 * kR, 0, 0};
  s.joint_normal = kNormal;
  s.install();
  s.evaluate();  // the first step after creation adds no increment
  return s;
}

// Moves particle 2 by `u` in one step and evaluates the law there (with the velocity that
// carried it, as the engine does).
PairResult displace(PairStepper<SmoothJoint>& s, const Vec3& u) {
  s.b.v = u * (1.0 / s.dt);
  s.move();
  const PairResult r = s.evaluate();
  s.b.v = {};
  return r;
}

// Relative tolerance: the displacements are exact to round-off (1e-9 m against 1e-3 m
// positions loses about 6 digits of the 16).
constexpr double kTol = 1e-8;

void expect_vec(const Vec3& got, const Vec3& want, double tol) {
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], tol) << "component " << c;
}

}  // namespace

TEST(SmoothJoint, StiffnessesArePerUnitAreaOfTheJointDisc) {
  const auto s = touching_joint(joint_params(false));
  EXPECT_NEAR(s.state.kn, kKn, 1e-12 * kKn);
  EXPECT_NEAR(s.state.ks, kKs, 1e-12 * kKs);
  EXPECT_EQ(s.state.normal.x, kNormal.x);  // n_j . n > 0 already: kept as given
  // Given the other way round, the normal is turned to point from 1 to 2.
  auto t = touching_joint(joint_params(false));
  t.joint_normal = -kNormal;
  t.install();
  EXPECT_EQ(t.state.normal.x, kNormal.x);
}

TEST(SmoothJoint, ClosingPushesAlongTheJointNormalNotTheBranch) {
  auto s = touching_joint(joint_params(false));
  const double u = 1e-9;
  const PairResult r = displace(s, -kNormal * u);
  expect_vec(r.f2, kNormal * (kKn * u), kTol * kKn * u);
  EXPECT_NEAR(s.energy(), 0.5 * kKn * u * u, kTol * kKn * u * u);
  // Lever-arm torques only, no couple; the torques balance the forces' moment (checked by the
  // conformance suite); here: the force is off the branch, so particle 2 is turned.
  EXPECT_EQ(norm(r.couple), 0.0);
  EXPECT_GT(std::abs(r.t2.z), 0.1 * kKn * u * kR * std::sin(kPi / 6));
}

TEST(SmoothJoint, SlidingInThePlaneShearsWithoutChangingTheNormalForce) {
  auto s = touching_joint(joint_params(false));
  const double u = 1e-9, w = 2e-9;
  displace(s, -kNormal * u);
  const PairResult r = displace(s, kTangent * w);
  expect_vec(r.f2, kNormal * (kKn * u) - kTangent * (kKs * w), kTol * kKn * u);
  EXPECT_NEAR(s.energy(), 0.5 * kKn * u * u + 0.5 * kKs * w * w, kTol * kKn * u * u);
}

TEST(SmoothJoint, CoulombSlidingDissipatesAndDilates) {
  // mu = 0.5 and psi = 10 deg: a shear push of w beyond the limit slides by
  // s = (K_s w - mu F_n) / K_s, books mu F_n s as slip and opens the joint by s tan(psi), which
  // raises F_n by K_n s tan(psi) from the next step on; the dilation's work is
  // F_n l + K_n l^2 / 2 with l = s tan(psi).
  auto s = touching_joint(joint_params(false, 0.5, 10.0));
  const double u = 1e-9, w = 4e-9;
  displace(s, -kNormal * u);
  const double fn = kKn * u;
  const PairResult r = displace(s, kTangent * w);
  const double slip = (kKs * w - 0.5 * fn) / kKs, lift = slip * std::tan(10 * kPi / 180);
  expect_vec(r.f2, kNormal * fn - kTangent * (0.5 * fn), kTol * fn);
  EXPECT_NEAR(s.dissipation.slip, 0.5 * fn * slip, kTol * fn * slip);
  EXPECT_NEAR(s.dissipation.dilation, fn * lift + 0.5 * kKn * lift * lift, kTol * fn * lift);
  EXPECT_NEAR(s.state.dilation, lift, kTol * lift);
  const PairResult next = displace(s, {});
  EXPECT_NEAR(dot(next.f2, kNormal), kKn * (u + lift), kTol * fn);
}

TEST(SmoothJoint, AnOpenedJointMustCloseTheWholeOpeningBeforeItPushes) {
  auto s = touching_joint(joint_params(false));
  const double u = 1e-9;
  EXPECT_EQ(norm(displace(s, kNormal * (2 * u)).f2), 0.0);  // opened by 2u: no tension
  EXPECT_EQ(norm(displace(s, -kNormal * u).f2), 0.0);       // closed by u: still open by u
  const PairResult r = displace(s, -kNormal * (1.5 * u));   // closed by 2.5u in all
  EXPECT_NEAR(dot(r.f2, kNormal), kKn * 0.5 * u, kTol * kKn * u);
}

TEST(SmoothJoint, BondedJointBreaksInTensionAtItsStrengthAndReleasesItsEnergy) {
  // sigma_c = 5 MPa: the joint pulled apart along n_j breaks once -F_n / A >= sigma_c, i.e. at an
  // opening of sigma_c A / K_n = sigma_c / k_n = 2.5e-7 m; the tension energy F_n^2 / (2 K_n) is
  // released, and the joint goes on unbonded (open: no force).
  auto s = touching_joint(joint_params(true));
  const double step = 1e-9, opening = 5e6 / kKnA;
  int k = 0;
  PairResult r;
  while (!s.failure.broken && k < 1000) {
    r = displace(s, kNormal * step);
    ++k;
  }
  ASSERT_TRUE(s.failure.broken);
  EXPECT_EQ(s.failure.mode, CrackMode::Tensile);
  // The 250th step reaches sigma_c, up to round-off that may leave it for the 251st.
  EXPECT_GE(k, static_cast<int>(std::lround(opening / step)));
  EXPECT_LE(k, static_cast<int>(std::lround(opening / step)) + 1);
  EXPECT_NEAR(-s.failure.Fn / kA, 5e6, kKn * step / kA);
  EXPECT_NEAR(s.failure.energy.tension, 0.5 * s.failure.Fn * s.failure.Fn / kKn,
              1e-12 * s.failure.energy.tension);
  EXPECT_EQ(norm(r.f2), 0.0);
  EXPECT_FALSE(s.state.bonded);
  EXPECT_EQ(norm(displace(s, kNormal * step).f2), 0.0);  // unbonded: no tension any more
}

TEST(SmoothJoint, BondedJointBreaksInShearAtTheMohrCoulombStrength) {
  // Closed by u = 5e-8 m (sigma_n = k_n u = 1 MPa), then sheared in the plane: the strength is
  // c + sigma_n tan(phi_b) = 10 MPa + 1 MPa tan 20 deg. After the break the joint slides at
  // mu F_n (mu = 0.5), and the released energy is the shear energy above that.
  auto s = touching_joint(joint_params(true, 0.5));
  const double u = 5e-8;
  displace(s, -kNormal * u);
  const double fn = kKn * u, strength = 10e6 + fn / kA * std::tan(20 * kPi / 180);
  const double step = 1e-9;
  PairResult r;
  int k = 0;
  while (!s.failure.broken && k < 10000) {
    r = displace(s, kTangent * step);
    ++k;
  }
  ASSERT_TRUE(s.failure.broken);
  EXPECT_EQ(s.failure.mode, CrackMode::Shear);
  EXPECT_NEAR(s.failure.tau, strength, kKs * step / kA);
  EXPECT_NEAR(s.failure.Fn, fn, 1e-9 * fn);
  const double fs = s.failure.Fs;
  EXPECT_NEAR(norm(r.f2 - kNormal * dot(r.f2, kNormal)), 0.5 * fn, 1e-9 * fn);
  EXPECT_NEAR(s.failure.energy.shear, 0.5 * (fs * fs - 0.25 * fn * fn) / kKs,
              1e-9 * s.failure.energy.shear);
  EXPECT_EQ(s.failure.energy.compression, 0.0);  // the normal spring is kept
}

TEST(SmoothJoint, PlanarJointIsASlabOfTheRunThickness) {
  PairStepper<SmoothJoint> s;
  s.params = joint_params(false);
  s.planar = true;
  s.thickness = 1e-4;
  s.a.R = s.b.R = kR;
  s.b.x = {2 * kR, 0, 0};
  s.joint_normal = kNormal;
  s.install();
  EXPECT_NEAR(s.state.kn, kKnA * 2 * kR * 1e-4, 1e-12 * kKn);
}

TEST(SmoothJoint, SeparatedPairLosesItsJointAndGetsAFreshOneOnTouching) {
  // Sliding apart beyond the contact range deletes the joint (its spring energy is lost without
  // work); touching again re-creates it stress-free at the new position.
  auto s = touching_joint(joint_params(false, 0.5));
  displace(s, -kNormal * 1e-9);
  EXPECT_TRUE(s.state.attached);
  displace(s, Vec3{0, 4e-4, 0});  // far along y: a gap of 7.7e-5 m, beyond 0.1 R
  EXPECT_FALSE(s.state.attached);
  EXPECT_GT(s.dissipation.deleted, 0.0);
  s.b.x = {2 * kR - 1e-9, 0, 0};
  const PairResult r = s.evaluate();  // touches again: re-created here, zero force
  EXPECT_TRUE(s.state.attached);
  EXPECT_EQ(norm(r.f2), 0.0);
  EXPECT_NEAR(dot(displace(s, -kNormal * 1e-9).f2, kNormal), kKn * 1e-9, kTol * kKn * 1e-9);
}

// ---- where the joints lie ----

TEST(JointPlane, CutsBranchesAcrossItWithinItsExtent) {
  JointPlane p;
  p.point = {0, 0, 0};
  p.normal = {0, 0, 1};
  EXPECT_TRUE(p.cuts({0, 0, -1}, {0, 0, 1}));
  EXPECT_TRUE(p.cuts({5, 3, 1}, {5, 3, -1}));
  EXPECT_FALSE(p.cuts({0, 0, 1}, {0, 0, 2}));
  p.radius = 2.0;  // a disc: the crossing point must lie within 2 of the centre
  EXPECT_TRUE(p.cuts({1.9, 0, -1}, {1.9, 0, 1}));
  EXPECT_FALSE(p.cuts({2.1, 0, -1}, {2.1, 0, 1}));
  EXPECT_TRUE(p.cuts({1, 0, -1}, {3, 0, 3}));   // crosses at x = 1.5
  EXPECT_FALSE(p.cuts({2, 0, -1}, {3, 0, 1}));  // crosses at x = 2.5
  JointPlane set;
  set.normal = {1, 0, 0};
  set.spacing = 1.0;  // planes at x = ..., -1, 0, 1, 2, ...
  EXPECT_TRUE(set.cuts({2.9, 0, 0}, {3.1, 0, 0}));
  EXPECT_FALSE(set.cuts({2.1, 0, 0}, {2.9, 0, 0}));
  EXPECT_TRUE(set.cuts({-0.4, 0, 0}, {0.2, 0, 0}));
}

namespace {

// Four grains in a row along x (touching), bonded, with a plane through the middle contact.
Simulation jointed_row(bool bonded, Vec3 normal, Motion motion = Motion::Driven) {
  ParticleStore ps(Dimension::Three, 1.0);
  for (int k = 0; k < 4; ++k)
    ps.add({.tag = static_cast<std::uint64_t>(k + 1),
            .position = {2 * kR * k, 0, 0},
            .radius = kR,
            .density = 2650,
            .motion = motion});
  EngineConfig cfg;
  cfg.energy_interval = 1;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.bond_touching_pairs<ParallelBond>(1e-9);
  sim.set_joint_params<SmoothJoint>(joint_params(bonded));
  JointPlane plane;
  plane.point = {3 * kR, 0, 0};
  plane.normal = normal;
  sim.add_joint_plane(plane);
  sim.initialise();
  return sim;
}

}  // namespace

TEST(SmoothJointEngine, JointsReplaceTheBondsThePlaneCuts) {
  for (const bool bonded : {false, true}) {
    Simulation sim = jointed_row(bonded, kNormal);
    EXPECT_EQ(sim.intact_bonds(), 2u) << "the middle bond of three is cut";
    EXPECT_EQ(sim.joint_count(), 1u);
    EXPECT_EQ(sim.bonded_joints(), bonded ? 1u : 0u);
    const auto& set = std::get<BondSet<SmoothJoint>>(sim.joints());
    EXPECT_EQ(set.pairs.first[0], 1u);
    EXPECT_EQ(set.pairs.second[0], 2u);
    EXPECT_NEAR(dot(set.state[0].normal, kNormal), 1.0, 1e-15);
  }
}

TEST(SmoothJointEngine, FreeGrainsOnABondedJointKeepTheirEnergyAndAngularMomentum) {
  // Two free grains on a strong bonded joint tilted 30 degrees from their branch, set moving and
  // spinning, undamped: the ledger's balance (work in = change of stored + dissipated) must
  // close, and the angular momentum about the origin must stay (the forces act at the contact
  // point with their lever arms). The balance carries the O(dt^2) error of the contact point
  // sweeping over the fixed joint plane as the pair turns: 4e-7 of the energy at the automatic
  // time step (6.3e-8 s), 1.4e-8 at a quarter of it, hence 1e-6. An unbooked loss or a spring
  // that does not store its work (centre velocities against lever-arm torques: 0.75 of the
  // work in a UCS) fails it by orders of magnitude.
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1, .position = {0, 0, 0}, .radius = kR, .density = 2650, .motion = Motion::Free});
  ps.add({.tag = 2,
          .position = {2 * kR, 0, 0},
          .radius = kR,
          .density = 2650,
          .velocity = {1e-3, -2e-3, 0.5e-3},
          .angular_velocity = {3, -1, 2},
          .motion = Motion::Free});
  EngineConfig cfg;
  cfg.energy_interval = 1;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  sim.add_bond<ParallelBond>(1, 2);
  auto p = joint_params(true);
  p.tensile_strength = p.cohesion = 1e12;
  sim.set_joint_params<SmoothJoint>(p);
  JointPlane plane;
  plane.point = {kR, 0, 0};
  plane.normal = kNormal;
  sim.add_joint_plane(plane);
  sim.initialise();
  ASSERT_EQ(sim.bonded_joints(), 1u);
  auto angular_momentum = [&] {
    const ParticleStore& q = sim.particles();
    Vec3 L;
    for (std::size_t i = 0; i < q.size(); ++i)
      L += cross(q.pos_rad[i].x, q.vel[i] * q.mass[i]) + q.angvel[i] * q.inertia[i];
    return L;
  };
  sim.step();
  const Vec3 L0 = angular_momentum();
  const double e0 = sim.ledger().stored();
  double worst = 0.0, most = 0.0;
  for (int k = 0; k < 5000; ++k) {
    sim.step();
    worst = std::max(worst, std::abs(sim.ledger().residual));
    most = std::max(most, sim.ledger().bond.total());
  }
  EXPECT_GT(most, 0.05 * e0) << "the joint must carry load";
  EXPECT_LT(worst, 1e-6 * e0);
  EXPECT_LT(norm(angular_momentum() - L0), 1e-9 * norm(L0));
}

TEST(SmoothJointEngine, JointedBlockBreaksJointsSlidesAndRestoresBitwiseFromACheckpoint) {
  // A compressed FCC block cut by an inclined bonded joint: the joints take load, break and
  // slide, and a checkpoint taken mid-way continues exactly as the uninterrupted run.
  auto with_joint = [](Simulation& sim) {
    auto p = joint_params(true, 0.3);
    p.tensile_strength = p.cohesion = 1e6;
    sim.set_joint_params<SmoothJoint>(p);
    JointPlane plane;
    plane.point = {2e-3, 2e-3, 6e-3};
    plane.normal = {std::sin(0.9), 0, std::cos(0.9)};
    sim.add_joint_plane(plane);
  };
  Simulation a = test::compressed_block(4, 4, 12, 2.0, 3e6, 0.7, with_joint);
  const std::size_t joints = a.bonded_joints();
  ASSERT_GT(joints, 10u);
  a.run(1237);
  std::stringstream buf;
  ArchiveWriter w(buf);
  a.save_state(w);
  ArchiveReader r(buf, "in-memory checkpoint");
  Simulation b = Simulation::restore(r);
  a.run(1500);
  b.run(1500);
  EXPECT_LT(a.bonded_joints(), joints) << "joints must break";
  EXPECT_GT(a.ledger().joint_slip, 0.0) << "broken joints must slide";
  std::size_t joint_cracks = 0;
  for (const CrackRecord& c : a.cracks()) joint_cracks += c.law == SmoothJoint::name ? 1 : 0;
  EXPECT_EQ(joint_cracks, joints - a.bonded_joints());
  const auto& pa = a.particles();
  const auto& pb = b.particles();
  EXPECT_EQ(0, std::memcmp(pa.pos_rad.data(), pb.pos_rad.data(), pa.size() * sizeof(PosRad)));
  EXPECT_EQ(a.ledger().joint_slip, b.ledger().joint_slip);
  EXPECT_EQ(a.ledger().residual, b.ledger().residual);
  EXPECT_EQ(a.bonded_joints(), b.bonded_joints());
  EXPECT_LT(std::abs(a.ledger().residual_relative), 1e-3);
}

namespace {

// Two blocks of two square layers each (spacing 2R), the upper one nested in the hollows of the
// lower (layer gap R sqrt 2): the most interlocked stacking. The lower block is held, the upper
// one moved rigidly: pressed down by 1e-7 m, then slid along +x by 0.05 R. Returns the total pair
// force on the upper block at the end of each phase.
std::pair<Vec3, Vec3> slide_nested_blocks(bool jointed, std::uint64_t* rebuilds = nullptr) {
  ParticleStore ps(Dimension::Three, 1.0);
  std::uint64_t tag = 1;
  const double h = kR * std::sqrt(2.0);
  const double z_layer[4] = {0, 2 * kR, 2 * kR + h, 4 * kR + h};
  for (int layer = 0; layer < 4; ++layer)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        const double shift = layer >= 2 ? kR : 0.0;
        ps.add({.tag = tag++,
                .position = {2 * kR * i + shift, 2 * kR * j + shift, z_layer[layer]},
                .radius = kR,
                .density = 2650,
                .motion = layer >= 2 ? Motion::Driven : Motion::Fixed});
      }
  LinearContact::Params contact;
  contact.friction = 0.2;
  EngineConfig cfg;
  cfg.skin =
      2e-6;  // a neighbour-list rebuild every micrometre of sliding: joints must survive them
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>(contact, {}));
  sim.bond_touching_pairs<ParallelBond>(1e-9);
  if (jointed) {
    sim.set_joint_params<SmoothJoint>(joint_params(false, 0.2));
    JointPlane plane;
    plane.point = {0, 0, 2 * kR + 0.5 * h};
    plane.normal = {0, 0, 1};
    sim.add_joint_plane(plane);
  }
  sim.initialise();
  auto drive = [&](const Vec3& v, int steps) {
    ParticleStore& q = sim.particles_mut();
    for (std::size_t i = 0; i < q.size(); ++i)
      if (q.motion[i] == Motion::Driven) q.drive_vel[i] = v;
    sim.run(static_cast<std::uint64_t>(steps));
    Vec3 f;
    for (std::size_t i = 0; i < q.size(); ++i)
      if (q.motion[i] == Motion::Driven) f += q.force[i];
    return f;
  };
  const double dt = sim.time_step();
  const int press = 100, slide = 1000;
  drive({0, 0, -1e-7 / (press * dt)}, press);
  // A step at rest: the pair laws see the velocity of the step before (the last of the press).
  const Vec3 pressed = drive({}, 1);
  const Vec3 slid = drive({0.05 * kR / (slide * dt), 0, 0}, slide);
  if (rebuilds) *rebuilds = sim.neighbour_rebuilds();
  return {pressed, slid};
}

}  // namespace

TEST(SmoothJointEngine, NestedBlocksSlideAlongTheJointAtItsFriction) {
  // Across a smooth joint the nested upper block slides as on a flat plane: the normal force of
  // the press stays (the grains do not ride up the hollows) and the shear force is mu times it.
  // Ordinary contacts between the same grains ride up: the normal force grows and the shear
  // resistance exceeds mu (the test's own check that the geometry is rough).
  std::uint64_t rebuilds = 0;
  const auto [pressed, slid] = slide_nested_blocks(true, &rebuilds);
  ASSERT_GT(pressed.z, 0.0);
  EXPECT_NEAR(slid.z, pressed.z, 1e-9 * pressed.z);
  EXPECT_NEAR(slid.x, -0.2 * slid.z, 1e-9 * slid.z);
  EXPECT_GT(rebuilds, 10u);
  const auto [pressed_c, slid_c] = slide_nested_blocks(false);
  EXPECT_GT(slid_c.z, 1.5 * pressed_c.z);
  EXPECT_GT(-slid_c.x, 0.3 * slid_c.z);
}

// ---- the experiment file ----

TEST(SmoothJointExperiment, PlanesAreReadAndBadOnesNamed) {
  const ExperimentSpec s = parse_experiment(
      "[joint]\nlaw = \"smooth_joint\"\nfriction = 0.2\n"
      "[[joint.planes]]\ndip_deg = 63\nradius = 6e-3\n"
      "[[joint.planes]]\nnormal = [1, 0, 0]\nspacing = 2e-3\ncentre = [1e-3, 0, 0]\n",
      "joints.toml", {});
  ASSERT_EQ(s.joint_planes.size(), 2u);
  EXPECT_EQ(std::get<SmoothJoint::Params>(s.joint).friction, 0.2);
  const Vec3 n = joint_normal(s.joint_planes[0], 3);
  EXPECT_NEAR(n.z, std::cos(63 * kPi / 180), 1e-15);  // dipping towards +x by default
  EXPECT_NEAR(n.x, std::sin(63 * kPi / 180), 1e-15);
  EXPECT_EQ(s.joint_planes[1].spacing, 2e-3);
  // The resolved experiment reads back the same planes.
  const ExperimentSpec again = parse_experiment(to_toml(s), "resolved.toml", {});
  ASSERT_EQ(again.joint_planes.size(), 2u);
  EXPECT_EQ(again.joint_planes[0].radius, 6e-3);
  EXPECT_EQ(again.joint_planes[1].centre[0], 1e-3);

  const auto fails_with = [](const std::string& text, const std::string& needle) {
    try {
      parse_experiment(text, "joints.toml", {});
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  fails_with("[[joint.planes]]\nradius = -1\n", "joint.planes[1].radius");
  fails_with("[[joint.planes]]\nspacing = 1e-3\nradius = 1e-3\n", "radius must be 0");
  fails_with("[[joint.planes]]\nnormal = [0, 0, 1]\ndip_deg = 30\n", "not both");
  fails_with("[[joint.planes]]\nthickness = 1\n", "unknown key of a joint plane");
  fails_with("[[joint.planes]]\nnormal = [0, 0, 0]\n", "zero vector");
  fails_with("[joint]\nplanes = 3\n", "array of tables");
  fails_with(
      "[engine]\ndimension = 2\n[contact]\nlaw = \"linear\"\n[sample]\nshape = "
      "\"rectangle\"\n[[joint.planes]]\nnormal = [0, 1, 1]\n",
      "no z part");
  fails_with(
      "[engine]\ndimension = 2\n[contact]\nlaw = \"linear\"\n[sample]\nshape = "
      "\"rectangle\"\n[[joint.planes]]\ndip_deg = 30\ndip_direction_deg = 0\n",
      "dips towards +x (90) or -x (270)");
  fails_with("[joint]\nstiffness = 1\n", "smooth_joint");
  fails_with("[joint]\nbonded = true\ncohesion = 1e6\n[[joint.planes]]\ndip_deg = 30\n",
             "tensile_strength > 0 and cohesion > 0");
}
