// The affine (Voigt, uniform-strain) elasticity of a random isotropic packing of grains joined by
// springs of normal stiffness kn and shear stiffness ks = kn / kappa (Walton 1987; Liao et al.
// 1997; in 2D Bathurst & Rothenburg 1988). Averaging kn n n n n + ks (projector) n n over
// isotropic contact normals gives
//   3D: nu = (kappa - 1) / (4 kappa + 1),  E proportional to kn (2 + 3 / kappa) / (4 + 1 / kappa);
//   2D: nu = (kappa - 1) / (3 kappa + 1),  E proportional to kn (1 + 1 / kappa) / (3 + 1 / kappa).
// Real packings depart from it (non-affine motion; and the gauges of a UCS test, clear of the
// platens' restraint, read more: 0.17 at kappa 2.5 where the estimate gives 0.14, 0.28 at kappa
// 10 where it gives 0.22), so the calibration uses its slope with the measured offset, not its
// values. Its limit is nu -> 1/4 in 3D, 1/3 in 2D as kappa -> infinity.
#pragma once

#include <limits>

namespace breccia {

struct AffineElasticity {
  int dimension = 3;

  double poisson(double kappa) const { return (kappa - 1.0) / (slope() * kappa + 1.0); }
  double poisson_limit() const { return 1.0 / slope(); }
  // The kappa whose affine Poisson's ratio is nu; infinite at or above the limit.
  double stiffness_ratio(double nu) const {
    if (nu >= poisson_limit()) return std::numeric_limits<double>::infinity();
    return (1.0 + nu) / (1.0 - slope() * nu);
  }
  // E / kn up to the packing's constant factor (coordination, radius, volume).
  double modulus_factor(double kappa) const {
    return dimension == 2 ? (1.0 + 1.0 / kappa) / (3.0 + 1.0 / kappa)
                          : (2.0 + 3.0 / kappa) / (4.0 + 1.0 / kappa);
  }

 private:
  double slope() const { return dimension == 2 ? 3.0 : 4.0; }
};

}  // namespace breccia
