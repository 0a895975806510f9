// The split of one sample over ranks (engine/domain.hpp), in one process: index ranges cut at
// whole blocks, and the ghost reference against a count by hand. tests/test_mpi_domain.cpp checks
// the ranks' own plan against this reference under mpirun.
#include <gtest/gtest.h>

#include "breccia/engine/domain.hpp"
#include "domain_cloud.hpp"

using namespace breccia;

TEST(Domain, RangesAreWholeBlocksInRankOrderAndAsEqualAsBlocksAllow) {
  // 10,000 particles: 10 grains of 1,024 (the last of 784) over 3 ranks: 3, 3, 4 grains, the
  // partial one with the last rank.
  const auto r = split_indexes(10000, 3);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].begin, 0u);
  EXPECT_EQ(r[0].end, 3072u);
  EXPECT_EQ(r[1].begin, 3072u);
  EXPECT_EQ(r[1].end, 6144u);
  EXPECT_EQ(r[2].begin, 6144u);
  EXPECT_EQ(r[2].end, 10000u);
  for (int ranks : {1, 2, 5, 7, 16})
    for (std::size_t n : {0u, 1u, 1023u, 1024u, 1025u, 99999u}) {
      const auto s = split_indexes(n, ranks);
      ASSERT_EQ(s.size(), static_cast<std::size_t>(ranks));
      std::size_t at = 0, most = 0, least = n;
      for (const IndexRange& k : s) {
        EXPECT_EQ(k.begin, at) << n << " over " << ranks;
        EXPECT_TRUE(k.begin % kDomainGrain == 0 || k.begin == n);
        at = k.end;
        most = std::max(most, k.size());
        least = std::min(least, k.size());
      }
      EXPECT_EQ(at, n);
      EXPECT_LE(most - least, kDomainGrain) << n << " over " << ranks;
    }
  // Fewer grains than ranks: the first ranks own nothing.
  const auto few = split_indexes(1500, 4);
  EXPECT_EQ(few[0].size(), 0u);
  EXPECT_EQ(few[1].size(), 0u);
  EXPECT_EQ(few[2].end, 1024u);
  EXPECT_EQ(few[3].end, 1500u);
}

// Three grains on a line, radius 1, skin 0.5: reach 2.5 between centres.
TEST(Domain, GhostsAreTheLaterParticlesWithinReachOfOwnOnes) {
  std::vector<PosRad> p(4);
  p[0] = {{0, 0, 0}, 1.0};
  p[1] = {{2.5, 0, 0}, 1.0};  // exactly at reach of 0: kept (the list's test is stricter)
  p[2] = {{5.0, 0, 0}, 1.0};  // 2.5 from 1, 5 from 0
  p[3] = {{0, 2.6, 0}, 1.0};  // just out of reach of 0
  EXPECT_EQ(ghosts_of(p, {0, 1}, 0.5), (std::vector<std::uint32_t>{1}));
  EXPECT_EQ(ghosts_of(p, {0, 2}, 0.5), (std::vector<std::uint32_t>{2}));
  EXPECT_EQ(ghosts_of(p, {0, 2}, 0.7), (std::vector<std::uint32_t>{2, 3}));
  EXPECT_TRUE(ghosts_of(p, {3, 4}, 10.0).empty()) << "the last range has no later particles";
}

// One rank: the plan has no ghosts and sends nothing.
TEST(Domain, OneRankPlansNoGhosts) {
  const auto cloud = breccia::testing::domain_cloud(3000, true);
  const GhostPlan plan = plan_ghosts(cloud, split_indexes(cloud.size(), 1), 0.3);
  EXPECT_TRUE(plan.ghosts.empty());
  ASSERT_EQ(plan.send.size(), 1u);
  EXPECT_TRUE(plan.send[0].empty());
}
