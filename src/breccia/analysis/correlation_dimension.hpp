#pragma once
// Correlation fractal dimension D2 of a point set (docs/analysis.md §6; Grassberger & Procaccia
// 1983): the slope of log10 C(r) against log10 r over an automatically chosen scaling range, with
// the pair counts from an all-pairs pass (N <= 5000) or a cell list over r_hi.
#include <cstddef>
#include <string>
#include <vector>

#include "breccia/analysis/gutenberg_richter.hpp"
#include "breccia/core/vec3.hpp"

namespace breccia::analysis {

// C(r) at each radius: the fraction of distinct pairs closer than r (strict).
std::vector<double> correlation_integral(const std::vector<Vec3>& points,
                                         const std::vector<double>& radii);

struct CorrelationDimension {
  double d2 = kNaN, standard_error = kNaN, r2 = kNaN;
  double r_min = kNaN, r_max = kNaN;
  std::size_t points = 0, radii_used = 0, pairs_at_r_min = 0;
  std::vector<std::string> flags;  // too_few_points, short_scaling_range, no_scaling_range,
                                   // above_dimension, eckmann_ruelle_limit, negative
  bool valid() const noexcept { return d2 == d2; }
};

struct D2Settings {
  double r_hi = 0.0;  // upper radius: 0.25 x the smallest sample dimension (required)
  int radii = 30;     // log-spaced in [r_lo, r_hi]
  std::size_t min_pairs = 20;
  int min_run = 5;           // radii in a candidate range
  double min_decades = 1.0;  // span of a candidate range (0.5 as a flagged fallback)
  std::size_t min_points = 50;
  int dimension = 3;
};

// D2 with the automatic scaling range of §6.2.
CorrelationDimension correlation_dimension(const std::vector<Vec3>& points, const D2Settings& s);

// D2 as the least-squares slope over given radii (no range search): for worked examples.
CorrelationDimension correlation_dimension_fixed(const std::vector<Vec3>& points,
                                                 const std::vector<double>& radii);

}  // namespace breccia::analysis
