#pragma once
// Internal to sample/: the three packing methods and the pieces they share. Each method returns
// the packed particles in its vessel; pack_sample() then orders, bonds and reports them.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "breccia/engine/simulation.hpp"
#include "breccia/sample/packing.hpp"

namespace breccia::packing {

using Log = std::function<void(const std::string&)>;

struct PackedState {
  std::vector<PosRad> particles;
  Region region;         // the vessel the particles fill (compacted, after preconsolidation)
  PackingReport report;  // stages, steps, convergence, floaters grown
};

PackedState pack_by_expansion(const PackingSettings& s, const Log& log);
PackedState pack_by_insertion(const PackingSettings& s, const Log& log);
PackedState pack_by_preconsolidation(const PackingSettings& s, const Log& log);

// --- shared pieces ---

// Radii for the target porosity of the vessel (docs/physics.md §7.1), largest first.
std::vector<double> draw_radii(const PackingSettings& s, const Region& region);

// Random sequential placement without overlap at `shrink` times the radii (§7.2 step 2). The
// k-th radius (largest first) goes into axial stratum k mod `strata`, so every part of the sample
// gets the same mix of sizes: the size composition of a slice does not fluctuate with the draw.
std::vector<PosRad> place_at_random(const std::vector<double>& radii, double shrink,
                                    const Region& region, std::uint64_t seed, int strata);

// Particles sorted into cells of 4 r_max (axis, then y, then x): neighbours close in memory.
void sort_spatially(std::vector<PosRad>& p, const Region& region);

// The contact model of the packing: the test's law with friction switched off.
ContactModel frictionless(const ContactModel& m);
const char* contact_law_name(const ContactModel& m);

// A simulation of `particles` in the rigid frictionless vessel of `region` (no bonds), strongly
// damped for quasi-static cycling.
Simulation vessel_simulation(const std::vector<PosRad>& particles, const Region& region,
                             const PackingSettings& s);

// Kinetic energy (translational and rotational) of a simulation's particles.
double kinetic_energy(const Simulation& sim);

struct FloaterFix {
  std::size_t found = 0, fitted = 0;
  double largest_growth = 0.0;  // relative to the nominal radius
};
// Places every floater (fewer than n_f other grains within `tol`: its bonds to be) snug in its
// cage: the largest sphere tangent to D + 1 of its nearest grains and walls, at most
// (1 + max_growth) x its nominal radius (floaters.cpp). Only the first `candidates` particles
// may be floaters (the others, such as wall rows, are only neighbours).
FloaterFix fit_floaters(Simulation& sim, const Region& region, double tol, int n_f,
                        double max_growth, const std::vector<double>& nominal_radius,
                        std::size_t candidates = static_cast<std::size_t>(-1));

// The packing servos' step (docs/physics.md §7.2 step 4): the increment g error / stiffness, capped
// at `cap` either way (the cap when nothing is touching yet). The affine stiffness overstates the
// response of a packing near jamming, so while the error keeps its sign without shrinking g grows
// by half each check (up to kMaxGain); when the sign flips, g halves (not below kMinGain).
class AdaptiveServo {
 public:
  static constexpr double kMinGain = 0.5;     // eta of §7.2 step 4
  static constexpr double kMaxGain = 1000.0;  // the adaptive gain's ceiling
  explicit AdaptiveServo(double cap) : cap_(cap) {}
  double increment(double error, double stiffness) {
    if (error * last_error_ < 0.0)
      gain_ = std::max(kMinGain, 0.5 * gain_);
    else if (last_error_ != 0.0 && std::abs(error) > 0.9 * std::abs(last_error_))
      gain_ = std::min(kMaxGain, 1.5 * gain_);
    last_error_ = error;
    return stiffness > 0.0 ? std::clamp(gain_ * error / stiffness, -cap_, cap_) : cap_;
  }

 private:
  double cap_, gain_ = kMinGain, last_error_ = 0.0;
};

// Whether a servoed stress has arrived at its goal, judged on the last kChecks readings: the
// newest and their mean within `tolerance` of the goal (relative), none of them off by more than
// `spread`. A single reading may then stray past the tolerance by the packing's own noise.
class StressWindow {
 public:
  static constexpr int kChecks = 5;
  StressWindow(double goal, double tolerance, double spread)
      : goal_(goal), tolerance_(tolerance * goal), spread_(spread * goal) {}
  bool push(double p) {
    last_[static_cast<std::size_t>(count_++ % kChecks)] = p;
    if (count_ < kChecks) return false;
    double sum = 0.0;
    for (double q : last_) {
      if (std::abs(q - goal_) > spread_) return false;
      sum += q;
    }
    return std::abs(sum / kChecks - goal_) <= tolerance_ && std::abs(p - goal_) <= tolerance_;
  }

 private:
  double goal_, tolerance_, spread_;
  std::array<double, kChecks> last_{};
  int count_ = 0;
};

class StageClock {
 public:
  StageClock(const Simulation* sim = nullptr);
  PackingStage done(std::string name, std::string note = {});

 private:
  const Simulation* sim_;
  std::uint64_t step0_ = 0;
  double t0_ = 0.0;
};

}  // namespace breccia::packing
