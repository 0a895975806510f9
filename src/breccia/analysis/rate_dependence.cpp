#include "breccia/analysis/rate_dependence.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <unsupported/Eigen/NonLinearOptimization>

#include "breccia/analysis/stress_strain.hpp"

namespace breccia::analysis {

namespace {

// Residuals UCS_j - model(rate_j) and their Jacobian for Eigen's Levenberg-Marquardt (MINPACK's
// lmder): parameters (a, b) or (a, b, c) of UCS = [c +] a exp(b rate).
struct ExponentialResiduals {
  using Scalar = double;
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;
  const std::vector<double>& x;
  const std::vector<double>& y;
  bool offset;
  int inputs() const { return offset ? 3 : 2; }
  int values() const { return static_cast<int>(x.size()); }
  int operator()(const Eigen::VectorXd& p, Eigen::VectorXd& r) const {
    for (std::size_t j = 0; j < x.size(); ++j)
      r[static_cast<Eigen::Index>(j)] =
          y[j] - ((offset ? p[2] : 0.0) + p[0] * std::exp(p[1] * x[j]));
    return 0;
  }
  int df(const Eigen::VectorXd& p, Eigen::MatrixXd& J) const {
    for (std::size_t j = 0; j < x.size(); ++j) {
      const auto k = static_cast<Eigen::Index>(j);
      const double e = std::exp(p[1] * x[j]);
      J(k, 0) = -e;
      J(k, 1) = -p[0] * x[j] * e;
      if (offset) J(k, 2) = -1.0;
    }
    return 0;
  }
};

struct LmResult {
  Eigen::VectorXd p;
  Eigen::VectorXd se;
  double rms = 0.0;
  bool ok = false;
};

LmResult levenberg_marquardt(const std::vector<double>& x, const std::vector<double>& y,
                             bool offset, Eigen::VectorXd start) {
  ExponentialResiduals f{x, y, offset};
  Eigen::LevenbergMarquardt<ExponentialResiduals> lm(f);
  lm.parameters.xtol = 1e-12;
  lm.parameters.ftol = 1e-14;
  lm.parameters.maxfev = 2000;
  const auto status = lm.minimize(start);
  LmResult out;
  out.p = start;
  Eigen::VectorXd r(f.values());
  f(start, r);
  const auto n = static_cast<double>(x.size()), np = static_cast<double>(f.inputs());
  out.rms = std::sqrt(r.squaredNorm() / n);
  Eigen::MatrixXd J(f.values(), f.inputs());
  f.df(start, J);
  // Covariance s^2 (J^T J)^-1 with J's columns scaled to unit length first: in pascals the
  // columns differ by ~1e7 (d/da ~ 1, d/db ~ a x), and unscaled J^T J looks singular to the LU.
  const Eigen::VectorXd scale = J.colwise().norm().transpose();
  out.se = Eigen::VectorXd::Constant(f.inputs(), std::nan(""));
  if (n > np && (scale.array() > 0.0).all()) {
    const Eigen::MatrixXd Js = J * scale.cwiseInverse().asDiagonal();
    const double s2 = r.squaredNorm() / (n - np);
    Eigen::FullPivLU<Eigen::MatrixXd> lu(Js.transpose() * Js);
    if (lu.isInvertible())
      out.se = (s2 * lu.inverse()).diagonal().cwiseMax(0.0).cwiseSqrt().cwiseQuotient(scale);
  }
  out.ok = status != Eigen::LevenbergMarquardtSpace::ImproperInputParameters && start.allFinite();
  return out;
}

}  // namespace

ExponentialRateFit fit_rate_dependence(const std::vector<double>& rate,
                                       const std::vector<double>& ucs) {
  ExponentialRateFit f;
  std::vector<double> x, y, ln_y;
  for (std::size_t j = 0; j < std::min(rate.size(), ucs.size()); ++j)
    if (ucs[j] > 0.0 && std::isfinite(ucs[j]) && std::isfinite(rate[j])) {
      x.push_back(rate[j]);
      y.push_back(ucs[j]);
      ln_y.push_back(std::log(ucs[j]));
    }
  f.points = x.size();
  if (x.size() < 3) {
    f.flag = "too_few_rates";
    return f;
  }
  const LinearFit start = fit_line(x, ln_y, 3);
  if (!start.valid) {
    f.flag = "no_fit";
    return f;
  }
  f.a_log = std::exp(start.intercept);
  f.b_log = start.slope;
  const LmResult two = levenberg_marquardt(x, y, false, Eigen::Vector2d(f.a_log, f.b_log));
  if (!two.ok) {
    f.flag = "no_fit";
    return f;
  }
  f.valid = true;
  f.a = two.p[0];
  f.b = two.p[1];
  f.a_se = two.se[0];
  f.b_se = two.se[1];
  f.rms = two.rms;
  for (std::size_t j = 0; j < rate.size() && j < ucs.size(); ++j)
    f.dynamic_increase.push_back(ucs[j] / f.a);
  if (x.size() >= 4) {
    // From the plateau c = 0.9 min UCS: the rest, a3 exp(b3 rate), starts as the two-parameter
    // fit of what is above it.
    const double c = 0.9 * *std::min_element(y.begin(), y.end());
    std::vector<double> ln_rest;
    for (double v : y) ln_rest.push_back(std::log(v - c));
    const LinearFit s3 = fit_line(x, ln_rest, 3);
    if (s3.valid) {
      const LmResult three =
          levenberg_marquardt(x, y, true, Eigen::Vector3d(std::exp(s3.intercept), s3.slope, c));
      f.three_valid = three.ok;
      f.a3 = three.p[0];
      f.b3 = three.p[1];
      f.c3 = three.p[2];
      f.rms3 = three.rms;
    }
  }
  return f;
}

}  // namespace breccia::analysis
