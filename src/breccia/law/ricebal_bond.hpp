#pragma once
// The RICEBAL 2D bond (Morgan 2015; Guo & Morgan 2007; seed 002), as docs/physics.md §4.4
// reconstructs it: an elastic bond between the centres of two planar grains with a total normal
// spring K_n = E_b A_b / d0, an incremental shear spring K_s = G_b A_b / d0 and a bending spring
// K_M = E_b I_b / d0. Overlapping grains also press through their Hertz-Mindlin contact, and the
// failure envelope reads the interface totals (bond plus contact): tensile when
// -f_n / A_b + beta |M| r_b / I_b >= T_b, else shear when |f_s| >= C_b A_b (1 - f_n / f_n,min)
// in tension or C_b A_b + mu f_n in compression. The normal spring may act in tension only.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "breccia/law/pair.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

struct RicebalBond {
  static constexpr std::string_view name = "ricebal_bond";
  static constexpr std::string_view summary =
      "RICEBAL 2D bond (seed 002): elastic normal, shear and bending springs; tensile strength "
      "T_b with the moment, cohesion C_b with friction in compression, on the interface totals.";
  static constexpr bool needs_frames = false;  // the shear and moment follow the velocities
  static constexpr bool planar_only = true;    // a law of disks and planar spheres

  struct Params {
    double modulus = 10e9;           // E_b
    double shear_modulus = 0.0;      // G_b; 0: E_b / (2 (1 + nu_b))
    double poisson_ratio = 0.2;      // nu_b, used only when G_b = 0
    double tensile_strength = 20e6;  // T_b
    double cohesion = 40e6;          // C_b, the shear strength at f_n = 0
    double friction = 0.5;           // mu of the compressive branch C_b A_b + mu f_n
    double moment_factor = 1.0;      // beta: the share of |M| r_b / I_b in the tensile check
    // Derived by prepare(), not input: the G_b the kernel uses.
    double shear_modulus_used = 0.0;
    // The envelope judges the interface totals (bond plus Hertz contact, docs/physics.md §4.4);
    // false: the bond's own loads, the alternative reading of the seed's lost equations.
    bool interface_totals = true;
    // The bond's normal spring acts in compression too (docs/physics.md §4.4); false: only once
    // the grains separate past touching (or past their installed gap), so that compression is
    // the Hertz contact's alone, the seeds' force-displacement figure (seed 000, Fig. S1b).
    bool normal_spring_in_compression = true;
    std::uint8_t unused[6]{};  // named, not padding (core/archive.hpp)
  };
  static void prepare(Params& p) noexcept {
    p.shear_modulus_used =
        p.shear_modulus > 0.0 ? p.shear_modulus : p.modulus / (2.0 * (1.0 + p.poisson_ratio));
  }
  static constexpr std::array<ParamField<Params>, 9> fields() {
    return {{
        {"modulus", "Pa", &Params::modulus, 0, kInf, false, true,
         "bond Young's modulus E_b: K_n = E_b A_b / d0, K_M = E_b I_b / d0"},
        {"shear_modulus", "Pa", &Params::shear_modulus, 0, kInf, true, true,
         "bond shear modulus G_b: K_s = G_b A_b / d0 (0: E_b / (2 (1 + nu_b)))"},
        {"poisson_ratio", "-", &Params::poisson_ratio, -1, 0.5, false, false,
         "nu_b, which sets G_b when shear_modulus = 0"},
        {"tensile_strength", "Pa", &Params::tensile_strength, 0, kInf, false, true,
         "T_b: tensile crack when -f_n / A_b + beta |M| r_b / I_b >= T_b"},
        {"cohesion", "Pa", &Params::cohesion, 0, kInf, false, true,
         "C_b: shear strength C_b A_b at f_n = 0, falling linearly to 0 at f_n = -T_b A_b"},
        {"friction", "-", &Params::friction, 0, kInf, true, true,
         "mu of the compressive shear strength C_b A_b + mu f_n (usually the grains' friction)"},
        {"moment_factor", "-", &Params::moment_factor, 0, 1, true, true,
         "beta: the tensile check is -f_n / A_b + beta |M| r_b / I_b >= T_b (1: the full "
         "bending stress, seed 000; 0: the normal force alone, the seed 002 text's reading)"},
        {"interface_totals", "-", &Params::interface_totals, 0, 0, true, true,
         "true: the envelope judges the interface totals, the bond's loads plus the overlapping "
         "grains' Hertz contact (whose normal force then adds mu f_n^c to the shear strength); "
         "false: the bond's own loads"},
        {"normal_spring_in_compression", "-", &Params::normal_spring_in_compression, 0, 0, true,
         true,
         "true: the bond's normal spring acts from the installed distance in both directions; "
         "false: only in tension past touching (or past an installed gap), compression being the "
         "Hertz contact's alone"},
    }};
  }
  static Params example_params() {
    Params p;
    prepare(p);
    return p;
  }
  static BondModuli moduli(const Params& p) noexcept {
    Params q = p;
    prepare(q);
    return {p.modulus, q.shear_modulus_used};
  }
  // The Hertz-Mindlin contact is added whenever the grains overlap (docs/physics.md §4.0, §4.4).
  static bool contact_while_bonded(const Params&) noexcept { return true; }

  struct State {
    double normal_force = 0.0;  // f_n^b, compression-positive
    double shear_force = 0.0;   // f_s^b along t = z x n (force on particle 2)
    double moment = 0.0;        // M^b about z (couple on particle 2)
    double d0 = 0.0;            // the normal spring's rest length
    double kn = 0.0, ks = 0.0, km = 0.0;
    double area = 0.0, inertia = 0.0, bond_radius = 0.0;
    bool started = false;       // the first step after installation adds no increment
    bool tension_only = false;  // the normal spring pulls but never pushes
    std::uint8_t unused[6]{};   // named, not padding (core/archive.hpp)
  };

  // A stress-free bond over the smaller grain's section: the circle of radius r_b for planar
  // spheres (RICEBAL), the slab 2 r_b t for disks of thickness t (so that bond and contact scale
  // with the same thickness).
  static State install(const Params& p, const PairGeometry& g, const BodyFrames&, std::uint64_t,
                       std::uint64_t) noexcept {
    State s;
    const double rb = std::min(g.R1, g.R2);
    s.bond_radius = rb;
    if (g.planar_sphere) {
      s.area = std::numbers::pi * rb * rb;
      s.inertia = 0.25 * std::numbers::pi * rb * rb * rb * rb;
    } else {
      s.area = 2.0 * rb * g.thickness;
      s.inertia = 2.0 / 3.0 * rb * rb * rb * g.thickness;
    }
    // A spring that acts only in tension rests at touching, or at the installed gap if wider.
    s.tension_only = !p.normal_spring_in_compression;
    s.d0 = s.tension_only ? std::max(g.d, g.R1 + g.R2) : g.d;
    Params q = p;
    prepare(q);
    s.kn = p.modulus * s.area / g.d;
    s.ks = q.shear_modulus_used * s.area / g.d;
    s.km = p.modulus * s.inertia / g.d;
    return s;
  }

  static double max_stiffness(const Params&, const State& s, const BondRadii&) noexcept {
    return std::max(s.kn, s.ks);
  }
  static double max_moment_stiffness(const Params&, const State& s, const BondRadii&) noexcept {
    return s.km;
  }
  static double normal_stiffness(const Params&, const State& s, const BondRadii&) noexcept {
    return s.kn;
  }
  static double shear_stiffness(const Params&, const State& s, const BondRadii&) noexcept {
    return s.ks;
  }

  // The bond's own loads of this step (forces on particle 2), before the failure check.
  static PairForce loads(State& s, const PairGeometry& g, double dt) noexcept {
    if (!s.started) dt = 0.0;  // v^{n-1/2} moved the grains before the bond existed
    s.started = true;
    const Vec3 t{-g.n.y, g.n.x, 0.0};  // z x n
    s.normal_force = -s.kn * (g.d - s.d0);
    if (s.tension_only) s.normal_force = std::min(s.normal_force, 0.0);
    s.shear_force -= s.ks * dot(g.vc, t) * dt;
    s.moment -= s.km * (g.w2.z - g.w1.z) * dt;
    return {g.n * s.normal_force + t * s.shear_force, Vec3{0.0, 0.0, s.moment}};
  }

  // The failure envelope on the interface totals: the bond's loads plus `contact_force`, the
  // force the pair's contact puts on particle 2 in this step (zero when the grains are apart).
  static void judge(const Params& p, const State& s, const PairGeometry& g,
                    const Vec3& contact_force, BondFailure& fail) noexcept {
    const Vec3 t{-g.n.y, g.n.x, 0.0};
    const Vec3 contact = p.interface_totals ? contact_force : Vec3{};
    const BondFailure judged =
        envelope(p, s, s.normal_force + dot(contact, g.n), s.shear_force + dot(contact, t));
    if (!judged.broken) return;
    fail = judged;
    fail.energy = energy(p, s, radii_of(g));
  }

  // The envelope on the bond's own loads, as if the grains were apart (what snapshots show).
  static BondFailure assess(const Params& p, const State& s, const BondRadii&) noexcept {
    return envelope(p, s, s.normal_force, s.shear_force);
  }

  // Tensile when -f_n / A_b + beta |M| r_b / I_b >= T_b (checked first), else shear when |f_s|
  // reaches C_b A_b (1 - f_n / f_n,min) in tension or C_b A_b + mu f_n in compression; f_n and f_s
  // are the interface's normal (compression-positive) and shear forces.
  static BondFailure envelope(const Params& p, const State& s, double fn, double fs) noexcept {
    BondFailure f;
    const double bending = p.moment_factor * std::abs(s.moment) * s.bond_radius / s.inertia;
    const double sigma_t = -fn / s.area + bending;
    const double fn_min = -p.tensile_strength * s.area;
    const double fs_max = fn < 0.0 ? p.cohesion * s.area * (1.0 - fn / fn_min)
                                   : p.cohesion * s.area + p.friction * fn;
    const bool tensile = sigma_t >= p.tensile_strength;
    const bool shear = !tensile && std::abs(fs) >= fs_max;
    f.broken = tensile || shear;
    f.mode = tensile || !shear ? CrackMode::Tensile : CrackMode::Shear;
    f.Fn = fn;
    f.Fs = std::abs(fs);
    f.Mt = 0.0;
    f.Mb = std::abs(s.moment);
    f.sigma = sigma_t;
    f.tau = std::abs(fs) / s.area;
    f.ratio_t = sigma_t / p.tensile_strength;
    f.ratio_s = fs_max > 0.0 ? std::abs(fs) / fs_max : std::numeric_limits<double>::quiet_NaN();
    f.index = larger_ratio(f.ratio_t, f.ratio_s);
    f.bond_radius = s.bond_radius;
    return f;
  }

  // One step of the bond alone (no contact force at the interface): the law's use outside the
  // engine, which judges it on the totals through loads() and judge().
  static PairForce compute(const Params& p, State& s, const PairGeometry& g, const BodyFrames&,
                           double dt, BondFailure& fail) noexcept {
    const PairForce pf = loads(s, g, dt);
    judge(p, s, g, {}, fail);
    return fail.broken ? PairForce{} : pf;
  }

  static BondEnergy energy(const Params&, const State& s, const BondRadii&) noexcept {
    BondEnergy e;
    const double en = 0.5 * s.normal_force * s.normal_force / s.kn;
    (s.normal_force < 0.0 ? e.tension : e.compression) = en;
    e.shear = 0.5 * s.shear_force * s.shear_force / s.ks;
    e.bending = 0.5 * s.moment * s.moment / s.km;
    return e;
  }
};

}  // namespace breccia
