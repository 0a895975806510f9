// Vectors, quaternions, the shear-history rotations and the counter-based generator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <optional>
#include <thread>

#include "breccia/core/float_mode.hpp"
#include "breccia/core/quat.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/core/vec3.hpp"
#include "breccia/state/tag_index.hpp"

using namespace breccia;

#if defined(__x86_64__) || defined(__i386__) || defined(__aarch64__)
constexpr bool kFlushModeExists = true;
#else
constexpr bool kFlushModeExists = false;
#endif

// 1e-300 x 1e-10 = 1e-310 lies below the smallest normal double (2.2e-308): a subnormal result
// unless the mode flushes it. volatile keeps the compiler from folding the products.
TEST(FloatMode, FlushesSubnormalResultsWhileHeldAndRestoresAfter) {
  if (!kFlushModeExists) GTEST_SKIP() << "no flush-to-zero mode on this processor";
  volatile double tiny = 1e-300, factor = 1e-10;
  const bool before = subnormals_flushed();
  {
    const SubnormalsFlushed flushed;
    EXPECT_TRUE(subnormals_flushed());
    EXPECT_EQ(tiny * factor, 0.0);
  }
  EXPECT_EQ(subnormals_flushed(), before);
  if (!before) EXPECT_EQ(std::fpclassify(tiny * factor), FP_SUBNORMAL);
}

TEST(FloatMode, SubnormalOperandsReadAsZeroWhereTheProcessorCan) {
#if defined(__x86_64__) || defined(__i386__)
  volatile double sub = std::numeric_limits<double>::denorm_min() * 1e6;  // about 4.9e-318
  ASSERT_EQ(std::fpclassify(sub), FP_SUBNORMAL);
  const SubnormalsFlushed flushed;
  EXPECT_EQ(sub * 1e300, 0.0);  // 4.9e-18 if the operand were read as it is
#else
  GTEST_SKIP() << "denormals-are-zero is an x86 mode";
#endif
}

// breccia's main() sets the mode before OpenMP starts its threads, which inherit it.
TEST(FloatMode, ThreadsStartedAfterwardsInheritTheMode) {
  if (!kFlushModeExists) GTEST_SKIP() << "no flush-to-zero mode on this processor";
  const SubnormalsFlushed flushed;
  bool in_thread = false;
  std::thread t([&] { in_thread = subnormals_flushed(); });
  t.join();
  EXPECT_TRUE(in_thread);
}

TEST(Quat, RotateMatchesMatrixOfPhysicsReference) {
  // docs/physics.md §0.4 matrix, body to world.
  const Quat q = normalized(Quat{0.3, -0.5, 0.7, 0.2});
  const Vec3 v{0.4, -1.2, 2.5};
  const double w = q.w, x = q.x, y = q.y, z = q.z;
  const Vec3 expect{
      (1 - 2 * (y * y + z * z)) * v.x + 2 * (x * y - w * z) * v.y + 2 * (x * z + w * y) * v.z,
      2 * (x * y + w * z) * v.x + (1 - 2 * (x * x + z * z)) * v.y + 2 * (y * z - w * x) * v.z,
      2 * (x * z - w * y) * v.x + 2 * (y * z + w * x) * v.y + (1 - 2 * (x * x + y * y)) * v.z};
  const Vec3 got = rotate(q, v);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], expect[k], 1e-14);
}

TEST(Quat, AxisAngleQuarterTurn) {
  const Quat q = from_axis_angle({0, 0, 1}, std::numbers::pi / 2);
  const Vec3 r = rotate(q, {1, 0, 0});
  EXPECT_NEAR(r.x, 0.0, 1e-15);
  EXPECT_NEAR(r.y, 1.0, 1e-15);
}

TEST(Quat, ExponentialUpdateComposesToAxisAngle) {
  // 1000 steps of a constant angular velocity give exactly the rotation by |w| t about w.
  const Vec3 w{0.3, -0.8, 0.5};
  Quat q;
  const double dt = 1e-3;
  for (int s = 0; s < 1000; ++s) q = integrate_orientation(q, w, dt);
  const Quat ref = from_axis_angle(w, norm(w) * 1.0);
  EXPECT_NEAR(q.w, ref.w, 1e-12);
  EXPECT_NEAR(q.x, ref.x, 1e-12);
  EXPECT_NEAR(q.y, ref.y, 1e-12);
  EXPECT_NEAR(q.z, ref.z, 1e-12);
}

TEST(Vec3, RotateBetweenTakesFromToTo) {
  const Vec3 a = unit({1, 0.2, -0.1}), b = unit({0.9, 0.35, 0.05});
  const Vec3 t = rotate_between(a, a, b);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(t[k], b[k], 1e-15);
  // A vector perpendicular to a stays perpendicular to b and keeps its length.
  const Vec3 p = unit(cross(a, {0, 0, 1})) * 3.0;
  const Vec3 q = rotate_between(p, a, b);
  EXPECT_NEAR(dot(q, b), 0.0, 1e-14);
  EXPECT_NEAR(norm(q), 3.0, 1e-14);
}

TEST(Vec3, SpinIsARotationWithSecondOrderAngle) {
  const Vec3 n{0, 0, 1}, v{2, 0, 0};
  const double psi = 1e-2;
  const Vec3 r = spin_about(v, n, psi);
  EXPECT_NEAR(norm(r), 2.0, 1e-15);
  const double angle = std::atan2(r.y, r.x);
  // Cayley angle 2 atan(psi / 2) = psi - psi^3 / 12 + psi^5 / 80 - ...
  EXPECT_NEAR(angle, psi - std::pow(psi, 3) / 12.0 + std::pow(psi, 5) / 80.0, 1e-16);
}

TEST(Rng, ReproducibleAndIndependentOfOrder) {
  EXPECT_EQ(uniform01(7, 1, 42), uniform01(7, 1, 42));
  EXPECT_NE(uniform01(7, 1, 42), uniform01(8, 1, 42));
  EXPECT_NE(uniform01(7, 1, 42), uniform01(7, 2, 42));
}

TEST(Rng, NormalMomentsAndTruncation) {
  // Mean and variance of 200k draws: standard errors 0.0022 and 0.0032; 5 sigma bounds.
  const int n = 200000;
  double s = 0, s2 = 0;
  for (int k = 0; k < n; ++k) {
    const double x = standard_normal(3, 9, static_cast<std::uint64_t>(k));
    s += x;
    s2 += x * x;
  }
  const double mean = s / n, var = s2 / n - mean * mean;
  EXPECT_NEAR(mean, 0.0, 0.011);
  EXPECT_NEAR(var, 1.0, 0.016);
  for (std::uint64_t k = 0; k < 2000; ++k) EXPECT_GT(positive_normal(1.0, 2.0, 5, 1, k), 0.0);
  EXPECT_EQ(positive_normal(3.0, 0.0, 5, 1, 1), 3.0);
}

TEST(Vec3, PlaneCarryMatchesTheReferenceTiltThenSpin) {
  // The engine's fused rotation (divisions hoisted, built once per pair) against the two
  // reference functions applied in turn.
  const Vec3 n_old = unit({0.3, -0.2, 0.93}), n = unit({0.31, -0.18, 0.93});
  const Vec3 v = cross(n_old, {1, 0, 0}) * 2.5;  // in the old plane
  const double psi = 3e-3;
  const Vec3 got = PlaneCarry(n_old, n, psi).apply(v);
  const Vec3 ref = spin_about(rotate_between(v, n_old, n), n, psi);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], ref[k], 1e-15);
  EXPECT_NEAR(dot(got, n), 0.0, 1e-15);
}

// Tags 0..N go to the table, far ones to the map; a table grown past map entries takes them
// over; every tag finds its index and an unknown one finds nothing.
TEST(TagIndex, DenseAndSparseTagsFindTheirIndexes) {
  TagIndex t;
  t.insert(5000, 0);  // beyond 2 x 0 + 1024: the map
  for (std::uint64_t k = 1; k <= 3000; ++k) t.insert(k, static_cast<std::size_t>(k));
  t.insert(std::uint64_t{1} << 40, 3001);  // always the map
  EXPECT_EQ(t.size(), 3002u);
  EXPECT_EQ(t.find(5000), std::optional<std::size_t>(0));
  for (std::uint64_t k = 1; k <= 3000; ++k) ASSERT_EQ(t.find(k), std::optional<std::size_t>(k));
  EXPECT_EQ(t.find(std::uint64_t{1} << 40), std::optional<std::size_t>(3001));
  EXPECT_FALSE(t.contains(0));
  EXPECT_FALSE(t.contains(3001));
  EXPECT_FALSE(t.contains(4999));
  EXPECT_FALSE(t.contains((std::uint64_t{1} << 40) + 1));
  // Growing the table over 5000 moved it from the map: still found after a further insert.
  t.insert(5001, 3002);
  EXPECT_EQ(t.find(5000), std::optional<std::size_t>(0));
  EXPECT_EQ(t.find(5001), std::optional<std::size_t>(3002));
  t.clear();
  EXPECT_FALSE(t.contains(1));
  EXPECT_EQ(t.size(), 0u);
}

// The launcher's environment as Open MPI and MPICH/Slurm's PMI write it; none: one process.
TEST(Ranks, LaunchReadFromTheLaunchersEnvironment) {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_RANK",
                        "OMPI_COMM_WORLD_LOCAL_SIZE", "PMI_SIZE", "PMI_RANK", "MPI_LOCALNRANKS"})
    unsetenv(v);
  breccia::ranks::Launch l = breccia::ranks::launch_from_environment();
  EXPECT_FALSE(l.launched);
  EXPECT_EQ(l.size, 1);
  setenv("PMI_SIZE", "4", 1);
  setenv("PMI_RANK", "3", 1);
  setenv("MPI_LOCALNRANKS", "2", 1);
  l = breccia::ranks::launch_from_environment();
  EXPECT_TRUE(l.launched);
  EXPECT_EQ(l.size, 4);
  EXPECT_EQ(l.rank, 3);
  EXPECT_EQ(l.local_size, 2);
  setenv("OMPI_COMM_WORLD_SIZE", "3", 1);  // Open MPI's own variables come first
  setenv("OMPI_COMM_WORLD_RANK", "1", 1);
  setenv("OMPI_COMM_WORLD_LOCAL_SIZE", "3", 1);
  l = breccia::ranks::launch_from_environment();
  EXPECT_EQ(l.size, 3);
  EXPECT_EQ(l.rank, 1);
  EXPECT_EQ(l.local_size, 3);
  setenv("OMPI_COMM_WORLD_SIZE", "three", 1);  // unreadable: the next launcher's
  EXPECT_EQ(breccia::ranks::launch_from_environment().size, 4);
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_RANK",
                        "OMPI_COMM_WORLD_LOCAL_SIZE", "PMI_SIZE", "PMI_RANK", "MPI_LOCALNRANKS"})
    unsetenv(v);
}

// One process always runs; several run only a command that spreads over ranks, in a build with
// MPI, and a refusal says why and what to do.
TEST(Ranks, SeveralProcessesRunOnlyWhatSpreadsOverRanks) {
  using breccia::ranks::launch_refusal;
  const std::vector<std::string> spread{"run", "sweep", "resume", "calibrate"};
  breccia::ranks::Launch one{true, 1, 0, 1}, two{true, 2, 1, 2};
  EXPECT_FALSE(launch_refusal(one, false, "generate", spread));
  EXPECT_FALSE(launch_refusal(two, true, "run", spread));
  const auto no_mpi = launch_refusal(two, false, "run", spread);
  ASSERT_TRUE(no_mpi);
  EXPECT_NE(no_mpi->find("built without MPI"), std::string::npos) << *no_mpi;
  EXPECT_NE(no_mpi->find("-DBRECCIA_MPI=ON"), std::string::npos) << *no_mpi;
  const auto generate = launch_refusal(two, true, "generate", spread);
  ASSERT_TRUE(generate);
  EXPECT_NE(generate->find("`breccia generate` runs in one process"), std::string::npos)
      << *generate;
  EXPECT_NE(generate->find("run, sweep, resume, calibrate"), std::string::npos) << *generate;
}

// Without a launcher a command is rank 0 of 1, and the collective calls are those of one process.
TEST(Ranks, OneProcessIsRankZeroOfOne) {
  EXPECT_EQ(breccia::ranks::rank(), 0);
  EXPECT_EQ(breccia::ranks::size(), 1);
  EXPECT_EQ(breccia::ranks::broadcast("text"), "text");
  EXPECT_EQ(breccia::ranks::gather("mine"), std::vector<std::string>{"mine"});
  EXPECT_EQ(breccia::ranks::on_root([] { return std::string("done"); }), "done");
  EXPECT_THROW(breccia::ranks::on_root([]() -> std::string { throw std::runtime_error("no"); }),
               std::runtime_error);
  EXPECT_TRUE(breccia::ranks::failure_is_shared(false));
  // One process is one group of one; groups of two do not divide it.
  {
    const breccia::ranks::Group group(1);
    EXPECT_EQ(group.index(), 0);
    EXPECT_EQ(group.count(), 1);
    EXPECT_EQ(breccia::ranks::size(), 1);
    EXPECT_EQ(breccia::ranks::launch_size(), 1);
    EXPECT_EQ(breccia::ranks::broadcast("text"), "text");
  }
  EXPECT_THROW(breccia::ranks::Group(2), std::invalid_argument);
  EXPECT_EQ(breccia::ranks::size(), 1);
}
