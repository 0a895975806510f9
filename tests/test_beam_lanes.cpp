// The quaternion bond four bonds at a time (QuaternionBond::compute_lanes, law/beam_lanes.hpp)
// against its scalar compute(): each lane performs the scalar operations in the scalar order and
// the build fuses no multiply-add (-ffp-contract=off), so a bond whose lane result stands must
// match compute() to the bit: loads, lever arms and the state's magnitudes. Lanes outside the
// series' range and bonds that break must not stand (the pair pass then takes them through
// compute()), and a lane must not write the state of a bond it leaves to compute().
#include <gtest/gtest.h>

#include <cstring>
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

bool same_bits(const Vec3& a, const Vec3& b) {
  return std::memcmp(&a, &b, sizeof(Vec3)) == 0;
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
      EXPECT_TRUE(same_bits(pf.force, out[l].force));
      EXPECT_TRUE(same_bits(pf.couple, out[l].couple));
      EXPECT_TRUE(same_bits(g.r1, out[l].r1));
      EXPECT_TRUE(same_bits(g.r2, out[l].r2));
      EXPECT_EQ(std::memcmp(&c.state, &lane_state[l], sizeof(BeamState)), 0);
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
