// Neighbour search against brute force, and contact history surviving list rebuilds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "breccia/core/error.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/engine/neighbour_grid.hpp"
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

void check_against_brute_force(bool planar) {
  const auto p = random_cloud(1500, planar, planar ? 5 : 6);
  const double skin = 1e-4;
  PairList list;
  build_neighbour_pairs(p, skin, planar, list);
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
}
}  // namespace

TEST(Neighbours, MatchBruteForce3D) {
  check_against_brute_force(false);
}
TEST(Neighbours, MatchBruteForce2D) {
  check_against_brute_force(true);
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
