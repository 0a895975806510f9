#pragma once
// Adaptive loading (boundary/adaptive_loading.hpp) as the platen-driven tests use it: their three
// experiment-file keys, and the step that moves both platens to the controller's new speed.
#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>

#include "breccia/boundary/adaptive_loading.hpp"
#include "breccia/boundary/wall.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

// The keys of a test's adaptive loading, for its Params table (P has the three members).
template <class P>
constexpr std::array<ParamField<P>, 3> adaptive_loading_fields() {
  return {{
      {"adaptive_speed_ratio", "-", &P::adaptive_speed_ratio, 1, 1000, true, true,
       "adaptive loading (docs/physics.md §6.1): the platens' speed follows the sample's state "
       "between platen_speed (the floor, near the peak) and this many times it, slowing as bonds "
       "break, the kinetic energy rises or the platens' forces part; 1 = constant speed (so "
       "does two-speed loading, elastic_speed > 0, where the test has it)"},
      {"adaptive_crack_rate", "-", &P::adaptive_crack_rate, 0, 1, false, true,
       "adaptive loading: the bonds a bar-wave transit may break at above the floor speed, as a "
       "fraction of those intact when loading began"},
      {"adaptive_kinetic_ratio", "-", &P::adaptive_kinetic_ratio, 0, 1e-3, false, true,
       "adaptive loading: the kinetic over strain energy it holds the loading to above the floor "
       "speed (the quasi-static check's limit is 1e-3)"},
  }};
}

// At a check: the controller's new speed factor from `r`, which two platens moving toward each
// other along `axis` (bottom up, top down) reach through a cosine over the check's interval.
// Returns the factors before and after.
inline std::array<double, 2> steer_platens(AdaptiveLoading& a, const LoadingReading& r,
                                           Wall& bottom, Wall& top, int axis, double time,
                                           double time_step) {
  const double before = a.factor();
  const double after = a.update(r);
  if (after == before) return {before, after};
  Vec3 up{};
  up[axis] = 1.0;
  const double duration = static_cast<double>(a.check_steps()) * time_step;
  for (auto [w, sign] : {std::pair<Wall*, double>{&bottom, 1.0}, {&top, -1.0}}) {
    w->target_velocity = up * (sign * a.floor_speed() * after);
    w->ramp = {time, duration, before / after};
    w->update_motion(time);
  }
  return {before, after};
}

// The step's speed factor over the floor (as Simulation::step sets it, at mid-step), at least 1:
// what a step adds to the paced steps (Protocol::paced_steps).
inline double paced_step(const Wall& platen, int axis, double floor_speed, double time,
                         double time_step) {
  const double v =
      std::abs(platen.target_velocity[axis]) * platen.ramp.factor(time + 0.5 * time_step);
  return std::max(1.0, v / floor_speed);
}

// summary.json's record of the rule a run loaded by, and the fastest it went.
inline nlohmann::json adaptive_loading_summary(const AdaptiveLoading& a) {
  const AdaptiveLoadingSettings& s = a.settings();
  return {{"speed_ratio", s.speed_ratio},
          {"crack_rate", s.crack_rate},
          {"kinetic_ratio", s.kinetic_ratio},
          {"target_platen_imbalance", AdaptiveLoading::kTargetImbalance},
          {"check_interval_steps", a.check_steps()},
          {"largest_speed_m_per_s", a.floor_speed() * a.max_factor()}};
}

}  // namespace breccia
