#include "breccia/analysis/stress_strain.hpp"

#include <algorithm>
#include <cmath>

namespace breccia::analysis {

PeakResult find_peak(const std::vector<double>& strain, const std::vector<double>& stress) {
  PeakResult p;
  for (std::size_t k = 0; k < stress.size() && k < strain.size(); ++k) {
    if (!p.found || stress[k] > p.stress) {
      p = {stress[k], strain[k], k, true};
    }
  }
  return p;
}

LinearFit fit_line(const std::vector<double>& x, const std::vector<double>& y,
                   std::size_t min_points) {
  LinearFit f;
  const std::size_t n = std::min(x.size(), y.size());
  f.points = n;
  if (n < min_points || n < 2) return f;
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  for (std::size_t k = 0; k < n; ++k) {
    sx += x[k];
    sy += y[k];
    sxx += x[k] * x[k];
    sxy += x[k] * y[k];
    syy += y[k] * y[k];
  }
  const double dn = static_cast<double>(n);
  const double vx = sxx - sx * sx / dn, vy = syy - sy * sy / dn, cxy = sxy - sx * sy / dn;
  if (!(vx > 0.0)) return f;
  f.slope = cxy / vx;
  f.intercept = (sy - f.slope * sx) / dn;
  f.r2 = vy > 0.0 ? cxy * cxy / (vx * vy) : 1.0;
  f.valid = true;
  return f;
}

LinearFit tangent_modulus(const std::vector<double>& strain, const std::vector<double>& stress,
                          double lo, double hi) {
  const PeakResult peak = find_peak(strain, stress);
  if (!peak.found || !(peak.stress > 0.0)) return LinearFit{};
  std::vector<double> x, y;
  for (std::size_t k = 0; k <= peak.index; ++k) {
    if (stress[k] < lo * peak.stress || stress[k] > hi * peak.stress) continue;
    x.push_back(strain[k]);
    y.push_back(stress[k]);
  }
  // Fewer than 3 points: no value rather than noise.
  return fit_line(x, y, 3);
}

}  // namespace breccia::analysis
