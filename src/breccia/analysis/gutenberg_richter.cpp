#include "breccia/analysis/gutenberg_richter.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace breccia::analysis {

BValue b_value(const std::vector<double>& magnitudes, double completeness, double bin_width,
               std::size_t min_events) {
  BValue r;
  r.completeness = completeness;
  std::vector<double> m;
  for (double x : magnitudes)
    if (std::isfinite(x) && x >= completeness - 1e-12) m.push_back(x);
  r.events = m.size();
  if (m.size() < std::max<std::size_t>(min_events, 2)) {
    r.flag = "too_few_events";
    return r;
  }
  double mean = 0.0;
  for (double x : m) mean += x;
  mean /= static_cast<double>(m.size());
  const double denom = mean - (completeness - 0.5 * bin_width);
  if (!(denom > 0.0)) {
    r.flag = "no_spread";
    return r;
  }
  r.b = std::log10(std::exp(1.0)) / denom;
  double ss = 0.0;
  for (double x : m) ss += (x - mean) * (x - mean);
  const double n = static_cast<double>(m.size());
  r.sigma = std::log(10.0) * r.b * r.b * std::sqrt(ss / (n * (n - 1.0)));
  r.a = std::log10(n) + r.b * completeness;
  return r;
}

Completeness completeness_max_curvature(const std::vector<double>& magnitudes, double bin,
                                        double correction, std::size_t min_events) {
  Completeness c;
  std::map<long long, std::size_t> hist;
  std::size_t n = 0;
  for (double x : magnitudes)
    if (std::isfinite(x)) {
      ++hist[std::llround(x / bin)];
      ++n;
    }
  if (n < min_events) {
    c.flag = "too_few_events";
    return c;
  }
  long long best = 0;
  std::size_t count = 0;
  for (const auto& [k, v] : hist)  // ascending: ties go to the smaller magnitude
    if (v > count) {
      best = k;
      count = v;
    }
  c.magnitude = static_cast<double>(best) * bin + correction;
  return c;
}

double moment_magnitude(double m0, double constant) {
  return m0 > 0.0 && std::isfinite(m0) ? 2.0 / 3.0 * std::log10(m0) + constant : kNaN;
}

double radiated_energy(double magnitude) {
  return std::pow(10.0, 4.8 + 1.5 * magnitude);
}

double energy_magnitude(double energy) {
  return energy > 0.0 && std::isfinite(energy) ? 2.0 / 3.0 * std::log10(energy) - 3.2 : kNaN;
}

std::vector<BValueWindow> b_value_windows(const std::vector<double>& magnitudes,
                                          const std::vector<double>& strain, double completeness,
                                          std::size_t window, std::size_t step,
                                          std::size_t min_events) {
  std::vector<double> m, e;
  for (std::size_t k = 0; k < magnitudes.size() && k < strain.size(); ++k)
    if (std::isfinite(magnitudes[k]) && magnitudes[k] >= completeness - 1e-12) {
      m.push_back(magnitudes[k]);
      e.push_back(strain[k]);
    }
  std::vector<BValueWindow> out;
  if (!std::isfinite(completeness) || window == 0 || step == 0) return out;
  for (std::size_t end = window; end <= m.size(); end += step) {
    const std::vector<double> w(m.begin() + static_cast<std::ptrdiff_t>(end - window),
                                m.begin() + static_cast<std::ptrdiff_t>(end));
    out.push_back({e[end - 1], b_value(w, completeness, 0.0, min_events)});
  }
  return out;
}

}  // namespace breccia::analysis
