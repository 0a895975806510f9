// Acoustic-emission and failure statistics against the worked examples of docs/analysis.md §3-§9
// and synthetic data with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include "breccia/analysis/ae_clustering.hpp"
#include "breccia/analysis/compression.hpp"
#include "breccia/analysis/correlation_dimension.hpp"
#include "breccia/analysis/crack_series.hpp"
#include "breccia/analysis/fragments.hpp"
#include "breccia/analysis/gutenberg_richter.hpp"
#include "breccia/analysis/moment_tensor.hpp"
#include "breccia/analysis/stages.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/observe/ae_monitor.hpp"

using namespace breccia;
using namespace breccia::analysis;

// ---- b-value (§5.5) ----

TEST(BValue, HandExampleWithUtsuCorrection) {
  const BValue b = b_value({1.0, 1.1, 1.3, 1.6, 2.0}, 1.0, 0.1, 0);
  ASSERT_TRUE(b.valid());
  EXPECT_NEAR(b.b, 0.4343 / 0.45, 2e-4);  // 0.9651
  EXPECT_NEAR(b.sigma, 0.3896, 1e-4);
  EXPECT_NEAR(b.a, 1.664, 1e-3);
}

TEST(BValue, DeterministicGutenbergRichterSamples) {
  for (auto [n, expected] : {std::pair{1000, 1.0003}, std::pair{100, 1.0035}}) {
    std::vector<double> m;
    for (int i = 1; i <= n; ++i) m.push_back(-std::log10(1.0 - (i - 0.5) / n));
    EXPECT_NEAR(b_value(m, 0.0, 0.0).b, expected, 1e-4) << n;
  }
}

TEST(BValue, RandomSampleWithinFourSigma) {
  std::mt19937_64 gen(42);
  std::exponential_distribution<double> x(std::log(10.0));
  std::vector<double> m;
  for (int i = 0; i < 10000; ++i) m.push_back(2.0 + x(gen));
  EXPECT_NEAR(b_value(m, 2.0).b, 1.0, 0.04);
}

TEST(BValue, BinnedMagnitudes) {
  std::vector<double> m;
  const int n = 1000;
  for (int i = 1; i <= n; ++i)
    m.push_back(std::round(10.0 * (-0.05 - std::log10(1.0 - (i - 0.5) / n))) / 10.0);
  EXPECT_NEAR(b_value(m, 0.0, 0.1).b, 0.9959, 1e-4);
}

TEST(BValue, FromEnergiesThroughTheEnergyMagnitude) {
  std::vector<double> m;
  const int n = 1000;
  const double beta = 2.0 / 3.0, ec = 1e-6;
  for (int i = 1; i <= n; ++i)
    m.push_back(energy_magnitude(ec * std::pow(1.0 - (i - 0.5) / n, -1.0 / beta)));
  EXPECT_NEAR(b_value(m, energy_magnitude(ec)).b, 1.0003, 1e-4);
}

TEST(BValue, TooFewEventsGiveNaNWithAFlag) {
  const BValue b = b_value({1.0, 1.5, 2.0}, 1.0);
  EXPECT_TRUE(std::isnan(b.b));
  EXPECT_EQ(b.flag, "too_few_events");
  EXPECT_TRUE(b_value_windows({1, 2, 3}, {0, 1, 2}, 1.0).empty());
}

TEST(BValue, MaximumCurvatureCompleteness) {
  std::vector<double> m{1.0, 1.1, 1.1, 1.2, 1.2, 1.2, 1.2, 1.3, 1.3, 1.3, 1.4, 1.4, 1.5, 1.6, 1.8};
  const Completeness c = completeness_max_curvature(m, 0.1, 0.2, 0);
  EXPECT_NEAR(c.magnitude, 1.4, 1e-12);
  EXPECT_TRUE(std::isnan(completeness_max_curvature(m).magnitude));  // < 50 events
}

TEST(BValue, EventWindowsStampTheLastEventStrain) {
  std::vector<double> m, e;
  const int n = 400;
  for (int i = 1; i <= n; ++i) {
    m.push_back(-std::log10(1.0 - ((i * 37) % n + 0.5) / n));  // shuffled quantiles
    e.push_back(1e-5 * i);
  }
  const auto w = b_value_windows(m, e, 0.0, 100, 10, 50);
  ASSERT_EQ(w.size(), 31u);
  EXPECT_DOUBLE_EQ(w.front().strain, 1e-5 * 100);
  EXPECT_DOUBLE_EQ(w.back().strain, 1e-5 * 400);
  for (const auto& x : w) EXPECT_NEAR(x.value.b, 1.0, 0.35);
}

TEST(BValue, SpearmanRhoWithTiesByHand) {
  // y's ranks with the tie at 7 shared: (1, 2, 3.5, 5, 3.5); centred on 3 against x's (-2..2):
  // sum dx dy = 8, sum dx^2 = 10, sum dy^2 = 9.5, rho = 8 / sqrt(95).
  EXPECT_NEAR(spearman_rho({1, 2, 3, 4, 5}, {5, 6, 7, 8, 7}), 8.0 / std::sqrt(95.0), 1e-15);
  // Any strictly falling series, however far from a line, is -1.
  EXPECT_DOUBLE_EQ(spearman_rho({0.1, 0.2, 0.3, 0.4}, {9.0, 2.0, 1.9, -50.0}), -1.0);
  EXPECT_TRUE(std::isnan(spearman_rho({1, 2, 3}, {4, 4, 4})));  // no ranking
  EXPECT_TRUE(std::isnan(spearman_rho({1}, {2})));
}

TEST(BValue, TrendBeforeThePeakFromTheWindows) {
  std::vector<BValueWindow> w;
  const double strain[] = {0.001, 0.002, 0.003, 0.0035, 0.004, 0.005, 0.006, 0.007};
  const double b[] = {3.0, 2.5, 2.6, 0.0, 2.0, 1.5, 1.2, 1.0};
  for (int k = 0; k < 8; ++k) {
    BValueWindow x{strain[k], {}};
    x.value.b = b[k];
    if (k == 3) x.value.flag = "too_few_events";  // an invalid window is skipped
    w.push_back(x);
  }
  // Up to the peak at 0.005: b = (3, 2.5, 2.6, 2, 1.5), ranks (5, 3, 4, 2, 1) against (1..5):
  // sum dx dy = -9 over sqrt(10 x 10), rho = -0.9.
  BValueTrend t = b_value_trend(w, 0.005, true);
  EXPECT_EQ(t.windows, 5u);
  EXPECT_DOUBLE_EQ(t.first_strain, 0.001);
  EXPECT_DOUBLE_EQ(t.first_b, 3.0);
  EXPECT_DOUBLE_EQ(t.last_strain, 0.005);
  EXPECT_DOUBLE_EQ(t.last_b, 1.5);
  EXPECT_NEAR(t.spearman_rho, -0.9, 1e-15);
  EXPECT_EQ(t.flag, "");
  t = b_value_trend(w, 0.005, true, 6);
  EXPECT_EQ(t.flag, "too_few_windows");
  EXPECT_TRUE(std::isnan(t.spearman_rho));
  EXPECT_DOUBLE_EQ(t.last_b, 1.5);
  EXPECT_EQ(b_value_trend(w, 0.0005, true).flag, "no_window_before_peak");
  EXPECT_EQ(b_value_trend(w, 0.005, false).flag, "no_peak");
}

// ---- magnitudes and moment tensors (§4.2, §4.3) ----

TEST(MomentTensor, OpeningDipoleAndDoubleCouple) {
  // Contacts at R = (+-a, 0, 0) with Delta F = (+-10, 0, 0) N: M_ij = sum dF_i R_j.
  const double a = 1e-4;
  Tensor3 m{};
  for (double s : {1.0, -1.0}) m[0][0] += (s * 10.0) * (s * a);
  SourceType t = source_type(m);
  EXPECT_NEAR(t.scalar_moment, 1.4142e-3, 1e-7);
  EXPECT_NEAR(moment_magnitude(t.scalar_moment), -7.900, 1e-3);
  EXPECT_NEAR(moment_magnitude(t.scalar_moment, -2.0 / 3.0 * 9.1), -7.966, 1e-3);
  EXPECT_NEAR(radiated_energy(moment_magnitude(t.scalar_moment)), 8.92e-8, 0.01e-8);
  EXPECT_NEAR(t.r_ratio, 42.9, 0.05);
  Tensor3 dc{};
  dc[0][1] = dc[1][0] = 2e-3;
  t = source_type(dc);
  EXPECT_NEAR(t.scalar_moment, 2e-3, 1e-15);
  EXPECT_NEAR(moment_magnitude(t.scalar_moment), -7.799, 1e-3);
  EXPECT_NEAR(t.dc_percent, 100.0, 1e-9);
  EXPECT_TRUE(std::isnan(moment_magnitude(0.0)));
}

TEST(MomentTensor, HudsonReferenceSources) {
  struct Case {
    std::array<double, 3> ev;
    double T, k, u, v;
  };
  const Case cases[] = {
      {{1, 0, -1}, 0, 0, 0, 0},
      {{1, 1, 1}, 0, 1, 0, 1},
      {{-1, -1, -1}, 0, -1, 0, -1},
      {{2, -1, -1}, -1, 0, -1, 0},
      {{-2, 1, 1}, 1, 0, 1, 0},
      {{1, 0, 0}, -1, 1.0 / 3, -2.0 / 3, 1.0 / 3},
      {{-1, 0, 0}, 1, -1.0 / 3, 2.0 / 3, -1.0 / 3},
      {{3, 1, 1}, -1, 5.0 / 9, -4.0 / 9, 5.0 / 9},
      {{-3, -1, -1}, 1, -5.0 / 9, 4.0 / 9, -5.0 / 9},
      {{2, 0.5, -1}, 0, 0.25, 0, 0.25},
  };
  for (const Case& c : cases) {
    Tensor3 m{};
    for (int k = 0; k < 3; ++k) m[k][k] = c.ev[k];
    const SourceType s = source_type(m);
    EXPECT_NEAR(s.T, c.T, 1e-12) << c.ev[0] << "," << c.ev[1] << "," << c.ev[2];
    EXPECT_NEAR(s.k, c.k, 1e-12) << c.ev[0];
    EXPECT_NEAR(s.u, c.u, 1e-12) << c.ev[0];
    EXPECT_NEAR(s.v, c.v, 1e-12) << c.ev[0];
  }
  Tensor3 crack{};
  crack[0][0] = 3;
  crack[1][1] = crack[2][2] = 1;
  EXPECT_NEAR(source_type(crack).dc_percent, 0.0, 1e-12);
  EXPECT_TRUE(source_type(Tensor3{}).zero);
  EXPECT_TRUE(std::isnan(source_type(Tensor3{}).scalar_moment));
}

TEST(MomentTensor, ClosedFormMatchesPiecewiseAndIsRotationInvariant) {
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    Tensor3 m{};
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) m[i][j] = m[j][i] = u(gen);
    const SourceType s = source_type(m);
    double pu = 0, pv = 0;
    hudson_piecewise(s.k, s.tau, pu, pv);
    ASSERT_NEAR(s.u, pu, 1e-9) << trial;
    ASSERT_NEAR(s.v, pv, 1e-9) << trial;
    if (trial < 50) {
      // R M R^T for a rotation about an arbitrary axis leaves every invariant unchanged.
      const double th = u(gen) * std::numbers::pi, c = std::cos(th), sn = std::sin(th);
      const double R[3][3] = {{c, -sn, 0}, {sn * 0.6, c * 0.6, -0.8}, {sn * 0.8, c * 0.8, 0.6}};
      Tensor3 r{};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l) r[i][j] += R[i][k] * m[k][l] * R[j][l];
      const SourceType q = source_type(r);
      EXPECT_NEAR(q.scalar_moment, s.scalar_moment, 1e-12);
      EXPECT_NEAR(q.u, s.u, 1e-9);
      EXPECT_NEAR(q.v, s.v, 1e-9);
    }
  }
}

// ---- correlation dimension (§6.5) ----

TEST(CorrelationDimension, FourCornersOfASquare) {
  const std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const auto c = correlation_integral(p, {1.2, 1.5});
  EXPECT_NEAR(c[0], 4.0 / 6.0, 1e-12);
  EXPECT_NEAR(c[1], 1.0, 1e-12);
}

namespace {
std::vector<double> log_radii(double lo, double hi, int n) {
  std::vector<double> r;
  for (int k = 0; k < n; ++k) r.push_back(lo * std::pow(hi / lo, k / double(n - 1)));
  return r;
}
std::vector<Vec3> uniform(int n, int dim, std::uint64_t seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) {
    const double x = u(gen), y = dim > 1 ? u(gen) : 0.0, z = dim > 2 ? u(gen) : 0.0;
    p.push_back({x, y, z});
  }
  return p;
}
}  // namespace

TEST(CorrelationDimension, LineSquareAndCube) {
  EXPECT_NEAR(correlation_dimension_fixed(uniform(1000, 1, 1), log_radii(0.01, 0.1, 11)).d2, 0.981,
              0.05);
  EXPECT_NEAR(correlation_dimension_fixed(uniform(2000, 2, 2), log_radii(0.01, 0.1, 11)).d2, 1.968,
              0.05);
  EXPECT_NEAR(correlation_dimension_fixed(uniform(4000, 3, 3), log_radii(0.05, 0.2, 11)).d2, 2.874,
              0.05);
  // Above 5000 points the pairs come from a cell list: same answer.
  EXPECT_NEAR(correlation_dimension_fixed(uniform(8000, 3, 4), log_radii(0.05, 0.2, 11)).d2, 2.874,
              0.05);
}

TEST(CorrelationDimension, AutomaticRangeOnASquare) {
  for (std::uint64_t seed : {11u, 12u, 13u, 14u}) {
    D2Settings s;
    s.r_hi = 0.25;
    s.dimension = 2;
    const CorrelationDimension d = correlation_dimension(uniform(2000, 2, seed), s);
    ASSERT_TRUE(d.valid()) << seed;
    EXPECT_GE(d.d2, 1.93) << seed;
    EXPECT_LE(d.d2, 2.03) << seed;
    EXPECT_GT(d.r2, 0.999) << seed;
    EXPECT_GE(std::log10(d.r_max / d.r_min), 1.0 - 1e-9);
  }
  D2Settings s;
  s.r_hi = 0.25;
  const CorrelationDimension few = correlation_dimension(uniform(20, 3, 1), s);
  EXPECT_FALSE(few.valid());
  EXPECT_EQ(few.flags.front(), "too_few_points");
}

// ---- clustering (§4.1) ----

TEST(Clustering, WorkedExampleWithRollingWindow) {
  const double vs = shear_wave_speed(20e9, 0.25, 2650 * 0.8);
  EXPECT_NEAR(vs, 1942.6, 0.1);
  const double td = event_duration(120e-6, vs);
  EXPECT_NEAR(td, 2.471e-7, 0.001e-7);
  const std::vector<double> t{0, 1.0e-7, 3.0e-7, 3.5e-7, 8.0e-7};
  const std::vector<Vec3> x{
      {0, 0, 0}, {100e-6, 0, 0}, {200e-6, 0, 0}, {1000e-6, 0, 0}, {250e-6, 0, 0}};
  const auto ev = cluster_cracks(t, x, {120e-6, td});
  EXPECT_EQ(ev, (std::vector<std::size_t>{0, 0, 0, 1, 2}));
}

TEST(Clustering, BridgingCrackMergesEvents) {
  // Two open events 200 um apart; a crack between them joins both (single linkage).
  const std::vector<double> t{0, 1e-8, 2e-8};
  const std::vector<Vec3> x{{0, 0, 0}, {200e-6, 0, 0}, {100e-6, 0, 0}};
  EXPECT_EQ(cluster_cracks(t, x, {120e-6, 1e-7}), (std::vector<std::size_t>{0, 0, 0}));
  EventClusterer c({120e-6, 1e-7});
  std::size_t kept = 99, gone = 99;
  c.merged = [&](std::size_t k, std::size_t g) {
    kept = k;
    gone = g;
  };
  c.add(0, t[0], x[0]);
  c.add(1, t[1], x[1]);
  EXPECT_EQ(c.open_events().size(), 2u);
  c.add(2, t[2], x[2]);
  EXPECT_EQ(kept, 0u);
  EXPECT_EQ(gone, 1u);
  EXPECT_EQ(c.open_events().size(), 1u);
  std::vector<std::size_t> closed;
  c.close_before(1.0, [&](std::size_t e) { closed.push_back(e); });
  EXPECT_EQ(closed, std::vector<std::size_t>{0});
}

TEST(Clustering, SourceRegionWorkedExampleWindowFromTheFirstCrack) {
  // The worked example's cracks: c3 falls 3e-7 s after E1's first crack, past T_d, so it opens
  // an event of its own where the rolling window kept it in E1; c5 comes after that one closed.
  const double td = event_duration(120e-6, shear_wave_speed(20e9, 0.25, 2650 * 0.8));
  const std::vector<double> t{0, 1.0e-7, 3.0e-7, 3.5e-7, 8.0e-7};
  const std::vector<Vec3> x{
      {0, 0, 0}, {100e-6, 0, 0}, {200e-6, 0, 0}, {1000e-6, 0, 0}, {250e-6, 0, 0}};
  EXPECT_EQ(cluster_cracks(t, x, {120e-6, td, Linkage::SourceRegion}),
            (std::vector<std::size_t>{0, 0, 1, 2, 3}));
}

TEST(Clustering, SourceRegionBoundsARunningRuptureAndNeverMerges) {
  // A rupture running along x within one window: single linkage makes one event of it; source
  // regions cut it where it leaves r_s of the first crack. The last crack lies 110 um from the
  // first region's first crack and 90 um from the second's: it joins the nearer, and merges none.
  const std::vector<double> t{0, 1e-9, 2e-9, 3e-9, 4e-9};
  const std::vector<Vec3> x{
      {0, 0, 0}, {100e-6, 0, 0}, {200e-6, 0, 0}, {300e-6, 0, 0}, {110e-6, 0, 0}};
  EXPECT_EQ(cluster_cracks(t, x, {120e-6, 1e-7}), (std::vector<std::size_t>{0, 0, 0, 0, 0}));
  EXPECT_EQ(cluster_cracks(t, x, {120e-6, 1e-7, Linkage::SourceRegion}),
            (std::vector<std::size_t>{0, 0, 1, 1, 1}));
  // Exactly at r_s joins (as the other linkages); ties go to the older region.
  const std::vector<Vec3> y{{0, 0, 0}, {240e-6, 0, 0}, {120e-6, 0, 0}};
  EXPECT_EQ(cluster_cracks({0, 1e-9, 2e-9}, y, {120e-6, 1e-7, Linkage::SourceRegion}),
            (std::vector<std::size_t>{0, 1, 0}));
}

TEST(Clustering, SourceRegionResumesExactlyFromACheckpoint) {
  const std::vector<double> t{0, 1e-9, 2e-9, 3e-9, 4e-9, 5e-8, 2e-7};
  const std::vector<Vec3> x{{0, 0, 0},      {100e-6, 0, 0}, {200e-6, 0, 0}, {300e-6, 0, 0},
                            {110e-6, 0, 0}, {20e-6, 0, 0},  {10e-6, 0, 0}};
  const ClusterSettings s{120e-6, 1e-7, Linkage::SourceRegion};
  EventClusterer whole(s);
  for (std::size_t k = 0; k < t.size(); ++k) whole.add(k, t[k], x[k]);
  EventClusterer first(s);
  for (std::size_t k = 0; k < 4; ++k) first.add(k, t[k], x[k]);
  std::stringstream buf;
  ArchiveWriter w(buf);
  first.save(w);
  ASSERT_TRUE(w.good());
  ArchiveReader r(buf, "in-memory checkpoint");
  EventClusterer resumed(s);
  resumed.load(r);
  for (std::size_t k = 4; k < t.size(); ++k) resumed.add(k, t[k], x[k]);
  for (std::size_t k = 0; k < t.size(); ++k)
    EXPECT_EQ(resumed.event_of(k), whole.event_of(k)) << "crack " << k;
  // The second-last crack joins the first region within its window (5e-8 s after its first
  // crack); the last comes after it closed at 1e-7 s.
  EXPECT_EQ(whole.event_of(5), 0u);
  EXPECT_NE(whole.event_of(6), 0u);
}

// ---- fragments (§9) ----

TEST(Fragments, HandMadeBondGraph) {
  const std::vector<double> m{10, 10, 10, 5, 5, 2}, v(6, 1.0);
  const std::vector<Vec3> x(6);
  const FragmentResult f = find_fragments(m, v, x, {{0, 1}, {1, 2}, {3, 4}});
  ASSERT_EQ(f.fragments.size(), 3u);
  EXPECT_EQ(f.fragments[0].mass, 30);
  EXPECT_EQ(f.fragments[1].mass, 10);
  EXPECT_EQ(f.fragments[2].mass, 2);
  EXPECT_EQ(f.biggest.count, 1u);
  EXPECT_EQ(f.intermediate.count, 1u);
  EXPECT_EQ(f.smallest.count, 1u);
  EXPECT_EQ(f.debris, 1u);
  EXPECT_EQ(f.smallest_no_debris.count, 0u);
  EXPECT_NEAR(f.largest_fraction, 30.0 / 42.0, 1e-12);
  EXPECT_EQ(f.fragment_of[5], 2u);
  EXPECT_EQ(f.fragment_of[3], 1u);
}

// ---- stages (§8) ----

TEST(Stages, WorkedExample) {
  std::vector<double> e, q;
  const double E = 20e9;
  for (int i = 0; i <= 10000; ++i) {
    const double x = i * 1e-6;
    double y;
    if (x <= 0.004)
      y = E * x;
    else if (x <= 0.006)
      y = 80e6 + E * (x - 0.004) - 5e12 * (x - 0.004) * (x - 0.004);
    else if (x <= 0.007)
      y = 100e6 - 60e6 * (x - 0.006) / 0.001;
    else
      y = 40e6;
    e.push_back(x);
    q.push_back(y);
  }
  StageSettings s;
  s.smoothing = 1;
  const Stages st = find_stages(e, q, 40e6, true, s);
  EXPECT_NEAR(st.linear_limit, 0.004633, 2e-6);
  EXPECT_NEAR(st.peak, 0.006, 1e-9);
  EXPECT_NEAR(st.residual_start, 0.0069, 2e-6);
  EXPECT_EQ(st.stage_of(0.001), 1);
  EXPECT_EQ(st.stage_of(0.005), 2);
  EXPECT_EQ(st.stage_of(0.0065), 3);
  EXPECT_EQ(st.stage_of(0.009), 4);
  const Stages none = find_stages(e, q, std::nan(""), true, s);
  EXPECT_EQ(none.stage_of(0.009), 3);
}

// ---- crack series (§3.2) ----

TEST(CrackSeries, VariancesAndShearFraction) {
  // Bins of 1e-4: counts (2, 4, 6, 8), energies (1, 3, 0, 4) uJ spread over each bin's cracks.
  std::vector<double> strain, energy;
  std::vector<char> shear;
  const int counts[4] = {2, 4, 6, 8};
  const double bin_energy[4] = {1e-6, 3e-6, 0.0, 4e-6};
  for (int b = 0; b < 4; ++b)
    for (int k = 0; k < counts[b]; ++k) {
      strain.push_back(1e-4 * b + 1e-6 * (k + 1));
      energy.push_back(bin_energy[b] / counts[b]);
      shear.push_back(b == 3 && k < 3 ? 1 : 0);
    }
  CrackSeriesSettings s;
  s.bin_width = 1e-4;
  s.window_bins = 4;
  const CrackSeries c = crack_series(strain, shear, energy, 0.0, 4e-4, s);
  ASSERT_EQ(c.count.size(), 4u);
  EXPECT_TRUE(std::isnan(c.mc_var[2])) << "fewer than W complete bins";
  EXPECT_NEAR(c.mc_var[3], 6.667, 1e-3);
  EXPECT_NEAR(c.ae_var[3], 3.333e-12, 1e-15);
  EXPECT_NEAR(c.shear_fraction[3], 3.0 / 20.0, 1e-12);
  EXPECT_EQ(c.cumulative[3], 20);
  // A window with 7 tensile and 3 shear cracks: SF = 0.30; with 9 cracks: NaN.
  std::vector<double> e10(10, 5e-5), en(10, 0.0);
  std::vector<char> sh{1, 1, 1, 0, 0, 0, 0, 0, 0, 0};
  s.bin_width = 1e-4;
  s.window_bins = 1;
  EXPECT_NEAR(crack_series(e10, sh, en, 0.0, 1e-4, s).shear_fraction[0], 0.30, 1e-12);
  e10.pop_back();
  sh.pop_back();
  en.pop_back();
  EXPECT_TRUE(std::isnan(crack_series(e10, sh, en, 0.0, 1e-4, s).shear_fraction[0]));
}

TEST(Clustering, GrainLinkageBySharedGrainsAndContacts) {
  // Option b of docs/analysis.md §4.1: crack (own grains, grains touched) with its own window T_c.
  EventClusterer c({0.0, 0.0, Linkage::Grain});
  const double tc = 1e-6;
  EXPECT_EQ(c.add_grain(0, 0.0, tc, {1, 2}, {1, 2, 3, 4}), 0u);
  EXPECT_EQ(c.add_grain(1, 0.5e-6, tc, {2, 7}, {2, 7, 8}), 0u);   // shares grain 2
  EXPECT_EQ(c.add_grain(2, 0.6e-6, tc, {8, 9}, {8, 9}), 0u);      // 8 touches grain 7
  EXPECT_EQ(c.add_grain(3, 0.7e-6, tc, {20, 21}, {20, 21}), 1u);  // elsewhere
  // The window refreshes with each crack: event 0 is open until 0.6 + 1.0 us.
  EXPECT_EQ(c.add_grain(4, 1.5e-6, tc, {9, 10}, {9, 10}), 0u);
  EXPECT_EQ(c.add_grain(5, 2.0e-6, tc, {21, 22}, {21, 22}), 2u);  // event 1 closed at 1.7 us
  // A crack touching both open events merges them.
  EXPECT_EQ(c.add_grain(6, 2.1e-6, tc, {10, 22}, {10, 22}), 0u);
  c.close_all();
  EXPECT_EQ(c.event_of(5), 0u);
  EXPECT_EQ(c.event_of(3), 1u);
}

// ---- continuum energy estimates (§2.3) ----

TEST(EnergyEstimates, ElasticEnergyDensityAndFractureEnergy) {
  // E = 20 GPa, nu = 0.25, sigma_1 = 100 MPa, sigma_3 = 10 MPa.
  EXPECT_NEAR(elastic_energy_density(100e6, 10e6, 20e9, 0.25), 228750.0, 1e-6);
  EXPECT_NEAR(deviatoric_elastic_energy_density(90e6, 10e6, 20e9, 0.25), 225000.0, 1e-6);
  EXPECT_NEAR(deviatoric_elastic_energy_density(90e6, 0.0, 20e9, 0.25), 202500.0, 1e-6);
  // Tang & Kaiser per crack: sigma 50 MPa, bond radius 0.1 mm, L = R1 + R2 = 0.2 mm, E_b 20 GPa.
  CrackRecord c;
  c.R1 = c.R2 = 0.1e-3;
  c.bond_radius = 0.1e-3;
  c.sigma = 50e6;
  c.tau = 0.0;
  c.mode = CrackMode::Tensile;
  ParallelBond::Params pb;
  pb.modulus = 20e9;
  pb.stiffness_ratio = 2.5;
  EXPECT_NEAR(fracture_energy(c, ParallelBond::moduli(pb), false, 1.0), 3.93e-7, 0.005e-7);
  // Shear: tau over G_b = E_b / kappa; 2D: bond volume 2 R t L.
  c.mode = CrackMode::Shear;
  c.sigma = 0.0;
  c.tau = 50e6;
  EXPECT_NEAR(fracture_energy(c, ParallelBond::moduli(pb), false, 1.0), 2.5 * 3.927e-7, 0.01e-7);
  c.mode = CrackMode::Tensile;
  c.sigma = 50e6;
  // v = 2 x 0.1 mm x 1 mm x 0.2 mm = 4e-11 m^3: (50e6)^2 x 4e-11 / 4e10 = 2.5e-6 J.
  EXPECT_NEAR(fracture_energy(c, ParallelBond::moduli(pb), true, 1e-3), 2.5e-6, 1e-15);
}
