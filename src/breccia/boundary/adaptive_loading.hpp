#pragma once
// Adaptive quasi-static loading (docs/physics.md §6.1): the speed of a test's platens follows the
// sample's state between the test's own quasi-static speed v (the floor: the speed near the
// peak) and r v (the ceiling). Every quarter of a bar-wave transit through the sample the
// controller reads the state and takes the slowest of three speeds:
//  - cracking: the bonds broken per unit strain over the last two transits, phi; the speed at
//    which a transit would break the fraction b of the bonds intact when loading began,
//    b V_bar / (2 phi) (a transit's strain is 2 v / V_bar). Damage that cascades needs transits
//    to settle; a sample that breaks few bonds a transit is loaded quasi-statically however fast.
//  - kinetic energy: E'_kin scales as the square of the platens' speed, so the current speed
//    times sqrt(k / (E'_kin / (E_c + E_b))) holds that ratio at the target k (the run's check
//    judges it against 1e-3).
//  - platen balance: the imbalance |F_top - F_bot| / F_mean scales with the speed, so the
//    current speed times 0.0125 / imbalance (the check's limit is 0.05).
// The factor then moves toward that speed by at most 2^(1/8) up or 2^(1/4) down a check (a
// doubling in two transits, a halving in one), through a cosine over the check's interval so that
// the platens never jump. Everything it reads is the state of the run (the crack count, the
// grains, the walls' forces), so a run stays bitwise at any thread or rank count and across a
// resume (the controller is part of the checkpoint).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace breccia {

struct AdaptiveLoadingSettings {
  double speed_ratio = 1.0;       // the ceiling over the floor speed; 1 = constant speed
  double crack_rate = 2e-4;       // b: bonds broken a transit, over those intact at the start
  double kinetic_ratio = 2.5e-4;  // k: target E'_kin / (E_c + E_b)
  bool on() const noexcept { return speed_ratio > 1.0; }
};

// What the controller reads at a check.
struct LoadingReading {
  double strain = 0.0;         // the test's strain measure (platen approach over the length)
  double cracks = 0.0;         // bonds broken since loading began
  double kinetic_ratio = 0.0;  // E'_kin / (E_c + E_b); 0 when nothing is stored yet
  double imbalance = 0.0;      // |F_top - F_bot| / F_mean; 0 when unloaded
};

class AdaptiveLoading {
 public:
  static constexpr int kWindow = 8;                   // checks over which phi is read (2 transits)
  static constexpr double kTargetImbalance = 0.0125;  // a quarter of the check's 0.05
  static constexpr double kChecksPerTransit = 4.0;
  static constexpr double kUpPerCheck = 1.0905077326652577;    // 2^(1/8)
  static constexpr double kDownPerCheck = 1.1892071150027210;  // 2^(1/4)

  AdaptiveLoading() = default;
  // Set when axial loading starts: the floor speed (m/s, each platen), the bar-wave speed and the
  // sample's length along the load (a transit is length / bar_wave_speed), the time step, the
  // bonds intact then, and the time from which it acts (the end of the start-up ramp).
  AdaptiveLoading(const AdaptiveLoadingSettings& s, double floor_speed, double bar_wave_speed,
                  double length, double time_step, double intact_bonds, double start_time)
      : settings_(s),
        floor_speed_(floor_speed),
        bar_wave_speed_(bar_wave_speed),
        intact_bonds_(std::max(intact_bonds, 1.0)),
        start_time_(start_time) {
    const double transit_steps = length / (bar_wave_speed * time_step);
    check_steps_ =
        static_cast<std::uint64_t>(std::max(5.0, std::round(transit_steps / kChecksPerTransit)));
    window_strain_.fill(std::numeric_limits<double>::quiet_NaN());
    window_cracks_.fill(0.0);
  }

  bool on() const noexcept { return settings_.on(); }
  std::uint64_t check_steps() const noexcept { return check_steps_; }
  // True when the step about to be taken at `time`, number `step`, is a check.
  bool due(std::uint64_t step, double time) const noexcept {
    return on() && time >= start_time_ && step % check_steps_ == 0;
  }
  // True when the step after this one is a check (the run samples the stored energy for it).
  bool due_next(std::uint64_t step, double time) const noexcept {
    return on() && time >= start_time_ && (step + 1) % check_steps_ == 0;
  }

  // The speed factor (over the floor) to move to from the reading `r` at a check.
  double update(const LoadingReading& r) noexcept {
    const double factor_now = factor_;
    const int slot = checks_ % kWindow;
    const double strain_then = window_strain_[static_cast<std::size_t>(slot)];
    const double cracks_then = window_cracks_[static_cast<std::size_t>(slot)];
    window_strain_[static_cast<std::size_t>(slot)] = r.strain;
    window_cracks_[static_cast<std::size_t>(slot)] = r.cracks;
    ++checks_;
    double target = settings_.speed_ratio;
    const double d_strain = r.strain - strain_then;
    if (std::isfinite(strain_then) && d_strain > 0.0 && r.cracks > cracks_then) {
      const double phi = (r.cracks - cracks_then) / (intact_bonds_ * d_strain);
      target =
          std::min(target, settings_.crack_rate * bar_wave_speed_ / (2.0 * phi * floor_speed_));
    } else if (!std::isfinite(strain_then) && r.cracks > 0.0) {
      target = std::min(target, factor_now);  // cracking, rate not yet known: hold
    }
    if (r.kinetic_ratio > 0.0)
      target = std::min(target, factor_now * std::sqrt(settings_.kinetic_ratio / r.kinetic_ratio));
    if (r.imbalance > 0.0) target = std::min(target, factor_now * kTargetImbalance / r.imbalance);
    target = std::clamp(target, factor_now / kDownPerCheck, factor_now * kUpPerCheck);
    factor_ = std::clamp(target, 1.0, settings_.speed_ratio);
    max_factor_ = std::max(max_factor_, factor_);
    return factor_;
  }

  double factor() const noexcept { return factor_; }
  double max_factor() const noexcept { return max_factor_; }
  double floor_speed() const noexcept { return floor_speed_; }
  const AdaptiveLoadingSettings& settings() const noexcept { return settings_; }

 private:
  AdaptiveLoadingSettings settings_{};
  double floor_speed_ = 0.0, bar_wave_speed_ = 0.0, intact_bonds_ = 1.0, start_time_ = 0.0;
  std::uint64_t check_steps_ = 1, checks_ = 0;
  double factor_ = 1.0, max_factor_ = 1.0;
  std::array<double, kWindow> window_strain_{}, window_cracks_{};
};

}  // namespace breccia
