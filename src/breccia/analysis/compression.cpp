#include "breccia/analysis/compression.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace breccia::analysis {

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

bool has_gauges(const CompressionSeries& s) {
  const std::size_t rows = std::min(s.axial_strain.size(), s.deviatoric.size());
  if (rows == 0 || s.gauge_axial_strain.size() < rows || s.gauge_lateral_strain.size() < rows)
    return false;
  for (std::size_t k = 0; k < rows; ++k)
    if (!std::isfinite(s.gauge_axial_strain[k]) || !std::isfinite(s.gauge_lateral_strain[k]))
      return false;
  return true;
}

namespace {

// The strains the moduli are measured with: the sample gauges when every row has them.
const std::vector<double>& moduli_strain(const CompressionSeries& s, const CompressionResult& r) {
  return r.moduli_from_gauges ? s.gauge_axial_strain : s.axial_strain;
}

// E_t50 with the window widening of docs/analysis.md §1.3, the platen reading over the same
// window, E_av and E_s50.
void read_moduli(const CompressionSeries& s, const PeakResult& peak, CompressionResult& r) {
  const auto& q = s.deviatoric;
  const auto& em = moduli_strain(s, r);
  for (double w = 0.1; w <= 0.25 + 1e-12; w += 0.05) {
    r.e_t50_lo = 0.5 - w;
    r.e_t50_hi = 0.5 + w;
    r.e_t50 = tangent_modulus(em, q, r.e_t50_lo, r.e_t50_hi);
    if (r.e_t50.points >= 5) break;
  }
  r.e_t50_platen = tangent_modulus(s.axial_strain, q, r.e_t50_lo, r.e_t50_hi);
  r.e_av = tangent_modulus(em, q, 0.25, 0.75);
  r.e_s50 = kNaN;
  for (std::size_t k = 1; k <= peak.index; ++k)
    if (q[k] >= 0.5 * peak.stress && q[k - 1] < 0.5 * peak.stress) {
      const double e50 =
          em[k - 1] + (em[k] - em[k - 1]) * (0.5 * peak.stress - q[k - 1]) / (q[k] - q[k - 1]);
      r.e_s50 = e50 > 0.0 ? 0.5 * peak.stress / e50 : kNaN;
      break;
    }
}

// Poisson's ratio over the E_t50 window.
void read_poisson(const CompressionSeries& s, const PeakResult& peak, CompressionResult& r) {
  const auto& q = s.deviatoric;
  const auto& em = moduli_strain(s, r);
  const auto& lateral = r.moduli_from_gauges ? s.gauge_lateral_strain : s.lateral_strain;
  r.poisson = kNaN;
  if (lateral.empty()) return;
  std::vector<double> x, y;
  for (std::size_t k = 0; k <= peak.index; ++k)
    if (q[k] >= r.e_t50_lo * peak.stress && q[k] <= r.e_t50_hi * peak.stress) {
      x.push_back(em[k]);
      y.push_back(lateral[k]);
    }
  const LinearFit l = fit_line(x, y);
  // Lateral strain is compression-positive, so expansion makes the slope negative.
  if (l.valid && x.size() >= 3) r.poisson = -l.slope;
}

// Crack initiation: 5 % of the cracks at peak (§1.5 method 1).
void read_crack_initiation(const CompressionSeries& s, const PeakResult& peak,
                           CompressionResult& r) {
  const std::size_t ip = peak.index;
  r.crack_initiation = kNaN;
  if (s.broken_bonds.size() <= ip || !(s.broken_bonds[ip] > 0.0)) {
    r.flags.push_back("no_cracks_before_peak");
    return;
  }
  for (std::size_t k = 0; k <= ip; ++k)
    if (s.broken_bonds[k] >= 0.05 * s.broken_bonds[ip]) {
      r.crack_initiation = s.deviatoric[k];
      return;
    }
}

// Crack damage: maximum of the 5-sample moving average of the volumetric strain (§1.6).
void read_crack_damage(const CompressionSeries& s, const PeakResult& peak, CompressionResult& r) {
  const std::size_t ip = peak.index;
  r.crack_damage = kNaN;
  if (s.volumetric_strain.size() <= ip) return;
  double best = -std::numeric_limits<double>::infinity();
  std::size_t icd = 0;
  for (std::size_t k = 0; k <= ip; ++k) {
    // Centred window of up to 5 samples, narrowed symmetrically near the ends (a lopsided
    // window would shift the maximum).
    const std::size_t h = std::min({std::size_t{2}, k, ip - k});
    const std::size_t a = k - h, b = k + h;
    double m = 0.0;
    for (std::size_t j = a; j <= b; ++j) m += s.volumetric_strain[j];
    m /= static_cast<double>(b - a + 1);
    if (m > best) {
      best = m;
      icd = k;
    }
  }
  r.crack_damage = s.deviatoric[icd];
  if (icd == ip) {
    r.no_reversal = true;
    r.crack_damage = peak.stress;
    r.flags.push_back("no_reversal");
  }
}

// Residual strength: median over the last 10 % of the strain record if flat (§1.7).
void read_residual(const CompressionSeries& s, const PeakResult& peak, std::size_t n,
                   CompressionResult& r) {
  const auto& e = s.axial_strain;
  r.residual = r.brittleness = kNaN;
  if (!r.peak_reached || !r.e_t50.valid) return;
  const double e_end = e[n - 1], e_start = e_end - 0.1 * (e_end - e[0]);
  std::vector<double> xs, ys;
  for (std::size_t k = peak.index + 1; k < n; ++k)
    if (e[k] >= e_start) {
      xs.push_back(e[k]);
      ys.push_back(s.deviatoric[k]);
    }
  const LinearFit l = fit_line(xs, ys);
  if (xs.size() >= 3 && l.valid && std::abs(l.slope) < 0.05 * r.e_t50.slope) {
    std::vector<double> sorted = ys;
    std::sort(sorted.begin(), sorted.end());
    const std::size_t m = sorted.size();
    r.residual = m % 2 ? sorted[m / 2] : 0.5 * (sorted[m / 2 - 1] + sorted[m / 2]);
    r.brittleness = (peak.stress - r.residual) / peak.stress;
  } else {
    r.flags.push_back("no_residual_plateau");
  }
}

}  // namespace

CompressionResult analyse_compression(const CompressionSeries& s) {
  CompressionResult r;
  const std::size_t n = std::min(s.axial_strain.size(), s.deviatoric.size());
  const PeakResult peak = find_peak(s.axial_strain, s.deviatoric);
  if (!peak.found || !(peak.stress > 0.0)) {
    r.flags.push_back("no_positive_stress");
    r.e_s50 = r.poisson = r.crack_initiation = r.crack_damage = r.residual = r.brittleness = kNaN;
    return r;
  }
  r.peak_reached = peak.index + 1 < n;
  if (!r.peak_reached) r.flags.push_back("peak_not_reached");
  r.peak_deviatoric = peak.stress;
  r.sigma1_at_peak = peak.stress + s.confining_stress;
  r.strain_at_peak = peak.strain;
  r.moduli_from_gauges = has_gauges(s);
  read_moduli(s, peak, r);
  read_poisson(s, peak, r);
  read_crack_initiation(s, peak, r);
  read_crack_damage(s, peak, r);
  read_residual(s, peak, n, r);
  return r;
}

MohrCoulombFit fit_mohr_coulomb(const std::vector<double>& sigma3,
                                const std::vector<double>& sigma1) {
  MohrCoulombFit f;
  std::vector<double> x, y;
  for (std::size_t k = 0; k < std::min(sigma3.size(), sigma1.size()); ++k)
    if (sigma3[k] >= 0.0) {
      x.push_back(sigma3[k]);
      y.push_back(sigma1[k]);
    }
  if (x.size() < 2) {
    f.flag = "fewer_than_two_tests";
    return f;
  }
  const LinearFit l = fit_line(x, y);
  if (!l.valid) {
    f.flag = "single_confining_stress";
    return f;
  }
  f.k = l.slope;
  f.ucs = l.intercept;
  f.r2 = x.size() > 2 ? l.r2 : kNaN;
  if (!(f.k > 1.0)) {
    f.flag = "nonpositive_friction";
    return f;
  }
  const double sin_phi = (f.k - 1.0) / (f.k + 1.0);
  f.friction_angle_deg = std::asin(sin_phi) * 180.0 / std::numbers::pi;
  f.cohesion = f.ucs / (2.0 * std::sqrt(f.k));
  f.tensile = f.ucs / f.k;
  f.valid = true;
  return f;
}

namespace {

// Levenberg-Marquardt of sigma_1 = sigma_3 + c sqrt(m sigma_3 / c + 1) (the Hoek-Brown envelope
// of intact rock, docs/analysis.md §1.9) over (c, m) from their start values; stresses in MPa.
// Returns the sum of squared residuals at the end.
double refine_hoek_brown(const std::vector<double>& s3, const std::vector<double>& s1, double& c,
                         double& m) {
  auto model = [](double x, double cc, double mm) { return x + cc * std::sqrt(mm * x / cc + 1.0); };
  const std::size_t n = s3.size();
  double lambda = 1e-3;
  auto cost = [&](double cc, double mm) {
    double e = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double d = s1[k] - model(s3[k], cc, mm);
      e += d * d;
    }
    return e;
  };
  double err = cost(c, m);
  for (int it = 0; it < 200 && c > 0 && m > 0; ++it) {
    double jtj[3] = {0, 0, 0}, jtr[2] = {0, 0};
    for (std::size_t k = 0; k < n; ++k) {
      const double root = std::sqrt(m * s3[k] / c + 1.0);
      const double dc = root - m * s3[k] / (2.0 * c * root);
      const double dm = s3[k] / (2.0 * root);
      const double res = s1[k] - model(s3[k], c, m);
      jtj[0] += dc * dc;
      jtj[1] += dc * dm;
      jtj[2] += dm * dm;
      jtr[0] += dc * res;
      jtr[1] += dm * res;
    }
    const double a = jtj[0] * (1 + lambda), b = jtj[1], d = jtj[2] * (1 + lambda);
    const double det = a * d - b * b;
    if (!(std::abs(det) > 0.0)) break;
    const double step_c = (d * jtr[0] - b * jtr[1]) / det;
    const double step_m = (a * jtr[1] - b * jtr[0]) / det;
    const double nc = c + step_c, nm = m + step_m;
    if (nc > 0.0 && nm > 0.0 && cost(nc, nm) < err) {
      c = nc;
      m = nm;
      const double ne = cost(c, m);
      const bool done = err - ne < 1e-14 * (1.0 + err);
      err = ne;
      lambda *= 0.3;
      if (done) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e12) break;
    }
  }
  return err;
}

}  // namespace

HoekBrownFit fit_hoek_brown(const std::vector<double>& sigma3, const std::vector<double>& sigma1) {
  HoekBrownFit f;
  const std::size_t n = std::min(sigma3.size(), sigma1.size());
  if (n < 2) {
    f.flag = "fewer_than_two_tests";
    return f;
  }
  std::vector<double> x(n), y(n);
  for (std::size_t k = 0; k < n; ++k) {
    x[k] = sigma3[k];
    y[k] = (sigma1[k] - sigma3[k]) * (sigma1[k] - sigma3[k]);
  }
  const LinearFit l = fit_line(x, y);
  double sc = 0.0, mi = 10.0;
  if (l.valid && l.intercept > 0.0) {
    f.sigma_ci_linear = std::sqrt(l.intercept);
    f.m_i_linear = l.slope / f.sigma_ci_linear;
    sc = f.sigma_ci_linear;
    mi = f.m_i_linear > 0.0 ? f.m_i_linear : 10.0;
  } else {
    f.flag = "linear_step_skipped";
    std::size_t kmin = 0;
    for (std::size_t k = 1; k < n; ++k)
      if (sigma3[k] < sigma3[kmin]) kmin = k;
    sc = sigma1[kmin] - sigma3[kmin];
  }
  // Levenberg-Marquardt on the sigma_1 residuals, in MPa for conditioning.
  std::vector<double> s3(n), s1(n);
  for (std::size_t k = 0; k < n; ++k) {
    s3[k] = sigma3[k] * 1e-6;
    s1[k] = sigma1[k] * 1e-6;
  }
  double c = sc * 1e-6, m = mi;
  const double err = refine_hoek_brown(s3, s1, c, m);
  f.sigma_ci = c * 1e6;
  f.m_i = m;
  f.rms = std::sqrt(err / static_cast<double>(n)) * 1e6;
  f.valid = c > 0.0 && m > 0.0;
  if (!f.valid) f.flag = "nonpositive_parameters";
  return f;
}

double elastic_energy_density(double s1, double s3, double e, double nu) {
  return (s1 * s1 + 2 * s3 * s3 - 2 * nu * (2 * s1 * s3 + s3 * s3)) / (2 * e);
}

double deviatoric_elastic_energy_density(double q, double s3, double e, double nu) {
  return (q * q + 2 * s3 * q * (1 - 2 * nu)) / (2 * e);
}

}  // namespace breccia::analysis
