// The analyses of the strain-rate study: the rate law of docs/analysis.md §11 on its worked
// examples and planted data, and the failure plane fitted to crack midpoints.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "breccia/analysis/crack_pattern.hpp"
#include "breccia/analysis/rate_dependence.hpp"

using namespace breccia::analysis;

TEST(RateDependence, WorkedExampleOfTheTwoParameterLaw) {
  // docs/analysis.md §11: rates 0.1, 1, 10 /s and UCS 100.501, 105.127, 164.872 MPa (100 e^(0.05 r)
  // to 3 decimals): ln UCS on the rate gives b = 0.0500 s and a = 100.0 MPa.
  const ExponentialRateFit f = fit_rate_dependence({0.1, 1, 10}, {100.501, 105.127, 164.872});
  ASSERT_TRUE(f.valid) << f.flag;
  EXPECT_NEAR(f.b_log, 0.0500, 5e-5);
  EXPECT_NEAR(f.a_log, 100.0, 0.01);
  // The untransformed fit lands on the same law; the data's rounding (1e-3 MPa) bounds the rest.
  EXPECT_NEAR(f.a, 100.0, 0.01);
  EXPECT_NEAR(f.b, 0.0500, 5e-5);
  EXPECT_LT(f.rms, 1e-3);
  ASSERT_EQ(f.dynamic_increase.size(), 3u);
  EXPECT_NEAR(f.dynamic_increase[2], 1.64872, 2e-4);
  EXPECT_FALSE(f.three_valid) << "three points do not fix three parameters and a scatter";
}

TEST(RateDependence, WorkedExampleOfTheThreeParameterLaw) {
  // docs/analysis.md §11: c = 80, a = 20, b = 0.1 at rates 0, 2, 5, 10 /s give 100.000, 104.428,
  // 112.974, 134.366 MPa. Four points fix the three parameters (to the data's rounding).
  const ExponentialRateFit f =
      fit_rate_dependence({0, 2, 5, 10}, {100.000, 104.428, 112.974, 134.366});
  ASSERT_TRUE(f.three_valid);
  EXPECT_NEAR(f.c3, 80.0, 0.05);
  EXPECT_NEAR(f.a3, 20.0, 0.05);
  EXPECT_NEAR(f.b3, 0.1, 1e-4);
  EXPECT_NEAR(f.c3 + f.a3, 100.0, 0.01) << "the quasi-static limit";
  EXPECT_LT(f.rms3, 2e-3);
  // The two-parameter law cannot follow the plateau: its residual is larger.
  EXPECT_GT(f.rms, 10 * f.rms3);
}

TEST(RateDependence, ScatterGivesStandardErrorsThatCoverThePlantedLaw) {
  // UCS = 50 e^(0.03 r) MPa with a +-1 % alternating scatter at six rates: the fit's standard
  // errors are finite and the planted values lie within three of them.
  const std::vector<double> r{0.05, 0.1, 0.5, 1, 5, 10};
  std::vector<double> ucs;
  for (std::size_t j = 0; j < r.size(); ++j)
    ucs.push_back(50.0 * std::exp(0.03 * r[j]) * (j % 2 ? 1.01 : 0.99));
  const ExponentialRateFit f = fit_rate_dependence(r, ucs);
  ASSERT_TRUE(f.valid);
  ASSERT_TRUE(std::isfinite(f.a_se) && std::isfinite(f.b_se));
  EXPECT_GT(f.a_se, 0.0);
  EXPECT_LT(std::abs(f.a - 50.0), 3 * f.a_se);
  EXPECT_LT(std::abs(f.b - 0.03), 3 * f.b_se);
}

TEST(RateDependence, StandardErrorsDoNotDependOnTheStrengthUnit) {
  // The same scattered law in pascals (as sweeps fit it) and in megapascals: the standard
  // errors of a scale with the unit and those of b do not change.
  const std::vector<double> r{0.5, 1, 5, 10};
  std::vector<double> mpa, pa;
  for (std::size_t j = 0; j < r.size(); ++j) {
    mpa.push_back(9.1 * std::exp(0.003 * r[j]) * (j % 2 ? 1.002 : 0.998));
    pa.push_back(1e6 * mpa.back());
  }
  const ExponentialRateFit m = fit_rate_dependence(r, mpa), p = fit_rate_dependence(r, pa);
  ASSERT_TRUE(m.valid && p.valid);
  ASSERT_TRUE(std::isfinite(p.a_se) && std::isfinite(p.b_se));
  EXPECT_NEAR(p.a_se, 1e6 * m.a_se, 1e-6 * p.a_se);
  EXPECT_NEAR(p.b_se, m.b_se, 1e-6 * m.b_se);
}

TEST(RateDependence, TooFewPositiveStrengthsGiveNoFit) {
  const ExponentialRateFit f = fit_rate_dependence({0.1, 1, 10}, {100.0, -1.0, 120.0});
  EXPECT_FALSE(f.valid);
  EXPECT_EQ(f.flag, "too_few_rates");
  EXPECT_EQ(f.points, 2u);
}

namespace {

// Crack midpoints scattered over a plane through the origin whose normal makes `theta_deg` with
// the z axis (the load), with a small deterministic jitter off the plane.
std::vector<breccia::Vec3> cracks_on_plane(double theta_deg, double jitter) {
  const double t = theta_deg * std::numbers::pi / 180.0;
  const breccia::Vec3 n{std::sin(t), 0.0, std::cos(t)};                     // unit normal
  const breccia::Vec3 u{std::cos(t), 0.0, -std::sin(t)}, v{0.0, 1.0, 0.0};  // in the plane
  std::vector<breccia::Vec3> p;
  for (int i = 0; i < 15; ++i)
    for (int j = 0; j < 10; ++j) {
      const double off = jitter * (((i * 7 + j * 3) % 5) - 2.0) / 2.0;
      p.push_back(u * (1e-3 * (i - 7)) + v * (1e-3 * (j - 4.5)) + n * off);
    }
  return p;
}

}  // namespace

TEST(FailurePlane, AnInclinedCrackPlaneGivesItsAngleToThePlaneNormalToTheLoad) {
  // A Coulomb shear plane at 60 degrees (45 + phi / 2 with phi = 30): its normal is 60 degrees
  // from the load. The jitter (+-5 um across a 14 x 9 mm plane) leaves the angle within 0.1
  // degree and the planarity near 1.
  const FailurePlane f = failure_plane(cracks_on_plane(60.0, 5e-6), 2, false);
  ASSERT_TRUE(f.valid);
  EXPECT_NEAR(f.angle_from_normal_plane_deg, 60.0, 0.1);
  EXPECT_GT(f.planarity, 0.99);
  // Axial splitting (a vertical plane) and a horizontal crack plane.
  EXPECT_NEAR(failure_plane(cracks_on_plane(90.0, 5e-6), 2, false).angle_from_normal_plane_deg,
              90.0, 0.1);
  EXPECT_NEAR(failure_plane(cracks_on_plane(0.0, 5e-6), 2, false).angle_from_normal_plane_deg, 0.0,
              0.1);
}

TEST(FailurePlane, TwoDimensionalCracksOnALineAndAnIsotropicCloud) {
  // 2D: the load along y; midpoints on a line at 55 degrees from the x axis.
  const double t = 55.0 * std::numbers::pi / 180.0;
  std::vector<breccia::Vec3> line, cloud;
  for (int k = 0; k < 60; ++k) {
    const double s = 1e-4 * (k - 30), off = 2e-6 * ((k % 3) - 1.0);
    line.push_back({s * std::cos(t) - off * std::sin(t), s * std::sin(t) + off * std::cos(t), 0});
  }
  const FailurePlane f = failure_plane(line, 1, true);
  ASSERT_TRUE(f.valid);
  EXPECT_NEAR(f.angle_from_normal_plane_deg, 55.0, 0.2);
  EXPECT_GT(f.planarity, 0.99);
  // A square grid of cracks has no preferred plane: planarity near 0.
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) cloud.push_back({1e-4 * i, 1e-4 * j, 0});
  EXPECT_LT(failure_plane(cloud, 1, true).planarity, 0.01);
  EXPECT_FALSE(
      failure_plane(std::vector<breccia::Vec3>(line.begin(), line.begin() + 10), 1, true).valid)
      << "too few cracks";
}
