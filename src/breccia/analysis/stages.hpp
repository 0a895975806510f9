#pragma once
// Deformation stages from the stress-strain curve (docs/analysis.md §8): I initiation
// (quasi-linear), II nucleation (to the peak), III rupture (post-peak drop), IV frictional sliding
// (residual).
#include <cstddef>
#include <string>
#include <vector>

#include "breccia/analysis/gutenberg_richter.hpp"

namespace breccia::analysis {

struct StageSettings {
  std::size_t smoothing = 5;   // centred moving average (samples) for boundary detection
  double tolerance = 0.02;     // deviation from the reference line, fraction of the peak
  double drop_fraction = 0.1;  // f_r: end of the drop at residual + f_r (peak - residual)
};

struct Stages {
  double linear_limit = kNaN;    // strain where stage II starts
  double peak = kNaN;            // stage III starts
  double residual_start = kNaN;  // stage IV starts
  double end = kNaN;
  double reference_modulus = kNaN;  // slope of the reference line
  std::vector<std::string> flags;   // no_peak, no_residual, ductile, reference_window_widened,
                                    // no_reference_line
  // Stage (1-4) of an axial strain; 0 where undefined.
  int stage_of(double strain) const noexcept;
};

// `residual` is the residual strength of §1.7 (NaN when there is no plateau); `peak_reached` as
// in the compression analysis.
Stages find_stages(const std::vector<double>& strain, const std::vector<double>& q, double residual,
                   bool peak_reached, const StageSettings& s = {});

inline const char* stage_name(int stage) {
  switch (stage) {
    case 1:
      return "I initiation";
    case 2:
      return "II nucleation";
    case 3:
      return "III rupture";
    case 4:
      return "IV frictional sliding";
    default:
      return "undefined";
  }
}

}  // namespace breccia::analysis
