// The same input gives bitwise the same trajectory with 1 and 2 threads (design.md: two-pass
// force computation, fixed-block reductions, breaks processed in bond order).
#include <gtest/gtest.h>

#include <cstring>

#include "block_fixture.hpp"
#include "breccia/core/parallel.hpp"

using namespace breccia;

namespace {
const int kDefaultThreads = max_threads();

struct Outcome {
  std::vector<PosRad> pos;
  std::vector<Vec3> vel, angvel;
  std::vector<std::uint64_t> crack_bonds;
  double wall_force = 0.0, work = 0.0, residual = 0.0;
};

Outcome run_with_threads(int threads) {
  set_threads(threads);
  // 5 x 5 x 20 FCC cells = 2000 particles, weak bonds so that some break under compression.
  Simulation sim = test::compressed_block(5, 5, 20, 2.0, 3e6);
  EXPECT_EQ(sim.particles().size(), 2000u);
  sim.run(2500);
  Outcome o;
  o.pos = sim.particles().pos_rad;
  o.vel = sim.particles().vel;
  o.angvel = sim.particles().angvel;
  for (const auto& c : sim.cracks()) o.crack_bonds.push_back(c.bond_tag);
  o.wall_force = sim.walls()[1].force.z;
  o.work = sim.walls()[1].work;
  o.residual = sim.ledger().residual;
  set_threads(kDefaultThreads);
  return o;
}
}  // namespace

TEST(Determinism, OneAndTwoThreadsGiveBitwiseEqualTrajectories) {
  const Outcome a = run_with_threads(1);
  const Outcome b = run_with_threads(2);
  ASSERT_FALSE(a.crack_bonds.empty()) << "the test must exercise bond breakage";
  EXPECT_EQ(a.crack_bonds, b.crack_bonds);
  ASSERT_EQ(a.pos.size(), b.pos.size());
  EXPECT_EQ(0, std::memcmp(a.pos.data(), b.pos.data(), a.pos.size() * sizeof(PosRad)));
  EXPECT_EQ(0, std::memcmp(a.vel.data(), b.vel.data(), a.vel.size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(a.angvel.data(), b.angvel.data(), a.angvel.size() * sizeof(Vec3)));
  EXPECT_EQ(a.wall_force, b.wall_force);
  EXPECT_EQ(a.work, b.work);
  EXPECT_EQ(a.residual, b.residual);
  EXPECT_NE(a.wall_force, 0.0);
}
