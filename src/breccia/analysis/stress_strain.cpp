#include "breccia/analysis/stress_strain.hpp"

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

LinearFit tangent_modulus(const std::vector<double>& strain, const std::vector<double>& stress,
                          double lo, double hi) {
  LinearFit f;
  const PeakResult peak = find_peak(strain, stress);
  if (!peak.found || !(peak.stress > 0.0)) return f;
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k <= peak.index; ++k) {
    const double s = stress[k];
    if (s < lo * peak.stress || s > hi * peak.stress) continue;
    const double x = strain[k];
    sx += x;
    sy += s;
    sxx += x * x;
    sxy += x * s;
    syy += s * s;
    ++n;
  }
  f.points = n;
  if (n < 3) return f;
  const double dn = static_cast<double>(n);
  const double vx = sxx - sx * sx / dn, vy = syy - sy * sy / dn, cxy = sxy - sx * sy / dn;
  if (!(vx > 0.0)) return f;
  f.slope = cxy / vx;
  f.intercept = (sy - f.slope * sx) / dn;
  f.r2 = vy > 0.0 ? cxy * cxy / (vx * vy) : 1.0;
  f.valid = true;
  return f;
}

}  // namespace breccia::analysis
