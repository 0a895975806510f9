#pragma once
// Rigid walls (docs/physics.md §6.1): an unbounded plane, a cylinder about an axis, or a sphere,
// moving with a prescribed velocity reached through a cosine ramp, driven by a controller (servo)
// that sets the velocity each step, or, given a mass, free: a rigid body (a projectile) that the
// contact forces and gravity move, integrated by the same leapfrog as the grains. The wall is body
// 1 of every wall contact.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "breccia/core/vec3.hpp"

namespace breccia {

enum class WallShape : std::uint8_t { Plane, Cylinder, Sphere, Rod };

// Cosine velocity ramp of the factor on the target velocity, from `from` to 1 over `duration`
// seconds starting at `start` (§6.1): from 0 as a test starts, or from above 1 when platens slow
// down to their target speed.
struct VelocityRamp {
  double start = 0.0;
  double duration = 0.0;
  double from = 0.0;
  double factor(double t) const noexcept {
    if (t <= start) return duration > 0.0 ? from : 1.0;
    if (duration <= 0.0 || t >= start + duration) return 1.0;
    return from + (1.0 - from) * 0.5 * (1.0 - std::cos(std::numbers::pi * (t - start) / duration));
  }
};

struct Wall {
  std::string name;
  WallShape shape = WallShape::Plane;
  // Plane: a point on it and the unit normal pointing into the sample.
  // Cylinder: a point on the axis, the unit axis, and the radius; particles are inside.
  // Sphere: the centre and the radius; particles are outside (a rigid ball).
  // Rod: a point on the axis, the unit axis, and the radius; particles are outside (a loading
  // nose or roller, moving as a whole).
  Vec3 point;
  Vec3 normal{0, 0, 1};
  Vec3 axis{0, 0, 1};
  double radius = 0.0;

  // Prescribed motion: plane or sphere velocity (any direction) or cylinder radial speed (positive
  // inward).
  Vec3 target_velocity;
  double target_radial_speed = 0.0;
  VelocityRamp ramp;
  bool controlled = false;  // true: a controller sets `velocity` / `radial_speed` each step
  // > 0: a free rigid body of this mass (kg; 2D: per thickness t, like the grains). It starts at
  // `velocity` and moves under minus its contact force plus gravity; it does not rotate.
  double mass = 0.0;

  // Current motion over the step being taken.
  Vec3 velocity;
  double radial_speed = 0.0;

  // Results of the last step.
  Vec3 force;  // resultant force the wall exerts on the particles
  std::size_t contacts = 0;
  double contact_stiffness = 0.0;  // sum of the normal stiffnesses of its contacts (servo gain)
  double work = 0.0;               // cumulative work done by the wall on the particles
  double radial_force = 0.0;  // cylinder: sum of F . n over its contacts (positive pushes inward)
  Vec3 force_prev;            // previous step's force (and radial force), for the trapezoidal
  double radial_force_prev = 0.0;  // work rule that matches the leapfrog kinetic energy
  // The motion of the last advance: the wall's last displacement, over which that rule books
  // the work (a servo sets `velocity` for the next step before the forces are computed).
  Vec3 advanced_velocity;
  double advanced_radial_speed = 0.0;
  double moved = 0.0;  // distance moved since the last neighbour rebuild

  static Wall plane(std::string name, Vec3 point, Vec3 inward_normal) {
    Wall w;
    w.name = std::move(name);
    w.shape = WallShape::Plane;
    w.point = point;
    w.normal = unit(inward_normal);
    return w;
  }
  // A free rigid ball (a projectile) of the given mass, starting at `velocity`.
  static Wall sphere(std::string name, Vec3 centre, double radius, double mass, Vec3 velocity) {
    Wall w;
    w.name = std::move(name);
    w.shape = WallShape::Sphere;
    w.point = centre;
    w.radius = radius;
    w.mass = mass;
    w.velocity = velocity;
    w.target_velocity = velocity;
    return w;
  }
  // A rigid rod (particles outside) moving at `velocity` (prescribed, through the ramp).
  static Wall rod(std::string name, Vec3 axis_point, Vec3 axis, double radius) {
    Wall w;
    w.name = std::move(name);
    w.shape = WallShape::Rod;
    w.point = axis_point;
    w.axis = unit(axis);
    w.radius = radius;
    return w;
  }
  bool free_body() const noexcept { return mass > 0.0; }
  // The curvature radius a contact law sees (PairGeometry::R1): a sphere's radius, a rod's in 2D
  // (a circle); 0 (flat) otherwise. A rod in 3D is curved across its axis only: its contacts
  // are taken as flat, which overstates their Hertz stiffness a little (the rod is a loading
  // nose; its contact compliance is not what a test measures).
  double convex_radius(bool planar) const noexcept {
    if (shape == WallShape::Sphere || (shape == WallShape::Rod && planar)) return radius;
    return 0.0;
  }
  static Wall cylinder(std::string name, Vec3 axis_point, Vec3 axis, double radius) {
    Wall w;
    w.name = std::move(name);
    w.shape = WallShape::Cylinder;
    w.point = axis_point;
    w.axis = unit(axis);
    w.radius = radius;
    return w;
  }

  // Velocity of the wall surface at a contact whose wall-to-particle normal is n.
  Vec3 surface_velocity(const Vec3& n) const noexcept {
    return shape == WallShape::Cylinder ? n * radial_speed : velocity;
  }

  // Signed gap between a sphere (x, R) and the wall surface, and the wall-to-particle normal.
  double gap(const Vec3& x, double R, Vec3& n) const noexcept {
    if (shape == WallShape::Plane) {
      n = normal;
      return dot(x - point, normal) - R;
    }
    const Vec3 rel = x - point;
    if (shape == WallShape::Sphere) {
      const double d = norm(rel);
      n = d > 0.0 ? rel * (1.0 / d) : Vec3{0, 0, 1};
      return d - radius - R;
    }
    if (shape == WallShape::Rod) {
      const Vec3 radial = rel - axis * dot(rel, axis);
      const double rho = norm(radial);
      n = rho > 0.0 ? radial * (1.0 / rho) : Vec3{0, 0, 1};
      return rho - radius - R;
    }
    const Vec3 radial = rel - axis * dot(rel, axis);
    const double rho = norm(radial);
    n = rho > 0.0 ? radial * (-1.0 / rho) : Vec3{};
    return radius - rho - R;
  }

  // Sets the motion for the step starting at time t (prescribed walls only).
  void update_motion(double t) noexcept {
    if (controlled || free_body()) return;
    const double f = ramp.factor(t);
    velocity = target_velocity * f;
    radial_speed = target_radial_speed * f;
  }

  void advance(double dt) noexcept {
    advanced_velocity = velocity;
    advanced_radial_speed = radial_speed;
    if (shape != WallShape::Cylinder) {
      point += velocity * dt;
      moved += norm(velocity) * dt;
    } else {
      radius -= radial_speed * dt;
      moved += std::abs(radial_speed) * dt;
    }
  }
};

// Contact history between particles and one wall: candidate particles (sorted) and their states.
template <class Law>
struct WallContacts {
  std::vector<std::uint32_t> particle;
  std::vector<typename Law::State> state;
  std::vector<Vec3> force, torque;   // on the particle, this step
  std::vector<double> normal_force;  // force . wall normal, this step
  std::vector<double> stiffness;     // normal (tangent) stiffness of the contact, this step
};

}  // namespace breccia
