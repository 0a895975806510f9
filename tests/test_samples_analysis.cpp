// Sample generation and import, and the compression-test analysis against the worked examples of
// docs/analysis.md §1.8-§1.9.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>

#include "breccia/analysis/compression.hpp"
#include "breccia/core/error.hpp"
#include "breccia/sample/geometry_file.hpp"
#include "breccia/sample/packing.hpp"
#include "breccia/sample/sample_import.hpp"

namespace fs = std::filesystem;
using namespace breccia;
using namespace breccia::analysis;

TEST(Analysis, WorkedExampleModuliAndPoisson) {
  // docs/analysis.md §1.8: q = E e (1 - e / 2 e_p), E = 20 GPa, e_p = 0.01, e_l = -0.25 e_a.
  CompressionSeries s;
  for (int k = 0; k <= 20; ++k) {
    const double e = 0.5e-3 * k;
    s.axial_strain.push_back(e);
    s.deviatoric.push_back(20e9 * e * (1 - e / 0.02));
    s.lateral_strain.push_back(-0.25 * e);
    s.volumetric_strain.push_back(0.5 * e);
    s.broken_bonds.push_back(0.0);
  }
  // One more sample past the peak so that the peak counts as reached.
  s.axial_strain.push_back(0.0105);
  s.deviatoric.push_back(99e6);
  s.lateral_strain.push_back(-0.25 * 0.0105);
  s.volumetric_strain.push_back(0.0);
  s.broken_bonds.push_back(0.0);
  const CompressionResult r = analyse_compression(s);
  EXPECT_TRUE(r.peak_reached);
  EXPECT_NEAR(r.peak_deviatoric, 100e6, 1.0);
  EXPECT_NEAR(r.strain_at_peak, 0.01, 1e-15);
  // The [0.4, 0.6] window holds 3 samples, so it is widened once to [0.35, 0.65] (5 samples).
  EXPECT_NEAR(r.e_t50_lo, 0.35, 1e-12);
  EXPECT_EQ(r.e_t50.points, 5u);
  EXPECT_NEAR(r.e_t50.slope, 14.00e9, 1e-6 * 14e9);
  EXPECT_NEAR(r.e_s50, 17.06e9, 0.005e9);
  EXPECT_NEAR(r.poisson, 0.25, 1e-12);
}

TEST(Analysis, ModuliComeFromTheGaugesWhenEveryRowHasThem) {
  // The worked example's curve with a sample gauge that reads half the platen strain and a
  // lateral gauge that reads the lateral strain: E_t50 and the secant double, nu doubles
  // (-d e_l / d e_gauge = 0.25 x 2), the platen E_t50 stays 14.00 GPa, and the peak strain is
  // the platen's. One row without a gauge reading (a test that has none) falls back whole.
  CompressionSeries s;
  for (int k = 0; k <= 20; ++k) {
    const double e = 0.5e-3 * k;
    s.axial_strain.push_back(e);
    s.deviatoric.push_back(20e9 * e * (1 - e / 0.02));
    s.lateral_strain.push_back(-0.25 * e);
    s.volumetric_strain.push_back(0.5 * e);
    s.gauge_axial_strain.push_back(0.5 * e);
    s.gauge_lateral_strain.push_back(-0.25 * e);
    s.broken_bonds.push_back(0.0);
  }
  s.axial_strain.push_back(0.0105);
  s.deviatoric.push_back(99e6);
  s.lateral_strain.push_back(-0.25 * 0.0105);
  s.volumetric_strain.push_back(0.0);
  s.gauge_axial_strain.push_back(0.5 * 0.0105);
  s.gauge_lateral_strain.push_back(-0.25 * 0.0105);
  s.broken_bonds.push_back(0.0);
  const CompressionResult r = analyse_compression(s);
  ASSERT_TRUE(r.moduli_from_gauges);
  EXPECT_NEAR(r.e_t50.slope, 28.00e9, 1e-6 * 28e9);
  EXPECT_NEAR(r.e_t50_platen.slope, 14.00e9, 1e-6 * 14e9);
  EXPECT_NEAR(r.e_s50, 2 * 17.06e9, 0.01e9);
  EXPECT_NEAR(r.poisson, 0.5, 1e-12);
  EXPECT_NEAR(r.strain_at_peak, 0.01, 1e-15);
  s.gauge_axial_strain[3] = std::numeric_limits<double>::quiet_NaN();
  const CompressionResult platen = analyse_compression(s);
  EXPECT_FALSE(platen.moduli_from_gauges);
  EXPECT_NEAR(platen.e_t50.slope, 14.00e9, 1e-6 * 14e9);
  EXPECT_NEAR(platen.poisson, 0.25, 1e-12);
}

TEST(Analysis, WorkedExampleCrackDamageAndInitiation) {
  // docs/analysis.md §1.8 volumetric example; the last sample is the peak, a drop follows.
  CompressionSeries s;
  const double ea[] = {1, 2, 3, 4, 5, 6, 7}, ev[] = {0.5, 1.0, 1.4, 1.6, 1.4, 0.6, 0.0};
  const double q[] = {20, 40, 58, 74, 86, 90, 50}, nb[] = {0, 50, 100, 400, 1000, 2000, 3000};
  for (int k = 0; k < 7; ++k) {
    s.axial_strain.push_back(ea[k] * 1e-3);
    s.deviatoric.push_back(q[k] * 1e6);
    s.volumetric_strain.push_back(ev[k] * 1e-3);
    s.lateral_strain.push_back(0.5 * (ev[k] - ea[k]) * 1e-3);
    s.broken_bonds.push_back(nb[k]);
  }
  const CompressionResult r = analyse_compression(s);
  // The 5-sample moving average of e_v peaks at the 4th sample (74 MPa).
  EXPECT_NEAR(r.crack_damage, 74e6, 1.0);
  EXPECT_FALSE(r.no_reversal);
  // 5 % of the 2000 cracks at peak = 100: first reached at the third sample.
  EXPECT_NEAR(r.crack_initiation, 58e6, 1.0);
}

TEST(Analysis, MohrCoulombWorkedExample) {
  const auto f = fit_mohr_coulomb({0, 10e6, 20e6}, {34.641e6, 64.641e6, 94.641e6});
  ASSERT_TRUE(f.valid);
  EXPECT_NEAR(f.k, 3.0, 1e-9);
  EXPECT_NEAR(f.friction_angle_deg, 30.0, 1e-6);
  EXPECT_NEAR(f.cohesion, 10e6, 1e-3 * 1e6);
  EXPECT_NEAR(f.ucs, 34.641e6, 1.0);
  EXPECT_FALSE(fit_mohr_coulomb({5e6}, {50e6}).valid);
  EXPECT_EQ(fit_mohr_coulomb({0, 10e6}, {50e6, 50e6}).flag, "nonpositive_friction");
}

TEST(Analysis, HoekBrownWorkedExample) {
  const auto f = fit_hoek_brown({0, 10e6, 20e6}, {100e6, 151.421e6, 193.205e6});
  ASSERT_TRUE(f.valid);
  EXPECT_NEAR(f.sigma_ci_linear, 100e6, 0.01e6);
  EXPECT_NEAR(f.m_i_linear, 10.0, 0.01);
  EXPECT_NEAR(f.sigma_ci, 100e6, 0.01e6);
  EXPECT_NEAR(f.m_i, 10.0, 0.01);
  EXPECT_LT(f.rms, 1e4);
}

TEST(Samples, RadiusDistributionsHaveTheirMoments) {
  RadiusDistribution u;
  u.r_min = 1e-3;
  u.r_max = 2e-3;
  RadiusDistribution ln;
  ln.kind = RadiusDistribution::Kind::Lognormal;
  ln.r_min = 0.1e-3;
  ln.r_max = 10e-3;
  ln.mean = 1e-3;
  ln.sd = 0.2e-3;
  const int n = 40000;
  double su = 0, sl = 0, sl2 = 0;
  for (int k = 0; k < n; ++k) {
    const double a = u.draw(7, k), b = ln.draw(7, k);
    ASSERT_GE(a, u.r_min);
    ASSERT_LE(a, u.r_max);
    su += a;
    sl += b;
    sl2 += b * b;
  }
  // Standard errors: uniform sd = 0.29 mm, lognormal sd = 0.2 mm; 5 sigma of the mean over n.
  EXPECT_NEAR(su / n, 1.5e-3, 5 * 0.29e-3 / std::sqrt(n));
  const double m = sl / n;
  EXPECT_NEAR(m, 1e-3, 5 * 0.2e-3 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sl2 / n - m * m), 0.2e-3, 0.01e-3);
  EXPECT_EQ(u.draw(7, 12), u.draw(7, 12)) << "a pure function of seed and index";
  RadiusDistribution bad = u;
  bad.r_max = 0.5e-3;
  EXPECT_THROW(bad.validate("test"), InputError);
}

TEST(Samples, GenGeoFileImports) {
  // Written by python3-gengeo (InsertGenerator3D, generateBonds with tolerance 1e-5).
  const GeometryData g =
      read_gengeo(std::string(BRECCIA_SOURCE_DIR) + "/tests/data/gengeo_small.geo", 2650, 1.0);
  EXPECT_EQ(g.dimension, Dimension::Three);
  EXPECT_EQ(g.particles.size(), 340u);
  EXPECT_EQ(g.bonds.size(), 889u);
  EXPECT_EQ(g.particles[0].tag, 1u) << "GenGeo id 0 becomes tag 1";
  EXPECT_DOUBLE_EQ(g.particles[0].radius, 0.3260281576);
  EXPECT_EQ(g.bonds[0], (std::pair<std::uint64_t, std::uint64_t>{1, 92}));
  EXPECT_NO_THROW(g.make_store());
}

TEST(Samples, XyzrTableImportsAndRejectsBadRows) {
  const fs::path f = fs::temp_directory_path() / "breccia_table.csv";
  std::ofstream(f) << "x,y,z,r\n0,0,0,1e-3\n2e-3, 0, 0, 1e-3  # comment\n\n";
  const GeometryData g = read_xyzr_table(f.string(), Dimension::Three, 2650, 1.0);
  ASSERT_EQ(g.particles.size(), 2u);
  EXPECT_EQ(g.particles[1].position.x, 2e-3);
  EXPECT_EQ(g.particles[1].tag, 2u);
  std::ofstream(f) << "0 0 0 1e-3\n1e-3 0 0 -1\n";
  try {
    read_xyzr_table(f.string(), Dimension::Three, 2650, 1.0);
    ADD_FAILURE() << "negative radius accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("breccia_table.csv:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos) << e.what();
  }
  std::ofstream(f) << "0 0 1e-3\n";
  EXPECT_THROW(read_xyzr_table(f.string(), Dimension::Three, 2650, 1.0), InputError);
  EXPECT_EQ(read_xyzr_table(f.string(), Dimension::Two, 2650, 1e-3).particles.size(), 1u);
  fs::remove(f);
}
