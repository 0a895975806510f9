#pragma once
// The quaternion bond of seed 004 (Zhao & Collins 2024), specified through its reference
// implementation LAMMPS bond_style bpm/rotational (docs/physics.md §4.3): the beam kinematics of
// §4.2 with chi_b = 1 and the present length d as the arm of both shear terms, and an additive
// breakage index B = <-F_n> / F_n^max + F_s / F_s^max + M_b / M_b^max + M_t / M_t^max >= 1.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "breccia/law/beam.hpp"
#include "breccia/law/beam_lanes.hpp"
#include "breccia/law/pair.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

struct QuaternionBond : beam::BeamLaw<QuaternionBond> {
  static constexpr std::string_view name = "quaternion_bond";
  static constexpr std::string_view summary =
      "Quaternion (total) bond of LAMMPS bpm/rotational: normal, shear, bending and twisting "
      "loads with an additive breakage index.";

  struct Params {
    double modulus = 10e9;             // E_b
    double poisson_ratio = 0.25;       // nu_b
    double tensile_strength = 20e6;    // sigma_t,b: F_n^max = sigma A, M_b^max = sigma I / R_b
    double shear_strength = 20e6;      // c_b: F_s^max = c A, M_t^max = c J / R_b
    bool signed_normal = false;        // LAMMPS: -F_n (compression lowers B), else max(0, -F_n)
    bool contact_while_bonded = true;  // false: no contact between bonded grains
    std::uint8_t unused[6]{};          // named, not padding (core/archive.hpp)
    RunGeometry run;                   // set by the engine: the section's shape
    // Derived by prepare(), not input: the strengths' reciprocals, for the per-step test.
    double inv_tensile_strength = 1.0 / 20e6, inv_shear_strength = 1.0 / 20e6;
  };
  static void prepare(Params& p) noexcept {
    p.inv_tensile_strength = 1.0 / p.tensile_strength;
    p.inv_shear_strength = 1.0 / p.shear_strength;
  }
  static constexpr std::array<ParamField<Params>, 6> fields() {
    return {{
        {"modulus", "Pa", &Params::modulus, 0, kInf, false, true,
         "bond Young's modulus E_b: K_r = E_b A / d0, K_b = E_b I / d0"},
        {"poisson_ratio", "-", &Params::poisson_ratio, -1, 0.5, false, false,
         "nu_b: G_b = E_b / (2 (1 + nu_b)), K_s = G_b A / d0, K_t = G_b J / d0"},
        {"tensile_strength", "Pa", &Params::tensile_strength, 0, kInf, false, true,
         "sigma_t,b: F_n^max = sigma_t,b A, M_b^max = sigma_t,b I / R_b (ESyS: c_b / tan phi_b)"},
        {"shear_strength", "Pa", &Params::shear_strength, 0, kInf, false, true,
         "c_b: F_s^max = c_b A, M_t^max = c_b J / R_b"},
        {"signed_normal", "-", &Params::signed_normal, 0, 0, true, true,
         "normal term -F_n / F_n^max as LAMMPS (compression lowers the index, which is kept >= 0) "
         "instead of max(0, -F_n) / F_n^max"},
        {"contact_while_bonded", "-", &Params::contact_while_bonded, 0, 0, true, true,
         "the contact law also acts between overlapping bonded grains (false: as LAMMPS without "
         "overlay/pair; their contact energy is booked as deleted)"},
    }};
  }
  static Params example_params() {
    Params p;
    prepare(p);
    return p;
  }
  static BondModuli moduli(const Params& p) noexcept {
    return isotropic_moduli(p.modulus, p.poisson_ratio);
  }
  static bool contact_while_bonded(const Params& p) noexcept { return p.contact_while_bonded; }

  // Planar spheres keep the disc section (§4.3): a 2D run of them is a 3D run in the plane.
  static beam::BeamModuli beam_moduli(const Params& p) noexcept {
    return {p.modulus, moduli(p).shear, 1.0, true};
  }
  static State install(const Params&, const PairGeometry& g, const BodyFrames& fr, std::uint64_t,
                       std::uint64_t) noexcept {
    return beam::install(g, fr);
  }

  // The breakage index B of the present loads; its larger part, tensile or shear, names the mode
  // (the index itself defines none).
  static BondFailure assess(const Params& p, const State& s, const BondRadii& r) noexcept {
    return assess(p, s, section(p, s, r));
  }
  static BondFailure assess(const Params& p, const State& s, const beam::BeamSection& c) noexcept {
    BondFailure f;
    const double tension = p.signed_normal ? -s.normal_force : std::max(0.0, -s.normal_force);
    // Peak stresses of the moments and the shear force (J = 0 in 2D: 1 / J reads 0).
    const double bend_stress = s.bend_moment * c.radius * c.inv_inertia;
    const double twist_stress = std::abs(s.twist_moment) * c.radius * c.inv_polar;
    const double shear_stress = s.shear_force * c.inv_area;
    const double tensile_index = (tension * c.inv_area + bend_stress) * p.inv_tensile_strength;
    const double shear_index = (shear_stress + twist_stress) * p.inv_shear_strength;
    f.index = std::max(0.0, tensile_index + shear_index);
    f.broken = f.index >= 1.0;
    f.mode = tensile_index >= shear_index ? CrackMode::Tensile : CrackMode::Shear;
    f.Fn = s.normal_force;
    f.Fs = s.shear_force;
    f.Mt = s.twist_moment;
    f.Mb = s.bend_moment;
    f.sigma = -s.normal_force * c.inv_area + bend_stress;
    f.tau = shear_stress + twist_stress;
    f.ratio_t = tensile_index;
    f.ratio_s = shear_index;
    f.bond_radius = c.radius;
    return f;
  }

  // Four 3D bonds at a time (beam_lanes.hpp), for a run in 3D (p.run not planar): compute() of
  // each bond where it stands (to the bit without fused multiply-adds). A bond that breaks or
  // leaves the series' range stands false and goes through compute(). Always inlined, so that
  // the pair pass's x86-64-v3 copy holds it (core/instruction_set.hpp).
  [[gnu::always_inline]] static void compute_lanes(const Params& p,
                                                   const beam::LaneBond (&b)[beam::kLanes],
                                                   beam::LaneResult (&out)[beam::kLanes]) noexcept {
    beam::LaneLoads L;
    beam::lanes_half_length_beams(b, p.modulus, moduli(p).shear, L);
    for (int l = 0; l < beam::kLanes; ++l) {
      const bool stands = L.small[l] && !assess(p, *b[l].state, L.section.lane(l)).broken;
      out[l] = beam::lane_result(L, l, stands);
    }
  }

  static PairForce compute(const Params& p, State& s, const PairGeometry& g, const BodyFrames& fr,
                           double, BondFailure& fail) noexcept {
    // LAMMPS's arms: the present length for both shear terms.
    const beam::BeamSection c = section(p, s, radii_of(g));
    const PairForce pf = beam::loads(s, c, g, fr, g.d, g.d);
    const BondFailure judged = assess(p, s, c);
    if (judged.broken) {
      fail = judged;
      beam::record(s, c, g, fail);
      return {};
    }
    return pf;
  }
};

}  // namespace breccia
