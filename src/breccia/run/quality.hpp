#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "breccia/analysis/compression.hpp"
#include "breccia/material/library.hpp"

namespace breccia {

// The quality monitors of a compression test over its pre-peak rows once the load exceeds 10 %
// of the peak (the ramp-up start is excluded), judged against docs/physics.md §6.1's limits.
struct QualityVerdict {
  double imbalance_pre = 0.0, ke_ratio_pre = 0.0, confine_err_pre = 0.0, confine_err_all = 0.0;
  // The same over the rows before the loading's first crack: there kinetic energy comes from
  // the loading alone; after, breaking bonds release it too (dynamic crack release that a lower
  // platen speed does not remove). `intact_rows` of them; none when bonds broke before the load
  // reached 10 % of the peak, and then the two sources cannot be told apart.
  double ke_ratio_intact = 0.0, imbalance_intact = 0.0;
  std::size_t intact_rows = 0;
  bool quasi_static() const { return imbalance_pre <= 0.05 && ke_ratio_pre <= 1e-3; }
  bool quasi_static_until_cracking() const {
    return intact_rows > 0 && imbalance_intact <= 0.05 && ke_ratio_intact <= 1e-3;
  }
};

// One row of the monitors per row of `series` (imbalance, ke_ratio; confine_err may be shorter).
QualityVerdict judge_quality(const analysis::CompressionSeries& series,
                             const std::vector<double>& imbalance,
                             const std::vector<double>& ke_ratio,
                             const std::vector<double>& confine_err,
                             const analysis::CompressionResult& an);

// The warnings a stress-strain test's summary carries, with what to change.
std::vector<std::string> quality_warnings(const QualityVerdict& q, double confining_stress);

// The warning for a run of `preset` at platen speed `speed` and density scaling `scaling` whose
// verification tests ran at `preset_speed` and `preset_scaling`; none when it loads no faster
// than kPresetLoadingTolerance times those by v sqrt(s) (or has no platens).
std::optional<std::string> preset_loading_warning(const std::string& preset, double preset_speed,
                                                  double preset_scaling, double speed,
                                                  double scaling);

}  // namespace breccia
