#pragma once
// Microcrack indicator series over axial strain (docs/analysis.md §3.2): strain bins of width
// Delta eps_b with counts by mode and summed energy, and trailing windows of W bins giving the
// shear fraction, the microcrack variance MCvar and the AE-energy variance AEvar (sample
// variances of the per-bin counts and energies). A window with fewer than W complete bins, or
// (shear fraction) fewer than min_cracks cracks, gives NaN, never a number from noise.
#include <cstddef>
#include <vector>

#include "breccia/analysis/gutenberg_richter.hpp"

namespace breccia::analysis {

struct CrackSeriesSettings {
  double bin_width = 5e-5;       // axial strain
  std::size_t window_bins = 10;  // W
  std::size_t min_cracks_sf = 10;
};

struct CrackSeries {
  std::vector<double> bin_end;                        // axial strain at the end of each bin
  std::vector<double> count, tensile, shear, energy;  // per bin
  std::vector<double> cumulative, cumulative_tensile, cumulative_shear;
  std::vector<double> shear_fraction, mc_var, ae_var;  // trailing window ending at the bin
};

// `strain`, `shear` (true for shear cracks) and `energy` per crack; bins from `start` to `end`.
CrackSeries crack_series(const std::vector<double>& strain, const std::vector<char>& shear,
                         const std::vector<double>& energy, double start, double end,
                         const CrackSeriesSettings& s = {});

// Sample variance (n - 1 denominator); NaN for fewer than 2 values.
double sample_variance(const double* v, std::size_t n);

}  // namespace breccia::analysis
