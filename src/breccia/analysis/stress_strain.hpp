#pragma once
// Headline results of a compression curve (docs/analysis.md §1.2-§1.3): peak strength, strain at
// peak, and Young's modulus as the least-squares slope of stress against axial strain over 40-60 %
// of the peak on the pre-peak branch (the ISRM tangent modulus E_t50). Pure functions over recorded
// series.
#include <cstddef>
#include <vector>

namespace breccia::analysis {

struct PeakResult {
  double stress = 0.0;  // Pa
  double strain = 0.0;
  std::size_t index = 0;
  bool found = false;
};

// Largest stress of the series (compression-positive).
PeakResult find_peak(const std::vector<double>& strain, const std::vector<double>& stress);

struct LinearFit {
  double slope = 0.0, intercept = 0.0, r2 = 0.0;
  std::size_t points = 0;
  bool valid = false;  // false with fewer than 3 points: no value rather than noise
};

// Ordinary least-squares line y = slope x + intercept; valid with at least `min_points` points
// and some spread in x.
LinearFit fit_line(const std::vector<double>& x, const std::vector<double>& y,
                   std::size_t min_points = 2);

// Least-squares line through the pre-peak points whose stress lies in [lo, hi] x peak.
LinearFit tangent_modulus(const std::vector<double>& strain, const std::vector<double>& stress,
                          double lo = 0.4, double hi = 0.6);

}  // namespace breccia::analysis
