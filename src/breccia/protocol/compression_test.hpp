#pragma once
// Compression between two rigid platens (physics.md §6.1): unconfined (UCS), or confined by
// servo-controlled lateral walls (§6.2) at a constant confining stress: triaxial in 3D (four plane
// walls around a prism, or a cylindrical wall around a cylinder) and biaxial in 2D (two walls).
// Stages: consolidation (platens and lateral walls servo to sigma_3 until steady), then axial
// loading at a prescribed platen speed reached through a cosine ramp, stopping at a maximum strain
// or once the stress has fallen to a fraction of the peak. Axis: z in 3D, y in 2D.
// Stresses and strains follow analysis.md §1.1, referred to the start of axial loading.
#include <cstddef>
#include <string>
#include <vector>

#include "breccia/boundary/servo.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

enum class LateralBoundary { Prism, Cylinder };

struct PlatenCompressionSettings {
  double platen_speed = 0.05;  // m/s, each platen
  double ramp_time = 0.0;      // s; 0 = automatic (10 bar-wave transits, at least 1000 steps)
  double max_strain = 0.02;
  double stop_fraction = 0.5;  // stop after the peak once stress < stop_fraction x peak
  double platen_friction = 0.0;
  double confining_stress = 0.0;          // Pa; > 0: confined by lateral servo walls
  double servo_relaxation = 0.5;          // alpha_s of §6.2
  double consolidation_tolerance = 0.01;  // relative; lateral stress error for "consolidated"
  std::uint64_t max_consolidation_steps = 200000;
};

struct AxialState {
  double strain = 0.0;
  double stress = 0.0;                         // Pa, sigma_1: mean platen force / current area
  double stress_nominal = 0.0;                 // Pa, over the area at the start of loading
  double force_bottom = 0.0, force_top = 0.0;  // N, compression-positive
  double lateral_strain = 0.0;                 // compression-positive (negative = expansion)
  double volumetric_strain = 0.0;
  double confining_stress = 0.0;  // Pa, measured on the lateral walls (0 when unconfined)
  double deviatoric = 0.0;        // q = sigma_1 - sigma_3 (target sigma_3)
};

class PlatenCompression {
 public:
  // Adds the platens (and lateral walls when confined) around the sample's extremes. Call before
  // Simulation::initialise().
  PlatenCompression(Simulation& sim, PlatenCompressionSettings settings,
                    LateralBoundary lateral = LateralBoundary::Prism);
  // Consolidates to the confining stress (if any), then sets the platen ramp. Call after
  // Simulation::initialise(). Returns the consolidation steps taken.
  std::uint64_t start(Simulation& sim, double bar_wave_speed);
  // Servo update of the lateral walls; call before every step during loading.
  void control(Simulation& sim);

  AxialState measure(const Simulation& sim) const;
  // Updates the peak tracking; true when the test should stop. The post-peak rule applies only
  // once bonds have started to break, so that ramp-up oscillations cannot end a test.
  bool finished(const AxialState& s, std::size_t broken_bonds);
  std::string stop_reason() const { return stop_reason_; }

  bool confined() const noexcept { return st_.confining_stress > 0.0; }
  double height0() const noexcept { return h0_; }
  double area() const noexcept { return area0_; }
  double width0() const noexcept { return w0_[0]; }
  double depth0() const noexcept { return w0_[1]; }  // 2D: the thickness
  double peak_stress() const noexcept { return peak_; }
  bool consolidated() const noexcept { return consolidated_; }
  LateralBoundary lateral() const noexcept { return lateral_; }
  const PlatenCompressionSettings& settings() const noexcept { return st_; }

  // Checkpoints: the protocol's state (its walls live in the simulation's state).
  void save_state(ArchiveWriter& a) const;
  static PlatenCompression restore(ArchiveReader& a);
  // Throws InputError naming `where` unless the restored walls and particles exist in `sim`.
  void check_restored(const Simulation& sim, const std::string& where) const;

 private:
  PlatenCompression() = default;
  template <class Archive>
  void transfer(Archive& a);
  double height(const Simulation& sim) const;
  // Current lateral extents (x, y widths; cylinder: diameter twice) from walls or particles.
  void widths(const Simulation& sim, double w[2]) const;
  double current_area(const Simulation& sim) const;
  void drive_lateral(Simulation& sim) const;
  double lateral_stress(const Simulation& sim) const;

  PlatenCompressionSettings st_;
  LateralBoundary lateral_ = LateralBoundary::Prism;
  int axis_ = 2;
  bool planar_ = false;
  double thickness_ = 1.0;
  std::size_t bottom_ = 0, top_ = 0;
  std::vector<std::size_t> side_;  // lateral walls: x0, x1, y0, y1 (prism) or the cylinder
  Vec3 centre_;                    // cylinder axis foot (x, y)
  // Unconfined: boundary particles that measure the lateral strain (analysis.md §1.1).
  std::vector<std::uint32_t> face_[4];  // x-, x+, y-, y+ (prism) or face_[0] = outer shell
  double h0_ = 0.0, area0_ = 0.0, w0_[2] = {0.0, 0.0};
  double peak_ = 0.0, k_min_ = 0.0;
  bool consolidated_ = true;
  StressServo servo_;
  std::string stop_reason_;
};

}  // namespace breccia
