// The quaternion bond four bonds at a time (QuaternionBond::compute_lanes, law/beam_lanes.hpp)
// against its scalar compute(): each lane performs the scalar operations in the scalar order, so
// a bond whose lane result stands must match compute() to the bit (loads, lever arms and the
// state's magnitudes) where no multiply-add is fused, as in the portable build. Lanes outside the
// series' range and bonds that break must not stand (the pair pass then takes them through
// compute()).
//
// Tolerance where the compiler may fuse (a build with FMA, __FMA__): a fused multiply-add rounds
// once where the unfused form rounds twice, so each fusion the two forms do not share moves an
// intermediate by at most one rounding of its own size. The loads leave the inputs through about
// twenty such steps of quantities of the loads' own order (products and rotations of unit
// vectors and quaternions, one root, the series), so the two forms differ by at most about 20
// eps of |F| and |C|; 64 eps leaves a factor three, as tests/test_beam_kernels.cpp does for its
// two kernels. The state's magnitudes are held to the same bound of |F| or |C|.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "breccia/law/quaternion_bond.hpp"

using namespace breccia;
using beam::BeamState;

namespace {

struct Case {
  Vec3 x1, x2;
  double R1, R2;
  Quat q1, q2;
  BeamState state;
};

#if defined(__FMA__)
constexpr double kTolerance = 64.0 * std::numeric_limits<double>::epsilon();
#else
constexpr double kTolerance = 0.0;
#endif

// `a` is `b` to the bit, or within kTolerance of |b| where products may be fused.
void expect_same(const Vec3& a, const Vec3& b) {
  if (kTolerance == 0.0)
    EXPECT_EQ(std::memcmp(&a, &b, sizeof(Vec3)), 0);
  else
    EXPECT_LE(norm(a - b), kTolerance * norm(b));
}
// A magnitude of the state: to the bit, or within kTolerance of the `scale` of its kind of load
// (|F| for the forces, |C| for the moments: the twist comes from a difference of quaternion parts
// of the whole rotation's size, so its round-off is relative to the whole, not to itself).
void expect_same(double a, double b, double scale) {
  if (kTolerance == 0.0)
    EXPECT_EQ(std::memcmp(&a, &b, sizeof(double)), 0);
  else
    EXPECT_LE(std::abs(a - b), kTolerance * scale);
}

// A bond installed between two touching grains, then moved by `strain` of its length and turned
// by up to `angle` radians at the second grain.
Case random_case(std::mt19937_64& rng, double strain, double angle) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> g;
  Case c;
  c.x1 = Vec3{u(rng), u(rng), u(rng)} * 1e-3;
  c.R1 = 2e-4 * (1.0 + 0.5 * u(rng));
  c.R2 = 2e-4 * (1.0 + 0.5 * u(rng));
  const Vec3 dir = unit(Vec3{g(rng), g(rng), g(rng)});
  const Vec3 x2 = c.x1 + dir * (c.R1 + c.R2);
  c.q1 = normalized(Quat{g(rng), g(rng), g(rng), g(rng)});
  const Quat q2 = normalized(Quat{g(rng), g(rng), g(rng), g(rng)});
  c.state = beam::install(pair_shape(c.x1, c.R1, x2, c.R2, false, 1.0), {c.q1, q2});
  c.x2 = x2 + Vec3{u(rng), u(rng), u(rng)} * (strain * (c.R1 + c.R2));
  c.q2 = normalized(q2 * from_axis_angle(unit(Vec3{g(rng), g(rng), g(rng)}), angle * u(rng)));
  return c;
}

struct Tally {
  int stood = 0, left = 0;
};

// Runs the cases four at a time through the lanes and one at a time through compute().
Tally compare(const QuaternionBond::Params& p, std::vector<Case> cases) {
  Tally t;
  for (std::size_t k = 0; k + beam::kLanes <= cases.size(); k += beam::kLanes) {
    beam::LaneBond lanes[beam::kLanes];
    BeamState lane_state[beam::kLanes];
    for (int l = 0; l < beam::kLanes; ++l) {
      const Case& c = cases[k + static_cast<std::size_t>(l)];
      lane_state[l] = c.state;
      lanes[l] = {c.x1, c.x2, c.R1, c.R2, c.q1, c.q2, &lane_state[l]};
    }
    beam::LaneResult out[beam::kLanes];
    QuaternionBond::compute_lanes(p, lanes, out);
    for (int l = 0; l < beam::kLanes; ++l) {
      Case c = cases[k + static_cast<std::size_t>(l)];
      const PairGeometry g = pair_shape(c.x1, c.R1, c.x2, c.R2, false, 1.0);
      BondFailure f;
      const PairForce pf = QuaternionBond::compute(p, c.state, g, {c.q1, c.q2}, 0.0, f);
      if (!out[l].stands) {
        ++t.left;
        // Left to compute(): broken there, or outside the series' range; its state untouched
        // unless the lane was within range.
        continue;
      }
      ++t.stood;
      EXPECT_FALSE(f.broken);
      expect_same(out[l].force, pf.force);
      expect_same(out[l].couple, pf.couple);
      expect_same(out[l].r1, g.r1);
      expect_same(out[l].r2, g.r2);
      const double fs = norm(pf.force), ms = norm(pf.couple);
      expect_same(lane_state[l].normal_force, c.state.normal_force, fs);
      expect_same(lane_state[l].shear_force, c.state.shear_force, fs);
      expect_same(lane_state[l].bend_moment, c.state.bend_moment, ms);
      expect_same(lane_state[l].twist_moment, c.state.twist_moment, ms);
    }
  }
  return t;
}

QuaternionBond::Params strong_bond() {
  QuaternionBond::Params p = QuaternionBond::example_params();
  p.tensile_strength = p.shear_strength = 1e12;
  QuaternionBond::prepare(p);
  return p;
}

}  // namespace

TEST(QuaternionBondLanes, SmallAnglesMatchComputeToTheBit) {
  std::mt19937_64 rng(11);
  std::vector<Case> cases;
  for (int k = 0; k < 4000; ++k) cases.push_back(random_case(rng, 1e-3, 1e-3));
  const Tally t = compare(strong_bond(), cases);
  EXPECT_EQ(t.stood, 4000);  // every lane within the series' range, none broken
}

TEST(QuaternionBondLanes, LargeAnglesAreLeftToCompute) {
  // Turns of up to 1 rad put most lanes past tan(angle) = 1/16: those must not stand, the rest
  // must match compute().
  std::mt19937_64 rng(12);
  std::vector<Case> cases;
  for (int k = 0; k < 4000; ++k) cases.push_back(random_case(rng, 1e-3, 1.0));
  const Tally t = compare(strong_bond(), cases);
  EXPECT_GT(t.left, 2000);
  EXPECT_GT(t.stood, 100);
}

TEST(QuaternionBondLanes, BrokenBondsAreLeftToCompute) {
  // A strength that about half of the bonds at 1e-3 strain exceed: every lane that stands is one
  // compute() finds intact, and the broken ones are left to it.
  std::mt19937_64 rng(13);
  std::vector<Case> cases;
  for (int k = 0; k < 4000; ++k) cases.push_back(random_case(rng, 1e-3, 1e-3));
  QuaternionBond::Params p = QuaternionBond::example_params();
  p.tensile_strength = p.shear_strength = 4e6;
  QuaternionBond::prepare(p);
  const Tally t = compare(p, cases);
  EXPECT_GT(t.left, 500);
  EXPECT_GT(t.stood, 500);
}
