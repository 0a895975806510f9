// The quasi-static verdict of a compression test and the advice its warning gives: which rows
// count as before the first crack, and that no claim is made from rows that do not exist.
#include <gtest/gtest.h>

#include "breccia/run/quality.hpp"

using breccia::judge_quality;
using breccia::quality_warnings;
using breccia::analysis::CompressionResult;
using breccia::analysis::CompressionSeries;

namespace {

// Eleven rows from the start of the loading (no load) to a peak of 100 MPa at 1 % strain, the
// load rising 10 MPa a row; `cracks` are the cumulative broken bonds per row, `imbalance` the
// platen-force imbalance per row.
struct Rows {
  CompressionSeries series;
  std::vector<double> imbalance, ke_ratio, confine_err;
  CompressionResult an;
  Rows(const std::vector<double>& cracks, const std::vector<double>& imb) {
    for (std::size_t k = 0; k < cracks.size(); ++k) {
      series.axial_strain.push_back(1e-3 * static_cast<double>(k));
      series.deviatoric.push_back(10e6 * static_cast<double>(k));
      series.broken_bonds.push_back(cracks[k]);
      imbalance.push_back(imb[k]);
      ke_ratio.push_back(1e-5);
      confine_err.push_back(0.0);
    }
    an.peak_reached = true;
    an.peak_deviatoric = 100e6;
    an.strain_at_peak = 10e-3;
  }
  breccia::QualityVerdict verdict() const {
    return judge_quality(series, imbalance, ke_ratio, confine_err, an);
  }
};

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST(Quality, AQuasiStaticTestHasNoWarning) {
  const Rows r({0, 0, 0, 0, 0, 0, 1, 5, 20, 60, 100}, std::vector<double>(11, 0.01));
  const auto q = r.verdict();
  EXPECT_TRUE(q.quasi_static());
  EXPECT_EQ(q.intact_rows, 5u);
  EXPECT_TRUE(quality_warnings(q, 0.0).empty());
}

TEST(Quality, BurstsOfCracksNearThePeakAreToldFromTheLoading) {
  // Balanced until the first crack (row 6), then out of balance: the cracks' doing.
  const Rows r({0, 0, 0, 0, 0, 0, 1, 5, 20, 60, 100},
               {0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.2, 0.2, 0.2, 0.2, 0.2});
  const auto q = r.verdict();
  EXPECT_FALSE(q.quasi_static());
  EXPECT_TRUE(q.quasi_static_until_cracking());
  const auto w = quality_warnings(q, 0.0);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_TRUE(contains(w[0], "bursts of breaking bonds")) << w[0];
}

TEST(Quality, AnUnbalancedLoadingIsToldToSlowDown) {
  const Rows r({0, 0, 0, 0, 0, 0, 1, 5, 20, 60, 100}, std::vector<double>(11, 0.2));
  const auto q = r.verdict();
  EXPECT_FALSE(q.quasi_static_until_cracking());
  const auto w = quality_warnings(q, 0.0);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_TRUE(contains(w[0], "lower test.platen_speed or engine.density_scaling")) << w[0];
  EXPECT_TRUE(contains(w[0], "0.2 before the first crack")) << w[0];
}

TEST(Quality, NoRowBeforeTheFirstCrackMakesNoClaimAboutTheLoading) {
  // Cracks from the first row above 10 % of the peak: nothing says the loading was balanced,
  // so the warning must not blame the cracks (it did when the empty window read as zero).
  const Rows r({0, 2, 4, 8, 16, 32, 50, 70, 90, 100, 110}, std::vector<double>(11, 0.2));
  const auto q = r.verdict();
  EXPECT_EQ(q.intact_rows, 0u);
  EXPECT_FALSE(q.quasi_static_until_cracking());
  const auto w = quality_warnings(q, 0.0);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_FALSE(contains(w[0], "bursts of breaking bonds")) << w[0];
  EXPECT_TRUE(contains(w[0], "no row before the first crack")) << w[0];
  EXPECT_TRUE(contains(w[0], "cannot tell")) << w[0];
}

TEST(Quality, BondsBrokenBeforeTheLoadingAreNotItsCracks) {
  // 40 bonds broke while the confinement was applied; the loading's first crack is at row 6.
  const Rows r({40, 40, 40, 40, 40, 40, 41, 45, 60, 100, 140},
               {0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.2, 0.2, 0.2, 0.2, 0.2});
  const auto q = r.verdict();
  EXPECT_EQ(q.intact_rows, 5u);
  EXPECT_TRUE(q.quasi_static_until_cracking());
}

TEST(Quality, TheConfinementBandIsCheckedOnlyUnderConfinement) {
  Rows r({0, 0, 0, 0, 0, 0, 1, 5, 20, 60, 100}, std::vector<double>(11, 0.01));
  r.confine_err[5] = 0.03;
  const auto q = r.verdict();
  EXPECT_DOUBLE_EQ(q.confine_err_pre, 0.03);
  EXPECT_TRUE(quality_warnings(q, 0.0).empty());
  ASSERT_EQ(quality_warnings(q, 10e6).size(), 1u);
  EXPECT_TRUE(contains(quality_warnings(q, 10e6)[0], "3 %"));
}

using breccia::kPresetLoadingTolerance;
using breccia::preset_loading_warning;

TEST(PresetLoading, ASlowerOrEqualLoadingIsQuiet) {
  // berea_2d's verification: 0.03 m/s at density scaling 100, v sqrt(s) = 0.3 m/s.
  EXPECT_FALSE(preset_loading_warning("berea_2d", 0.03, 100, 0.03, 100));
  EXPECT_FALSE(preset_loading_warning("berea_2d", 0.03, 100, 0.015, 100));
  EXPECT_FALSE(preset_loading_warning("berea_2d", 0.03, 100, 0.06, 25));  // 0.3 m/s again
  // Just inside the tolerance: 1.5 x 0.3 = 0.45 m/s.
  EXPECT_FALSE(preset_loading_warning("berea_2d", 0.03, 100, 0.0449, 100));
}

TEST(PresetLoading, TheSixtyThousandDiskBenchmarksLoadingWarns) {
  // bench/biaxial-60k: 0.15 m/s at density scaling 500 is 0.15 x sqrt(500) = 3.354 m/s, 11.18
  // times the preset's 0.3 m/s.
  const auto w = preset_loading_warning("berea_2d", 0.03, 100, 0.15, 500);
  ASSERT_TRUE(w);
  EXPECT_NE(w->find("11.2 times"), std::string::npos) << *w;
  EXPECT_NE(w->find("3.35 m/s"), std::string::npos) << *w;
  EXPECT_NE(w->find("berea_2d"), std::string::npos) << *w;
  EXPECT_TRUE(preset_loading_warning("berea_2d", 0.03, 100, 0.0451, 100));
  EXPECT_GT(kPresetLoadingTolerance, 1.0);
}

TEST(PresetLoading, NoPlatensOrNoRecordedLoadingIsQuiet) {
  EXPECT_FALSE(preset_loading_warning("berea", 0.03, 10, 0.0, 10));  // no platens
  EXPECT_FALSE(preset_loading_warning("berea", 0.0, 0.0, 0.3, 10));  // record without loading
}
