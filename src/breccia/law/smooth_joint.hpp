#pragma once
// The PFC smooth joint (docs/physics.md §5; Mas Ivars et al. 2011): a pair that a joint plane cuts
// interacts through springs aligned with the joint plane instead of its own contact normal, so
// grains on either side slide along the plane however bumpy their spheres are. The springs follow
// the contact point's relative motion split along the fixed joint normal (ARCHITECTURE.md: the
// force acts there with its lever-arm torques, as in PFC, so the springs must store that work);
// the normal force comes from the normal displacement accumulated since the joint was made, so an
// opening of D must close by D before the joint pushes. The shear force is incremental with a
// Coulomb limit and optional dilation; a bonded joint carries tension until its tensile or
// Mohr-Coulomb shear strength is reached and then goes on unbonded with the same state.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "breccia/law/frictional.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

struct SmoothJoint {
  static constexpr std::string_view name = "smooth_joint";
  static constexpr std::string_view summary =
      "PFC smooth joint: springs along a joint plane, Coulomb sliding with dilation; optionally "
      "bonded (tension, then Mohr-Coulomb shear).";

  struct Params {
    double normal_stiffness = 2e13;  // k_n^j, Pa/m
    double shear_stiffness = 8e12;   // k_s^j, Pa/m
    double friction = 0.5;           // mu_j
    double dilation_angle_deg = 0;   // psi_j
    double radius_multiplier = 1.0;  // lambda_j
    bool bonded = false;
    std::uint8_t unused[7]{};       // named, not padding (core/archive.hpp)
    double tensile_strength = 0;    // sigma_c^j
    double cohesion = 0;            // c^j
    double friction_angle_deg = 0;  // phi_b^j
    // Derived by prepare(), not input.
    double tan_dilation = 0.0, tan_bond_friction = 0.0;
  };
  static void prepare(Params& p) noexcept {
    p.tan_dilation = std::tan(p.dilation_angle_deg * kDegree);
    p.tan_bond_friction = std::tan(p.friction_angle_deg * kDegree);
  }
  static constexpr std::array<ParamField<Params>, 9> fields() {
    return {{
        {"normal_stiffness", "Pa/m", &Params::normal_stiffness, 0, kInf, false, true,
         "k_n^j: normal stiffness per unit area of the joint; K_n = k_n^j A, A = pi R^2 "
         "(2 R t in 2D), R = lambda min(R1, R2)"},
        {"shear_stiffness", "Pa/m", &Params::shear_stiffness, 0, kInf, false, true,
         "k_s^j: shear stiffness per unit area"},
        {"friction", "-", &Params::friction, 0, kInf, true, true,
         "mu_j: Coulomb friction coefficient of the joint surface"},
        {"dilation_angle_deg", "deg", &Params::dilation_angle_deg, 0, 90, true, false,
         "psi_j: sliding by s opens the joint by s tan(psi)"},
        {"radius_multiplier", "-", &Params::radius_multiplier, 0, 1, false, true,
         "lambda_j: joint radius R = lambda min(R1, R2)"},
        {"bonded", "-", &Params::bonded, 0, 0, true, true,
         "joints start bonded (bonded pairs across the plane keep a bonded joint) and carry "
         "tension up to tensile_strength"},
        {"tensile_strength", "Pa", &Params::tensile_strength, 0, kInf, true, true,
         "sigma_c^j of a bonded joint (tension-positive normal stress)"},
        {"cohesion", "Pa", &Params::cohesion, 0, kInf, true, true,
         "c^j of a bonded joint: shear strength c + sigma_n tan(phi_b), sigma_n "
         "compression-positive"},
        {"friction_angle_deg", "deg", &Params::friction_angle_deg, 0, 90, true, false,
         "phi_b^j: friction angle of the bonded joint's shear strength"},
    }};
  }
  static Params example_params() {
    Params p;
    p.bonded = true;
    p.tensile_strength = 5e6;
    p.cohesion = 10e6;
    p.friction_angle_deg = 20;
    p.dilation_angle_deg = 5;
    prepare(p);
    return p;
  }

  // Combinations the field table cannot refuse on its own.
  static void check(const Params& p, const std::string& where) {
    if (p.bonded && !(p.tensile_strength > 0.0 && p.cohesion > 0.0))
      throw InputError(where, "joint.bonded", "true",
                       "a bonded joint needs tensile_strength > 0 and cohesion > 0 (now " +
                           num(p.tensile_strength) + " and " + num(p.cohesion) +
                           " Pa); without them every joint would break at once");
  }

  static bool starts_bonded(const Params& p) noexcept { return p.bonded; }

  struct State {
    Vec3 normal;                // n_j, fixed in space, oriented so that n_j . n >= 0 at assignment
    Vec3 shear_force;           // F_s, in the joint plane
    double normal_force = 0.0;  // F_n along n_j, compression-positive (output and energy)
    double opening = 0.0;   // u_n - u_n0: normal displacement since (re)creation, opening-positive
    double dilation = 0.0;  // u_dil
    double kn = 0.0, ks = 0.0;  // K_n = k_n^j A, K_s = k_s^j A
    double area = 0.0;
    double joint_radius = 0.0;  // R_bar
    double release_gap = 0.0;   // surface gap beyond which an unbonded joint is deleted
    bool bonded = false;
    bool attached = false;     // false: the pair is apart; the joint is re-created when it touches
    bool fresh = false;        // no step since (re)creation: the first shear increment is zero
    std::uint8_t unused[5]{};  // named, not padding (core/archive.hpp)
  };

  // A joint between a pair, stress-free at the current geometry. `joint_normal` is the plane's
  // unit normal; it is turned to point from particle 1 to particle 2. A joint of a pair that is
  // apart (gap > 0) and not bonded waits until the pair touches.
  static State install(const Params& p, const PairGeometry& g, Vec3 joint_normal,
                       bool bonded) noexcept {
    State s;
    if (dot(joint_normal, g.n) < 0.0) joint_normal = -joint_normal;
    s.normal = joint_normal;
    s.joint_radius = p.radius_multiplier * std::min(g.R1, g.R2);
    s.area = g.planar ? 2.0 * s.joint_radius * g.thickness
                      : std::numbers::pi * s.joint_radius * s.joint_radius;
    s.kn = p.normal_stiffness * s.area;
    s.ks = p.shear_stiffness * s.area;
    s.bonded = bonded;
    if (bonded || g.delta >= 0.0) attach(s, g);
    return s;
  }

  static bool is_bonded(const State& s) noexcept { return s.bonded; }
  static double max_stiffness(const Params&, const State& s, const BondRadii&) noexcept {
    return std::max(s.kn, s.ks);
  }
  static double shear_stiffness(const Params&, const State& s, const BondRadii&) noexcept {
    return s.ks;
  }
  static double max_moment_stiffness(const Params&, const State&, const BondRadii&) noexcept {
    return 0.0;
  }

  // One step. A bonded joint that fails reports the failure and goes on unbonded in the same step
  // (its force after the conversion is returned); `fail.energy` is the drop of stored energy.
  static PairForce compute(const Params& p, State& s, const PairGeometry& g, double dt,
                           PairDissipation& dis, BondFailure& fail) noexcept {
    if (!s.attached) {
      if (g.delta < 0.0) return {};
      attach(s, g);
    } else if (!s.bonded && -g.delta > s.release_gap) {
      // The pair has left the contact range: the joint is deleted (its springs' energy leaves
      // without work) and re-created, stress-free, when the two touch again.
      dis.deleted += energy(p, s, radii_of(g)).total();
      s.attached = false;
      s.normal_force = 0.0;
      s.shear_force = {};
      return {};
    }
    if (s.fresh) dt = 0.0;  // the velocity of the last half step moved the pair before (re)creation
    s.fresh = false;
    // Relative motion of the contact point (the point where the force acts, so that the springs
    // store the work of the force and its lever-arm torques alike), split along the joint.
    const double vn = dot(g.vc, s.normal);
    const Vec3 vs = g.vc - s.normal * vn;
    s.opening += vn * dt;
    double fn = s.kn * (s.dilation - s.opening);
    if (s.bonded) {
      const Vec3 fs = s.shear_force - vs * (s.ks * dt);
      const double sigma = -fn / s.area;  // tension-positive
      const double tau = norm(fs) / s.area;
      const double tau_c = p.cohesion - sigma * p.tan_bond_friction;
      const bool tensile = sigma >= p.tensile_strength;
      const bool shear = !tensile && tau >= tau_c;
      s.normal_force = fn;
      s.shear_force = fs;
      if (!tensile && !shear) return {s.normal * fn + fs, {}};
      const BondEnergy before = energy(p, s, radii_of(g));
      fail.broken = true;
      fail.mode = tensile ? CrackMode::Tensile : CrackMode::Shear;
      fail.Fn = fn;
      fail.Fs = norm(fs);
      fail.sigma = sigma;
      fail.tau = tau;
      fail.ratio_t = p.tensile_strength > 0.0 ? sigma / p.tensile_strength : kInf;
      fail.ratio_s = tau_c > 0.0 ? tau / tau_c : std::numeric_limits<double>::quiet_NaN();
      fail.bond_radius = s.joint_radius;
      s.bonded = false;
      // Unbonded now: the same state under the no-tension and Coulomb rules, no new motion.
      const PairForce out = slide(p, s, fn, s.shear_force, dis, /*books_losses=*/false);
      const BondEnergy after = energy(p, s, radii_of(g));
      fail.energy = {before.tension - after.tension, before.compression - after.compression,
                     before.shear - after.shear, 0.0, 0.0};
      return out;
    }
    return slide(p, s, fn, s.shear_force - vs * (s.ks * dt), dis, true);
  }

  // Stored energy by component: F_n^2 / (2 K_n) (tension or compression) and |F_s|^2 / (2 K_s).
  static BondEnergy energy(const Params&, const State& s, const BondRadii&) noexcept {
    BondEnergy e;
    if (!s.attached || s.kn <= 0.0) return e;
    (s.normal_force < 0.0 ? e.tension : e.compression) =
        0.5 * s.normal_force * s.normal_force / s.kn;
    e.shear = 0.5 * norm2(s.shear_force) / s.ks;
    return e;
  }

  static constexpr double kDegree = std::numbers::pi / 180.0;

 private:
  static void attach(State& s, const PairGeometry& g) noexcept {
    s.attached = true;
    s.fresh = true;
    // The contact-detection range of §5: a tenth of the smaller radius beyond the gap at
    // creation, so that a joint opened by a small amount keeps its history (the whole opening
    // must close before it pushes) while a pair that slid or moved apart is let go.
    s.release_gap = std::max(s.release_gap, std::max(0.0, -g.delta) + 0.1 * std::min(g.R1, g.R2));
    s.opening = 0.0;
    s.dilation = 0.0;
    s.shear_force = {};
    s.normal_force = 0.0;
  }

  // The unbonded joint with trial forces (fn, fs): open below zero normal force, else the Coulomb
  // limit with dilation. Slip and the work of dilation are booked when `books_losses`.
  static PairForce slide(const Params& p, State& s, double fn, const Vec3& fs_trial,
                         PairDissipation& dis, bool books_losses) noexcept {
    if (fn <= 0.0) {
      // Open: no force; the shear spring's energy leaves without work.
      if (books_losses) dis.deleted += 0.5 * norm2(s.shear_force) / s.ks;
      s.normal_force = 0.0;
      s.shear_force = {};
      return {};
    }
    const double limit = p.friction * fn;
    Vec3 fs = fs_trial;
    const double ft = norm(fs);
    if (ft > limit) {
      const double slip = (ft - limit) / s.ks;
      if (books_losses) {
        dis.slip += limit * slip;
        // Dilation lengthens the compressed normal spring at fixed positions: the energy it
        // gains, K_n ((e + d)^2 - e^2) / 2 with e = F_n / K_n, is work the Coulomb rule does not
        // see (the asperities' lift), booked as such.
        const double lift = slip * p.tan_dilation;
        dis.dilation += fn * lift + 0.5 * s.kn * lift * lift;
        s.dilation += lift;
      }
      fs *= limit / ft;
    }
    s.normal_force = fn;
    s.shear_force = fs;
    return {s.normal * fn + fs, {}};
  }
};

}  // namespace breccia
