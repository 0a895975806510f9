#pragma once
// Potyondy & Cundall (2004) parallel bond, with the cohesion-friction shear strength of the later
// linear parallel bond (docs/physics.md §4.1): an incremental elastic beam glued over a disc (3D)
// or a slab of thickness t (2D) of radius R_bar = lambda min(R1, R2), carrying normal and shear
// force, twisting and bending moment. Fails in tension when sigma_max >= sigma_c (checked first),
// else in shear when tau_max >= c - sigma_avg tan(phi); with phi = 0 this is the 2004 model.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "breccia/core/rng.hpp"
#include "breccia/law/pair.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

struct ParallelBond {
  static constexpr std::string_view name = "parallel_bond";
  static constexpr std::string_view summary =
      "Potyondy-Cundall parallel bond (incremental), tension then Mohr-Coulomb shear failure.";
  static constexpr bool needs_frames = false;  // incremental: velocities suffice

  struct Params {
    double radius_multiplier = 1.0;  // lambda_bar
    double modulus = 10e9;           // E_bar_c
    double stiffness_ratio = 2.5;    // kappa_bar = k_n / k_s
    double tensile_strength = 20e6;  // mean sigma_c
    double tensile_strength_sd = 0;  // standard deviation of sigma_c
    double cohesion = 20e6;          // mean c (tau_c of the 2004 model)
    double cohesion_sd = 0;
    double friction_angle_deg = 0;  // phi_bar; 0 = 2004 model
    double moment_factor = 1.0;     // beta_bar
    // Derived by prepare(), not input: tan(phi) and 1 / kappa_bar, kept out of the per-step
    // kernel.
    double tan_friction = 0.0;
    double shear_fraction = 1.0 / 2.5;
    RunGeometry run;  // set by the engine: the section's shape (disc in 3D, slab in 2D)
  };
  static void prepare(Params& p) noexcept {
    p.tan_friction = std::tan(p.friction_angle_deg * kDegree);
    p.shear_fraction = 1.0 / p.stiffness_ratio;
  }
  static constexpr std::array<ParamField<Params>, 9> fields() {
    return {{
        {"radius_multiplier", "-", &Params::radius_multiplier, 0, 1, false, true,
         "lambda: bond radius R_bar = lambda min(R1, R2)"},
        {"modulus", "Pa", &Params::modulus, 0, kInf, false, true,
         "bond modulus E_bar; k_n = E_bar / (R1 + R2) per unit area"},
        {"stiffness_ratio", "-", &Params::stiffness_ratio, 0, kInf, false, true,
         "kappa_bar = k_n / k_s"},
        {"tensile_strength", "Pa", &Params::tensile_strength, 0, kInf, false, true,
         "mean tensile strength sigma_c"},
        {"tensile_strength_sd", "Pa", &Params::tensile_strength_sd, 0, kInf, true, true,
         "standard deviation of sigma_c (normal, redrawn when <= 0)"},
        {"cohesion", "Pa", &Params::cohesion, 0, kInf, false, true,
         "mean cohesion c (the shear strength tau_c when the friction angle is 0)"},
        {"cohesion_sd", "Pa", &Params::cohesion_sd, 0, kInf, true, true,
         "standard deviation of c (normal, redrawn when <= 0)"},
        {"friction_angle_deg", "deg", &Params::friction_angle_deg, 0, 90, true, false,
         "bond friction angle phi: tau_c = c - sigma_avg tan(phi), sigma_avg tension-positive"},
        {"moment_factor", "-", &Params::moment_factor, 0, 1, true, true,
         "beta: share of the moments in the peak stresses"},
    }};
  }
  static Params example_params() {
    Params p;
    prepare(p);
    return p;
  }

  // E_bar and the shear modulus k_s L = E_bar / kappa_bar of the papers' crack energy.
  static BondModuli moduli(const Params& p) noexcept {
    return {p.modulus, p.modulus / p.stiffness_ratio};
  }
  // The linear contact acts in parallel with the bond (docs/physics.md §4.0).
  static bool contact_while_bonded(const Params&) noexcept { return true; }

  // What a bond carries from step to step, and the strengths drawn at installation; its section
  // and stiffnesses follow from its grains' radii and the parameters (section()), which keeps a
  // bond at 104 bytes.
  struct State {
    Vec3 shear_force;  // F_s
    Vec3 bend_moment;  // M_b
    Vec3 n_old;        // normal of the previous step; zero until the first step after install
    double normal_force = 0.0;  // F_n, compression-positive
    double twist_moment = 0.0;  // M_t
    double tensile_strength = 0.0;
    double cohesion = 0.0;
  };

  // R_bar = lambda min(R1, R2) and k_n = E_bar / (R1 + R2), the beam's length being the sum of
  // the radii.
  static double bond_radius(const Params& p, const BondRadii& r) noexcept {
    return p.radius_multiplier * std::min(r.R1, r.R2);
  }
  static double stiffness_per_area(const Params& p, const BondRadii& r) noexcept {
    return p.modulus / (r.R1 + r.R2);
  }

  // The bond's section and what follows from it: a disc of radius R_bar in 3D, a slab of the
  // disks' thickness t in 2D (no twist).
  struct Section {
    double kn, ks;       // force stiffnesses K_n = k_n A, K_s = K_n / kappa_bar
    double kb, kt;       // moment stiffnesses K_b = k_n I, K_t = k_n / kappa_bar J (0 in 2D)
    double inv_area;     // 1 / A
    double bend_coeff;   // R_bar / I: peak bending stress per unit moment
    double twist_coeff;  // R_bar / J (0 in 2D)
  };
  static Section section(const Params& p, const BondRadii& r) noexcept {
    const double rb = bond_radius(p, r), kn_area = stiffness_per_area(p, r);
    double area = 0.0, inertia = 0.0, polar = 0.0;
    if (p.run.planar) {
      area = 2.0 * rb * p.run.thickness;                     // slab of thickness t
      inertia = 2.0 / 3.0 * rb * rb * rb * p.run.thickness;  // I = 2/3 R^3 t; no twist in 2D
    } else {
      area = std::numbers::pi * rb * rb;  // disc
      inertia = 0.25 * std::numbers::pi * rb * rb * rb * rb;
      polar = 2.0 * inertia;
    }
    // One division, whose result only the failure test waits for: every bond derives its
    // section at every step.
    const double inv_area_inertia = 1.0 / (area * inertia);
    Section c;
    c.kn = kn_area * area;
    c.ks = c.kn * p.shear_fraction;
    c.kb = kn_area * inertia;
    c.kt = kn_area * p.shear_fraction * polar;
    c.inv_area = inertia * inv_area_inertia;
    c.bend_coeff = rb * (area * inv_area_inertia);
    c.twist_coeff = polar > 0.0 ? 0.5 * c.bend_coeff : 0.0;  // R_bar / J, J = 2 I
    return c;
  }

  // Installs a stress-free bond at the current geometry. Strengths are drawn from the counter-based
  // generator keyed by the bond tag, so they do not depend on creation order.
  static State install(const Params& p, const PairGeometry&, const BodyFrames&, std::uint64_t seed,
                       std::uint64_t bond_tag) noexcept {
    State s;
    constexpr std::uint64_t kTensileStream = 0x7e51, kCohesionStream = 0xc0e5;
    s.tensile_strength =
        positive_normal(p.tensile_strength, p.tensile_strength_sd, seed, kTensileStream, bond_tag);
    s.cohesion = positive_normal(p.cohesion, p.cohesion_sd, seed, kCohesionStream, bond_tag);
    return s;
  }

  // Largest translational and rotational stiffness for the time-step estimate (§1.5).
  static double max_stiffness(const Params& p, const State&, const BondRadii& r) noexcept {
    const Section c = section(p, r);
    return std::max(c.kn, c.ks);
  }
  static double max_moment_stiffness(const Params& p, const State&, const BondRadii& r) noexcept {
    const Section c = section(p, r);
    return std::max(c.kb, c.kt);
  }
  static double normal_stiffness(const Params& p, const State&, const BondRadii& r) noexcept {
    return section(p, r).kn;
  }
  static double shear_stiffness(const Params& p, const State&, const BondRadii& r) noexcept {
    return section(p, r).ks;
  }

  // One step. On failure the bond's force is not applied (§4.0 decision) and `fail` carries the
  // record; the caller removes the bond.
  static PairForce compute(const Params& p, State& s, const PairGeometry& g, const BodyFrames&,
                           double dt, BondFailure& fail) noexcept {
    // The increments use v^{n-1/2}, the velocity that carried the particles from x^{n-1} to x^n.
    // A bond installed at x^n has not seen that motion, so its first step adds nothing.
    const bool fresh = s.n_old.x == 0.0 && s.n_old.y == 0.0 && s.n_old.z == 0.0;
    if (fresh) dt = 0.0;
    // 1. Carry the shear force and bending moment into the current contact plane.
    Vec3 fs = s.shear_force, mb = s.bend_moment;
    if (!fresh) {
      const PlaneCarry carry(s.n_old, g.n, 0.5 * dot(g.w1 + g.w2, g.n) * dt);
      fs = carry.apply(fs);
      mb = carry.apply(mb);
    }
    // 2. Increments from the relative motion.
    const double vn = g.vn();
    const Vec3 vt = g.vc - g.n * vn;
    const Vec3 wr = g.w2 - g.w1;
    const double wtw = dot(wr, g.n);
    const Vec3 wb = wr - g.n * wtw;
    const Section c = section(p, radii_of(g));
    const double fn = s.normal_force - c.kn * vn * dt;
    fs -= vt * (c.ks * dt);
    const double mt = s.twist_moment - c.kt * wtw * dt;
    mb -= wb * (c.kb * dt);
    s.normal_force = fn;
    s.shear_force = fs;
    s.twist_moment = mt;
    s.bend_moment = mb;
    s.n_old = g.n;

    // The decision needs only the peak stresses; the record's ratios are made when it breaks.
    const PeakStresses k = peak_stresses(p, s, c);
    if (k.tensile(s) || k.shear()) {
      fail = record(p, s, radii_of(g), k);
      fail.energy = energy(s, c);
      return {};
    }
    return {g.n * fn + fs, g.n * mt + mb};
  }

  // compute()'s force of the last step from the state it left (zero before the first step and
  // for a bond that broke, whose force was not applied: the engine reads intact bonds only).
  static bool state_holds_force(const Params&) noexcept { return true; }
  static Vec3 state_force(const State& s) noexcept {
    return s.n_old * s.normal_force + s.shear_force;
  }

  // The peak stresses on the periphery of the cement (tension-positive sigma) and the shear
  // strength at the present mean normal stress: tensile when sigma_max reaches sigma_c (tested
  // first), else shear when tau_max reaches c - sigma_avg tan(phi).
  struct PeakStresses {
    double mb_abs, fs_abs, sigma_max, tau_max, tau_c;
    bool tensile(const State& s) const noexcept { return sigma_max >= s.tensile_strength; }
    bool shear() const noexcept { return tau_max >= tau_c; }
  };
  static PeakStresses peak_stresses(const Params& p, const State& s, const Section& c) noexcept {
    PeakStresses k;
    k.mb_abs = norm(s.bend_moment);
    k.fs_abs = norm(s.shear_force);
    const double sigma_avg = -s.normal_force * c.inv_area;
    k.sigma_max = sigma_avg + p.moment_factor * k.mb_abs * c.bend_coeff;
    k.tau_max = k.fs_abs * c.inv_area + p.moment_factor * std::abs(s.twist_moment) * c.twist_coeff;
    k.tau_c = s.cohesion - sigma_avg * p.tan_friction;
    return k;
  }

  // The failure criterion on the bond's present loads, as the crack record and snapshots give it.
  static BondFailure assess(const Params& p, const State& s, const BondRadii& r) noexcept {
    return record(p, s, r, peak_stresses(p, s, section(p, r)));
  }

  static BondFailure record(const Params& p, const State& s, const BondRadii& r,
                            const PeakStresses& k) noexcept {
    BondFailure f;
    const bool tensile = k.tensile(s);
    f.broken = tensile || k.shear();
    f.mode = tensile || !k.shear() ? CrackMode::Tensile : CrackMode::Shear;
    f.Fn = s.normal_force;
    f.Fs = k.fs_abs;
    f.Mt = s.twist_moment;
    f.Mb = k.mb_abs;
    f.sigma = k.sigma_max;
    f.tau = k.tau_max;
    f.ratio_t = k.sigma_max / s.tensile_strength;
    f.ratio_s = k.tau_c > 0.0 ? k.tau_max / k.tau_c : std::numeric_limits<double>::quiet_NaN();
    f.index = larger_ratio(f.ratio_t, f.ratio_s);
    f.bond_radius = bond_radius(p, r);
    return f;
  }

  // Stored elastic energy by component (§4.0).
  static BondEnergy energy(const Params& p, const State& s, const BondRadii& r) noexcept {
    return energy(s, section(p, r));
  }
  static BondEnergy energy(const State& s, const Section& c) noexcept {
    BondEnergy e;
    const double en = 0.5 * s.normal_force * s.normal_force / c.kn;
    (s.normal_force < 0.0 ? e.tension : e.compression) = en;
    e.shear = 0.5 * norm2(s.shear_force) / c.ks;
    e.bending = 0.5 * norm2(s.bend_moment) / c.kb;
    e.twisting = c.kt > 0.0 ? 0.5 * s.twist_moment * s.twist_moment / c.kt : 0.0;
    return e;
  }

  static constexpr double kDegree = std::numbers::pi / 180.0;
};

}  // namespace breccia
