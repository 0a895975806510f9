#pragma once
// Hertz normal contact with an incremental Mindlin no-slip tangential spring and Coulomb friction
// (docs/physics.md §3.3), unloading rescale of the shear force after LAMMPS
// `mindlin_rescale/force`, Tsuji-type dashpots (§2.2). In 2D it needs planar-sphere bodies (§3.4):
// disks have no Hertz law.
#include <array>
#include <cmath>
#include <numbers>

#include "breccia/law/frictional.hpp"
#include "breccia/law/param_table.hpp"
#include "breccia/law/rolling_resistance.hpp"

namespace breccia {

// The parameters, shared by the law's two state layouts (see LinearContactLaw).
struct HertzMindlinParams {
  double shear_modulus = 29e9;  // G of the grain material
  double poisson_ratio = 0.2;   // nu
  double friction = 0.5;
  double normal_damping_ratio = 0;
  double shear_damping_ratio = 0;
  bool unloading_rescale = true;
  std::uint8_t unused[7]{};     // named, not padding (core/archive.hpp)
  double rolling_friction = 0;  // mu_r (§3.5)
  double twisting_friction = 0;
  double rolling_damping_ratio = 0;
};

template <bool Rolling>
struct HertzMindlinLaw {
  static constexpr std::string_view name = "hertz_mindlin";
  static constexpr std::string_view summary =
      "Hertz normal force, Mindlin no-slip tangential stiffness, Coulomb friction.";
  static constexpr bool rolling = Rolling;
  template <bool R>
  using with_rolling = HertzMindlinLaw<R>;

  using Params = HertzMindlinParams;
  static constexpr std::array<ParamField<Params>, 9> fields() {
    return with_rolling_fields<Params, 6>({{
        {"shear_modulus", "Pa", &Params::shear_modulus, 0, kInf, false, true,
         "grain shear modulus G"},
        {"poisson_ratio", "-", &Params::poisson_ratio, -1, 0.5, false, false,
         "grain Poisson ratio nu"},
        {"friction", "-", &Params::friction, 0, kInf, true, true,
         "Coulomb friction coefficient mu"},
        {"normal_damping_ratio", "-", &Params::normal_damping_ratio, 0, 1, true, false,
         "damping ratio of the Tsuji normal dashpot (0 = none)"},
        {"shear_damping_ratio", "-", &Params::shear_damping_ratio, 0, 1, true, false,
         "damping ratio of the tangential dashpot (0 = none)"},
        {"unloading_rescale", "-", &Params::unloading_rescale, 0, 0, true, true,
         "scale the stored shear force by a_new/a_old when the contact radius shrinks"},
    }});
  }
  static Params example_params() { return {}; }

  struct State : RollingSlot<Rolling> {
    Vec3 shear_force;
    Vec3 n_old;
    double normal_force = 0.0;  // elastic Hertz force
    double overlap = 0.0;       // delta of the last step
    double kt = 0.0;            // tangential stiffness of the last step
  };

  // Effective modulus E* and shear modulus G* for identical grains, or grain on a rigid wall.
  static double e_star(const Params& p, bool wall) noexcept {
    const double E = 2.0 * p.shear_modulus * (1.0 + p.poisson_ratio);
    const double one = (1.0 - p.poisson_ratio * p.poisson_ratio) / E;
    return 1.0 / (wall ? one : 2.0 * one);
  }
  static double g_star(const Params& p, bool wall) noexcept {
    const double one = (2.0 - p.poisson_ratio) / p.shear_modulus;
    return 1.0 / (wall ? one : 2.0 * one);
  }
  // A flat wall has R1 = 0 (infinite curvature radius); a sphere wall its own radius.
  static double r_star(const PairGeometry& g) noexcept {
    if (g.wall && !(g.R1 > 0.0)) return g.R2;
    return g.R1 * g.R2 / (g.R1 + g.R2);
  }

  // Tangent stiffnesses at the current overlap, for the time-step estimate (§1.5); the stiffness
  // vanishes at first touch, so the engine also applies the Rayleigh limit below.
  static void timestep_stiffness(const Params& p, const PairGeometry& g, double& kn,
                                 double& ks) noexcept {
    const double a = std::sqrt(r_star(g) * std::max(g.delta, 0.0));
    kn = 2.0 * e_star(p, g.wall) * a;
    ks = 8.0 * g_star(p, g.wall) * a;
  }
  // Rayleigh-wave time of the smallest particle (§1.5, Li, Xu & Thornton 2005).
  static double rayleigh_time_step(const Params& p, double r_min, double density) noexcept {
    return std::numbers::pi * r_min * std::sqrt(density / p.shear_modulus) /
           (0.1631 * p.poisson_ratio + 0.8766);
  }

  // The Hertz quantities at the pair's overlap: contact radius a = sqrt(R* delta), normal force
  // 4/3 E* sqrt(R*) delta^(3/2), tangential stiffness 8 G* a.
  struct Hertz {
    double r_star, a, e_star, fn, kt;
  };
  static Hertz hertz(const Params& p, const PairGeometry& g) noexcept {
    Hertz h;
    h.r_star = r_star(g);
    h.a = std::sqrt(h.r_star * g.delta);
    h.e_star = e_star(p, g.wall);
    h.fn = 4.0 / 3.0 * h.e_star * h.a * g.delta;
    h.kt = 8.0 * g_star(p, g.wall) * h.a;
    return h;
  }
  // Separated: the contact is deleted; its shear spring energy leaves without work.
  static PairForce separate(State& s, PairDissipation& dis) noexcept {
    if (s.kt > 0.0) dis.deleted += 0.5 * norm2(s.shear_force) / s.kt + rolling_energy(s);
    s = State{};
    return {};
  }

  // Frictionless and without dashpots, the shear force stays zero and the force is the Hertz
  // normal force alone: a function of the pair's shape, so the pair pass need not load the
  // grains' velocities (the packings' vessel runs so).
  static bool needs_motion_with(const Params& p) noexcept {
    return p.friction > 0.0 || p.normal_damping_ratio > 0.0 || p.shear_damping_ratio > 0.0 ||
           (Rolling && rolling_limits(p).on());
  }

  static PairForce compute(const Params& p, State& s, const PairGeometry& g, double dt,
                           PairDissipation& dis) noexcept {
    if (needs_motion_with(p)) return compute_with_motion(p, s, g, dt, dis);
    // What compute_with_motion gives with a zero friction limit, without reading g's motion.
    if (g.delta <= 0.0) return separate(s, dis);
    const Hertz h = hertz(p, g);
    s = State{};
    s.n_old = g.n;
    s.normal_force = h.fn;
    s.overlap = g.delta;
    s.kt = h.kt;
    return {g.n * h.fn, {}};
  }

  // The general law; with needs_motion_with false it is the reference of compute's shortcut.
  static PairForce compute_with_motion(const Params& p, State& s, const PairGeometry& g, double dt,
                                       PairDissipation& dis) noexcept {
    if (g.delta <= 0.0) return separate(s, dis);
    const Hertz h = hertz(p, g);
    const double fn = h.fn, kt = h.kt;
    Vec3 fs;
    if (s.kt > 0.0) {
      const PlaneCarry carry = contact_carry(s.n_old, g, dt);
      fs = carry.apply(s.shear_force);
      if constexpr (Rolling) s.rolling.moment = carry.apply(s.rolling.moment);
      const double e_before = 0.5 * norm2(fs) / s.kt;
      const double a_old = std::sqrt(h.r_star * s.overlap);
      if (p.unloading_rescale && h.a < a_old) fs *= h.a / a_old;
      // Energy the shear spring loses (or gains) when its stiffness changes, not by work (§2.4).
      dis.deleted += e_before - 0.5 * norm2(fs) / kt;
    }
    const double vn = g.vn();
    const Vec3 vt = g.vc - g.n * vn;
    const ShearResult shear = coulomb_shear(fs, vt, kt, dt, p.friction * fn, dis);
    s.shear_force = shear.force;
    s.n_old = g.n;
    s.normal_force = fn;
    s.overlap = g.delta;
    s.kt = kt;

    Vec3 force = g.n * fn + shear.force;
    Vec3 couple;
    if constexpr (Rolling) couple = rolling_step(rolling_limits(p), s.rolling, g, kt, fn, dt, dis);
    if (p.normal_damping_ratio > 0.0 || p.shear_damping_ratio > 0.0) {
      // Tsuji form with the tangent stiffnesses (§2.2).
      const double c = 2.0 * std::sqrt(5.0 / 6.0), m = g.m_star();
      force += dashpot_force(g, fn, vn, vt,
                             c * p.normal_damping_ratio * std::sqrt(2.0 * h.e_star * h.a * m),
                             c * p.shear_damping_ratio * std::sqrt(kt * m), shear.sliding, dt, dis);
    }
    return {force, couple};
  }

  // compute()'s force of the last step, elastic normal plus shear, from the state it left (zero
  // once separated); with dashpots the step's force also had a damping part that no state keeps.
  static bool state_holds_force(const Params& p) noexcept {
    return p.normal_damping_ratio == 0.0 && p.shear_damping_ratio == 0.0;
  }
  static Vec3 state_force(const State& s) noexcept {
    return s.n_old * s.normal_force + s.shear_force;
  }

  static double stored_energy(const Params&, const State& s) noexcept {
    if (s.kt == 0.0) return 0.0;
    return 0.4 * s.normal_force * s.overlap + 0.5 * norm2(s.shear_force) / s.kt + rolling_energy(s);
  }
};

using HertzMindlin = HertzMindlinLaw<false>;

}  // namespace breccia
