#pragma once
// Where the microcracks of a test lie: their share in each quarter of the sample along the loading
// axis (a compression test that fails through its body, by a shear band or axial splitting, has
// no end quarter dominating; one that crushes an end has), and, for a Brazilian disc, how close
// they lie to the loaded diameter (a central split keeps them within a narrow band). Pure
// functions over crack positions.
#include <array>
#include <cstddef>
#include <vector>

namespace breccia::analysis {

// Share of the cracks in each quarter of [lo, hi] along the axis (positions outside go to the
// nearest end quarter). All zero without cracks.
std::array<double, 4> quarter_shares(const std::vector<double>& axial_positions, double lo,
                                     double hi);

struct SplitPattern {
  std::size_t cracks = 0, early = 0;  // all, and the first `early_fraction` of them by time
  double early_tensile_share = 0.0;   // of the early cracks
  // Share within |offset| <= band x R of the loaded diameter (R the disc radius).
  double early_in_band = 0.0, all_in_band = 0.0;
  double early_mean_offset = 0.0;  // mean |offset| / R of the early cracks
  double band = 0.0;
};

// `offsets`: signed distance of each crack from the loaded diameter, in crack order (time);
// `tensile`: its mode. A uniform scatter over the disc puts (2 / pi) (b sqrt(1 - b^2) + asin b)
// of them in a band of half-width b R (31 % for b = 0.25); a central split puts most there.
SplitPattern split_pattern(const std::vector<double>& offsets, const std::vector<bool>& tensile,
                           double disc_radius, double early_fraction = 0.2, double band = 0.25);

}  // namespace breccia::analysis
