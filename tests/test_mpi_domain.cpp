// One sample split over the ranks of mpirun (ctest starts this program at 1 to 4 ranks): every
// rank's ghost plan, made knowing its own particles only, is the one-process reference
// (ghosts_of), and what each rank sends an earlier one is what that one keeps.
#include <gtest/gtest.h>

#include <string>

#include "breccia/core/ranks.hpp"
#include "breccia/engine/domain.hpp"
#include "domain_cloud.hpp"

using namespace breccia;

namespace {

std::string as_text(const std::vector<std::uint32_t>& v) {
  std::string s;
  for (std::uint32_t x : v) s += std::to_string(x) + " ";
  return s;
}

// Every rank's plan for a cloud checked against the reference and against the others' plans.
void check_plan(std::size_t n, bool curve_order, double skin) {
  const auto cloud = breccia::testing::domain_cloud(n, curve_order);
  const auto ranges = split_indexes(n, ranks::size());
  const IndexRange own = ranges[static_cast<std::size_t>(ranks::rank())];
  const std::vector<PosRad> mine(cloud.begin() + static_cast<std::ptrdiff_t>(own.begin),
                                 cloud.begin() + static_cast<std::ptrdiff_t>(own.end));
  const GhostPlan plan = plan_ghosts(mine, ranges, skin);
  EXPECT_EQ(plan.ghosts, ghosts_of(cloud, own, skin)) << "rank " << ranks::rank();
  ASSERT_EQ(plan.ghost_pos_rad.size(), plan.ghosts.size());
  for (std::size_t k = 0; k < plan.ghosts.size(); ++k) {
    EXPECT_EQ(plan.ghost_pos_rad[k].x, cloud[plan.ghosts[k]].x);
    EXPECT_EQ(plan.ghost_pos_rad[k].r, cloud[plan.ghosts[k]].r);
  }
  // What this rank sends rank r, as global indexes, must be r's ghosts from this rank.
  std::vector<std::string> sent(static_cast<std::size_t>(ranks::size()));
  for (std::size_t r = 0; r < sent.size(); ++r) {
    std::vector<std::uint32_t> global;
    for (std::uint32_t k : plan.send[r])
      global.push_back(static_cast<std::uint32_t>(own.begin + k));
    sent[r] = as_text(global);
  }
  const std::vector<std::string> got = ranks::exchange(sent);
  for (std::size_t s = 0; s < got.size(); ++s) {
    std::vector<std::uint32_t> from_s;
    for (std::uint32_t g : plan.ghosts)
      if (ranges[s].contains(g)) from_s.push_back(g);
    EXPECT_EQ(got[s], as_text(from_s)) << "rank " << ranks::rank() << " from rank " << s;
  }
}

}  // namespace

// In the order of a space-filling curve, as a run keeps its grains: compact domains.
TEST(MpiDomain, GhostPlanIsTheReferenceInCurveOrder) {
  check_plan(6000, true, 0.3);
}

// In drawn order every rank's grains spread over the whole box: each rank is offered nearly every
// later grain and must keep exactly those within reach.
TEST(MpiDomain, GhostPlanIsTheReferenceInDrawnOrder) {
  check_plan(3000, false, 0.1);
}

// Fewer grains than ranks have blocks for: the first ranks own none and must still take part.
TEST(MpiDomain, RanksWithoutParticlesTakePart) {
  check_plan(1500, true, 0.3);
}

int main(int argc, char** argv) {
  const ranks::World world(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  // Only root prints the tests' progress; every rank reports its failures.
  if (!ranks::root()) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  return RUN_ALL_TESTS();
}
