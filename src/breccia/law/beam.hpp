#pragma once
// The kinematics and elastic loads shared by the total beam bonds (docs/physics.md §4.2, §4.3): the
// ESyS-Particle brittle beam and the quaternion bond of LAMMPS bpm/rotational differ in their
// shear arms and their failure rules only.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "breccia/core/quat.hpp"
#include "breccia/law/pair.hpp"

namespace breccia {

namespace beam {

// The length of (a, b) for components of a unit vector or quaternion: no overflow to guard
// against, so the plain root (std::hypot's scaling took a sixth of a quaternion bond's time).
// Below 1e-154 the square underflows and the length reads 0, an angle far below round-off.
inline double unit_part_length(double a, double b) noexcept {
  return std::sqrt(a * a + b * b);
}

// atan(t) / t for z = t^2 <= 1/256: the series to t^12 (the next term is below 1e-18). A
// template so that the four-lane kernel (beam_lanes.hpp) runs the same operations on its vectors.
template <class T>
inline T atan_over_t(T z) noexcept {
  T p = z * (1.0 / 13.0) - 1.0 / 11.0;
  p = p * z + 1.0 / 9.0;
  p = p * z - 1.0 / 7.0;
  p = p * z + 1.0 / 5.0;
  p = p * z - 1.0 / 3.0;
  return 1.0 + z * p;
}

// atan2(y, x) for the angles of a bond, which stay small until it breaks: for x > 0 and
// |y| <= x / 16 the series of atan(t), t = y / x, and std::atan2 otherwise. Within 2 ulp of
// std::atan2 (tests/test_quaternion_bond.cpp) and about three times faster on the small angles,
// which are nearly all of them.
inline double bond_angle(double y, double x) noexcept {
  if (!(x > 0.0 && std::abs(y) <= 0.0625 * x)) return std::atan2(y, x);
  const double t = y / x;
  return t * atan_over_t(t * t);
}

// Shortest-arc rotation taking z to the unit vector r (§4.2 step 4).
inline Quat z_to(const Vec3& r) noexcept {
  if (r.z <= -1.0 + 1e-15) return {0.0, 1.0, 0.0, 0.0};  // anti-parallel: about x
  const double c = std::sqrt(0.5 * (1.0 + r.z)), s = std::sqrt(std::max(0.0, 0.5 * (1.0 - r.z)));
  const double rho = unit_part_length(r.x, r.y);
  if (rho == 0.0) return {1.0, 0.0, 0.0, 0.0};
  return {c, -s * r.y / rho, s * r.x / rho, 0.0};
}

// The relative displacement of the two ends in the frames of §4.2: what the forces and the
// failure test need, in the body frame of particle 1 (f_r, f_gamma) and the bond frame (the rest).
struct Deformation {
  Vec3 r_hat;        // present branch direction, body-1 frame
  double stretch;    // d - d0
  Vec3 shear_gamma;  // gamma p_hat (rad; the angle that carried the branch off its reference)
  Quat bond_frame;   // q_m: bond frame to body-1 frame
  double bend;       // theta
  Vec3 bend_axis;    // b' (bond frame)
  double twist;      // psi
};

// `n_body1`: the unit branch direction in the body-1 frame; `d`: the centre distance.
inline Deformation deform(const Vec3& n_body1, double d, const Vec3& r0, double d0,
                          const Quat& relative) noexcept {
  Deformation f;
  f.r_hat = n_body1;
  f.stretch = d - d0;
  const double gamma = bond_angle(norm(cross(f.r_hat, r0)), dot(f.r_hat, r0));
  f.shear_gamma = {};
  if (gamma >= 1e-12) f.shear_gamma = unit(r0 - f.r_hat * dot(r0, f.r_hat)) * gamma;
  f.bond_frame = z_to(f.r_hat);
  // q_m* q q_m rotates the vector part only (exactly zero stays zero: no bend from round-off).
  const Vec3 axis = rotate(conj(f.bond_frame), Vec3{relative.x, relative.y, relative.z});
  Quat q{relative.w, axis.x, axis.y, axis.z};
  if (q.w < 0.0) q = {-q.w, -q.x, -q.y, -q.z};
  const double xy = unit_part_length(q.x, q.y), wz = unit_part_length(q.w, q.z);
  f.twist = 2.0 * bond_angle(q.z, q.w);
  f.bend = 2.0 * bond_angle(xy, wz);
  f.bend_axis = {};
  if (xy > 0.0) {
    if (wz > 0.0) {
      f.bend_axis = Vec3{q.w * q.x - q.y * q.z, q.w * q.y + q.x * q.z, 0.0} * (1.0 / (wz * xy));
    } else {
      f.twist = 0.0;  // bent by pi: no twist is defined
      f.bend_axis = Vec3{q.x, q.y, 0.0} * (1.0 / xy);
    }
  }
  return f;
}

// The state of a beam bond (§4.2, §4.3): the reference of installation and the last step's
// magnitudes for the stored energy and the failure test. The beam's radius, its section and its
// stiffnesses follow from the length, the grains' radii and the law's moduli (section()), which
// keeps a bond at 96 bytes.
struct BeamState {
  Vec3 r0;          // reference branch direction, body-1 frame
  Quat q0;          // reference relative orientation q1* q2
  double d0 = 0.0;  // reference centre distance (the beam length L)
  double normal_force = 0.0, shear_force = 0.0, bend_moment = 0.0, twist_moment = 0.0;
};

// What a beam law's section and stiffnesses are made of: its moduli, the bending factor chi_b,
// whether planar spheres keep the disc section (§4.3), and the beam's radius: min(R1, R2), or
// half the length (ESyS's meanR_scaling, LAMMPS's bpm/rotational).
struct BeamModuli {
  double young = 0.0, shear = 0.0, bending_factor = 1.0;
  bool disc_for_planar_spheres = false;
  bool min_radius = false;
};

// The beam's radius R_b.
inline double beam_radius(const BeamState& s, const BeamModuli& m, const BondRadii& r) noexcept {
  return m.min_radius ? std::min(r.R1, r.R2) : 0.5 * s.d0;
}

// The beam's section (a disc in 3D, a slab of the disks' thickness in 2D), its stiffnesses, and
// the reciprocals the failure rules use. Every bond derives it at every step, from one division.
struct BeamSection {
  double radius;                            // R_b
  double kr, ks, kb, kt;                    // K_r, K_s, chi_b K_b (effective), K_t
  double area, inertia, polar;              // A, I, J (J = 0 in 2D: no twist)
  double inv_area, inv_inertia, inv_polar;  // 1 / A, 1 / I, 1 / J (0 in 2D)
};
// A disc section of radius r (inv_r = 1 / r): its area, moments and their reciprocals. A
// template, so that the four-lane kernel (beam_lanes.hpp) runs the same operations in the same
// order on its vectors.
template <class Section, class T>
[[gnu::always_inline]] inline void disc_section(Section& c, T r, T inv_r) noexcept {
  c.area = std::numbers::pi * r * r;
  c.inertia = 0.25 * std::numbers::pi * r * r * r * r;
  c.polar = 2.0 * c.inertia;
  c.inv_area = std::numbers::inv_pi * inv_r * inv_r;
  c.inv_inertia = 4.0 * std::numbers::inv_pi * inv_r * inv_r * inv_r * inv_r;
  c.inv_polar = 0.5 * c.inv_inertia;
}
inline BeamSection section(const BeamState& s, const BeamModuli& m, const RunGeometry& run,
                           const BondRadii& radii) noexcept {
  const double r = beam_radius(s, m, radii);
  const bool slab = run.planar && !(m.disc_for_planar_spheres && run.planar_sphere);
  const double t = slab ? run.thickness : 1.0;
  const double x = 1.0 / (r * t * s.d0);  // 1 / R_b, 1 / t and 1 / L follow from it
  const double inv_r = t * s.d0 * x, inv_length = r * t * x;
  BeamSection c;
  c.radius = r;
  if (slab) {
    c.area = 2.0 * r * t;
    c.inertia = 2.0 / 3.0 * r * r * r * t;
    c.polar = 0.0;
    const double inv_t = r * s.d0 * x;
    c.inv_area = 0.5 * inv_r * inv_t;
    c.inv_inertia = 1.5 * inv_r * inv_r * inv_r * inv_t;
    c.inv_polar = 0.0;
  } else {
    disc_section(c, r, inv_r);
  }
  c.kr = m.young * c.area * inv_length;
  c.ks = m.shear * c.area * inv_length;
  c.kb = m.bending_factor * m.young * c.inertia * inv_length;
  c.kt = m.shear * c.polar * inv_length;
  return c;
}

// A stress-free beam at the present geometry: radius R_b (d0 / 2, or min(R1, R2)).
inline BeamState install(const PairGeometry& g, const BodyFrames& fr) noexcept {
  BeamState s;
  s.d0 = g.d;
  s.r0 = rotate(conj(fr.q1), g.n);
  s.q0 = conj(fr.q1) * fr.q2;
  return s;
}

// The beam meets the crack plane at x1 + arm1 d; the geometry's contact point lies at
// x1 + (R1 - delta / 2) n. Zero for touching grains.
inline double point_shift(const PairGeometry& g) noexcept {
  const double arm1 = g.R1 / (g.R1 + g.R2);  // radii do not change once bonded
  return g.d * arm1 - g.R1 + 0.5 * g.delta;
}

// The reference computation of loads() below, step by step in the frames of §4.2: force and
// couple on particle 2 (§0.3) from the present configuration (§4.2 steps 1-8), with
// the shear arm `arm` of the branch rotation and `arm_theta` of the rotation-induced shear (d0
// for ESyS's beam, d for LAMMPS's bpm/rotational). Stores the magnitudes of step 9 in `s`. The
// couple includes moving the force to the beam point, so that the engine's lever-arm torques are
// the beam's.
inline PairForce reference_loads(BeamState& s, const BeamSection& c, const PairGeometry& g,
                                 const BodyFrames& fr, double arm, double arm_theta) noexcept {
  const Quat to_body1 = conj(fr.q1);
  const Deformation f =
      deform(rotate(to_body1, g.n), g.d, s.r0, s.d0, to_body1 * fr.q2 * conj(s.q0));
  // Forces on particle 1 in the body-1 frame (f_r, f_gamma) and the bond frame (the rest).
  const Vec3 f_r = f.r_hat * (c.kr * f.stretch);
  const Vec3 f_gamma = f.shear_gamma * (-c.ks * arm);
  const Vec3 z{0.0, 0.0, 1.0};
  const Vec3 f_theta = cross(z, f.bend_axis) * (0.5 * c.ks * arm_theta * f.bend);
  const Vec3 m_bend = f.bend_axis * (c.kb * f.bend);
  const Vec3 m_twist = z * (c.kt * f.twist);
  const Vec3 shear_body1 = f_gamma + rotate(f.bond_frame, f_theta);
  const Vec3 force = -rotate(fr.q1, f_r + shear_body1);
  const Vec3 couple = -rotate(fr.q1, rotate(f.bond_frame, m_bend + m_twist));
  s.normal_force = -c.kr * f.stretch;
  s.shear_force = norm(shear_body1);
  s.bend_moment = norm(m_bend);
  s.twist_moment = c.kt * f.twist;
  return {force, couple + cross(g.n * point_shift(g), force)};
}

// Force and couple on particle 2 (§0.3), as reference_loads() but in the world frame: the angle
// between two directions and the swing-twist split of a rotation about an axis do not depend on
// the frame they are read in, so the branch, the reference and the relative rotation are taken
// to the world frame once (one rotation, two products) instead of the bond and body frames and
// back (six rotations and the shortest arc's roots). With the relative rotation's vector part v,
// its twist part v.n and its swing part v_perp = v - (v.n) n, the bond frame's bending axis
// (w x - y z, w y + x z, 0) / (|(w, z)| |(x, y)|) is (w v_perp + (v.n) n x v_perp) / (...) in any
// frame. Agrees with reference_loads() to round-off (tests/test_beam_kernels.cpp). loads() below
// takes it for angles past the series' range.
inline PairForce loads_any_angle(BeamState& s, const BeamSection& c, const PairGeometry& g,
                                 const BodyFrames& fr, double arm, double arm_theta) noexcept {
  const Vec3& n = g.n;
  const Vec3 r0 = rotate(fr.q1, s.r0);
  Quat q = fr.q2 * conj(s.q0) * conj(fr.q1);  // q1 (q1* q2 q0*) q1*
  if (q.w < 0.0) q = {-q.w, -q.x, -q.y, -q.z};
  const double stretch = g.d - s.d0;
  const double cos_gamma = dot(n, r0);
  const double gamma = bond_angle(norm(cross(n, r0)), cos_gamma);
  Vec3 shear_gamma{};
  if (gamma >= 1e-12) shear_gamma = unit(r0 - n * cos_gamma) * gamma;
  const Vec3 v{q.x, q.y, q.z};
  const double along = dot(v, n);
  const Vec3 v_perp = v - n * along;
  const double xy = norm(v_perp), wz = unit_part_length(q.w, along);
  double twist = 2.0 * bond_angle(along, q.w);
  const double bend = 2.0 * bond_angle(xy, wz);
  Vec3 bend_axis{};
  if (xy > 0.0) {
    if (wz > 0.0) {
      bend_axis = (v_perp * q.w + cross(n, v_perp) * along) * (1.0 / (wz * xy));
    } else {
      twist = 0.0;  // bent by pi: no twist is defined
      bend_axis = v_perp * (1.0 / xy);
    }
  }
  // Loads on particle 1, world frame; particle 2 takes their opposites.
  const Vec3 shear =
      shear_gamma * (-c.ks * arm) + cross(n, bend_axis) * (0.5 * c.ks * arm_theta * bend);
  const Vec3 force = -(n * (c.kr * stretch) + shear);
  const Vec3 couple = -(bend_axis * (c.kb * bend) + n * (c.kt * twist));
  s.normal_force = -c.kr * stretch;
  s.shear_force = norm(shear);
  s.bend_moment = xy > 0.0 ? c.kb * bend : 0.0;
  s.twist_moment = c.kt * twist;
  return {force, couple + cross(n * point_shift(g), force)};
}

// loads_any_angle() for the small angles of nearly every step (each of gamma, the bend and the
// twist with tan(angle / 2 or 1) <= 1/16): every angle enters as angle / sin(angle) times a
// vector, and atan(t) / t is a series in t^2, so no root is taken on the way to the loads, and
// the three divisions share one. With t = tan(gamma) = |n x r0| / (n.r0) the branch term is
// (r0 - (n.r0) n) atan(t) / (t (n.r0)); with t_b = |v_perp| / |(w, v.n)| the bend
// theta = 2 atan(t_b) about the axis (w v_perp + (v.n) n x v_perp) / (|(w, v.n)| |v_perp|)
// gives the moment (w v_perp + (v.n) n x v_perp) 2 K_b atan(t_b) / (t_b (w^2 + (v.n)^2)), and
// n x axis, the direction of the bend's shear, is (w n x v_perp - (v.n) v_perp) / (...).
inline PairForce loads(BeamState& s, const BeamSection& c, const PairGeometry& g,
                       const BodyFrames& fr, double arm, double arm_theta) noexcept {
  const Vec3& n = g.n;
  const Vec3 r0 = rotate(fr.q1, s.r0);
  Quat q = fr.q2 * conj(s.q0) * conj(fr.q1);
  if (q.w < 0.0) q = {-q.w, -q.x, -q.y, -q.z};
  const double cos_gamma = dot(n, r0), sin2_gamma = norm2(cross(n, r0));
  const Vec3 v{q.x, q.y, q.z};
  const double along = dot(v, n);
  const Vec3 v_perp = v - n * along;
  const double xy2 = norm2(v_perp), wz2 = q.w * q.w + along * along;
  constexpr double kSeries = 1.0 / 256.0;  // (1/16)^2
  const bool small = cos_gamma > 0.0 && sin2_gamma <= kSeries * cos_gamma * cos_gamma &&
                     q.w > 0.0 && along * along <= kSeries * q.w * q.w && xy2 <= kSeries * wz2;
  if (!small) return loads_any_angle(s, c, g, fr, arm, arm_theta);
  const double inv = 1.0 / (cos_gamma * q.w * wz2);
  const double inv_cos = inv * q.w * wz2, inv_w = inv * cos_gamma * wz2,
               inv_wz2 = inv * cos_gamma * q.w;
  const Vec3 shear_gamma = (r0 - n * cos_gamma) *
                           (atan_over_t(sin2_gamma * inv_cos * inv_cos) * inv_cos);  // gamma p_hat
  const double tb2 = xy2 * inv_wz2, bend_series = 2.0 * atan_over_t(tb2);            // theta / t_b
  const double t_twist = along * inv_w, twist = 2.0 * t_twist * atan_over_t(t_twist * t_twist);
  const Vec3 n_x_v = cross(n, v_perp);
  const Vec3 m_bend = (v_perp * q.w + n_x_v * along) * (c.kb * bend_series * inv_wz2);
  const Vec3 shear =
      shear_gamma * (-c.ks * arm) +
      (n_x_v * q.w - v_perp * along) * (0.5 * c.ks * arm_theta * bend_series * inv_wz2);
  const Vec3 force = -(n * (c.kr * (g.d - s.d0)) + shear);
  const Vec3 couple = -(m_bend + n * (c.kt * twist));
  s.normal_force = -c.kr * (g.d - s.d0);
  s.shear_force = norm(shear);
  s.bend_moment = c.kb * bend_series * std::sqrt(tb2);
  s.twist_moment = c.kt * twist;
  return {force, couple + cross(n * point_shift(g), force)};
}

// Stored energy by component; K_b is the effective chi_b K_b (§4.0).
inline BondEnergy energy(const BeamState& s, const BeamSection& c) noexcept {
  BondEnergy e;
  const double en = 0.5 * s.normal_force * s.normal_force / c.kr;
  (s.normal_force < 0.0 ? e.tension : e.compression) = en;
  e.shear = 0.5 * s.shear_force * s.shear_force / c.ks;
  e.bending = c.kb > 0.0 ? 0.5 * s.bend_moment * s.bend_moment / c.kb : 0.0;
  e.twisting = c.kt > 0.0 ? 0.5 * s.twist_moment * s.twist_moment / c.kt : 0.0;
  return e;
}

// Fills the crack record's forces from the breaking step's state.
inline void record(const BeamState& s, const BeamSection& c, const PairGeometry& g,
                   BondFailure& fail) noexcept {
  fail.broken = true;
  fail.Fn = s.normal_force;
  fail.Fs = s.shear_force;
  fail.Mt = s.twist_moment;
  fail.Mb = s.bend_moment;
  fail.bond_radius = c.radius;
  fail.point_shift = point_shift(g);
  fail.energy = energy(s, c);
}

// What the engine asks of every beam law's state, and the isotropic moduli of its beam
// (G = E / (2 (1 + nu))): the two beam laws derive from it and name their moduli in
// `beam_moduli(params)`.
template <class Law>
struct BeamLaw {
  using State = BeamState;
  static constexpr bool needs_frames = true;   // total formulation: reads the orientations
  static constexpr bool needs_motion = false;  // and the pair's shape, never its velocities
  template <class Params>
  static BeamSection section(const Params& p, const State& s, const BondRadii& r) noexcept {
    return beam::section(s, Law::beam_moduli(p), p.run, r);
  }
  template <class Params>
  static double max_stiffness(const Params& p, const State& s, const BondRadii& r) noexcept {
    const BeamSection c = section(p, s, r);
    return std::max(c.kr, c.ks);
  }
  template <class Params>
  static double max_moment_stiffness(const Params& p, const State& s, const BondRadii& r) noexcept {
    const BeamSection c = section(p, s, r);
    return std::max(c.kb, c.kt);
  }
  template <class Params>
  static double normal_stiffness(const Params& p, const State& s, const BondRadii& r) noexcept {
    return section(p, s, r).kr;
  }
  template <class Params>
  static double shear_stiffness(const Params& p, const State& s, const BondRadii& r) noexcept {
    return section(p, s, r).ks;
  }
  template <class Params>
  static BondEnergy energy(const Params& p, const State& s, const BondRadii& r) noexcept {
    return beam::energy(s, section(p, s, r));
  }
  static BondModuli isotropic_moduli(double young, double poisson_ratio) noexcept {
    return {young, young / (2.0 * (1.0 + poisson_ratio))};
  }
};

}  // namespace beam

}  // namespace breccia
