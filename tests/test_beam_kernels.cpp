// The world-frame beam kernel (beam::loads) against its step-by-step reference in the frames of
// docs/physics.md §4.2 (beam::reference_loads): the same loads from the same configurations, to
// round-off.
//
// Tolerance. Both paths read the same unit quaternions and unit vectors; each angle (gamma, the
// bend theta, the twist psi) leaves them through at most about twenty roundings of quantities of
// order one (products, rotations, one root, one atan2 or its series), so either path's angle is
// within about 10 eps of the exact one, absolutely. A force differs by at most K_s (arm +
// arm_theta) times that, a couple by (K_b + K_t) times it, plus the same relative round-off of the
// parts they share (K_r (d - d0), which both compute alike). 64 eps leaves a factor three over that
// count. The reference's shortest arc from z to the branch loses accuracy as the branch nears -z in
// the first grain's frame (its cosine then comes from 1 + r_z), so the draws keep r_z > -0.9.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "breccia/law/beam.hpp"

using namespace breccia;

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return unit(Vec3{g(rng), g(rng), g(rng)});
}

Quat random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return normalized(Quat{g(rng), g(rng), g(rng), g(rng)});
}

Quat small_rotation(std::mt19937_64& rng, double max_angle) {
  std::uniform_real_distribution<double> u(0.0, max_angle);
  return from_axis_angle(random_unit(rng), u(rng));
}

struct Draw {
  beam::BeamState state;
  beam::BeamSection section;
  PairGeometry geometry;
  BodyFrames frames;
};

// A bond installed between two grains of random orientations, then moved: the branch turned by
// up to `max_angle` from its reference and the second grain turned by up to `max_angle` more
// than the first, the length changed by up to 1 %.
Draw random_bond(std::mt19937_64& rng, double max_angle) {
  Draw d;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double R1 = 0.5e-3 * (1.0 + 0.3 * u(rng)), R2 = 0.5e-3 * (1.0 + 0.3 * u(rng));
  const BodyFrames installed{random_rotation(rng), random_rotation(rng)};
  d.state.q0 = conj(installed.q1) * installed.q2;
  d.state.d0 = R1 + R2;
  d.frames.q1 = small_rotation(rng, 10.0) * installed.q1;  // any present orientation
  d.frames.q2 = d.frames.q1 * conj(installed.q1) * small_rotation(rng, max_angle) * installed.q2;
  d.state.r0 = rotate(conj(installed.q1), random_unit(rng));
  const Vec3 n = rotate(small_rotation(rng, max_angle), rotate(d.frames.q1, d.state.r0));
  d.geometry.n = n;
  d.geometry.d = d.state.d0 * (1.0 + 0.01 * u(rng));
  d.geometry.R1 = R1;
  d.geometry.R2 = R2;
  d.geometry.delta = R1 + R2 - d.geometry.d;
  const beam::BeamModuli moduli{10e9, 4e9, 1.0, false};
  d.section = beam::section(d.state, moduli, RunGeometry{}, radii_of(d.geometry));  // R_b = d0 / 2
  return d;
}

void expect_agree(double max_angle, std::uint64_t seed, bool lammps_arms) {
  std::mt19937_64 rng(seed);
  int compared = 0;
  for (int i = 0; i < 2000; ++i) {
    Draw d = random_bond(rng, max_angle);
    if (rotate(conj(d.frames.q1), d.geometry.n).z <= -0.9) continue;
    const double arm = lammps_arms ? d.geometry.d : d.state.d0;
    beam::BeamState ref = d.state, fast = d.state;
    const PairForce a = beam::reference_loads(ref, d.section, d.geometry, d.frames, arm, arm);
    const PairForce b = beam::loads(fast, d.section, d.geometry, d.frames, arm, arm);
    const beam::BeamSection& c = d.section;
    const double angle_error = 64.0 * kEps;
    const double force_tol =
        c.ks * 2.0 * arm * angle_error + 64.0 * kEps * c.kr * std::abs(d.geometry.d - d.state.d0);
    const double couple_tol =
        (c.kb + c.kt) * angle_error + force_tol * (arm + std::abs(beam::point_shift(d.geometry)));
    ASSERT_LE(norm(a.force - b.force), force_tol) << "draw " << i;
    ASSERT_LE(norm(a.couple - b.couple), couple_tol) << "draw " << i;
    ASSERT_LE(std::abs(ref.normal_force - fast.normal_force), force_tol) << "draw " << i;
    ASSERT_LE(std::abs(ref.shear_force - fast.shear_force), force_tol) << "draw " << i;
    ASSERT_LE(std::abs(ref.bend_moment - fast.bend_moment), c.kb * angle_error) << "draw " << i;
    ASSERT_LE(std::abs(ref.twist_moment - fast.twist_moment), c.kt * angle_error) << "draw " << i;
    ++compared;
  }
  EXPECT_GT(compared, 1500);
}

}  // namespace

TEST(BeamKernels, WorldFrameLoadsMatchTheReferenceAtSmallAngles) {
  // Bonds break at angles of order 1e-3 to 1e-2 rad; these are nearly all the steps of a run.
  expect_agree(0.02, 1, true);
  expect_agree(0.02, 2, false);
}

TEST(BeamKernels, WorldFrameLoadsMatchTheReferenceAtLargeAngles) {
  // Beyond the atan2 series (|y| > x / 16) and up to bends of several tenths of pi.
  expect_agree(1.5, 3, true);
  expect_agree(1.5, 4, false);
}

TEST(BeamKernels, PureTwistMakesNoBend) {
  // The second grain turned about the branch only: exactly zero swing in both paths.
  const Vec3 n{0.0, 0.0, 1.0};
  beam::BeamState s;
  s.d0 = 1e-3;
  s.r0 = n;
  const BodyFrames fr{Quat{}, from_axis_angle(n, 0.01)};
  PairGeometry g;
  g.n = n;
  g.d = s.d0;
  g.R1 = g.R2 = 0.5e-3;
  const beam::BeamSection c =
      beam::section(s, beam::BeamModuli{10e9, 4e9, 1.0, false}, RunGeometry{}, radii_of(g));
  const PairForce f = beam::loads(s, c, g, fr, g.d, g.d);
  EXPECT_EQ(s.bend_moment, 0.0);
  EXPECT_EQ(s.shear_force, 0.0);
  EXPECT_NEAR(s.twist_moment, c.kt * 0.01, c.kt * 0.01 * 1e-12);
  EXPECT_NEAR(f.couple.z, -c.kt * 0.01, c.kt * 0.01 * 1e-12);
}
