// One sample split over the ranks of mpirun (ctest starts this program at 1 to 4 ranks): every
// rank's ghost plan, made knowing its own particles only, is the one-process reference
// (ghosts_of), and what each rank sends an earlier one is what that one keeps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>

#include "block_fixture.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/engine/domain.hpp"
#include "breccia/engine/neighbour_grid.hpp"
#include "domain_cloud.hpp"
#include "pair_harness.hpp"

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

// Groups of consecutive ranks (a sweep's runs split over groups): while a group lives, rank, size,
// root and every collective are the group's; other groups' ranks neither see nor wait for them;
// after it, the launch's again. Groups that do not divide the launch are refused.
TEST(MpiDomain, GroupsOfRanksSpeakOfTheirGroup) {
  const int n = ranks::size(), me = ranks::rank();
  for (int each = 1; each <= n; ++each) {
    if (n % each != 0) {
      EXPECT_THROW(ranks::Group{each}, std::invalid_argument);
      continue;
    }
    {
      const ranks::Group group(each);
      EXPECT_EQ(group.count(), n / each);
      EXPECT_EQ(group.index(), me / each);
      EXPECT_EQ(group.first_rank(), me / each * each);
      EXPECT_EQ(ranks::size(), each);
      EXPECT_EQ(ranks::rank(), me % each);
      EXPECT_EQ(ranks::launch_size(), n);
      EXPECT_EQ(ranks::launch_rank(), me);
      // The group's root speaks for it; each group hears its own.
      EXPECT_EQ(ranks::broadcast(std::to_string(me)), std::to_string(group.first_rank()));
      const std::vector<std::string> all = ranks::all_gather(std::to_string(me));
      ASSERT_EQ(all.size(), static_cast<std::size_t>(each));
      for (int r = 0; r < each; ++r) EXPECT_EQ(all[r], std::to_string(group.first_rank() + r));
      // A flag raised on the last group's root only reaches that group.
      const bool last_group = group.index() == group.count() - 1;
      const std::uint32_t flags = ranks::any_flags(last_group && ranks::root() ? 1u : 0u);
      EXPECT_EQ(flags, last_group ? 1u : 0u) << "rank " << me;
    }
    EXPECT_EQ(ranks::size(), n);
    EXPECT_EQ(ranks::rank(), me);
    EXPECT_EQ(ranks::broadcast(std::to_string(me)), "0");
  }
}

// Fewer grains than ranks have blocks for: the first ranks own none and must still take part.
TEST(MpiDomain, RanksWithoutParticlesTakePart) {
  check_plan(1500, true, 0.3);
}

namespace {

// A pair load that rounds differently in every order it could be summed in: a soft repulsion
// that falls with the cube of the distance, on the second particle of (i, j).
Vec3 toy_load(const PosRad& a, const PosRad& b) {
  const Vec3 d = b.x - a.x;
  const double l = std::sqrt(norm2(d));
  return d * ((a.r + b.r) / (l * l * l + 0.1));
}

// The pair pass of one process over `p`, in the engine's order (state/pair_list.hpp): blocks of
// kParticleBlock particles own the pairs of their first particles and sum into their own
// particles' totals in pair order; a pair whose second particle lies in a later block leaves its
// share in a cross slot, added after the totals in slot order. The pairs are those listed at
// `built` (the last rebuild), as the engine's are.
std::vector<Vec3> one_process_loads(const std::vector<PosRad>& built, const std::vector<PosRad>& p,
                                    double skin) {
  PairList list;
  build_neighbour_pairs(built, skin, false, list);
  list.build_cross_index(p.size());
  std::vector<Vec3> total(p.size());
  std::vector<Vec3> cross;
  for (std::size_t b = 0; b * kParticleBlock < p.size(); ++b) {
    const std::size_t end = std::min(p.size(), (b + 1) * kParticleBlock);
    for (std::size_t i = b * kParticleBlock; i < end; ++i)
      for (std::uint32_t k = list.offsets[i]; k < list.offsets[i + 1]; ++k) {
        const std::uint32_t j = list.second[k];
        const Vec3 f = toy_load(p[i], p[j]);
        total[i] -= f;
        if (j < end)
          total[j] += f;
        else
          cross.push_back(f);
      }
  }
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::uint32_t m = list.cross_in_offsets[i]; m < list.cross_in_offsets[i + 1]; ++m)
      total[i] += cross[list.cross_in[m]];
  return total;
}

// The same pass on this rank: its own particles and its ghosts (moved since the plan: their
// positions come from their owners), its own blocks only; a share for a ghost goes back to its
// owner, and a particle's total is its own sum, then what earlier ranks sent, then its cross
// slots.
std::vector<Vec3> rank_loads(const std::vector<PosRad>& built, const std::vector<PosRad>& mine,
                             const GhostPlan& plan, const std::vector<IndexRange>& ranges,
                             double skin) {
  std::vector<PosRad> local_built = built, local = mine;
  for (const PosRad& g : plan.ghost_pos_rad) local_built.push_back(g);
  for (const PosRad& g : ghost_values(plan, mine)) local.push_back(g);
  PairList list;
  build_neighbour_pairs(local_built, skin, false, list);
  const std::size_t n = mine.size();
  std::vector<Vec3> total(n);
  std::vector<std::vector<Vec3>> cross(n);  // per particle, in pair order
  std::vector<Share<Vec3>> shares;
  for (std::size_t b = 0; b * kParticleBlock < n; ++b) {
    const std::size_t end = std::min(n, (b + 1) * kParticleBlock);
    for (std::size_t i = b * kParticleBlock; i < end; ++i)
      for (std::uint32_t k = list.offsets[i]; k < list.offsets[i + 1]; ++k) {
        const std::uint32_t j = list.second[k];
        const Vec3 f = toy_load(local[i], local[j]);
        total[i] -= f;
        if (j < end)
          total[j] += f;
        else if (j < n)
          cross[j].push_back(f);
        else
          shares.push_back({plan.ghosts[j - n], f});
      }
  }
  const IncomingShares<Vec3> in = return_shares(ranges, shares);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t m = in.offsets[i]; m < in.offsets[i + 1]; ++m) total[i] += in.values[m];
    for (const Vec3& f : cross[i]) total[i] += f;
  }
  return total;
}

}  // namespace

// The loads summed over ranks are those of one process to the bit: the ranks walk the blocks and
// pairs one process walks, and the shares that cross ranks arrive in cross-slot order. The
// ghosts' positions are sent again after every grain moved (as each step will).
TEST(MpiDomain, PairLoadsOverRanksAreThoseOfOneProcessToTheBit) {
  const double skin = 0.3;
  auto cloud = breccia::testing::domain_cloud(6000, true);
  const auto ranges = split_indexes(cloud.size(), ranks::size());
  const IndexRange own = ranges[static_cast<std::size_t>(ranks::rank())];
  std::vector<PosRad> mine(cloud.begin() + static_cast<std::ptrdiff_t>(own.begin),
                           cloud.begin() + static_cast<std::ptrdiff_t>(own.end));
  const GhostPlan plan = plan_ghosts(mine, ranges, skin);
  // Every grain moves (by less than the skin: the lists stand until the next rebuild).
  const std::vector<PosRad> built = cloud, mine_built = mine;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    cloud[i].x += Vec3{0.02 * uniform01(9, 1, i), -0.02 * uniform01(9, 2, i), 0.01};
  for (std::size_t k = 0; k < mine.size(); ++k) mine[k] = cloud[own.begin + k];
  const std::vector<Vec3> reference = one_process_loads(built, cloud, skin);
  const std::vector<Vec3> ours = rank_loads(mine_built, mine, plan, ranges, skin);
  ASSERT_EQ(ours.size(), own.size());
  std::size_t differ = 0;
  for (std::size_t k = 0; k < ours.size(); ++k)
    if (!(ours[k] == reference[own.begin + k])) ++differ;
  EXPECT_EQ(differ, 0u) << "rank " << ranks::rank() << " of " << ranks::size();
}

namespace {

// A field's bytes, to compare across ranks.
template <class T>
std::string bytes_of(const std::vector<T>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}
template <class T>
void append_bytes(std::string& out, const T& x) {
  out.append(reinterpret_cast<const char*>(&x), sizeof(T));
}

// Root's text on every rank (the others pass nothing).
std::string from_root(const std::string& mine) {
  return ranks::all_gather(ranks::root() ? mine : std::string())[0];
}

// How many elements of sizeof(T) bytes differ between two fields' bytes.
template <class T>
std::size_t differing(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size()) / sizeof(T);
  std::size_t n = 0;
  for (std::size_t at = 0; at < a.size(); at += sizeof(T))
    n += std::memcmp(a.data() + at, b.data() + at, sizeof(T)) != 0 ? 1 : 0;
  return n;
}

// What the tests compare of a simulation, field by field: every particle's state and loads, the
// walls, the ledger and the crack catalogue.
struct ComparedState {
  std::string pos_rad, vel, angvel, force, torque, orientation, displacement, walls, ledger, cracks;
};

ComparedState compared_state(const Simulation& sim) {
  const ParticleStore& p = sim.particles();
  ComparedState s{bytes_of(p.pos_rad),
                  bytes_of(p.vel),
                  bytes_of(p.angvel),
                  bytes_of(p.force),
                  bytes_of(p.torque),
                  bytes_of(p.orientation),
                  bytes_of(p.displacement),
                  {},
                  {},
                  {}};
  for (const auto& w : sim.walls()) {
    append_bytes(s.walls, w.force);
    append_bytes(s.walls, w.work);
    append_bytes(s.walls, w.contacts);
  }
  append_bytes(s.ledger, sim.ledger());
  for (const CrackRecord& c : sim.cracks()) {
    s.cracks += c.law;
    append_bytes(s.cracks, c.bond_tag);
    append_bytes(s.cracks, c.position);
    append_bytes(s.cracks, c.energy.total());
  }
  return s;
}

// Steps the one-process copy (on root alone: the other ranks compare with root's) and the split
// simulation side by side.
void step_both(Simulation& reference, Simulation& split, int steps) {
  for (int s = 0; s < steps; ++s) {
    if (ranks::root()) reference.step();
    split.step();
  }
}

// A split simulation against the one-process copy root stepped: every particle's state and
// loads, the walls, the ledger and the crack catalogue, to the bit, on every rank.
void expect_same_state(Simulation& split, const Simulation& reference) {
  split.gather_particles();
  const ComparedState a = compared_state(split);
  const ComparedState b = ranks::root() ? compared_state(reference) : ComparedState{};
  const std::string where = "rank " + std::to_string(ranks::rank()) + " of " +
                            std::to_string(ranks::size()) + ", step " +
                            std::to_string(split.step_count());
  EXPECT_EQ(differing<PosRad>(a.pos_rad, from_root(b.pos_rad)), 0u) << where;
  EXPECT_EQ(differing<Vec3>(a.vel, from_root(b.vel)), 0u) << where;
  EXPECT_EQ(differing<Vec3>(a.angvel, from_root(b.angvel)), 0u) << where;
  EXPECT_EQ(differing<Vec3>(a.force, from_root(b.force)), 0u) << where;
  EXPECT_EQ(differing<Vec3>(a.torque, from_root(b.torque)), 0u) << where;
  EXPECT_EQ(differing<Quat>(a.orientation, from_root(b.orientation)), 0u) << where;
  EXPECT_EQ(differing<Vec3>(a.displacement, from_root(b.displacement)), 0u) << where;
  EXPECT_TRUE(a.walls == from_root(b.walls)) << "the walls' force, work and contacts, " << where;
  EXPECT_TRUE(a.ledger == from_root(b.ledger)) << "the energy ledger, " << where;
  const std::string cracks = from_root(b.cracks);
  EXPECT_EQ(a.cracks.size(), cracks.size()) << "the crack catalogue's length, " << where;
  EXPECT_TRUE(a.cracks == cracks) << "the crack catalogue, " << where;
}

// An inclined bonded smooth joint across the crushed block of the tests below.
void with_inclined_joint(Simulation& sim) {
  SmoothJoint::Params p;
  p.friction = 0.3;
  p.bonded = true;
  p.tensile_strength = 1e6;
  p.cohesion = 1e6;
  p.friction_angle_deg = 20;
  sim.set_joint_params<SmoothJoint>(p);
  JointPlane plane;
  plane.point = {3.5e-3, 3.5e-3, 14e-3};
  plane.normal = {std::sin(0.9), 0, std::cos(0.9)};
  sim.add_joint_plane(plane);
}

}  // namespace

// A bonded block crushed between two platens until thousands of bonds break and the lists are
// rebuilt (at about step 1,000), split over the ranks from its start: the state is that of one
// process at every check (root steps a one-process copy beside its part). 2,000 grains are two
// kDomainGrain grains: at 3 and 4 ranks the first ranks own none.
TEST(MpiDomain, EngineStepsOverRanksAreThoseOfOneProcessToTheBit) {
  set_threads(1);
  Simulation reference = test::compressed_block(5, 5, 20, 8.0, 3e6);
  Simulation split = test::compressed_block(5, 5, 20, 8.0, 3e6);
  split.split_over_ranks();
  EXPECT_EQ(split.split(), ranks::size() > 1);
  step_both(reference, split, 400);
  expect_same_state(split, reference);
  step_both(reference, split, 700);
  ASSERT_GT(split.cracks().size(), 1000u) << "the test must break bonds";
  ASSERT_GT(split.neighbour_rebuilds(), 1u) << "the test must rebuild the lists";
  expect_same_state(split, reference);
}

// A split made in mid-run, between two rebuilds, keeps the lists of the last one: the run goes
// on as one process's, through the next rebuild. 4,096 grains: one kDomainGrain grain for each of
// 4 ranks.
TEST(MpiDomain, ASplitInMidRunGoesOnAsOneProcess) {
  set_threads(1);
  Simulation reference = test::compressed_block(8, 8, 16, 8.0, 3e6);
  Simulation split = test::compressed_block(8, 8, 16, 8.0, 3e6);
  step_both(reference, split, 333);
  ASSERT_GT(split.cracks().size(), 0u) << "the split must come after bonds broke";
  split.split_over_ranks();
  step_both(reference, split, 1050 - 333);
  ASSERT_GT(split.neighbour_rebuilds(), 1u) << "the test must rebuild the lists";
  expect_same_state(split, reference);
  // Packing's changes read every grain: refused on a split sample, on every rank alike.
  if (split.split()) {
    EXPECT_THROW(split.scale_radii(1.01), std::logic_error);
    EXPECT_THROW(split.displace_particle(0, {1e-6, 0, 0}), std::logic_error);
  }
}

// A reader's grains are brought from their owners alone: the listed grains are then those of
// one process, every other grain's entries are left as they were, and a whole gather completes
// the rest. A list that is not ascending is refused on every rank alike, before any exchange.
TEST(MpiDomain, GatheredGrainsAreCurrentAndTheOthersUntouched) {
  set_threads(1);
  Simulation reference = test::compressed_block(8, 8, 16, 8.0, 3e6);
  Simulation split = test::compressed_block(8, 8, 16, 8.0, 3e6);
  split.split_over_ranks();
  for (int s = 0; s < 60; ++s) {  // every rank steps its copy: each compares its listed grains
    reference.step();
    split.step();
  }
  std::vector<std::uint32_t> listed;
  for (std::uint32_t i = 5; i < split.particles().size(); i += 97) listed.push_back(i);
  const std::vector<PosRad> before = split.particles().pos_rad;
  const std::vector<Vec3> vel_before = split.particles().vel;
  EXPECT_THROW(split.gather_grains({.all = false, .some = std::vector<std::uint32_t>{9, 3}}),
               std::logic_error);
  split.gather_grains({.all = false, .some = listed});
  const ParticleStore& a = split.particles();
  const ParticleStore& b = reference.particles();
  std::size_t listed_wrong = 0, others_changed = 0, others_stale = 0;
  for (std::size_t i = 0, k = 0; i < a.size(); ++i) {
    const bool in_list = k < listed.size() && listed[k] == i;
    if (in_list) ++k;
    const bool same_as_one_process =
        std::memcmp(&a.pos_rad[i], &b.pos_rad[i], sizeof(PosRad)) == 0 &&
        std::memcmp(&a.vel[i], &b.vel[i], sizeof(Vec3)) == 0 &&
        std::memcmp(&a.force[i], &b.force[i], sizeof(Vec3)) == 0;
    if (in_list) {
      listed_wrong += same_as_one_process ? 0 : 1;
      continue;
    }
    if (split.owned_particles().contains(i)) continue;
    others_changed += std::memcmp(&a.pos_rad[i], &before[i], sizeof(PosRad)) != 0 ||
                              std::memcmp(&a.vel[i], &vel_before[i], sizeof(Vec3)) != 0
                          ? 1
                          : 0;
    others_stale += same_as_one_process ? 0 : 1;
  }
  const std::string where =
      "rank " + std::to_string(ranks::rank()) + " of " + std::to_string(ranks::size());
  EXPECT_EQ(listed_wrong, 0u) << where;
  EXPECT_EQ(others_changed, 0u) << where;
  // The unlisted grains of other ranks are behind one process (they moved in 60 steps): what
  // the listed ones show is the gather's doing.
  if (split.split()) {
    EXPECT_GT(others_stale, 0u) << where;
  }
  expect_same_state(split, reference);
}

// An inclined bonded joint across the crushed block: its joints break and slide on every rank
// they belong to, and the unbonded joints that neighbour rebuilds add take their tags in pair
// order across the ranks.
TEST(MpiDomain, JointedBlockOverRanksIsThatOfOneProcess) {
  set_threads(1);
  Simulation reference = test::compressed_block(5, 5, 20, 8.0, 3e6, 0.7, with_inclined_joint);
  Simulation split = test::compressed_block(5, 5, 20, 8.0, 3e6, 0.7, with_inclined_joint);
  ASSERT_GT(reference.bonded_joints(), 0u);
  split.split_over_ranks();
  step_both(reference, split, 1100);
  ASSERT_GT(split.neighbour_rebuilds(), 1u);
  expect_same_state(split, reference);
}

namespace {

// A bonded block thrown apart: every grain starts with a velocity that grows with its distance
// from the centre, and soft, unbreakable bonds stretch beyond the lists' reach before they pull
// the grains back, through many neighbour rebuilds; partners beyond reach then lie on other ranks
// (4,096 grains: one kDomainGrain grain for each of 4 ranks).
Simulation expanding_block(double bond_modulus, double rate) {
  const double R = 0.5e-3;
  ParticleStore ps = fcc_block(8, 8, 16, R, 2650);
  Vec3 centre{};
  for (const PosRad& q : ps.pos_rad) centre += q.x / static_cast<double>(ps.size());
  for (std::size_t i = 0; i < ps.size(); ++i) ps.vel[i] = (ps.pos_rad[i].x - centre) * rate;
  EngineConfig cfg;
  cfg.local_damping = 0.0;
  cfg.energy_interval = 50;
  LinearContact::Params lp;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>(lp, lp));
  ParallelBond::Params bp;
  bp.modulus = bond_modulus;
  bp.tensile_strength = bp.cohesion = 1e15;
  sim.set_bond_params<ParallelBond>(bp);
  sim.bond_touching_pairs<ParallelBond>(1e-9);
  sim.initialise();
  return sim;
}

// The bonds whose grains lie on two ranks and beyond the lists' reach (positions of `sim`, made
// whole first).
std::size_t far_bonds_across_ranks(
    Simulation& sim, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& bonds,
    double skin) {
  sim.gather_particles();
  const auto ranges = split_indexes(sim.particles().size(), ranks::size());
  const auto rank_of = [&](std::uint32_t i) {
    std::size_t r = 0;
    while (!ranges[r].contains(i)) ++r;
    return r;
  };
  std::size_t n = 0;
  for (const auto& [i, j] : bonds)
    n += rank_of(i) != rank_of(j) &&
                 !within_reach(sim.particles().pos_rad[i], sim.particles().pos_rad[j], skin)
             ? 1
             : 0;
  return n;
}

}  // namespace

// Bonded partners beyond the lists' reach stay ghosts of the ranks that hold their bonds, at the
// split and at every rebuild: the stretched block steps as one process through rebuilds made
// while such bonds cross ranks.
TEST(MpiDomain, BondPartnersBeyondReachStayGhostsThroughRebuilds) {
  if (ranks::size() == 1) GTEST_SKIP() << "one rank has no partner on another";
  set_threads(1);
  // Strain rate 2.5e4 /s against bonds whose lattice swings at about 6e4 rad/s: the block
  // stretches by up to about 40 %, and past the skin (0.4 radii) after about 250 steps.
  Simulation reference = expanding_block(5e5, 2.5e4);
  Simulation split = expanding_block(5e5, 2.5e4);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> bonds;
  reference.for_each_intact_bond(
      [&](std::uint32_t i, std::uint32_t j) { bonds.emplace_back(i, j); });
  const double skin = 0.4 * 0.5e-3;  // the default: 0.4 x the mean radius
  split.split_over_ranks();
  bool rebuilt_with_far_bonds = false;
  for (int chunk = 0; chunk < 8; ++chunk) {
    const std::size_t far = far_bonds_across_ranks(split, bonds, skin);
    const std::uint64_t rebuilds = split.neighbour_rebuilds();
    step_both(reference, split, 50);
    rebuilt_with_far_bonds =
        rebuilt_with_far_bonds || (far > 0 && split.neighbour_rebuilds() > rebuilds);
  }
  EXPECT_TRUE(rebuilt_with_far_bonds) << "the test must rebuild while far bonds cross ranks";
  ASSERT_EQ(split.sample_counts().intact_bonds, bonds.size()) << "no bond may break";
  expect_same_state(split, reference);
}

namespace {

// The simulation's checkpoint bytes.
std::string checkpoint_of(const Simulation& sim) {
  std::ostringstream out;
  ArchiveWriter w(out);
  sim.save_state(w);
  return out.str();
}

// Where two checkpoints first differ, with the last section label before it ("" if they do not).
std::string first_difference(const std::string& a, const std::string& b) {
  if (a == b) return "";
  std::size_t at = 0;
  while (at < a.size() && at < b.size() && a[at] == b[at]) ++at;
  std::string label = "(none)";
  std::size_t best = 0;
  for (const char* name : {"simulation", "contacts", "bonds", "walls", "clock", "cracks", "ledger"})
    if (const auto p = a.rfind(name, at); p != std::string::npos && p >= best) {
      best = p;
      label = name;
    }
  return "sizes " + std::to_string(a.size()) + " and " + std::to_string(b.size()) +
         ", first difference at byte " + std::to_string(at) + " in section '" + label + "'";
}

}  // namespace

// A split sample gathered whole again is one process's to the bit: its checkpoint is that
// process's, byte for byte, after breaks, a rebuild and new joints; split again, it goes on as
// one process, and gathers again to the same bytes. Before that, the pair loads around grains
// (what the AE monitor reads) are those one process lists.
TEST(MpiDomain, AGatheredSplitIsOneProcessToTheBit) {
  set_threads(1);
  Simulation reference = test::compressed_block(5, 5, 20, 8.0, 3e6, 0.7, with_inclined_joint);
  Simulation split = test::compressed_block(5, 5, 20, 8.0, 3e6, 0.7, with_inclined_joint);
  split.split_over_ranks();
  step_both(reference, split, 1100);
  ASSERT_GT(split.neighbour_rebuilds(), 1u);
  ASSERT_GT(split.cracks().size(), 100u);
  // The pair loads around grains of every rank's range, as one process lists them.
  const std::size_t n = reference.particles().size();
  const std::vector<std::uint32_t> grains = {0, 7, static_cast<std::uint32_t>(n / 2),
                                             static_cast<std::uint32_t>(n - 1)};
  std::vector<std::uint32_t> offsets_split, offsets_one;
  std::vector<Simulation::PairLoad> loads_split, loads_one;
  split.pair_loads_around(grains, offsets_split, loads_split);
  if (ranks::root()) reference.pair_loads_around(grains, offsets_one, loads_one);
  EXPECT_TRUE(bytes_of(offsets_split) == from_root(bytes_of(offsets_one)))
      << "rank " << ranks::rank();
  EXPECT_GT(loads_split.size(), 20u);
  std::string loads_here;
  for (const Simulation::PairLoad& l : loads_split) {
    append_bytes(loads_here, l.other);
    append_bytes(loads_here, l.force);
  }
  std::string loads_there;
  for (const Simulation::PairLoad& l : loads_one) {
    append_bytes(loads_there, l.other);
    append_bytes(loads_there, l.force);
  }
  EXPECT_TRUE(loads_here == from_root(loads_there)) << "rank " << ranks::rank();
  split.unsplit();
  EXPECT_FALSE(split.split());
  const auto root_checkpoint = [&] {
    return from_root(ranks::root() ? checkpoint_of(reference) : std::string());
  };
  EXPECT_EQ(first_difference(checkpoint_of(split), root_checkpoint()), "")
      << "rank " << ranks::rank();
  split.split_over_ranks();
  step_both(reference, split, 150);
  expect_same_state(split, reference);
  split.unsplit();
  EXPECT_EQ(first_difference(checkpoint_of(split), root_checkpoint()), "")
      << "rank " << ranks::rank();
}

// Dynamic damping over ranks: each rank marks its own grains from every rank's cracks of the
// step, so a split made in mid-run, with marks already set, steps as one process through the
// next rebuild, and the gathered marks are one process's (the checkpoints hold them).
TEST(MpiDomain, DynamicDampingOverRanksIsThatOfOneProcess) {
  set_threads(1);
  const auto dynamic = [](Simulation& sim) { sim.set_dynamic_damping(0.0, 2e-3, 2e-5); };
  Simulation reference = test::compressed_block(5, 5, 20, 8.0, 3e6, 0.7, dynamic);
  Simulation split = test::compressed_block(5, 5, 20, 8.0, 3e6, 0.7, dynamic);
  step_both(reference, split, 500);
  ASSERT_GT(split.cracks().size(), 0u) << "the split must come after bonds broke";
  split.split_over_ranks();
  step_both(reference, split, 600);
  ASSERT_GT(split.neighbour_rebuilds(), 1u) << "the test must rebuild the lists";
  std::size_t marked = 0;
  for (std::size_t i = 0; i < split.particles().size(); ++i)
    marked += std::isfinite(split.dynamically_damped_until(i)) ? 1 : 0;
  EXPECT_GT(marked, 100u) << "rank " << ranks::rank();
  expect_same_state(split, reference);
  split.unsplit();
  EXPECT_EQ(first_difference(checkpoint_of(split),
                             from_root(ranks::root() ? checkpoint_of(reference) : std::string())),
            "")
      << "rank " << ranks::rank();
}

namespace {

// Runs a law block split over the ranks beside a one-process copy and compares them: spheres
// (4,096: a kDomainGrain grain for each of 4 ranks) or disks (2,160: two grains).
template <class CL, class BL>
void expect_law_block_over_ranks() {
  set_threads(1);
  const int size = planar_only_law<BL> ? 6 : 4;
  Simulation reference = test::law_block<CL, BL>(false, size);
  Simulation split = test::law_block<CL, BL>(false, size);
  split.split_over_ranks();
  step_both(reference, split, 300);
  ASSERT_GT(split.sample_counts().intact_bonds, 0u);
  expect_same_state(split, reference);
}

template <class Law>
class EveryBondLawOverRanks : public ::testing::Test {};
TYPED_TEST_SUITE(EveryBondLawOverRanks, test::GTypes<BondLaws>::type);
template <class Law>
class EveryContactLawOverRanks : public ::testing::Test {};
TYPED_TEST_SUITE(EveryContactLawOverRanks, test::GTypes<EngineContactLaws>::type);

}  // namespace

// Every registered law steps over ranks as in one process (ctest runs these at 2 ranks: the laws
// differ in what a pair computes, not in how the ranks share it).
TYPED_TEST(EveryBondLawOverRanks, StepsAreThoseOfOneProcess) {
  expect_law_block_over_ranks<LinearContact, TypeParam>();
}
TYPED_TEST(EveryContactLawOverRanks, StepsAreThoseOfOneProcess) {
  expect_law_block_over_ranks<TypeParam, ParallelBond>();
}

namespace {

// What the other ranks print: their failed assertions alone, each with its rank and test (named
// when the test starts: asking gtest for the current test while it reports a result deadlocks).
class FailurePrinter : public ::testing::EmptyTestEventListener {
  std::string test_;
  void OnTestStart(const ::testing::TestInfo& t) override {
    test_ = std::string(t.test_suite_name()) + "." + t.name();
  }
  void OnTestPartResult(const ::testing::TestPartResult& r) override {
    if (!r.failed()) return;
    std::fprintf(stderr, "rank %d: %s failed at %s:%d\n%s\n", ranks::rank(), test_.c_str(),
                 r.file_name() ? r.file_name() : "?", r.line_number(), r.message());
  }
};

}  // namespace

int main(int argc, char** argv) {
  const ranks::World world(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  // Only root prints the tests' progress; every other rank prints its failures.
  if (!ranks::root()) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
    listeners.Append(new FailurePrinter);
  }
  return RUN_ALL_TESTS();
}
