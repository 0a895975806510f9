#include "breccia/analysis/stages.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "breccia/analysis/stress_strain.hpp"

namespace breccia::analysis {

int Stages::stage_of(double e) const noexcept {
  if (!(e == e)) return 0;
  if (linear_limit == linear_limit && e < linear_limit) return 1;
  if (peak == peak && e < peak) return linear_limit == linear_limit ? 2 : 0;
  if (peak != peak) return 0;
  if (residual_start == residual_start) return e < residual_start ? 3 : 4;
  return 3;  // no plateau: the drop lasts to the end of the record
}

Stages find_stages(const std::vector<double>& e, const std::vector<double>& q, double residual,
                   bool peak_reached, const StageSettings& s) {
  Stages st;
  const std::size_t n = std::min(e.size(), q.size());
  if (n < 3) {
    st.flags.push_back("no_peak");
    return st;
  }
  st.end = e[n - 1];
  // Centred moving average (shrinking at the ends).
  std::vector<double> qs(n);
  const std::size_t h = s.smoothing / 2;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i >= h ? i - h : 0, b = std::min(n - 1, i + h);
    double sum = 0.0;
    for (std::size_t k = a; k <= b; ++k) sum += q[k];
    qs[i] = sum / static_cast<double>(b - a + 1);
  }
  const PeakResult pk = find_peak(e, q);
  if (!pk.found) {
    st.flags.push_back("no_peak");
    return st;
  }
  const std::size_t ip = pk.index;
  const double qp = pk.stress;
  // Reference line over the pre-peak samples in [0.2, 0.5] q_peak (widened to [0.1, 0.6]).
  auto reference = [&](double lo, double hi) {
    std::vector<double> x, y;
    for (std::size_t i = 0; i <= ip; ++i)
      if (qs[i] >= lo * qp && qs[i] <= hi * qp) {
        x.push_back(e[i]);
        y.push_back(qs[i]);
      }
    LinearFit f = fit_line(x, y, 5);
    return std::pair(f, x.empty() ? 0.0 : x.back());
  };
  auto [line, window_end] = reference(0.2, 0.5);
  if (!line.valid) {
    std::tie(line, window_end) = reference(0.1, 0.6);
    if (line.valid) st.flags.push_back("reference_window_widened");
  }
  if (line.valid) {
    st.reference_modulus = line.slope;
    // First sample after the window from which the deviation exceeds tol up to the peak.
    std::size_t first = ip;
    for (std::size_t i = ip + 1; i-- > 0;) {
      if (e[i] <= window_end) break;
      const double dev = (line.slope * e[i] + line.intercept - qs[i]) / qp;
      if (dev > s.tolerance)
        first = i;
      else
        break;
    }
    st.linear_limit = e[first];
  } else {
    st.flags.push_back("no_reference_line");
  }
  if (!peak_reached) {
    st.flags.push_back("no_peak");
    return st;
  }
  st.peak = e[ip];
  if (!(residual == residual)) {
    st.flags.push_back("no_residual");
    return st;
  }
  if (qp - residual < 0.05 * qp) {
    st.flags.push_back("ductile");
    st.residual_start = st.peak;  // stage III empty
    return st;
  }
  const double threshold = residual + s.drop_fraction * (qp - residual);
  for (std::size_t i = ip + 1; i < n; ++i)
    if (qs[i] <= threshold) {
      st.residual_start = e[i];
      break;
    }
  if (!(st.residual_start == st.residual_start)) st.flags.push_back("no_residual");
  return st;
}

}  // namespace breccia::analysis
