#include "breccia/analysis/crack_pattern.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace breccia::analysis {

std::array<double, 4> quarter_shares(const std::vector<double>& z, double lo, double hi) {
  std::array<double, 4> share{};
  if (z.empty() || !(hi > lo)) return share;
  for (double v : z) {
    const int q = std::clamp(static_cast<int>(std::floor(4.0 * (v - lo) / (hi - lo))), 0, 3);
    share[static_cast<std::size_t>(q)] += 1.0;
  }
  for (double& s : share) s /= static_cast<double>(z.size());
  return share;
}

SplitPattern split_pattern(const std::vector<double>& offsets, const std::vector<bool>& tensile,
                           double disc_radius, double early_fraction, double band) {
  SplitPattern p;
  p.band = band;
  p.cracks = offsets.size();
  if (offsets.empty() || !(disc_radius > 0.0)) return p;
  p.early = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::ceil(early_fraction * static_cast<double>(offsets.size()))));
  double in_band = 0.0, early_in = 0.0, early_tensile = 0.0, early_offset = 0.0;
  for (std::size_t k = 0; k < offsets.size(); ++k) {
    const double u = std::abs(offsets[k]) / disc_radius;
    const bool in = u <= band;
    in_band += in ? 1.0 : 0.0;
    if (k < p.early) {
      early_in += in ? 1.0 : 0.0;
      early_tensile += (k < tensile.size() && tensile[k]) ? 1.0 : 0.0;
      early_offset += u;
    }
  }
  const double e = static_cast<double>(p.early);
  p.all_in_band = in_band / static_cast<double>(offsets.size());
  p.early_in_band = early_in / e;
  p.early_tensile_share = early_tensile / e;
  p.early_mean_offset = early_offset / e;
  return p;
}

FailurePlane failure_plane(const std::vector<Vec3>& positions, int axis, bool planar,
                           std::size_t min_cracks) {
  FailurePlane f;
  f.cracks = positions.size();
  if (positions.size() < std::max<std::size_t>(min_cracks, 3)) return f;
  const int dim = planar ? 2 : 3;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Vec3& p : positions) mean += Eigen::Vector3d(p.x, p.y, p.z);
  mean /= static_cast<double>(positions.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vec3& p : positions) {
    const Eigen::Vector3d d = Eigen::Vector3d(p.x, p.y, p.z) - mean;
    cov += d * d.transpose();
  }
  // In 2D the cracks lie in the x-y plane: the spread is that of its 2 x 2 block.
  const Eigen::MatrixXd c = cov.topLeftCorner(dim, dim);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c);  // eigenvalues in increasing order
  if (eig.info() != Eigen::Success || !(eig.eigenvalues()[1] > 0.0)) return f;
  const Eigen::VectorXd n = eig.eigenvectors().col(0);
  f.normal = {n[0], n[1], dim == 3 ? n[2] : 0.0};
  f.planarity = 1.0 - eig.eigenvalues()[0] / eig.eigenvalues()[1];
  // The plane's angle to the plane normal to the load equals its normal's angle to the load.
  const double along = std::min(1.0, std::abs(n[axis]));
  f.angle_from_normal_plane_deg = std::acos(along) * 180.0 / std::numbers::pi;
  f.valid = true;
  return f;
}

}  // namespace breccia::analysis
