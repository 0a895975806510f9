#pragma once
// Four beam bonds at a time: the shape of each bonded pair, its section and the small-angle loads
// of beam::loads(), evaluated in four lanes of one vector value (GCC's and Clang's vector
// extensions). Each lane performs the scalar kernel's operations in the scalar kernel's order, so
// where no multiply-add is fused (the portable x86-64 build) a lane's result is the scalar result
// to the bit; a build for a CPU with FMA lets the compiler fuse products in either form, and the
// two then agree to a few eps (tests/test_beam_lanes.cpp). What the vector form buys is four
// independent dependency chains in one instruction window, where the scalar bond waits on its own
// chain (a quaternion product, a division, the series, a root). Lanes outside the series' range,
// and bonds that break, are left to the scalar path.
#include <cstdint>

#include "breccia/law/beam.hpp"

namespace breccia::beam {

inline constexpr int kLanes = 4;
using Lanes = double __attribute__((vector_size(32)));
using LaneMask = std::int64_t __attribute__((vector_size(32)));

// The IEEE square root of every lane (correctly rounded, as std::sqrt), through the compiler's
// builtins rather than <immintrin.h>, whose AVX-512 part GCC 12 warns inside.
[[gnu::always_inline]] inline Lanes lane_sqrt(Lanes v) noexcept {
#if defined(__AVX__)
  return __builtin_ia32_sqrtpd256(v);
#elif defined(__SSE2__)
  using Half = double __attribute__((vector_size(16)));
  const Half lo = __builtin_ia32_sqrtpd(Half{v[0], v[1]});
  const Half hi = __builtin_ia32_sqrtpd(Half{v[2], v[3]});
  return Lanes{lo[0], lo[1], hi[0], hi[1]};
#else
  Lanes r;
  for (int l = 0; l < kLanes; ++l) r[l] = std::sqrt(v[l]);
  return r;
#endif
}
[[gnu::always_inline]] inline Lanes lane_select(LaneMask m, Lanes a, Lanes b) noexcept {
  return m ? a : b;
}

// Vec3 and Quat in lanes, with the scalar types' operations written the same way.
struct LaneVec3 {
  Lanes x, y, z;
};
struct LaneQuat {
  Lanes w, x, y, z;
};
[[gnu::always_inline]] inline LaneVec3 operator+(const LaneVec3& a, const LaneVec3& b) noexcept {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
[[gnu::always_inline]] inline LaneVec3 operator-(const LaneVec3& a, const LaneVec3& b) noexcept {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
[[gnu::always_inline]] inline LaneVec3 operator-(const LaneVec3& a) noexcept {
  return {-a.x, -a.y, -a.z};
}
[[gnu::always_inline]] inline LaneVec3 operator*(const LaneVec3& a, Lanes s) noexcept {
  return {a.x * s, a.y * s, a.z * s};
}
[[gnu::always_inline]] inline Lanes dot(const LaneVec3& a, const LaneVec3& b) noexcept {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
[[gnu::always_inline]] inline LaneVec3 cross(const LaneVec3& a, const LaneVec3& b) noexcept {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
[[gnu::always_inline]] inline Lanes norm2(const LaneVec3& a) noexcept {
  return dot(a, a);
}
[[gnu::always_inline]] inline LaneQuat operator*(const LaneQuat& a, const LaneQuat& b) noexcept {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + b.w * a.x + a.y * b.z - a.z * b.y,
      a.w * b.y + b.w * a.y + a.z * b.x - a.x * b.z, a.w * b.z + b.w * a.z + a.x * b.y - a.y * b.x};
}
[[gnu::always_inline]] inline LaneQuat conj(const LaneQuat& q) noexcept {
  return {q.w, -q.x, -q.y, -q.z};
}
[[gnu::always_inline]] inline LaneVec3 rotate(const LaneQuat& q, const LaneVec3& v) noexcept {
  const LaneVec3 u{q.x, q.y, q.z};
  const LaneVec3 t = cross(u, v) * Lanes{2.0, 2.0, 2.0, 2.0};
  return v + t * q.w + cross(u, t);
}
// One beam bond as the lanes read it: its grains' centres, radii and orientations, its state.
struct LaneBond {
  Vec3 x1, x2;
  double R1, R2;
  Quat q1, q2;
  BeamState* state;
};

// The four bonds' inputs as lanes.
struct LaneInputs {
  LaneVec3 x1, x2, r0;
  Lanes R1, R2, d0;
  LaneQuat q1, q2, q0;
};
[[gnu::always_inline]] inline LaneInputs gather(const LaneBond (&b)[kLanes]) noexcept {
  LaneInputs in;
  for (int l = 0; l < kLanes; ++l) {
    in.x1.x[l] = b[l].x1.x, in.x1.y[l] = b[l].x1.y, in.x1.z[l] = b[l].x1.z;
    in.x2.x[l] = b[l].x2.x, in.x2.y[l] = b[l].x2.y, in.x2.z[l] = b[l].x2.z;
    in.R1[l] = b[l].R1, in.R2[l] = b[l].R2;
    in.q1.w[l] = b[l].q1.w, in.q1.x[l] = b[l].q1.x, in.q1.y[l] = b[l].q1.y;
    in.q1.z[l] = b[l].q1.z;
    in.q2.w[l] = b[l].q2.w, in.q2.x[l] = b[l].q2.x, in.q2.y[l] = b[l].q2.y;
    in.q2.z[l] = b[l].q2.z;
    const BeamState& s = *b[l].state;
    in.r0.x[l] = s.r0.x, in.r0.y[l] = s.r0.y, in.r0.z[l] = s.r0.z;
    in.q0.w[l] = s.q0.w, in.q0.x[l] = s.q0.x, in.q0.y[l] = s.q0.y, in.q0.z[l] = s.q0.z;
    in.d0[l] = s.d0;
  }
  return in;
}

// pair_shape() in lanes.
struct LaneShape {
  LaneVec3 n, r1, r2;
  Lanes d, delta;
};
[[gnu::always_inline]] inline LaneShape lane_shape(const LaneInputs& in) noexcept {
  LaneShape g;
  const LaneVec3 dvec = in.x2 - in.x1;
  g.d = lane_sqrt(dot(dvec, dvec));
  g.n = dvec * (1.0 / g.d);
  g.delta = in.R1 + in.R2 - g.d;
  const LaneVec3 xc_rel = g.n * (in.R1 - 0.5 * g.delta);
  g.r1 = xc_rel;
  g.r2 = xc_rel - dvec;
  return g;
}

// section() in lanes for a 3D disc section of radius d0 / 2 (t = 1, chi_b = 1).
struct LaneSection {
  Lanes radius, kr, ks, kb, kt, area, inertia, polar, inv_area, inv_inertia, inv_polar;
  BeamSection lane(int l) const noexcept {
    BeamSection c;
    c.radius = radius[l];
    c.kr = kr[l], c.ks = ks[l], c.kb = kb[l], c.kt = kt[l];
    c.area = area[l], c.inertia = inertia[l], c.polar = polar[l];
    c.inv_area = inv_area[l], c.inv_inertia = inv_inertia[l], c.inv_polar = inv_polar[l];
    return c;
  }
};
[[gnu::always_inline]] inline LaneSection half_length_section(Lanes d0, double young,
                                                              double shear) noexcept {
  LaneSection c;
  const Lanes r = 0.5 * d0;
  const Lanes x = 1.0 / (r * d0);
  const Lanes inv_r = d0 * x, inv_length = r * x;
  c.radius = r;
  disc_section(c, r, inv_r);
  c.kr = young * c.area * inv_length;
  c.ks = shear * c.area * inv_length;
  c.kb = 1.0 * young * c.inertia * inv_length;
  c.kt = shear * c.polar * inv_length;
  return c;
}

// What the lanes hand back: the loads on particle 2 (the couple moved to the centre as loads()
// does), the lever arms of the torques, the sections, and which lanes lie within the series'
// range (the law's failure test is the caller's).
struct LaneLoads {
  LaneVec3 force, couple, r1, r2;
  LaneSection section;
  LaneMask small;
};

// Shape, section and small-angle loads of four 3D beam bonds whose radius is half their length
// and whose shear arms are the present length (the quaternion bond of bpm/rotational): loads()
// in lanes. Writes the magnitudes of step 9 into the states of the lanes within the series'
// range only.
[[gnu::always_inline]] inline void lanes_half_length_beams(const LaneBond (&b)[kLanes],
                                                           double young, double shear,
                                                           LaneLoads& out) noexcept {
  const LaneInputs in = gather(b);
  const LaneShape g = lane_shape(in);
  const LaneSection c = half_length_section(in.d0, young, shear);
  const LaneVec3& n = g.n;
  const LaneVec3 r0 = rotate(in.q1, in.r0);
  LaneQuat q = in.q2 * conj(in.q0) * conj(in.q1);
  const LaneMask flip = q.w < 0.0;
  q = {lane_select(flip, -q.w, q.w), lane_select(flip, -q.x, q.x), lane_select(flip, -q.y, q.y),
       lane_select(flip, -q.z, q.z)};
  const Lanes cos_gamma = dot(n, r0), sin2_gamma = norm2(cross(n, r0));
  const LaneVec3 v{q.x, q.y, q.z};
  const Lanes along = dot(v, n);
  const LaneVec3 v_perp = v - n * along;
  const Lanes xy2 = norm2(v_perp), wz2 = q.w * q.w + along * along;
  constexpr double kSeries = 1.0 / 256.0;
  out.small = (cos_gamma > 0.0) & (sin2_gamma <= kSeries * cos_gamma * cos_gamma) & (q.w > 0.0) &
              (along * along <= kSeries * q.w * q.w) & (xy2 <= kSeries * wz2);
  const Lanes inv = 1.0 / (cos_gamma * q.w * wz2);
  const Lanes inv_cos = inv * q.w * wz2, inv_w = inv * cos_gamma * wz2,
              inv_wz2 = inv * cos_gamma * q.w;
  const LaneVec3 shear_gamma =
      (r0 - n * cos_gamma) * (atan_over_t(sin2_gamma * inv_cos * inv_cos) * inv_cos);
  const Lanes tb2 = xy2 * inv_wz2, bend_series = 2.0 * atan_over_t(tb2);
  const Lanes t_twist = along * inv_w, twist = 2.0 * t_twist * atan_over_t(t_twist * t_twist);
  const LaneVec3 n_x_v = cross(n, v_perp);
  const LaneVec3 m_bend = (v_perp * q.w + n_x_v * along) * (c.kb * bend_series * inv_wz2);
  const Lanes d = g.d;
  const LaneVec3 shear_f = shear_gamma * (-c.ks * d) + (n_x_v * q.w - v_perp * along) *
                                                           (0.5 * c.ks * d * bend_series * inv_wz2);
  const LaneVec3 force = -(n * (c.kr * (d - in.d0)) + shear_f);
  const LaneVec3 couple = -(m_bend + n * (c.kt * twist));
  const Lanes normal_force = -c.kr * (d - in.d0), shear_force = lane_sqrt(norm2(shear_f));
  const Lanes bend_moment = c.kb * bend_series * lane_sqrt(tb2), twist_moment = c.kt * twist;
  // point_shift(): the beam meets the crack plane at x1 + arm1 d
  const Lanes arm1 = in.R1 / (in.R1 + in.R2);
  const Lanes shift = d * arm1 - in.R1 + 0.5 * g.delta;
  out.force = force;
  out.couple = couple + cross(n * shift, force);
  out.r1 = g.r1;
  out.r2 = g.r2;
  out.section = c;
  for (int l = 0; l < kLanes; ++l) {
    if (!out.small[l]) continue;
    BeamState& s = *b[l].state;
    s.normal_force = normal_force[l];
    s.shear_force = shear_force[l];
    s.bend_moment = bend_moment[l];
    s.twist_moment = twist_moment[l];
  }
}

// One bond's result from the lanes, as the pair pass applies it: the loads on particle 2 and the
// lever arms of the two torques; `stands` is false where the scalar path must take the bond
// (outside the series' range, or broken).
struct LaneResult {
  Vec3 force, couple, r1, r2;
  bool stands = false;
};

// Lane l of the loads as a LaneResult.
inline LaneResult lane_result(const LaneLoads& L, int l, bool stands) noexcept {
  return {{L.force.x[l], L.force.y[l], L.force.z[l]},
          {L.couple.x[l], L.couple.y[l], L.couple.z[l]},
          {L.r1.x[l], L.r1.y[l], L.r1.z[l]},
          {L.r2.x[l], L.r2.y[l], L.r2.z[l]},
          stands};
}

}  // namespace breccia::beam
