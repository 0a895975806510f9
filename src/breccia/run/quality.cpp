#include "breccia/run/quality.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace breccia {

QualityVerdict judge_quality(const analysis::CompressionSeries& series,
                             const std::vector<double>& imbalance,
                             const std::vector<double>& ke_ratio,
                             const std::vector<double>& confine_err,
                             const analysis::CompressionResult& an) {
  QualityVerdict q;
  // Bonds broken before the loading (while the confinement was applied) are not its cracks.
  const double cracks_before = series.broken_bonds.empty() ? 0.0 : series.broken_bonds.front();
  for (std::size_t k = 0; k < series.deviatoric.size(); ++k) {
    if (k < confine_err.size()) q.confine_err_all = std::max(q.confine_err_all, confine_err[k]);
    const bool pre = series.axial_strain[k] <= an.strain_at_peak &&
                     series.deviatoric[k] >= 0.1 * an.peak_deviatoric;
    if (!pre) continue;
    q.imbalance_pre = std::max(q.imbalance_pre, imbalance[k]);
    q.ke_ratio_pre = std::max(q.ke_ratio_pre, ke_ratio[k]);
    if (series.broken_bonds[k] <= cracks_before) {
      q.ke_ratio_intact = std::max(q.ke_ratio_intact, ke_ratio[k]);
      q.imbalance_intact = std::max(q.imbalance_intact, imbalance[k]);
      ++q.intact_rows;
    }
    if (k < confine_err.size()) q.confine_err_pre = std::max(q.confine_err_pre, confine_err[k]);
  }
  return q;
}

namespace {

std::string before_first_crack(const QualityVerdict& q, double value) {
  return q.intact_rows > 0 ? fmt::format("{:.3g} before the first crack", value)
                           : std::string("no row before the first crack");
}

// What the excess comes from, as far as the rows tell, and what to change.
std::string quasi_static_advice(const QualityVerdict& q) {
  if (q.quasi_static_until_cracking())
    return "the loading was quasi-static until bonds broke: the excess comes from bursts of "
           "breaking bonds near the peak, which a lower platen speed does not remove";
  const std::string lower =
      "lower test.platen_speed or engine.density_scaling (their strain per wave transit sets "
      "how quasi-static a test is, docs/physics.md), or the peak carries inertia";
  if (q.intact_rows == 0)
    return "bonds broke before the load reached 10 % of the peak, so the rows cannot tell the "
           "loading's share from the cracks'; " +
           lower;
  return lower;
}

}  // namespace

std::vector<std::string> quality_warnings(const QualityVerdict& q, double confining_stress) {
  std::vector<std::string> w;
  if (!q.quasi_static())
    w.push_back(fmt::format(
        "the test was not quasi-static before the peak: platen force imbalance {:.3g} (limit "
        "0.05; {}), kinetic/strain energy {:.3g} (limit 1e-3; {}); {}",
        q.imbalance_pre, before_first_crack(q, q.imbalance_intact), q.ke_ratio_pre,
        before_first_crack(q, q.ke_ratio_intact), quasi_static_advice(q)));
  if (confining_stress > 0.0 && q.confine_err_pre > 0.02)
    w.push_back(fmt::format(
        "the confining stress left its 2 % band before the peak (largest error {:.3g} %)",
        100 * q.confine_err_pre));
  return w;
}

std::optional<std::string> preset_loading_warning(const std::string& preset, double preset_speed,
                                                  double preset_scaling, double speed,
                                                  double scaling) {
  if (!(speed > 0.0 && preset_speed > 0.0 && preset_scaling > 0.0 && scaling > 0.0))
    return std::nullopt;
  const double run = speed * std::sqrt(scaling);
  const double calibrated = preset_speed * std::sqrt(preset_scaling);
  if (run <= kPresetLoadingTolerance * calibrated) return std::nullopt;
  return fmt::format(
      "the platens load {:.3g} times less quasi-statically than {}'s verification tests "
      "(speed x sqrt(density scaling): {:.3g} m/s at {:g} m/s and {:g}, against {:.3g} m/s at "
      "{:g} m/s and {:g}): the peak and the modulus carry inertia the preset's values do not; "
      "lower test.platen_speed or engine.density_scaling to the preset's (docs/physics.md §6.1)",
      run / calibrated, preset, run, speed, scaling, calibrated, preset_speed, preset_scaling);
}

}  // namespace breccia
