#include "breccia/analysis/crack_pattern.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace breccia::analysis
