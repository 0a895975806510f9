#include "breccia/analysis/moment_tensor.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace breccia::analysis {

SourceType source_type(const Tensor3& m, bool planar) {
  SourceType s;
  const int d = planar ? 2 : 3;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  double norm2 = 0.0, anti2 = 0.0;
  for (int i = 0; i < d; ++i)
    for (int j = 0; j < d; ++j) {
      const double mij = m[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
      const double mji = m[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)];
      a(i, j) = 0.5 * (mij + mji);
      norm2 += mij * mij;
      anti2 += 0.25 * (mij - mji) * (mij - mji);
    }
  if (!(norm2 > 0.0) || !std::isfinite(norm2)) return s;
  s.zero = false;
  s.antisymmetry = std::sqrt(anti2 / norm2);
  std::array<double, 3> ev{0.0, 0.0, 0.0};
  if (planar) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(a.topLeftCorner<2, 2>());
    ev = {es.eigenvalues()(1), es.eigenvalues()(0), 0.0};
  } else {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(a);
    ev = {es.eigenvalues()(2), es.eigenvalues()(1), es.eigenvalues()(0)};  // descending
  }
  s.eigenvalues = ev;
  double sum2 = 0.0, tr = 0.0;
  for (int k = 0; k < d; ++k) {
    sum2 += ev[static_cast<std::size_t>(k)] * ev[static_cast<std::size_t>(k)];
    tr += ev[static_cast<std::size_t>(k)];
  }
  s.scalar_moment = std::sqrt(0.5 * sum2);
  s.isotropic = tr / d;
  double dev_abs = 0.0;
  for (int k = 0; k < d; ++k) dev_abs += std::abs(ev[static_cast<std::size_t>(k)] - s.isotropic);
  s.r_ratio = 100.0 * tr / (std::abs(tr) + dev_abs);
  if (planar) {
    s.eigenvalues[2] = kNaN;
    return s;
  }
  // Deviatoric eigenvalues ordered by absolute value: m1 smallest, m3 largest.
  std::array<double, 3> dev{ev[0] - s.isotropic, ev[1] - s.isotropic, ev[2] - s.isotropic};
  std::sort(dev.begin(), dev.end(), [](double x, double y) { return std::abs(x) < std::abs(y); });
  s.k = s.isotropic / (std::abs(s.isotropic) + std::abs(dev[2]));
  s.T = dev[2] != 0.0 ? 2.0 * dev[0] / std::abs(dev[2]) : 0.0;
  s.tau = s.T * (1.0 - std::abs(s.k));
  const double lmax = std::max({std::abs(ev[0]), std::abs(ev[1]), std::abs(ev[2])});
  s.u = -2.0 / 3.0 * (ev[0] + ev[2] - 2.0 * ev[1]) / lmax;
  s.v = (ev[0] + ev[1] + ev[2]) / (3.0 * lmax);
  s.iso_percent = 100.0 * s.k;
  s.clvd_percent = 100.0 * s.tau;
  s.dc_percent = 100.0 * (1.0 - std::abs(s.k) - std::abs(s.tau));
  return s;
}

void hudson_piecewise(double k, double tau, double& u, double& v) {
  if (tau > 0.0 && k > 0.0) {
    if (tau < 4.0 * k) {
      u = tau / (1.0 - tau / 2.0);
      v = k / (1.0 - tau / 2.0);
    } else {
      u = tau / (1.0 - 2.0 * k);
      v = k / (1.0 - 2.0 * k);
    }
  } else if (tau < 0.0 && k < 0.0) {
    if (tau > 4.0 * k) {
      u = tau / (1.0 + tau / 2.0);
      v = k / (1.0 + tau / 2.0);
    } else {
      u = tau / (1.0 + 2.0 * k);
      v = k / (1.0 + 2.0 * k);
    }
  } else {
    u = tau;
    v = k;
  }
}

}  // namespace breccia::analysis
