#pragma once
// Servo control of a wall to a target normal stress (docs/physics.md §6.2, after the PFC servo):
// V = G (sigma_target - sigma_measured), G = alpha A / (k_sum dt), where k_sum is the summed normal
// stiffness of the wall's contacts, so that one step corrects the fraction alpha of the error.
// Positive V moves the wall into the sample. Stresses are compression-positive.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "breccia/boundary/wall.hpp"

namespace breccia {

struct StressServo {
  double target_stress = 0.0;  // Pa
  double relaxation = 0.5;     // alpha_s, 0 < alpha_s <= 1
  double max_speed = 1.0;      // m/s, |V| is clamped to this

  // Velocity into the sample for a wall of loaded area `area` whose contacts push back with
  // `measured_stress` and have summed stiffness `contact_stiffness` (a free wall, with no
  // contacts, approaches at the capped speed). `min_stiffness` stands in for k_sum then.
  double speed(double measured_stress, double area, double contact_stiffness, double dt,
               double min_stiffness) const noexcept {
    const double k = std::max(contact_stiffness, min_stiffness);
    const double v = relaxation * area / (k * dt) * (target_stress - measured_stress);
    return std::clamp(v, -max_speed, max_speed);
  }

  // Drives a plane wall: its stress is the normal force it exerts over `area`.
  void drive(Wall& w, double area, double dt, double min_stiffness) const noexcept {
    const double stress = dot(w.force, w.normal) / area;
    w.controlled = true;
    w.velocity = w.normal * speed(stress, area, w.contact_stiffness, dt, min_stiffness);
  }

  // Proportional-integral drive of a plane wall (the side walls of a 2D biaxial test). The
  // proportional drive above lags behind a dilating sample by v_dilation / G_eff, and G_eff is a
  // fraction of G: the sample behind the wall's contacts is softer than the contacts themselves.
  // On a 2D hexagonal block at 2 MPa the lag reached 5.6 % of sigma_3 before the peak. Each step
  // adds kIntegralShare of the proportional correction to `integral` (a velocity, held by the
  // caller and clamped like the velocity), which takes the lag out.
  static constexpr double kIntegralShare = 0.05;
  void drive_pi(Wall& w, double area, double dt, double min_stiffness,
                double& integral) const noexcept {
    const double stress = dot(w.force, w.normal) / area;
    w.controlled = true;
    w.velocity =
        w.normal * speed_pi(stress, area, w.contact_stiffness, dt, min_stiffness, integral);
  }
  // The proportional-integral speed itself, for a body that is not a wall (a grit layer).
  double speed_pi(double measured_stress, double area, double contact_stiffness, double dt,
                  double min_stiffness, double& integral) const noexcept {
    const double p = speed(measured_stress, area, contact_stiffness, dt, min_stiffness);
    integral = std::clamp(integral + kIntegralShare * p, -max_speed, max_speed);
    return std::clamp(p + integral, -max_speed, max_speed);
  }

  // Drives a cylinder wall of length `height` through its radius (positive speed shrinks it);
  // its stress is the summed radial contact force over the lateral area 2 pi R H (§6.3).
  void drive_cylinder(Wall& w, double height, double dt, double min_stiffness) const noexcept {
    const double area = 2.0 * std::numbers::pi * w.radius * height;
    w.controlled = true;
    w.radial_speed = speed(w.radial_force / area, area, w.contact_stiffness, dt, min_stiffness);
  }
};

}  // namespace breccia
