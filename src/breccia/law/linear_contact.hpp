#pragma once
// Linear spring contact with Coulomb friction and optional dashpots (docs/physics.md §3.1, §3.2,
// §2.2), after Cundall & Strack (1979) with the PFC 5+ "deformability" stiffness k_n = A E_c / L.
// This is the exemplar every contact law copies: Params with a field table, per-contact State,
// and noexcept kernels.
#include <array>
#include <cmath>
#include <numbers>

#include "breccia/law/frictional.hpp"
#include "breccia/law/param_table.hpp"
#include "breccia/law/rolling_resistance.hpp"

namespace breccia {

// The parameters, shared by the law's two state layouts (below).
struct LinearContactParams {
  double modulus = 10e9;            // E_c
  double stiffness_ratio = 2.5;     // kappa = k_n / k_s
  double friction = 0.5;            // mu
  double normal_damping_ratio = 0;  // beta_n
  double shear_damping_ratio = 0;   // beta_s
  double rolling_friction = 0;      // mu_r (§3.5)
  double twisting_friction = 0;     // mu_t
  double rolling_damping_ratio = 0;
  bool ball_stiffness = false;  // PFC 3.x/4 convention (Potyondy & Cundall 2004)
  std::uint8_t unused[7]{};     // named, not padding (core/archive.hpp)
};

// Rolling: whether each contact's state holds the rolling and twisting moments (§3.5). The
// registry names the law without them; the engine takes the variant with them when the
// parameters turn rolling resistance on (make_contact_model), so that runs without it keep a
// 64-byte state.
template <bool Rolling>
struct LinearContactLaw {
  static constexpr std::string_view name = "linear";
  static constexpr std::string_view summary =
      "Linear spring with Coulomb friction; k_n = A E_c / L (PFC 5+ deformability).";
  static constexpr bool rolling = Rolling;
  template <bool R>
  using with_rolling = LinearContactLaw<R>;

  using Params = LinearContactParams;
  static constexpr std::array<ParamField<Params>, 9> fields() {
    return with_rolling_fields<Params, 6>({{
        {"modulus", "Pa", &Params::modulus, 0, kInf, false, true,
         "effective contact modulus E_c; k_n = A E_c / L with A = pi r^2 (2 r t in 2D), "
         "r = min(R1, R2), L = R1 + R2 (wall: r = L = R)"},
        {"stiffness_ratio", "-", &Params::stiffness_ratio, 0, kInf, false, true,
         "kappa = k_n / k_s"},
        {"friction", "-", &Params::friction, 0, kInf, true, true,
         "Coulomb friction coefficient mu"},
        {"normal_damping_ratio", "-", &Params::normal_damping_ratio, 0, 1, true, false,
         "critical damping ratio of the normal dashpot (0 = none)"},
        {"shear_damping_ratio", "-", &Params::shear_damping_ratio, 0, 1, true, false,
         "critical damping ratio of the shear dashpot (0 = none)"},
        {"ball_stiffness", "-", &Params::ball_stiffness, 0, 0, true, true,
         "PFC 3.x/4 convention (Potyondy & Cundall 2004): each ball has k_n = 4 R E_c (2D: "
         "2 t E_c) and a contact the two in series, 4 E_c R1 R2 / (R1 + R2) (2D: t E_c); a wall "
         "takes the ball's own; false: the PFC 5+ deformability above"},
    }});
  }
  static Params example_params() { return {}; }

  struct State : RollingSlot<Rolling> {
    Vec3 shear_force;           // F_s, kept in the current contact plane
    Vec3 n_old;                 // normal of the previous step (zero: new contact)
    double normal_force = 0.0;  // spring part of F_n, kept for energy and output
    double kn = 0.0;            // normal stiffness of this pair (set at first touch)
  };

  static double normal_stiffness(const Params& p, const PairGeometry& g) noexcept {
    if (p.ball_stiffness) {
      const double one = g.planar ? 2.0 * g.thickness * p.modulus : 4.0 * g.R2 * p.modulus;
      if (g.wall) return one;
      return g.planar ? 0.5 * one : 4.0 * p.modulus * g.R1 * g.R2 / (g.R1 + g.R2);
    }
    const double r = g.wall ? g.R2 : std::min(g.R1, g.R2);
    const double L = g.wall ? g.R2 : g.R1 + g.R2;
    const double area = g.planar ? 2.0 * r * g.thickness : std::numbers::pi * r * r;
    return area * p.modulus / L;
  }
  // Normal and shear stiffness for the time-step estimate (§1.5), for a pair that may touch.
  static void timestep_stiffness(const Params& p, const PairGeometry& g, double& kn,
                                 double& ks) noexcept {
    kn = normal_stiffness(p, g);
    ks = kn / p.stiffness_ratio;
  }

  // Frictionless and without dashpots, the force is the normal spring's alone: a function of the
  // pair's shape, so the pair pass need not load the grains' velocities.
  static bool needs_motion_with(const Params& p) noexcept {
    return p.friction > 0.0 || p.normal_damping_ratio > 0.0 || p.shear_damping_ratio > 0.0 ||
           (Rolling && rolling_limits(p).on());
  }

  // One step of the contact. Returns the force on particle 2; books dissipation into `dis`.
  static PairForce compute(const Params& p, State& s, const PairGeometry& g, double dt,
                           PairDissipation& dis) noexcept {
    if (needs_motion_with(p)) return compute_with_motion(p, s, g, dt, dis);
    // What compute_with_motion gives with a zero friction limit, without reading g's motion.
    if (g.delta <= 0.0) return separate(p, s, dis);
    if (s.kn == 0.0) s.kn = normal_stiffness(p, g);
    const double fn = s.kn * g.delta;
    s.shear_force = {};
    s.n_old = g.n;
    s.normal_force = fn;
    return {g.n * fn, {}};
  }

  // The general law; with needs_motion_with false it is the reference of compute's shortcut.
  static PairForce compute_with_motion(const Params& p, State& s, const PairGeometry& g, double dt,
                                       PairDissipation& dis) noexcept {
    if (g.delta <= 0.0) return separate(p, s, dis);
    const bool has_history = s.kn != 0.0;
    if (!has_history) s.kn = normal_stiffness(p, g);
    const double kn = s.kn;
    const double ks = kn / p.stiffness_ratio;
    Vec3 fs;
    if (has_history) {
      const PlaneCarry carry = contact_carry(s.n_old, g, dt);
      fs = carry.apply(s.shear_force);
      if constexpr (Rolling) s.rolling.moment = carry.apply(s.rolling.moment);
    }
    const double vn = g.vn();
    const Vec3 vt = g.vc - g.n * vn;
    const double fn = kn * g.delta;
    const ShearResult shear = coulomb_shear(fs, vt, ks, dt, p.friction * fn, dis);
    s.shear_force = shear.force;
    s.n_old = g.n;
    s.normal_force = fn;

    Vec3 force = g.n * fn + shear.force;
    Vec3 couple;
    if constexpr (Rolling) couple = rolling_step(rolling_limits(p), s.rolling, g, ks, fn, dt, dis);
    if (p.normal_damping_ratio > 0.0 || p.shear_damping_ratio > 0.0) {
      const double m = g.m_star();
      force +=
          dashpot_force(g, fn, vn, vt, 2.0 * p.normal_damping_ratio * std::sqrt(m * kn),
                        2.0 * p.shear_damping_ratio * std::sqrt(m * ks), shear.sliding, dt, dis);
    }
    return {force, couple};
  }

  // Separated: the contact is deleted; its shear spring energy leaves without work.
  static PairForce separate(const Params& p, State& s, PairDissipation& dis) noexcept {
    if (s.kn > 0.0)
      dis.deleted += 0.5 * norm2(s.shear_force) * p.stiffness_ratio / s.kn + rolling_energy(s);
    s = State{};
    return {};
  }

  // compute()'s force of the last step, elastic normal plus shear, from the state it left (zero
  // once separated); with dashpots the step's force also had a damping part that no state keeps.
  static bool state_holds_force(const Params& p) noexcept {
    return p.normal_damping_ratio == 0.0 && p.shear_damping_ratio == 0.0;
  }
  static Vec3 state_force(const State& s) noexcept {
    return s.n_old * s.normal_force + s.shear_force;
  }

  // Elastic energy stored in the contact (§3.6).
  static double stored_energy(const Params& p, const State& s) noexcept {
    if (s.kn == 0.0) return 0.0;
    return 0.5 * (s.normal_force * s.normal_force + norm2(s.shear_force) * p.stiffness_ratio) /
               s.kn +
           rolling_energy(s);
  }
};

using LinearContact = LinearContactLaw<false>;

}  // namespace breccia
