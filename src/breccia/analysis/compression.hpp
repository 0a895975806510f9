#pragma once
// Macroscopic results of a compression test (docs/analysis.md §1.2-§1.7) and strength envelopes
// from a set of tests (§1.9). Pure functions over recorded series; stresses compression-positive.
#include <cstddef>
#include <string>
#include <vector>

#include "breccia/analysis/stress_strain.hpp"

namespace breccia::analysis {

struct CompressionSeries {
  std::vector<double> axial_strain, deviatoric, lateral_strain, volumetric_strain;
  // Strain gauges on the sample (AxialState): empty, or one value per row. When every row has
  // finite values, E and nu come from them, as the ISRM method for deformability measures strain
  // away from the platens; the platen approach `axial_strain` stays the test's strain (peak
  // strain, curves).
  std::vector<double> gauge_axial_strain, gauge_lateral_strain;
  std::vector<double> broken_bonds;  // cumulative
  double confining_stress = 0.0;     // sigma_3 set-point, Pa
};

struct CompressionResult {
  bool peak_reached = false;  // false when the maximum is the last sample
  double peak_deviatoric = 0.0, sigma1_at_peak = 0.0, strain_at_peak = 0.0;
  LinearFit e_t50;                        // over [0.4, 0.6] q_peak, widened to >= 5 samples (§1.3)
  double e_t50_lo = 0.4, e_t50_hi = 0.6;  // the window actually used
  LinearFit e_av;                         // over [0.25, 0.75] q_peak
  double e_s50 = 0.0;                     // secant at 50 % of the peak (NaN if not crossed)
  double poisson = 0.0;                   // -slope of lateral vs axial strain over the E_t50 window
  bool moduli_from_gauges = false;        // E and nu from the sample gauges, not the platens
  LinearFit e_t50_platen;                 // E_t50 against the platen approach (same window)
  double crack_initiation = 0.0;          // q at 5 % of the cracks at peak (NaN without cracks)
  double crack_damage = 0.0;              // q at the maximum volumetric strain before the peak
  bool no_reversal = false;
  double residual = 0.0;     // median q over the last 10 % of the strain record (NaN: no plateau)
  double brittleness = 0.0;  // (q_peak - residual) / q_peak
  std::vector<std::string> flags;
};

// True when every row has finite gauge readings: the moduli are then read with the gauges.
bool has_gauges(const CompressionSeries& s);

CompressionResult analyse_compression(const CompressionSeries& s);

struct MohrCoulombFit {
  bool valid = false;
  double k = 0.0, friction_angle_deg = 0.0, cohesion = 0.0, ucs = 0.0, tensile = 0.0, r2 = 0.0;
  std::string flag;
};
// Least squares of sigma_1 on sigma_3 (principal-stress form, §1.9); Pa in, Pa out.
MohrCoulombFit fit_mohr_coulomb(const std::vector<double>& sigma3,
                                const std::vector<double>& sigma1);

struct HoekBrownFit {
  bool valid = false;
  double sigma_ci_linear = 0.0, m_i_linear = 0.0;  // step 1 (linearisation)
  double sigma_ci = 0.0, m_i = 0.0;                // step 2 (least squares on sigma_1)
  double rms = 0.0;                                // Pa
  std::string flag;
};
// Intact Hoek-Brown (s = 1, a = 0.5), §1.9: linearised fit, then Levenberg-Marquardt.
HoekBrownFit fit_hoek_brown(const std::vector<double>& sigma3, const std::vector<double>& sigma1);

// Continuum energy estimates of the source papers (docs/analysis.md §2.3), Pa in, J/m^3 out.
// Elastic strain-energy density of isotropic linear elasticity under a triaxial state
// (sigma_2 = sigma_3).
double elastic_energy_density(double sigma1, double sigma3, double youngs, double poisson);
// The part added by the deviatoric stage: u_e(sigma_1) - u_e(sigma_1 = sigma_3), q = sigma_1 -
// sigma_3.
double deviatoric_elastic_energy_density(double q, double sigma3, double youngs, double poisson);

}  // namespace breccia::analysis
