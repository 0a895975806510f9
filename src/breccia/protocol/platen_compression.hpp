#pragma once
// Axial compression between two rigid platens: the demonstration protocol of the engine (the full
// UCS and triaxial protocols build on it). Stages: ramp the platens up to speed, load, stop at a
// maximum strain or once the stress has fallen to a fraction of the peak. Axis: z in 3D, y in 2D.
// Stress and strain follow analysis.md §1.1 (compression-positive, nominal area).
#include <cstddef>
#include <string>

#include "breccia/engine/simulation.hpp"

namespace breccia {

struct PlatenCompressionSettings {
  double platen_speed = 0.05;  // m/s, each platen
  double ramp_time = 0.0;      // s; 0 = automatic (10 bar-wave transits, at least 1000 steps)
  double max_strain = 0.02;
  double stop_fraction = 0.5;  // stop after the peak once stress < stop_fraction x peak
  double platen_friction = 0.0;
};

struct AxialState {
  double strain = 0.0;
  double stress = 0.0;                         // Pa, mean of the two platens over the nominal area
  double force_bottom = 0.0, force_top = 0.0;  // N, compression-positive
};

class PlatenCompression {
 public:
  // Adds the two platens touching the sample's extremes. Call before Simulation::initialise().
  PlatenCompression(Simulation& sim, PlatenCompressionSettings settings);
  // Sets the ramp once the time step is known. Call after Simulation::initialise().
  void start(Simulation& sim, double bar_wave_speed);

  AxialState measure(const Simulation& sim) const;
  // Updates the peak tracking; true when the test should stop. The post-peak rule applies only
  // once bonds have started to break, so that ramp-up oscillations cannot end a test.
  bool finished(const AxialState& s, std::size_t broken_bonds);
  std::string stop_reason() const { return stop_reason_; }

  double height0() const noexcept { return h0_; }
  double area() const noexcept { return area_; }
  double peak_stress() const noexcept { return peak_; }

 private:
  PlatenCompressionSettings st_;
  int axis_ = 2;
  std::size_t bottom_ = 0, top_ = 0;
  double h0_ = 0.0, area_ = 0.0, peak_ = 0.0;
  std::string stop_reason_;
};

}  // namespace breccia
