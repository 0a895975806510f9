#pragma once
// ESyS-Particle's rotational brittle beam (BrittleBeamPrms; Wang 2009 kinematics), physics.md §4.2:
// an elastic cylinder (3D) or slab (2D) between the two centres, in a total formulation: forces
// and moments follow from the present positions and orientations against the reference state of
// installation, so nothing drifts. Six relative motions (stretch, two shears, twist, two bends)
// with four stiffnesses; Mohr-Coulomb failure on the beam's peak stresses with a tensile cut-off.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "breccia/core/quat.hpp"
#include "breccia/law/pair.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

namespace beam {

// Shortest-arc rotation taking z to the unit vector r (§4.2 step 4).
inline Quat z_to(const Vec3& r) noexcept {
  if (r.z <= -1.0 + 1e-15) return {0.0, 1.0, 0.0, 0.0};  // anti-parallel: about x
  const double c = std::sqrt(0.5 * (1.0 + r.z)), s = std::sqrt(std::max(0.0, 0.5 * (1.0 - r.z)));
  const double rho = std::hypot(r.x, r.y);
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
  const double gamma = std::atan2(norm(cross(f.r_hat, r0)), dot(f.r_hat, r0));
  f.shear_gamma = {};
  if (gamma >= 1e-12) f.shear_gamma = unit(r0 - f.r_hat * dot(r0, f.r_hat)) * gamma;
  f.bond_frame = z_to(f.r_hat);
  // q_m* q q_m rotates the vector part only (exactly zero stays zero: no bend from round-off).
  const Vec3 axis = rotate(conj(f.bond_frame), Vec3{relative.x, relative.y, relative.z});
  Quat q{relative.w, axis.x, axis.y, axis.z};
  if (q.w < 0.0) q = {-q.w, -q.x, -q.y, -q.z};
  const double xy = std::hypot(q.x, q.y), wz = std::hypot(q.w, q.z);
  f.twist = 2.0 * std::atan2(q.z, q.w);
  f.bend = 2.0 * std::atan2(xy, wz);
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

}  // namespace beam

struct BrittleBeam {
  static constexpr std::string_view name = "brittle_beam";
  static constexpr std::string_view summary =
      "ESyS-Particle rotational brittle beam (total formulation), Mohr-Coulomb failure with a "
      "tensile cut-off.";
  static constexpr bool needs_frames = true;  // reads the bodies' orientations

  struct Params {
    double modulus = 10e9;        // E_b
    double poisson_ratio = 0.25;  // nu_b: G_b = E_b / (2 (1 + nu_b))
    double cohesion = 20e6;       // c_b
    double tan_friction = 1.0;    // tan(phi_b)
    double tensile_cutoff = 1.0;  // T
    double bending_factor = 1.0;  // chi_b: 1 beam theory and LAMMPS, 0.5 ESyS
    double moment_factor = 1.0;   // beta_1: moments in the normal stress
    double twist_factor = 1.0;    // beta_2: moments in the shear stress
    bool min_radius = false;      // R_b = min(R1, R2) (ESyS meanR_scaling = false), else d0 / 2
    bool contact_while_bonded = true;  // false: no contact force between bonded grains (ESyS)
  };
  static void prepare(Params&) noexcept {}
  static constexpr std::array<ParamField<Params>, 10> fields() {
    return {{
        {"modulus", "Pa", &Params::modulus, 0, kInf, false, true,
         "beam Young's modulus E_b: K_r = E_b A / L, K_b = E_b I / L with L = d0"},
        {"poisson_ratio", "-", &Params::poisson_ratio, -1, 0.5, false, false,
         "beam Poisson's ratio nu_b: G_b = E_b / (2 (1 + nu_b)), K_s = G_b A / L, K_t = G_b J / L"},
        {"cohesion", "Pa", &Params::cohesion, 0, kInf, false, true,
         "c_b: shear failure when tau > c_b - sigma tan(phi_b)"},
        {"tan_friction", "-", &Params::tan_friction, 0, kInf, true, true,
         "tan(phi_b) of the Mohr-Coulomb line (about 1 in the ESyS tutorial)"},
        {"tensile_cutoff", "-", &Params::tensile_cutoff, 0, 1, false, true,
         "T: tensile failure when sigma tan(phi_b) / c_b > T (1 = at the apex of the Coulomb "
         "line)"},
        {"bending_factor", "-", &Params::bending_factor, 0, 1, false, true,
         "chi_b: bending moment chi_b K_b theta (1 beam theory, 0.5 as ESyS-Particle 2.3.5)"},
        {"moment_factor", "-", &Params::moment_factor, 0, 1, true, true,
         "beta_1: share of the bending moment in the peak normal stress"},
        {"twist_factor", "-", &Params::twist_factor, 0, 1, true, true,
         "beta_2: share of the twisting moment in the peak shear stress"},
        {"min_radius", "-", &Params::min_radius, 0, 0, true, true,
         "beam radius min(R1, R2) (ESyS meanR_scaling = false) instead of d0 / 2"},
        {"contact_while_bonded", "-", &Params::contact_while_bonded, 0, 0, true, true,
         "the contact law also acts between overlapping bonded grains (false: as ESyS, whose "
         "bonded pairs have no contact; their contact energy is booked as deleted)"},
    }};
  }
  static Params example_params() { return {}; }
  static BondModuli moduli(const Params& p) noexcept {
    return {p.modulus, p.modulus / (2.0 * (1.0 + p.poisson_ratio))};
  }
  static bool contact_while_bonded(const Params& p) noexcept { return p.contact_while_bonded; }

  struct State {
    Vec3 r0;                                        // reference branch direction, body-1 frame
    Quat q0;                                        // reference relative orientation q1* q2
    double d0 = 0.0;                                // reference centre distance (the beam length L)
    double kr = 0.0, ks = 0.0, kb = 0.0, kt = 0.0;  // K_r, K_s, chi_b K_b (effective), K_t
    double area = 0.0, inertia = 0.0, polar = 0.0;  // A, I, J (J = 0 in 2D: no twist)
    double radius = 0.0;                            // R_b
    double arm1 = 0.0;  // R1 / (R1 + R2): where the beam meets the crack plane
    // The last step's magnitudes, for the stored energy.
    double normal_force = 0.0, shear_force = 0.0, bend_moment = 0.0, twist_moment = 0.0;
  };

  static State install(const Params& p, const PairGeometry& g, const BodyFrames& fr, std::uint64_t,
                       std::uint64_t) noexcept {
    State s;
    s.d0 = g.d;
    s.r0 = rotate(conj(fr.q1), g.n);
    s.q0 = conj(fr.q1) * fr.q2;
    const double rb = p.min_radius ? std::min(g.R1, g.R2) : 0.5 * g.d;
    s.radius = rb;
    if (g.planar) {
      s.area = 2.0 * rb * g.thickness;
      s.inertia = 2.0 / 3.0 * rb * rb * rb * g.thickness;
    } else {
      s.area = std::numbers::pi * rb * rb;
      s.inertia = 0.25 * std::numbers::pi * rb * rb * rb * rb;
      s.polar = 2.0 * s.inertia;
    }
    const double G = moduli(p).shear;
    s.kr = p.modulus * s.area / s.d0;
    s.ks = G * s.area / s.d0;
    s.kb = p.bending_factor * p.modulus * s.inertia / s.d0;
    s.kt = G * s.polar / s.d0;
    s.arm1 = g.R1 / (g.R1 + g.R2);
    return s;
  }

  static double max_stiffness(const State& s) noexcept { return std::max(s.kr, s.ks); }
  static double max_moment_stiffness(const State& s) noexcept { return std::max(s.kb, s.kt); }
  static double shear_stiffness(const State& s) noexcept { return s.ks; }

  static PairForce compute(const Params& p, State& s, const PairGeometry& g, const BodyFrames& fr,
                           double, BondFailure& fail) noexcept {
    const Quat to_body1 = conj(fr.q1);
    const beam::Deformation f =
        beam::deform(rotate(to_body1, g.n), g.d, s.r0, s.d0, to_body1 * fr.q2 * conj(s.q0));
    // Forces on particle 1 in the body-1 frame (f_r, f_gamma) and the bond frame (the rest).
    const Vec3 f_r = f.r_hat * (s.kr * f.stretch);
    const Vec3 f_gamma = f.shear_gamma * (-s.ks * s.d0);
    const Vec3 z{0.0, 0.0, 1.0};
    const Vec3 f_theta = cross(z, f.bend_axis) * (0.5 * s.ks * s.d0 * f.bend);
    const Vec3 m_bend = f.bend_axis * (s.kb * f.bend);
    const Vec3 m_twist = z * (s.kt * f.twist);
    // In the world frame, on particle 2 (§0.3).
    const Vec3 shear_body1 = f_gamma + rotate(f.bond_frame, f_theta);
    Vec3 force = -rotate(fr.q1, f_r + shear_body1);
    const Vec3 couple = -rotate(fr.q1, rotate(f.bond_frame, m_bend + m_twist));
    s.normal_force = -s.kr * f.stretch;
    s.shear_force = norm(shear_body1);
    s.bend_moment = norm(m_bend);
    s.twist_moment = s.kt * f.twist;
    // Peak stresses on the beam's rim (tension-positive sigma).
    const double sigma =
        -s.normal_force / s.area + p.moment_factor * s.bend_moment * s.radius / s.inertia;
    const double tau =
        s.shear_force / s.area +
        (s.polar > 0.0 ? p.twist_factor * std::abs(s.twist_moment) * s.radius / s.polar : 0.0);
    const double tensile_index = sigma * p.tan_friction / p.cohesion;
    const double shear_limit = p.cohesion - sigma * p.tan_friction;
    const bool tensile = tensile_index > p.tensile_cutoff;
    const bool shear = !tensile && tau > shear_limit;
    if (tensile || shear) {
      fail.broken = true;
      fail.mode = tensile ? CrackMode::Tensile : CrackMode::Shear;
      fail.Fn = s.normal_force;
      fail.Fs = s.shear_force;
      fail.Mt = s.twist_moment;
      fail.Mb = s.bend_moment;
      fail.sigma = sigma;
      fail.tau = tau;
      fail.ratio_t = tensile_index / p.tensile_cutoff;
      fail.ratio_s =
          shear_limit > 0.0 ? tau / shear_limit : std::numeric_limits<double>::quiet_NaN();
      fail.bond_radius = s.radius;
      fail.point_shift = point_shift(s, g);
      fail.energy = energy(s);
      return {};
    }
    // The couple of moving the force from the geometry's contact point to the beam's keeps the
    // lever-arm torques those of the beam (§4.2 step 8).
    return {force, couple + cross(g.n * point_shift(s, g), force)};
  }

  // The beam meets the crack plane at x1 + arm1 d; the geometry's contact point lies at
  // x1 + (R1 - delta / 2) n. Zero for touching grains.
  static double point_shift(const State& s, const PairGeometry& g) noexcept {
    return g.d * s.arm1 - g.R1 + 0.5 * g.delta;
  }

  static BondEnergy energy(const State& s) noexcept {
    BondEnergy e;
    const double en = 0.5 * s.normal_force * s.normal_force / s.kr;
    (s.normal_force < 0.0 ? e.tension : e.compression) = en;
    e.shear = 0.5 * s.shear_force * s.shear_force / s.ks;
    e.bending = s.kb > 0.0 ? 0.5 * s.bend_moment * s.bend_moment / s.kb : 0.0;
    e.twisting = s.kt > 0.0 ? 0.5 * s.twist_moment * s.twist_moment / s.kt : 0.0;
    return e;
  }
};

}  // namespace breccia
