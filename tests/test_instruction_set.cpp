// The hot kernels in more than one instruction set (core/instruction_set.hpp): within a set the
// trajectory is the same to the bit at any thread count; between the baseline and x86-64-v3 it
// differs by the rounding of fused multiply-adds, and only by that (docs/physics.md §1.7).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "block_fixture.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/instruction_set.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/run/sample_build.hpp"
#include "breccia/spec/experiment.hpp"

using namespace breccia;

namespace {

struct Trajectory {
  std::vector<PosRad> pos;
  std::vector<Vec3> vel;
  std::vector<std::uint64_t> crack_bonds;
  double wall_force = 0.0;
  double radius = 0.0;
};

enum class Block { Breaking, Elastic, Lanes };

// The FCC block of the determinism tests (2,000 grains, parallel bonds of 3 MPa that break under
// the platens, or of 3 GPa that do not), or a quaternion-bonded block whose bonds go through the
// four-lane kernel.
Trajectory run(InstructionSet set, int threads, Block block) {
  const int saved = max_threads();
  set_threads(threads);
  const bool lanes = block == Block::Lanes;
  Simulation sim =
      lanes ? test::law_block<LinearContact, QuaternionBond>(false, 3, set)
            : test::compressed_block(5, 5, 20, 2.0, block == Block::Breaking ? 3e6 : 3e9,
                                     block == Block::Breaking ? 0.7 : 0.0, {}, false, set);
  EXPECT_EQ(sim.instruction_set(), set);
  sim.run(lanes ? 600 : 2500);
  Trajectory t;
  t.pos = sim.particles().pos_rad;
  t.vel = sim.particles().vel;
  for (const auto& c : sim.cracks()) t.crack_bonds.push_back(c.bond_tag);
  t.wall_force = sim.walls()[1].force.z;
  t.radius = sim.particles().pos_rad[0].r;
  set_threads(saved);
  return t;
}

bool bitwise_equal(const Trajectory& a, const Trajectory& b) {
  return a.pos.size() == b.pos.size() &&
         std::memcmp(a.pos.data(), b.pos.data(), a.pos.size() * sizeof(PosRad)) == 0 &&
         std::memcmp(a.vel.data(), b.vel.data(), a.vel.size() * sizeof(Vec3)) == 0 &&
         a.crack_bonds == b.crack_bonds && a.wall_force == b.wall_force;
}

// The largest distance between the two runs' grain centres.
double largest_shift(const Trajectory& a, const Trajectory& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.pos.size(); ++i)
    d = std::max(d, std::sqrt(norm2(a.pos[i].x - b.pos[i].x)));
  return d;
}

}  // namespace

TEST(InstructionSet, NamesRoundTripAndTheBaselineAlwaysRuns) {
  for (InstructionSet set : kInstructionSets)
    EXPECT_EQ(instruction_set_from_name(instruction_set_name(set)), set);
  EXPECT_EQ(instruction_set_name(InstructionSet::baseline), "baseline");
  EXPECT_EQ(instruction_set_name(InstructionSet::x86_64_v3), "x86-64-v3");
  EXPECT_FALSE(instruction_set_from_name("x86-64-v4"));
  EXPECT_FALSE(instruction_set_from_name("avx2"));
  EXPECT_TRUE(instruction_set_supported(InstructionSet::baseline));
  EXPECT_TRUE(instruction_set_supported(best_instruction_set()));
  EXPECT_EQ(best_instruction_set(), instruction_set_supported(InstructionSet::x86_64_v3)
                                        ? InstructionSet::x86_64_v3
                                        : InstructionSet::baseline);
}

TEST(InstructionSet, TheExperimentNamesItsSetOrIsToldWhatTheCpuRuns) {
  ExperimentSpec spec =
      parse_experiment("[engine]\ninstruction_set = \"baseline\"\n", "e.toml", {});
  EXPECT_EQ(instruction_set_of(spec), InstructionSet::baseline);
  spec = parse_experiment("", "e.toml", {});
  EXPECT_EQ(spec.instruction_set, "auto");
  EXPECT_EQ(instruction_set_of(spec), best_instruction_set());
  try {
    parse_experiment("[engine]\ninstruction_set = \"x86-64-v4\"\n", "e.toml", {});
    FAIL() << "an unknown set must be refused";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "engine.instruction_set");
    EXPECT_NE(std::string(e.what()).find("x86-64-v3"), std::string::npos) << e.what();
  }
  spec = parse_experiment("[engine]\ninstruction_set = \"x86-64-v3\"\n", "e.toml", {});
  if (instruction_set_supported(InstructionSet::x86_64_v3)) {
    EXPECT_EQ(instruction_set_of(spec), InstructionSet::x86_64_v3);
  } else {
    EXPECT_THROW(instruction_set_of(spec), InputError);
    EXPECT_THROW(
        test::compressed_block(2, 2, 2, 1.0, 1e6, 0.7, {}, false, InstructionSet::x86_64_v3),
        InputError);
  }
}

TEST(InstructionSet, EverySetIsBitwiseAtOneAndTwoThreads) {
  for (Block block : {Block::Breaking, Block::Lanes})
    for (InstructionSet set : kInstructionSets) {
      if (!instruction_set_supported(set)) continue;
      const Trajectory one = run(set, 1, block), two = run(set, 2, block);
      EXPECT_TRUE(bitwise_equal(one, two)) << instruction_set_name(set);
      EXPECT_NE(one.wall_force, 0.0);
      if (block == Block::Breaking) {
        EXPECT_FALSE(one.crack_bonds.empty()) << "the run must break bonds";
      }
    }
}

// Before any bond breaks and without local damping: a break is a threshold, and so is the sign of
// a grain's velocity that local damping's force follows, so once rounding tips one over it the two
// runs go separate ways (with the damping of 0.7 the elastic block's grains part by 4e-6 of a
// radius in 2,500 steps), as runs at two platen speeds would.
TEST(InstructionSet, TheSetsDifferOnlyByTheRoundingOfFusedMultiplyAdds) {
  if (!instruction_set_supported(InstructionSet::x86_64_v3))
    GTEST_SKIP() << "this CPU has no x86-64-v3: only the baseline runs";
  for (Block block : {Block::Elastic, Block::Lanes}) {
    const Trajectory base = run(InstructionSet::baseline, 1, block);
    const Trajectory v3 = run(InstructionSet::x86_64_v3, 1, block);
    ASSERT_TRUE(base.crack_bonds.empty() && v3.crack_bonds.empty());
    // The v3 kernels ran (their fused multiply-adds round differently) ...
    EXPECT_FALSE(bitwise_equal(base, v3));
    // ... and agree with the baseline as rounding does. Measured: the largest shift of a grain
    // 8e-13 of its radius (elastic block, 2,500 steps) and 7e-14 (lanes, 600 steps), the platen
    // force 4e-13 and 1.2e-12 apart relatively; the bounds are ten times these. A kernel that lost
    // or misplaced a term would shift grains by a fraction of a step's platen advance, 1e-4 of a
    // radius here.
    EXPECT_LT(largest_shift(base, v3), 1e-11 * base.radius);
    EXPECT_NEAR(v3.wall_force, base.wall_force, 1e-11 * std::abs(base.wall_force));
  }
}
