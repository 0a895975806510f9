// Neighbour search against brute force, and contact history surviving list rebuilds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "block_fixture.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/engine/pair_lists.hpp"
#include "breccia/engine/simulation.hpp"

using namespace breccia;

namespace {
std::vector<PosRad> random_cloud(std::size_t n, bool planar, std::uint64_t seed) {
  std::vector<PosRad> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    p[i].x = {0.02 * uniform01(seed, 1, i), 0.015 * uniform01(seed, 2, i),
              planar ? 0.0 : 0.01 * uniform01(seed, 3, i)};
    p[i].r = 2e-4 + 4e-4 * uniform01(seed, 4, i);
  }
  return p;
}

// The pair pass's cross index (state/pair_list.hpp) against its definition: block b's cross slots
// are its pairs whose second particle lies beyond the block, numbered in pair order; particle j
// finds exactly the slots of its cross pairs, ascending.
void check_cross_index(const PairList& list, std::size_t n) {
  const std::size_t blocks = (n + kParticleBlock - 1) / kParticleBlock;
  ASSERT_GT(blocks, 1u);  // the cloud spans several blocks
  ASSERT_EQ(list.cross_begin.size(), blocks + 1);
  std::vector<std::uint32_t> second_of_slot;
  for (std::size_t b = 0; b < blocks; ++b) {
    EXPECT_EQ(list.cross_begin[b], second_of_slot.size());
    const std::size_t end = std::min(n, (b + 1) * kParticleBlock);
    for (std::size_t k = 0; k < list.size(); ++k)
      if (list.first[k] >= b * kParticleBlock && list.first[k] < end && list.second[k] >= end)
        second_of_slot.push_back(list.second[k]);
  }
  ASSERT_GT(second_of_slot.size(), 0u);
  EXPECT_EQ(list.cross_begin[blocks], second_of_slot.size());
  ASSERT_EQ(list.cross_slots(), second_of_slot.size());
  std::vector<int> seen(second_of_slot.size(), 0);
  for (std::size_t j = 0; j < n; ++j)
    for (auto m = list.cross_in_offsets[j]; m < list.cross_in_offsets[j + 1]; ++m) {
      const std::uint32_t slot = list.cross_in[m];
      EXPECT_EQ(second_of_slot[slot], j);
      if (m > list.cross_in_offsets[j]) {
        EXPECT_LT(list.cross_in[m - 1], slot);
      }
      ++seen[slot];
    }
  for (int c : seen) EXPECT_EQ(c, 1);
}

void check_against_brute_force(bool planar) {
  const auto p = random_cloud(1500, planar, planar ? 5 : 6);
  const double skin = 1e-4;
  PairList list;
  build_neighbour_pairs(p, skin, planar, list);
  list.build_cross_index(p.size());
  std::set<std::pair<std::uint32_t, std::uint32_t>> expected;
  for (std::uint32_t i = 0; i < p.size(); ++i)
    for (std::uint32_t j = i + 1; j < p.size(); ++j) {
      const double cut = p[i].r + p[j].r + skin;
      if (norm2(p[j].x - p[i].x) < cut * cut) expected.insert({i, j});
    }
  ASSERT_GT(expected.size(), 500u);
  ASSERT_EQ(list.size(), expected.size());
  std::size_t k = 0;
  for (const auto& [i, j] : expected) {  // sorted by (i, j), as the list must be
    EXPECT_EQ(list.first[k], i);
    EXPECT_EQ(list.second[k], j);
    ++k;
  }
  // The gather indexes cover every pair exactly once from each side.
  std::vector<int> seen(list.size(), 0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (auto s = list.offsets[i]; s < list.offsets[i + 1]; ++s) {
      EXPECT_EQ(list.first[s], i);
      ++seen[s];
    }
    for (auto m = list.in_offsets[i]; m < list.in_offsets[i + 1]; ++m) {
      EXPECT_EQ(list.second[list.in_slot[m]], i);
      ++seen[list.in_slot[m]];
    }
  }
  for (int c : seen) EXPECT_EQ(c, 2);
  check_cross_index(list, p.size());
}
}  // namespace

TEST(Neighbours, MatchBruteForce3D) {
  check_against_brute_force(false);
}
TEST(Neighbours, MatchBruteForce2D) {
  check_against_brute_force(true);
}

// A block's states in the order of first touch, with the entries of opened contacts zeroed, are
// rewritten in pair order with the histories in force only; each pair keeps its own state.
TEST(ContactHistory, RepackPutsTheStatesInPairOrder) {
  using State = LinearContact::State;
  auto state = [](double kn) {
    State s;
    s.kn = kn;
    s.n_old = {1, 0, 0};
    return s;
  };
  // Pairs 0..5 (pair k's state marked kn = 10 + k): pair 4 touched first, pair 1 opened (its entry
  // zeroed), pairs 2 and 5 never touched.
  std::vector<State> store = {state(14), State{}, state(10), state(13)};
  std::vector<std::uint32_t> history = {2, 1, kNoHistory, 3, 0, kNoHistory};
  engine_detail::repack_history(0, history.size(), history, store);
  ASSERT_EQ(store.size(), 3u);
  EXPECT_EQ(history, std::vector<std::uint32_t>({0, kNoHistory, kNoHistory, 1, 2, kNoHistory}));
  EXPECT_EQ(store[0].kn, 10.0);
  EXPECT_EQ(store[1].kn, 13.0);
  EXPECT_EQ(store[2].kn, 14.0);
}

// Only pairs that touched since the last rebuild hold a contact state: through breakage, grains
// moving apart and rebuilds, the pairs with history are exactly those whose grains overlapped at
// the last step's positions, every store entry belongs to exactly one pair, and the entries of
// contacts that opened are zeroed.
TEST(ContactHistory, OnlyPairsInTouchHoldAState) {
  Simulation sim = test::compressed_block(5, 5, 12, 2.0, 1e4);  // weak bonds: they break
  for (std::size_t i = 0; i < sim.particles().size(); ++i)
    for (int a = 0; a < 3; ++a) sim.particles_mut().vel[i][a] = 0.01 * standard_normal(3, a, i);
  sim.run(300);
  const auto rebuilds = sim.neighbour_rebuilds();
  std::vector<PosRad> before = sim.particles().pos_rad;
  for (int s = 0; s < 20000 && sim.neighbour_rebuilds() < rebuilds + 2; ++s) {
    before = sim.particles().pos_rad;
    sim.step();
  }
  ASSERT_GT(sim.neighbour_rebuilds(), rebuilds) << "the test must cross rebuilds";
  ASSERT_LT(sim.intact_bonds(), 100u) << "the test must break the bonds";
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        std::size_t touching = 0, with_history = 0;
        std::vector<std::vector<int>> owner(c.stores.size());
        for (std::size_t b = 0; b < c.stores.size(); ++b) owner[b].assign(c.stores[b].size(), 0);
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const PosRad& p = before[c.pairs.first[k]];
          const PosRad& q = before[c.pairs.second[k]];
          const bool touches = norm(q.x - p.x) < p.r + q.r;
          touching += touches ? 1 : 0;
          EXPECT_EQ(c.has_history(k), touches) << k;
          if (c.history[k] == kNoHistory) continue;
          ++owner[c.pairs.first[k] / kParticleBlock][c.history[k]];
          if (!c.has_history(k)) {
            EXPECT_EQ(c.state(k).normal_force, 0.0);
            EXPECT_EQ(norm(c.state(k).shear_force), 0.0);
            continue;
          }
          ++with_history;
          EXPECT_GT(norm(c.state(k).n_old), 0.5);
        }
        ASSERT_GT(touching, 50u);
        EXPECT_EQ(with_history, c.active());
        EXPECT_EQ(with_history, sim.active_contacts());
        for (const auto& owners : owner)
          for (int o : owners) EXPECT_EQ(o, 1) << "every entry belongs to exactly one pair";
      },
      sim.contact_model());
}

TEST(Neighbours, ContactHistorySurvivesRebuild) {
  // Particle 2 is pressed onto fixed particle 1 and dragged sideways (shear spring loads); a far
  // particle flies off to force neighbour-list rebuilds; the shear force carries on unchanged.
  const double R = 0.5e-3;
  ParticleStore ps(Dimension::Three, 1.0);
  ps.add({.tag = 1, .position = {0, 0, 0}, .radius = R, .density = 2650, .motion = Motion::Fixed});
  ps.add({.tag = 2,
          .position = {2 * R - 1e-6, 0, 0},
          .radius = R,
          .density = 2650,
          .velocity = {0, 1e-3, 0},
          .motion = Motion::Driven});
  ps.add(
      {.tag = 3, .position = {0, 0.01, 0}, .radius = R, .density = 2650, .velocity = {0, 0, 50.0}});
  EngineConfig cfg;
  cfg.time_step = 1e-8;
  LinearContact::Params lp;
  lp.friction = 10.0;  // no slip
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>(lp, lp));
  sim.initialise();
  const auto rebuilds0 = sim.neighbour_rebuilds();
  for (int k = 0; k < 2000; ++k) sim.step();
  EXPECT_GT(sim.neighbour_rebuilds(), rebuilds0 + 5);
  // Shear force = k_s (tangential path) = k_s * steps * v dt.
  const double ks = 7.853981633974483e6 / 2.5;
  const double expected = ks * 1e-3 * 1e-8 * 2000;
  const Vec3 f = sim.particles().force[1];
  // Normal of the configuration the force belongs to (before the last drift).
  const Vec3 x2 = sim.particles().pos_rad[1].x - sim.particles().vel[1] * sim.time_step();
  const Vec3 n = unit(x2 - sim.particles().pos_rad[0].x);
  EXPECT_NEAR(norm(f - n * dot(f, n)), expected, 1e-6 * expected);
}

TEST(Neighbours, ADisplacedGrainIsSeenAtTheNextStep) {
  // A grain moved by displace_particle from three skins away into contact: the next step's
  // forces are those of a simulation built with it there (the lists must be rebuilt at once;
  // without the rebuild the pair is missing and the force is zero).
  const double R = 0.5e-3, overlap = 1e-6;
  auto pair_at = [&](double distance) {
    ParticleStore ps(Dimension::Three, 1.0);
    ps.add({.tag = 1, .position = {0, 0, 0}, .radius = R, .density = 2650});
    ps.add({.tag = 2, .position = {distance, 0, 0}, .radius = R, .density = 2650});
    EngineConfig cfg;
    cfg.time_step = 1e-8;
    cfg.skin = 0.1 * R;
    LinearContact::Params lp;
    return Simulation(std::move(ps), cfg, make_contact_model<LinearContact>(lp, lp));
  };
  Simulation moved = pair_at(2 * R + 3 * 0.1 * R);
  moved.initialise();
  moved.step();
  EXPECT_EQ(moved.particles().force[0].x, 0.0);
  const Vec3 x1 = moved.particles().pos_rad[1].x;
  moved.displace_particle(1, Vec3{2 * R - overlap, 0, 0} - x1);
  moved.step();
  Simulation built = pair_at(2 * R - overlap);
  built.initialise();
  built.step();
  ASSERT_LT(built.particles().force[0].x, 0.0);
  EXPECT_EQ(moved.particles().force[0].x, built.particles().force[0].x);
  EXPECT_EQ(moved.particles().force[1].x, built.particles().force[1].x);
  EXPECT_THROW(moved.displace_particle(0, {std::nan(""), 0, 0}), InputError);
  EXPECT_THROW(moved.displace_particle(2, {1e-6, 0, 0}), InputError);
}

// A finished run frees its interactions before the analysis: the grains, bonds and cracks stay
// as they were, the pair data is gone, and the simulation refuses to go on or to be saved.
TEST(Neighbours, RetiredInteractionsKeepGrainsBondsAndCracks) {
  Simulation sim = test::compressed_block(4, 4, 4, 0.5, 2e6);
  for (int s = 0; s < 3000 && sim.cracks().size() == 0; ++s) sim.step();
  ASSERT_GT(sim.cracks().size(), 0u);
  ASSERT_GT(sim.active_contacts(), 0u);
  const std::size_t bonds = sim.intact_bonds(), cracks = sim.cracks().size();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> before, after;
  sim.for_each_intact_bond([&](std::uint32_t i, std::uint32_t j) { before.emplace_back(i, j); });
  const std::vector<PosRad> grains = sim.particles().pos_rad;

  sim.retire_interactions();
  EXPECT_TRUE(sim.retired());
  EXPECT_EQ(sim.neighbour_pairs(), 0u);
  EXPECT_EQ(sim.active_contacts(), 0u);
  EXPECT_EQ(sim.intact_bonds(), bonds);
  EXPECT_EQ(sim.cracks().size(), cracks);
  sim.for_each_intact_bond([&](std::uint32_t i, std::uint32_t j) { after.emplace_back(i, j); });
  EXPECT_EQ(after, before);
  ASSERT_EQ(sim.particles().size(), grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) {
    EXPECT_EQ(sim.particles().pos_rad[i].x, grains[i].x);
    EXPECT_EQ(sim.particles().pos_rad[i].r, grains[i].r);
  }
  EXPECT_THROW(sim.step(), std::logic_error);
  std::ostringstream out;
  ArchiveWriter a(out);
  EXPECT_THROW(sim.save_state(a), std::logic_error);
  EXPECT_TRUE(out.str().empty());
}
