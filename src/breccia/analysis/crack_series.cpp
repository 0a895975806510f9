#include "breccia/analysis/crack_series.hpp"

#include <cmath>

namespace breccia::analysis {

double sample_variance(const double* v, std::size_t n) {
  if (n < 2) return kNaN;
  double mean = 0.0;
  for (std::size_t k = 0; k < n; ++k) mean += v[k];
  mean /= static_cast<double>(n);
  double ss = 0.0;
  for (std::size_t k = 0; k < n; ++k) ss += (v[k] - mean) * (v[k] - mean);
  return ss / static_cast<double>(n - 1);
}

CrackSeries crack_series(const std::vector<double>& strain, const std::vector<char>& shear,
                         const std::vector<double>& energy, double start, double end,
                         const CrackSeriesSettings& s) {
  CrackSeries r;
  if (!(end > start) || !(s.bin_width > 0.0)) return r;
  const auto bins = static_cast<std::size_t>(std::ceil((end - start) / s.bin_width - 1e-9));
  r.bin_end.resize(bins);
  r.count.assign(bins, 0.0);
  r.tensile.assign(bins, 0.0);
  r.shear.assign(bins, 0.0);
  r.energy.assign(bins, 0.0);
  for (std::size_t j = 0; j < bins; ++j)
    r.bin_end[j] = start + static_cast<double>(j + 1) * s.bin_width;
  for (std::size_t c = 0; c < strain.size(); ++c) {
    if (!(strain[c] >= start)) continue;  // before loading (or NaN)
    auto j = static_cast<std::size_t>((strain[c] - start) / s.bin_width);
    if (j >= bins) j = bins - 1;
    r.count[j] += 1.0;
    (shear[c] ? r.shear : r.tensile)[j] += 1.0;
    r.energy[j] += energy[c];
  }
  r.cumulative.resize(bins);
  r.cumulative_tensile.resize(bins);
  r.cumulative_shear.resize(bins);
  double a = 0, t = 0, sh = 0;
  for (std::size_t j = 0; j < bins; ++j) {
    a += r.count[j];
    t += r.tensile[j];
    sh += r.shear[j];
    r.cumulative[j] = a;
    r.cumulative_tensile[j] = t;
    r.cumulative_shear[j] = sh;
  }
  r.shear_fraction.assign(bins, kNaN);
  r.mc_var.assign(bins, kNaN);
  r.ae_var.assign(bins, kNaN);
  const std::size_t w = s.window_bins;
  for (std::size_t j = w > 0 ? w - 1 : bins; j < bins; ++j) {
    const std::size_t first = j + 1 - w;
    r.mc_var[j] = sample_variance(&r.count[first], w);
    r.ae_var[j] = sample_variance(&r.energy[first], w);
    double n = 0, ns = 0;
    for (std::size_t k = first; k <= j; ++k) {
      n += r.count[k];
      ns += r.shear[k];
    }
    if (n >= static_cast<double>(s.min_cracks_sf)) r.shear_fraction[j] = ns / n;
  }
  return r;
}

}  // namespace breccia::analysis
