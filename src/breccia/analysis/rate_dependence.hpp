#pragma once
// Strain-rate dependence of strength (docs/analysis.md §11): UCS(rate) = a exp(b rate), fitted
// first by least squares on ln UCS (the start) and then by Levenberg-Marquardt on the untransformed
// residuals; and the three-parameter form UCS = c + a exp(b rate) for a low-rate plateau. `a`
// (or c + a) is the quasi-static strength; UCS / a the dynamic increase factor. Pure functions.
#include <cstddef>
#include <string>
#include <vector>

namespace breccia::analysis {

struct ExponentialRateFit {
  bool valid = false;
  std::string flag;  // why not valid: "too_few_rates" (fewer than 3 positive strengths), "no_fit"
  std::size_t points = 0;
  // ln UCS = ln a + b rate by least squares: the start of the fits below.
  double a_log = 0.0, b_log = 0.0;
  // UCS = a exp(b rate), Levenberg-Marquardt; standard errors from s^2 (J^T J)^-1.
  double a = 0.0, b = 0.0, a_se = 0.0, b_se = 0.0, rms = 0.0;
  // UCS = c + a3 exp(b3 rate), from c = 0.9 min UCS; valid with at least 4 points.
  bool three_valid = false;
  double c3 = 0.0, a3 = 0.0, b3 = 0.0, rms3 = 0.0;
  std::vector<double> dynamic_increase;  // UCS_j / a, in the order given
};

// `rate` in 1/s, `ucs` in Pa (or any unit: a and c come out in it); non-positive strengths are
// left out.
ExponentialRateFit fit_rate_dependence(const std::vector<double>& rate,
                                       const std::vector<double>& ucs);

}  // namespace breccia::analysis
