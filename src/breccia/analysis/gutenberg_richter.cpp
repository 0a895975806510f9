#include "breccia/analysis/gutenberg_richter.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

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

namespace {

// Ranks from 1, ties sharing the mean of the ranks they span.
std::vector<double> mean_ranks(const std::vector<double>& v) {
  std::vector<std::size_t> order(v.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  std::vector<double> rank(v.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && v[order[j + 1]] == v[order[i]]) ++j;
    const double mean = 0.5 * static_cast<double>(i + j) + 1.0;
    for (std::size_t k = i; k <= j; ++k) rank[order[k]] = mean;
    i = j + 1;
  }
  return rank;
}

}  // namespace

double spearman_rho(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = std::min(x.size(), y.size());
  if (n < 2) return kNaN;
  const std::vector<double> rx =
      mean_ranks({x.begin(), x.begin() + static_cast<std::ptrdiff_t>(n)});
  const std::vector<double> ry =
      mean_ranks({y.begin(), y.begin() + static_cast<std::ptrdiff_t>(n)});
  const double mean = 0.5 * static_cast<double>(n + 1);  // of either set of ranks
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    sxy += (rx[k] - mean) * (ry[k] - mean);
    sxx += (rx[k] - mean) * (rx[k] - mean);
    syy += (ry[k] - mean) * (ry[k] - mean);
  }
  return sxx > 0.0 && syy > 0.0 ? sxy / std::sqrt(sxx * syy) : kNaN;
}

BValueTrend b_value_trend(const std::vector<BValueWindow>& windows, double peak_strain,
                          bool peak_reached, std::size_t min_windows) {
  BValueTrend t;
  if (!peak_reached || !std::isfinite(peak_strain)) {
    t.flag = "no_peak";
    return t;
  }
  std::vector<double> strain, b;
  for (const auto& w : windows)
    if (w.value.valid() && w.strain <= peak_strain) {
      strain.push_back(w.strain);
      b.push_back(w.value.b);
    }
  t.windows = b.size();
  if (b.empty()) {
    t.flag = "no_window_before_peak";
    return t;
  }
  t.first_strain = strain.front();
  t.first_b = b.front();
  t.last_strain = strain.back();
  t.last_b = b.back();
  if (b.size() < min_windows) {
    t.flag = "too_few_windows";
    return t;
  }
  t.spearman_rho = spearman_rho(strain, b);
  return t;
}

}  // namespace breccia::analysis
