#pragma once
// Unit quaternion q = (w, x, y, z), scalar first, mapping body to world (docs/physics.md §0.4).
#include <cmath>

#include "breccia/core/vec3.hpp"

namespace breccia {

struct Quat {
  double w = 1.0, x = 0.0, y = 0.0, z = 0.0;
  friend constexpr bool operator==(const Quat&, const Quat&) = default;
};

constexpr Quat operator*(const Quat& a, const Quat& b) noexcept {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + b.w * a.x + a.y * b.z - a.z * b.y,
      a.w * b.y + b.w * a.y + a.z * b.x - a.x * b.z, a.w * b.z + b.w * a.z + a.x * b.y - a.y * b.x};
}
constexpr Quat conj(const Quat& q) noexcept {
  return {q.w, -q.x, -q.y, -q.z};
}
constexpr double norm2(const Quat& q) noexcept {
  return q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
}
inline Quat normalized(const Quat& q) noexcept {
  const double s = 1.0 / std::sqrt(norm2(q));
  return {q.w * s, q.x * s, q.y * s, q.z * s};
}

// World image of body vector v: q v q*.
constexpr Vec3 rotate(const Quat& q, const Vec3& v) noexcept {
  const Vec3 u{q.x, q.y, q.z};
  const Vec3 t = cross(u, v) * 2.0;
  return v + t * q.w + cross(u, t);
}

inline Quat from_axis_angle(const Vec3& axis, double angle) noexcept {
  const Vec3 a = unit(axis);
  const double s = std::sin(0.5 * angle);
  return {std::cos(0.5 * angle), a.x * s, a.y * s, a.z * s};
}

// Exact exponential update for a world-frame angular velocity held over dt (§1.4), followed by
// renormalisation.
inline Quat integrate_orientation(const Quat& q, const Vec3& omega, double dt) noexcept {
  const double phi = norm(omega) * dt;
  Quat dq;
  if (phi < 1e-8) {
    dq = {1.0 - phi * phi / 8.0, 0.5 * dt * omega.x, 0.5 * dt * omega.y, 0.5 * dt * omega.z};
  } else {
    const double s = std::sin(0.5 * phi) / norm(omega);
    dq = {std::cos(0.5 * phi), omega.x * s, omega.y * s, omega.z * s};
  }
  return normalized(dq * q);
}

}  // namespace breccia
