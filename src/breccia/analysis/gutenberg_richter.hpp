#pragma once
// Frequency-magnitude statistics of acoustic-emission catalogues (docs/analysis.md §5): the b-value
// by maximum likelihood (Aki 1965, Utsu's binning correction) with the Shi & Bolt (1982) error, the
// magnitude of completeness by maximum curvature (+0.2, Woessner & Wiemer 2005), and the
// magnitude relations of §4.2-§4.4 (moment magnitude, Kanamori's energy relation in joules).
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace breccia::analysis {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct BValue {
  double b = kNaN, sigma = kNaN, a = kNaN;
  double completeness = kNaN;  // M_c used
  std::size_t events = 0;      // events with M >= M_c
  std::string flag;            // why b is NaN ("too_few_events", "no_spread")
  bool valid() const noexcept { return flag.empty(); }
};

// b-value of the magnitudes at or above `completeness`; NaN with a flag when fewer than
// `min_events` remain. `bin_width` is the magnitude rounding (0 for continuous magnitudes).
BValue b_value(const std::vector<double>& magnitudes, double completeness, double bin_width = 0.0,
               std::size_t min_events = 50);

struct Completeness {
  double magnitude = kNaN;
  std::string flag;
};
// Maximum curvature: centre of the most populated bin of width `bin` (centres at multiples of
// `bin`) plus `correction`. NaN with a flag below `min_events` events.
Completeness completeness_max_curvature(const std::vector<double>& magnitudes, double bin = 0.1,
                                        double correction = 0.2, std::size_t min_events = 50);

// Moment magnitude from the scalar moment (N m), with the DEM convention constant -6.0 (§4.2).
// NaN for a zero or negative moment.
double moment_magnitude(double scalar_moment, double constant = -6.0);
// Kanamori's Gutenberg-Richter energy relation in joules: log10 E = 4.8 + 1.5 M.
double radiated_energy(double magnitude);
// Magnitude-like value of an energy (J): M = 2/3 log10 E - 3.2 (§4.4, §5.3). NaN for E <= 0.
double energy_magnitude(double energy);

// b-values in causal event-count windows (§5.4): `window` events above M_c, advanced by `step`;
// each value is stamped with the strain of the window's last event.
struct BValueWindow {
  double strain = 0.0;  // of the last event in the window
  BValue value;
};
std::vector<BValueWindow> b_value_windows(const std::vector<double>& magnitudes,
                                          const std::vector<double>& strain, double completeness,
                                          std::size_t window = 100, std::size_t step = 10,
                                          std::size_t min_events = 50);

// Spearman's rank correlation of two equally long series: Pearson's coefficient of their ranks,
// tied values sharing the mean of their ranks. NaN for fewer than 2 pairs or a constant series.
double spearman_rho(const std::vector<double>& x, const std::vector<double>& y);

// How the b-value moves toward failure (§5.4): the valid windows stamped at or before the peak
// strain, the first and the last of them, and Spearman's rho of b against strain over them
// (-1: b falls at every window). rho is NaN with a flag below `min_windows` windows; everything is
// NaN without a peak.
struct BValueTrend {
  std::size_t windows = 0;  // valid windows at or before the peak
  double first_strain = kNaN, first_b = kNaN, last_strain = kNaN, last_b = kNaN;
  double spearman_rho = kNaN;
  std::string flag;  // "", "no_peak", "no_window_before_peak", "too_few_windows"
};
BValueTrend b_value_trend(const std::vector<BValueWindow>& windows, double peak_strain,
                          bool peak_reached, std::size_t min_windows = 5);

}  // namespace breccia::analysis
