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

}  // namespace breccia::analysis
