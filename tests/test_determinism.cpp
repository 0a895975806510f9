// The same input gives bitwise the same trajectory with 1 and 2 threads (ARCHITECTURE.md,
// "Determinism without atomics": per-pair force slots, fixed-block reductions, breaks processed in
// bond order).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "block_fixture.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/sample/lattice.hpp"
#include "pair_harness.hpp"

using namespace breccia;

namespace {
const int kDefaultThreads = max_threads();

struct Outcome {
  std::vector<PosRad> pos;
  std::vector<Vec3> vel, angvel;
  std::vector<std::uint64_t> crack_bonds;
  double wall_force = 0.0, work = 0.0, residual = 0.0;
};

// Dynamic damping over two grain diameters for a window of 20 us (hundreds of steps).
void with_dynamic_damping(Simulation& sim) {
  sim.set_dynamic_damping(0.0, 2e-3, 2e-5);
}

// How many grains dynamic damping has reached so far.
std::size_t grains_damped_less(const Simulation& sim) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < sim.particles().size(); ++i)
    n += std::isfinite(sim.dynamically_damped_until(i)) ? 1 : 0;
  return n;
}

Outcome run_with_threads(int threads, bool dynamic_damping = false) {
  set_threads(threads);
  // 5 x 5 x 20 FCC cells = 2000 particles, weak bonds so that some break under compression.
  Simulation sim = test::compressed_block(5, 5, 20, 2.0, 3e6, 0.7,
                                          dynamic_damping ? with_dynamic_damping : nullptr);
  EXPECT_EQ(sim.particles().size(), 2000u);
  sim.run(2500);
  if (dynamic_damping) {
    EXPECT_GT(grains_damped_less(sim), 100u);
  }
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

class ThreadCounts : public ::testing::TestWithParam<bool> {};

TEST_P(ThreadCounts, OneAndTwoThreadsGiveBitwiseEqualTrajectories) {
  const Outcome a = run_with_threads(1, GetParam());
  const Outcome b = run_with_threads(2, GetParam());
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

// Without and with dynamic damping: its marks are a maximum over the step's cracks, taken in
// any order.
INSTANTIATE_TEST_SUITE_P(LocalAndDynamicDamping, ThreadCounts, ::testing::Bool());

// Dynamic damping's grid search against the plain reference: each step's cracks mark exactly the
// grains whose centres lay within the radius of their contact points at the step's start (the
// marks come before the step's integration), with the crack's time plus the window, through
// bond breaks and neighbour rebuilds.
TEST(DynamicDamping, MarksAreThoseOfASearchOverEveryGrain) {
  Simulation sim = test::compressed_block(5, 5, 20, 8.0, 3e6, 0.7, with_dynamic_damping);
  const double radius = sim.config().dynamic_damping_radius;
  const double window = sim.config().dynamic_damping_time;
  const std::size_t n = sim.particles().size();
  std::vector<double> expected(n, -std::numeric_limits<double>::infinity());
  std::vector<Vec3> x(n);
  std::size_t checked_cracks = 0;
  while (sim.step_count() < 1100) {
    for (std::size_t i = 0; i < n; ++i) x[i] = sim.particles().pos_rad[i].x;
    const std::size_t before = sim.cracks().size();
    sim.step();
    for (std::size_t k = before; k < sim.cracks().size(); ++k) {
      const CrackRecord c = sim.cracks()[k];
      for (std::size_t i = 0; i < n; ++i)
        if (norm2(x[i] - c.position) <= radius * radius)
          expected[i] = std::max(expected[i], c.time + window);
      ++checked_cracks;
    }
    for (std::size_t i = 0; i < n; ++i)
      ASSERT_EQ(sim.dynamically_damped_until(i), expected[i])
          << "grain " << i << " at step " << sim.step_count();
  }
  EXPECT_GT(checked_cracks, 500u) << "the test must break bonds";
  EXPECT_GT(sim.neighbour_rebuilds(), 1u) << "the test must rebuild the lists";
}

// The pair pass sums each pair's loads straight into its particles' totals, block by block, with
// cross slots for pairs that leave a block (state/pair_list.hpp). Against the plain reference, the
// pair forces summed per particle in another order: they agree to rounding. Each particle sums
// at most ~30 terms, so the two orders differ by at most 30 epsilon of the sum of the terms'
// magnitudes; the moment balance (Newton's third law for the pairs' forces and couples) holds to
// the same order.
// A small sample's few blocks go one at a time, so that every thread gets some (four blocks in
// one chunk of four left the second of two threads idle); many blocks go four at a time.
TEST(Parallel, FewBlocksAreHandedOutOneAtATime) {
  const std::ptrdiff_t threads = max_threads();
  EXPECT_EQ(1, block_chunk(4));
  EXPECT_EQ(1, block_chunk(8 * threads - 1));
  EXPECT_EQ(2, block_chunk(8 * threads));
  EXPECT_EQ(4, block_chunk(16 * threads));
  EXPECT_EQ(4, block_chunk(1000 * threads));
}

TEST(PairPass, ParticleTotalsAreTheSumsOfTheirPairs) {
  const double R = 0.5e-3;
  ParticleStore ps = fcc_block(6, 6, 16, R, 2650);  // 2,304 grains: five particle blocks
  ASSERT_GT(ps.size(), 4 * kParticleBlock);
  for (std::size_t i = 0; i < ps.size(); ++i)
    ps.vel[i] = Vec3{uniform01(7, 1, i) - 0.5, uniform01(7, 2, i) - 0.5, uniform01(7, 3, i) - 0.5};
  EngineConfig cfg;
  cfg.local_damping = 0.0;
  LinearContact::Params lp;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>(lp, lp));
  ParallelBond::Params bp;
  bp.tensile_strength = bp.cohesion = 1e9;  // intact: bonds and contacts both load
  sim.set_bond_params<ParallelBond>(bp);
  sim.bond_touching_pairs<ParallelBond>(1e-9);
  sim.initialise();
  sim.run(40);
  std::vector<Vec3> x(sim.particles().size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = sim.particles().pos_rad[i].x;
  sim.step();  // the loads of this step belong to the positions x
  const ParticleStore& p = sim.particles();
  std::vector<Vec3> reference(p.size()), magnitude(p.size());
  std::size_t cross_pairs = 0;
  std::visit(
      [&](const auto& c) {
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const std::uint32_t i = c.pairs.first[k], j = c.pairs.second[k];
          const Vec3 f = sim.pair_force(c, k);
          reference[i] -= f;
          reference[j] += f;
          for (int a = 0; a < 3; ++a) {
            magnitude[i][a] += std::abs(f[a]);
            magnitude[j][a] += std::abs(f[a]);
          }
          cross_pairs += i / kParticleBlock != j / kParticleBlock ? 1 : 0;
        }
      },
      sim.contact_model());
  ASSERT_GT(cross_pairs, 100u) << "the test must exercise the cross slots";
  const double eps = std::numeric_limits<double>::epsilon();
  Vec3 centre;
  for (const Vec3& xi : x) centre += xi * (1.0 / static_cast<double>(x.size()));
  Vec3 moment, moment_scale;
  double loaded = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(p.force[i][a], reference[i][a], 30.0 * eps * magnitude[i][a]) << i;
    loaded += norm(p.force[i]);
    moment += cross(x[i] - centre, p.force[i]) + p.torque[i];
    moment_scale += Vec3{norm(x[i] - centre) * norm(magnitude[i]), norm(p.torque[i]), 0.0};
  }
  ASSERT_GT(loaded, 0.0);
  EXPECT_LT(norm(moment), 30.0 * eps * (moment_scale.x + moment_scale.y));
}

// A checkpoint taken between two steps, restored into a new simulation, continues bit for bit as
// the original: positions, velocities, wall forces and work, the crack catalogue and the energy
// ledger after further steps that break bonds and rebuild the neighbour lists.
class CheckpointedRun : public ::testing::TestWithParam<bool> {};

TEST_P(CheckpointedRun, RestoredSimulationContinuesBitwiseEqual) {
  Simulation a =
      test::compressed_block(4, 4, 12, 2.0, 3e6, 0.7, GetParam() ? with_dynamic_damping : nullptr);
  a.run(1237);  // mid-ramp, between energy samples and rebuilds
  if (GetParam()) {
    ASSERT_GT(grains_damped_less(a), 0u) << "the checkpoint must hold dynamic damping's marks";
  }
  std::stringstream buf;
  ArchiveWriter w(buf);
  a.save_state(w);
  ASSERT_TRUE(w.good());
  ArchiveReader r(buf, "in-memory checkpoint");
  Simulation b = Simulation::restore(r);
  const std::uint64_t rebuilds = a.neighbour_rebuilds();
  const std::size_t cracks = a.cracks().size();
  a.run(1500);
  b.run(1500);
  ASSERT_GT(a.cracks().size(), cracks) << "the continuation must break bonds";
  ASSERT_GT(a.neighbour_rebuilds(), rebuilds) << "the continuation must rebuild neighbour lists";
  EXPECT_EQ(a.step_count(), b.step_count());
  EXPECT_EQ(a.time(), b.time());
  const auto& pa = a.particles();
  const auto& pb = b.particles();
  ASSERT_EQ(pa.size(), pb.size());
  EXPECT_EQ(0, std::memcmp(pa.pos_rad.data(), pb.pos_rad.data(), pa.size() * sizeof(PosRad)));
  EXPECT_EQ(0, std::memcmp(pa.vel.data(), pb.vel.data(), pa.size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(pa.angvel.data(), pb.angvel.data(), pa.size() * sizeof(Vec3)));
  ASSERT_EQ(a.cracks().size(), b.cracks().size());
  for (std::size_t k = 0; k < a.cracks().size(); ++k) {
    EXPECT_EQ(a.cracks()[k].bond_tag, b.cracks()[k].bond_tag);
    EXPECT_EQ(a.cracks()[k].step, b.cracks()[k].step);
    EXPECT_EQ(a.cracks()[k].law, b.cracks()[k].law);
  }
  EXPECT_EQ(a.walls()[1].force.z, b.walls()[1].force.z);
  EXPECT_EQ(a.walls()[1].work, b.walls()[1].work);
  EXPECT_EQ(a.ledger().residual, b.ledger().residual);
  EXPECT_EQ(a.ledger().friction, b.ledger().friction);
  EXPECT_EQ(a.intact_bonds(), b.intact_bonds());
}

// Dynamic damping's marks are saved and carried on.
INSTANTIATE_TEST_SUITE_P(LocalAndDynamicDamping, CheckpointedRun, ::testing::Bool());

TEST(Checkpoint, TruncatedOrForeignDataIsRefusedWithAClearError) {
  Simulation a = test::compressed_block(2, 2, 2, 2.0, 3e6);
  a.run(10);
  std::stringstream buf;
  ArchiveWriter w(buf);
  a.save_state(w);
  const std::string whole = buf.str();
  for (std::size_t cut : {whole.size() / 2, whole.size() - 1, std::size_t{20}}) {
    std::stringstream part(whole.substr(0, cut));
    ArchiveReader r(part, "cut.bin");
    try {
      (void)Simulation::restore(r);
      ADD_FAILURE() << "a checkpoint cut at " << cut << " bytes was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cut.bin"), std::string::npos) << e.what();
    }
  }
  std::stringstream junk(std::string(4096, 'x'));
  ArchiveReader r(junk, "junk.bin");
  EXPECT_THROW((void)Simulation::restore(r), InputError);
}

namespace {

// Saves a simulation mid-run, restores it, and runs both on: they must stay bitwise equal.
void expect_exact_continuation(Simulation& a) {
  a.run(300);
  std::stringstream buf;
  ArchiveWriter w(buf);
  a.save_state(w);
  ASSERT_TRUE(w.good());
  ArchiveReader r(buf, "in-memory checkpoint");
  Simulation b = Simulation::restore(r);
  a.run(400);
  b.run(400);
  ASSERT_GT(a.intact_bonds(), 0u);
  const auto& pa = a.particles();
  const auto& pb = b.particles();
  ASSERT_EQ(pa.size(), pb.size());
  EXPECT_EQ(0, std::memcmp(pa.pos_rad.data(), pb.pos_rad.data(), pa.size() * sizeof(PosRad)));
  EXPECT_EQ(0, std::memcmp(pa.angvel.data(), pb.angvel.data(), pa.size() * sizeof(Vec3)));
  EXPECT_EQ(a.intact_bonds(), b.intact_bonds());
  EXPECT_EQ(a.ledger().bond.total(), b.ledger().bond.total());
  EXPECT_EQ(a.ledger().contact, b.ledger().contact);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(a.walls()[1].force[k], b.walls()[1].force[k]);
}

// Runs `kept` (the pair pass keeps every pair's force) and `read` (the default) side by side
// and compares every pair's force after each stretch of steps, to the bit: where the laws' states
// give the forces back, Simulation::pair_force sums them in the pass's order from the same
// numbers (no fused multiply-add: the build is ISO C++, whose default leaves a * b + c alone).
// Returns the nonzero forces compared.
std::size_t expect_same_pair_forces(Simulation& kept, Simulation& read, int stretches, int steps) {
  std::size_t nonzero = 0;
  for (int s = 0; s < stretches; ++s) {
    kept.run(static_cast<std::uint64_t>(steps));
    read.run(static_cast<std::uint64_t>(steps));
    std::visit(
        [&]<class CL>(const ContactSet<CL>& a) {
          const auto& b = std::get<ContactSet<CL>>(read.contact_model());
          EXPECT_EQ(a.pairs.size(), b.pairs.size());
          for (std::size_t k = 0; k < std::min(a.pairs.size(), b.pairs.size()); ++k) {
            const Vec3 fa = kept.pair_force(a, k), fb = read.pair_force(b, k);
            EXPECT_EQ(0, std::memcmp(&fa, &fb, sizeof(Vec3)))
                << "step " << kept.step_count() << " pair " << k << ": " << fa.x << " " << fb.x;
            nonzero += norm2(fa) > 0.0 ? 1 : 0;
          }
        },
        kept.contact_model());
  }
  EXPECT_TRUE(kept.keeps_pair_forces());
  EXPECT_EQ(0, std::memcmp(kept.particles().pos_rad.data(), read.particles().pos_rad.data(),
                           kept.particles().size() * sizeof(PosRad)));
  return nonzero;
}

template <class Law>
class CheckpointOfEveryBondLaw : public ::testing::Test {};
TYPED_TEST_SUITE(CheckpointOfEveryBondLaw, test::GTypes<BondLaws>::type);
template <class Law>
class CheckpointOfEveryContactLaw : public ::testing::Test {};
TYPED_TEST_SUITE(CheckpointOfEveryContactLaw, test::GTypes<EngineContactLaws>::type);

}  // namespace

// Every registered law goes through a checkpoint and comes back exactly: its sets are saved under
// its name, so a new law is covered here without a format change by hand.
TYPED_TEST(CheckpointOfEveryBondLaw, RestoredSimulationContinuesBitwiseEqual) {
  Simulation a = test::law_block<LinearContact, TypeParam>();
  expect_exact_continuation(a);
}
TYPED_TEST(CheckpointOfEveryContactLaw, RestoredSimulationContinuesBitwiseEqual) {
  Simulation a = test::law_block<TypeParam, ParallelBond>();
  expect_exact_continuation(a);
}

// A bonded block squeezed until bonds break, with frictional contacts: the engine keeps no array
// of pair forces (parallel bonds and linear contacts keep their forces in their states), and
// the forces it reads back are the pass's to the bit, before and after bonds break and across
// neighbour rebuilds.
TEST(PairForces, ReadFromTheStatesAreThePassForcesToTheBit) {
  Simulation kept = test::compressed_block(4, 4, 12, 2.0, 3e6, 0.7, {}, true);
  Simulation read = test::compressed_block(4, 4, 12, 2.0, 3e6);
  const std::size_t nonzero = expect_same_pair_forces(kept, read, 10, 250);
  EXPECT_FALSE(read.keeps_pair_forces());
  ASSERT_GT(read.cracks().size(), 10u) << "the test must break bonds";
  ASSERT_GT(read.neighbour_rebuilds(), 1u) << "the test must rebuild the neighbour list";
  EXPECT_GT(nonzero, 1000u);
  EXPECT_EQ(0, std::memcmp(&kept.ledger(), &read.ledger(), sizeof(EnergyLedger)));
}

// Every bond law and contact layout: the states give the forces back where the law says so, and
// the engine keeps the array where it does not (beams, laws judged on the interface, rolling
// layouts included); the forces read are the pass's either way.
TYPED_TEST(CheckpointOfEveryBondLaw, PairForcesReadBackAreThePassForces) {
  Simulation kept = test::law_block<LinearContact, TypeParam>(true);
  Simulation read = test::law_block<LinearContact, TypeParam>();
  EXPECT_GT(expect_same_pair_forces(kept, read, 4, 100), 0u);
  EXPECT_EQ(read.keeps_pair_forces(), !has_state_force<TypeParam>);
}
TYPED_TEST(CheckpointOfEveryContactLaw, PairForcesReadBackAreThePassForces) {
  Simulation kept = test::law_block<TypeParam, ParallelBond>(true);
  Simulation read = test::law_block<TypeParam, ParallelBond>();
  EXPECT_GT(expect_same_pair_forces(kept, read, 4, 100), 0u);
  EXPECT_EQ(read.keeps_pair_forces(), !has_state_force<TypeParam>);
}

// A contact dashpot's force depends on the step's velocities, which no state keeps: the engine
// keeps the array, and so it does with dashpots on the bonds.
TEST(PairForces, DashpotsKeepTheArray) {
  const auto block = [](double contact_damping, double bond_damping) {
    ParticleStore ps = fcc_block(2, 2, 3, 0.5e-3, 2650);
    EngineConfig cfg;
    cfg.bond_normal_damping_ratio = bond_damping;
    HertzMindlin::Params hp;
    hp.normal_damping_ratio = contact_damping;
    Simulation sim(std::move(ps), cfg, make_contact_model<HertzMindlin>(hp, hp));
    sim.bond_touching_pairs<ParallelBond>(1e-9);
    sim.initialise();
    sim.run(2);
    return sim.keeps_pair_forces();
  };
  EXPECT_FALSE(block(0.0, 0.0));
  EXPECT_TRUE(block(0.1, 0.0));
  EXPECT_TRUE(block(0.0, 0.1));
}
