#pragma once
// Rolling and twisting resistance of a contact (docs/physics.md §3.5): the elastic-plastic
// spring-dashpot of Ai et al. (2011, "type C"), with PFC's `rrlinear` stiffness k_r = k_s R^2.
// Every contact law carries it the same way: three fields appended to its parameter table, a
// RollingSlot base of its state, and one call after its shear update. A law comes in two state
// layouts, with and without the moments (`Law::with_rolling<bool>`); the engine holds the one its
// parameters need (make_contact_model), so a run without rolling resistance pays nothing for it.
#include <array>
#include <cmath>
#include <cstddef>

#include "breccia/law/pair.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

// The three keys every contact law takes for it. P is the law's Params, with members of these
// names.
template <class P>
constexpr std::array<ParamField<P>, 3> rolling_fields() {
  return {{
      {"rolling_friction", "-", &P::rolling_friction, 0, kInf, true, true,
       "rolling friction mu_r: the rolling moment is at most mu_r R F_n, R = R1 R2 / (R1 + R2); "
       "rolling stiffness k_s R^2 (0 = grains roll freely)"},
      {"twisting_friction", "-", &P::twisting_friction, 0, kInf, true, true,
       "twisting friction mu_t: the twisting moment is at most mu_t R F_n, stiffness k_s R^2 "
       "(0 = grains twist freely)"},
      {"rolling_damping_ratio", "-", &P::rolling_damping_ratio, 0, 1, true, false,
       "critical damping ratio of the rolling dashpot, active while the rolling spring is "
       "below its limit (0 = none)"},
  }};
}

// A law's own fields followed by the rolling fields.
template <class P, std::size_t N>
constexpr std::array<ParamField<P>, N + 3> with_rolling_fields(
    const std::array<ParamField<P>, N>& own) {
  std::array<ParamField<P>, N + 3> all{};
  for (std::size_t k = 0; k < N; ++k) all[k] = own[k];
  const auto rolling = rolling_fields<P>();
  for (std::size_t k = 0; k < 3; ++k) all[N + k] = rolling[k];
  return all;
}

// The stored moment on particle 2: the rolling part normal to n plus the twisting part along n,
// and the stiffness it was stored with (for its energy; the Hertz shear stiffness changes).
struct RollingSpring {
  Vec3 moment;
  double k = 0.0;
};

// The moments in a contact's state, or nothing.
template <bool On>
struct RollingSlot {};
template <>
struct RollingSlot<true> {
  RollingSpring rolling;
};

struct RollingLimits {
  double rolling_friction = 0.0, twisting_friction = 0.0, damping_ratio = 0.0;
  bool on() const noexcept { return rolling_friction > 0.0 || twisting_friction > 0.0; }
};
template <class P>
RollingLimits rolling_limits(const P& p) noexcept {
  return {p.rolling_friction, p.twisting_friction, p.rolling_damping_ratio};
}

// Rolling radius R = R1 R2 / (R1 + R2); against a flat wall the grain's radius.
inline double rolling_radius(const PairGeometry& g) noexcept {
  if (g.wall && !(g.R1 > 0.0)) return g.R2;
  return g.R1 * g.R2 / (g.R1 + g.R2);
}

// Moment of inertia of a grain about its contact point, I + m R^2: 7/5 m R^2 for a sphere (and a
// planar sphere), 3/2 m R^2 for a disk.
inline double inertia_about_contact(double m, double R, const PairGeometry& g) noexcept {
  return (g.planar && !g.planar_sphere ? 1.5 : 1.4) * m * R * R;
}
// The pair's equivalent inertia for the rolling dashpot (Ai et al. 2011).
inline double rolling_inertia(const PairGeometry& g) noexcept {
  const double i2 = inertia_about_contact(g.m2, g.R2, g);
  if (g.wall) return i2;
  const double i1 = inertia_about_contact(g.m1, g.R1, g);
  return i1 * i2 / (i1 + i2);
}

// Elastic energy of the springs of a contact's state (none without the slot).
inline double rolling_energy(const RollingSpring& s) noexcept {
  return s.k > 0.0 ? 0.5 * norm2(s.moment) / s.k : 0.0;
}
inline double rolling_energy(const RollingSlot<true>& s) noexcept {
  return rolling_energy(s.rolling);
}
inline double rolling_energy(const RollingSlot<false>&) noexcept {
  return 0.0;
}

// One step of the spring. `s.moment` must already be carried into the current contact plane;
// k_s is the contact's shear stiffness of the step and fn its elastic normal force. The relative
// rotation (w2 - w1) dt loads the rolling part (normal to n) and the twisting part (along n); each
// is limited to mu R F_n and its slip booked as friction (docs/physics.md §3.5). A change of k_s
// (Hertz) changes the stored energy without work: booked as deleted. Returns the couple on
// particle 2: the springs plus the rolling dashpot while the rolling spring holds.
inline Vec3 rolling_step(const RollingLimits& lim, RollingSpring& s, const PairGeometry& g,
                         double ks, double fn, double dt, PairDissipation& dis) noexcept {
  const double R = rolling_radius(g);
  const double k = ks * R * R;
  if (s.k > 0.0) dis.deleted += 0.5 * norm2(s.moment) * (1.0 / s.k - 1.0 / k);
  s.k = k;
  const Vec3 w = g.w2 - g.w1;
  const double w_twist = dot(w, g.n);
  const Vec3 w_roll = w - g.n * w_twist;
  const double m_twist = dot(s.moment, g.n);
  Vec3 roll = (s.moment - g.n * m_twist) - w_roll * (k * dt);
  double twist = m_twist - w_twist * k * dt;

  bool roll_holds = true;
  const double roll_limit = lim.rolling_friction * R * fn;
  const double roll2 = norm2(roll);
  if (roll2 > roll_limit * roll_limit) {
    const double r = std::sqrt(roll2);
    dis.slip += roll_limit * (r - roll_limit) / k;
    roll *= roll_limit / r;
    roll_holds = false;
  }
  const double twist_limit = lim.twisting_friction * R * fn;
  if (std::abs(twist) > twist_limit) {
    dis.slip += twist_limit * (std::abs(twist) - twist_limit) / k;
    twist = std::copysign(twist_limit, twist);
  }
  s.moment = roll + g.n * twist;

  Vec3 couple = s.moment;
  if (lim.damping_ratio > 0.0 && roll_holds) {
    const double c = 2.0 * lim.damping_ratio * std::sqrt(rolling_inertia(g) * k);
    couple -= w_roll * c;
    dis.viscous += c * norm2(w_roll) * dt;
  }
  return couple;
}

}  // namespace breccia
