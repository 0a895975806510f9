#pragma once
// Plain 3-vector of doubles. 2D simulations use the same type with z = 0 so that every law is
// written once (docs/physics.md §0.5).
#include <cmath>

namespace breccia {

struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;

  constexpr Vec3& operator+=(const Vec3& o) noexcept {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  constexpr Vec3& operator-=(const Vec3& o) noexcept {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  constexpr Vec3& operator*=(double s) noexcept {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
  constexpr double operator[](int k) const noexcept { return k == 0 ? x : (k == 1 ? y : z); }
  constexpr double& operator[](int k) noexcept { return k == 0 ? x : (k == 1 ? y : z); }
  friend constexpr bool operator==(const Vec3&, const Vec3&) = default;
};

constexpr Vec3 operator+(Vec3 a, const Vec3& b) noexcept {
  return a += b;
}
constexpr Vec3 operator-(Vec3 a, const Vec3& b) noexcept {
  return a -= b;
}
constexpr Vec3 operator-(const Vec3& a) noexcept {
  return {-a.x, -a.y, -a.z};
}
constexpr Vec3 operator*(Vec3 a, double s) noexcept {
  return a *= s;
}
constexpr Vec3 operator*(double s, Vec3 a) noexcept {
  return a *= s;
}
constexpr Vec3 operator/(const Vec3& a, double s) noexcept {
  return {a.x / s, a.y / s, a.z / s};
}

constexpr double dot(const Vec3& a, const Vec3& b) noexcept {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr Vec3 cross(const Vec3& a, const Vec3& b) noexcept {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
constexpr double norm2(const Vec3& a) noexcept {
  return dot(a, a);
}
inline double norm(const Vec3& a) noexcept {
  return std::sqrt(norm2(a));
}
inline Vec3 unit(const Vec3& a) noexcept {
  const double n = norm(a);
  return n > 0.0 ? a / n : Vec3{};
}

// Rotates v by the rotation that takes unit vector `from` to unit vector `to` about their common
// perpendicular (Rodrigues, written without normalising the axis so it stays exact as the angle
// goes to zero). Used to carry shear-spring history into the current contact plane (§3.1).
constexpr Vec3 rotate_between(const Vec3& v, const Vec3& from, const Vec3& to) noexcept {
  const Vec3 a = cross(from, to);
  const double c = dot(from, to);
  if (c <= -1.0 + 1e-12) return -v;  // antiparallel: undefined axis, never met in practice
  const Vec3 av = cross(a, v);
  return v + av + cross(a, av) * (1.0 / (1.0 + c));
}

// Rotates v (perpendicular to unit n) about n by the Cayley transform of angle psi. This is an
// exact rotation (norm preserved) by 2*atan(psi/2) = psi - psi^3/12 + ..., i.e. second-order in
// the time step like the integrator, at a fraction of the cost of sin/cos.
constexpr Vec3 spin_about(const Vec3& v, const Vec3& n, double psi) noexcept {
  const double h = 0.5 * psi;
  const double inv = 1.0 / (1.0 + h * h);
  const double c = (1.0 - h * h) * inv;
  const double s = 2.0 * h * inv;
  return v * c + cross(n, v) * s + n * (dot(n, v) * (1.0 - c));
}

// The rotation that carries history vectors (shear force, bending moment) from the previous
// contact plane into the current one: the tilt taking n_old to n followed by a spin about n
// (docs/physics.md §3.1, decision 19). Built once per pair and step, applied to several vectors;
// the same as spin_about(rotate_between(v, n_old, n), n, psi), which stays as the test reference.
struct PlaneCarry {
  Vec3 axis;  // n_old x n
  double inv_one_plus_c = 1.0;
  Vec3 n;
  double c = 1.0, s = 0.0;  // Cayley cosine and sine of the spin

  PlaneCarry(const Vec3& n_old, const Vec3& n_new, double psi) noexcept
      : axis(cross(n_old, n_new)), n(n_new) {
    inv_one_plus_c = 1.0 / (1.0 + dot(n_old, n_new));
    const double h = 0.5 * psi;
    const double inv = 1.0 / (1.0 + h * h);
    c = (1.0 - h * h) * inv;
    s = 2.0 * h * inv;
  }
  // Inlined: out of line, the contact kernels lost 6 % of the pair pass to the call.
  [[gnu::always_inline]] Vec3 apply(const Vec3& v) const noexcept {
    const Vec3 av = cross(axis, v);
    const Vec3 t = v + av + cross(axis, av) * inv_one_plus_c;
    return t * c + cross(n, t) * s + n * (dot(n, t) * (1.0 - c));
  }
};

}  // namespace breccia
