#pragma once
// ESyS-Particle's rotational brittle beam (BrittleBeamPrms; Wang 2009 kinematics), docs/physics.md
// §4.2: an elastic cylinder (3D) or slab (2D) between the two centres, in a total formulation:
// forces and moments follow from the present positions and orientations against the reference state
// of installation, so nothing drifts. Six relative motions (stretch, two shears, twist, two bends)
// with four stiffnesses; Mohr-Coulomb failure on the beam's peak stresses with a tensile cut-off.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "breccia/law/beam.hpp"
#include "breccia/law/pair.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

struct BrittleBeam : beam::BeamLaw<BrittleBeam> {
  static constexpr std::string_view name = "brittle_beam";
  static constexpr std::string_view summary =
      "ESyS-Particle rotational brittle beam (total formulation), Mohr-Coulomb failure with a "
      "tensile cut-off.";

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
    std::uint8_t unused[6]{};          // named, not padding (core/archive.hpp)
    RunGeometry run;                   // set by the engine: the section's shape
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
    return isotropic_moduli(p.modulus, p.poisson_ratio);
  }
  static bool contact_while_bonded(const Params& p) noexcept { return p.contact_while_bonded; }

  static beam::BeamModuli beam_moduli(const Params& p) noexcept {
    return {p.modulus, moduli(p).shear, p.bending_factor, false, p.min_radius};
  }
  static State install(const Params&, const PairGeometry& g, const BodyFrames& fr, std::uint64_t,
                       std::uint64_t) noexcept {
    return beam::install(g, fr);
  }

  // Mohr-Coulomb on the beam's peak stresses (tension-positive sigma) with the tensile cut-off.
  static BondFailure assess(const Params& p, const State& s, const BondRadii& r) noexcept {
    return assess(p, s, section(p, s, r));
  }
  // The peak stresses (tension-positive sigma; J = 0 in 2D, where 1 / J reads 0) and which
  // branch of the envelope they reach.
  struct Envelope {
    double sigma, tau, tensile_index, shear_limit;
    bool tensile, shear;
  };
  static Envelope envelope(const Params& p, const State& s, const beam::BeamSection& c) noexcept {
    Envelope e;
    e.sigma =
        -s.normal_force * c.inv_area + p.moment_factor * s.bend_moment * c.radius * c.inv_inertia;
    e.tau = s.shear_force * c.inv_area +
            p.twist_factor * std::abs(s.twist_moment) * c.radius * c.inv_polar;
    e.tensile_index = e.sigma * p.tan_friction / p.cohesion;
    e.shear_limit = p.cohesion - e.sigma * p.tan_friction;
    e.tensile = e.tensile_index > p.tensile_cutoff;
    e.shear = !e.tensile && e.tau > e.shear_limit;
    return e;
  }
  static BondFailure assess(const Params& p, const State& s, const beam::BeamSection& c) noexcept {
    return record(p, s, c, envelope(p, s, c));
  }
  static BondFailure record(const Params& p, const State& s, const beam::BeamSection& c,
                            const Envelope& e) noexcept {
    BondFailure f;
    f.broken = e.tensile || e.shear;
    f.mode = e.tensile || !e.shear ? CrackMode::Tensile : CrackMode::Shear;
    f.Fn = s.normal_force;
    f.Fs = s.shear_force;
    f.Mt = s.twist_moment;
    f.Mb = s.bend_moment;
    f.sigma = e.sigma;
    f.tau = e.tau;
    f.ratio_t = e.tensile_index / p.tensile_cutoff;
    f.ratio_s =
        e.shear_limit > 0.0 ? e.tau / e.shear_limit : std::numeric_limits<double>::quiet_NaN();
    f.index = larger_ratio(f.ratio_t, f.ratio_s);
    f.bond_radius = c.radius;
    return f;
  }

  static PairForce compute(const Params& p, State& s, const PairGeometry& g, const BodyFrames& fr,
                           double, BondFailure& fail) noexcept {
    // ESyS's arms: d0 for the shear of the branch rotation and for the rotation-induced shear.
    const beam::BeamSection c = section(p, s, radii_of(g));
    const PairForce pf = beam::loads(s, c, g, fr, s.d0, s.d0);
    const Envelope e = envelope(p, s, c);
    if (!e.tensile && !e.shear) return pf;  // the record's ratios only for a break
    fail = record(p, s, c, e);
    beam::record(s, c, g, fail);
    return {};
  }
};

}  // namespace breccia
