#pragma once
// Source parameters of a moment tensor (docs/analysis.md §4.2-§4.3): scalar moment (Silver & Jordan
// 1982), the isotropic/deviatoric split, the Hudson et al. (1989) source-type parameters k, T,
// tau and plot coordinates (u, v), the DC/CLVD/ISO percentages, and the Feignier & Young (1992)
// R ratio. Eigenvalues come from Eigen's symmetric solver on the symmetrised tensor.
#include <array>

#include "breccia/analysis/gutenberg_richter.hpp"

namespace breccia::analysis {

using Tensor3 = std::array<std::array<double, 3>, 3>;

struct SourceType {
  std::array<double, 3> eigenvalues{kNaN, kNaN, kNaN};  // descending
  double scalar_moment = kNaN;                          // N m
  double antisymmetry = kNaN;  // |antisymmetric part| / |M|: large = not in equilibrium
  double isotropic = kNaN;     // M_iso = tr(M) / 3
  double k = kNaN, T = kNaN, tau = kNaN;
  double u = kNaN, v = kNaN;  // Hudson plot coordinates (closed form)
  double iso_percent = kNaN, clvd_percent = kNaN, dc_percent = kNaN;
  double r_ratio = kNaN;  // 100 tr / (|tr| + sum |m'|): > 30 tensile, < -30 implosive
  bool zero = true;       // M = 0: every parameter NaN (flag zero_moment)
};

// Source type of a 3D moment tensor (N m), symmetrised first. In 2D pass the 2x2 tensor in the
// upper-left block and `planar` = true: the Hudson parameters are undefined there (NaN) and the
// R ratio uses the two in-plane eigenvalues.
SourceType source_type(const Tensor3& m, bool planar = false);

// Hudson coordinates by the piecewise definition from (k, tau): for testing the closed form.
void hudson_piecewise(double k, double tau, double& u, double& v);

}  // namespace breccia::analysis
