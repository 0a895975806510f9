#pragma once
// Adaptive loading (boundary/adaptive_loading.hpp) as the platen-driven tests use it: their three
// experiment-file keys, and the step that moves both platens to the controller's new speed.
#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>

#include "breccia/boundary/adaptive_loading.hpp"
#include "breccia/boundary/wall.hpp"
#include "breccia/engine/simulation.hpp"
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

// The controller a test's keys ask for (off unless adaptive_speed_ratio > 1; P also has
// platen_speed, the floor), acting from `start_time`, the end of the start-up ramp. `length` is
// the sample's along the load.
template <class P>
AdaptiveLoading adaptive_loading_of(const P& p, double bar_wave_speed, double length,
                                    const Simulation& sim, double start_time) {
  if (!(p.adaptive_speed_ratio > 1.0)) return {};
  return AdaptiveLoading({p.adaptive_speed_ratio, p.adaptive_crack_rate, p.adaptive_kinetic_ratio},
                         p.platen_speed, bar_wave_speed, length, sim.time_step(),
                         static_cast<double>(sim.intact_bond_sites()), start_time);
}

// True when the coming step is a check; the step before one samples the stored energy for it.
inline bool adaptive_check_now(const AdaptiveLoading& a, Simulation& sim) {
  if (a.due_next(sim.step_count(), sim.time())) sim.request_energy_sample();
  return a.due(sim.step_count(), sim.time());
}

// What a check reads: the strain and the bonds broken since loading began, the kinetic energy the
// loading does not prescribe (over the stored energy of the step before), and the loading forces
// at the two ends (compression- or tension-positive), whose imbalance the run's check judges.
inline LoadingReading loading_reading(const Simulation& sim, double strain, double cracks,
                                      double fluctuating_kinetic, double force_bottom,
                                      double force_top) {
  LoadingReading r;
  r.strain = strain;
  r.cracks = cracks;
  const double stored = sim.ledger().bond.total() + sim.ledger().contact;
  if (stored > 0.0) r.kinetic_ratio = fluctuating_kinetic / stored;
  const double mean = 0.5 * (force_bottom + force_top);
  if (mean > 0.0) r.imbalance = std::abs(force_top - force_bottom) / mean;
  return r;
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
