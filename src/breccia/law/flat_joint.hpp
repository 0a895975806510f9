#pragma once
// The flat-joint bond of Potyondy (2012) (docs/physics.md §4.6): the two grains meet on a flat
// interface, a disc of radius R = lambda min(R1, R2) (3D) or a segment of half-length R across the
// disks' thickness t (2D), cut into elements (N_r rings of N_alpha sectors in 3D, N_r segments in
// 2D). The interface's faces are rigidly attached to the grains: their relative normal
// displacement varies linearly over the interface (the gap g(x) = g_s + (theta_b x x) . n, with
// theta_b the relative bend rotation), and each element's normal force and moment are the
// integrals of k_n g over its area. A bonded element carries tension and shear until its tensile
// strength or its Mohr-Coulomb shear strength is reached; an unbonded element carries compression
// on its closed part only and a Coulomb-limited shear force. Elements break one by one, each a
// microcrack, so an interface degrades in steps, and a fully broken interface still resists
// rolling through its faces until they part.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/law/frictional.hpp"
#include "breccia/law/pair.hpp"
#include "breccia/law/param_table.hpp"

namespace breccia {

namespace flat {

inline constexpr int kMaxElements = 8;
// An unbonded element that is only partly closed is integrated over its cells: 4 x 4 per
// annular sector in 3D, 16 along a segment in 2D.
inline constexpr int kCellsPerSide = 4;
inline constexpr int kCells = kCellsPerSide * kCellsPerSide;

// Area integrals of a piece of the interface in the interface frame (e1, e2), for unit radius
// (and unit thickness in 2D): A = int dA, S = int x dA, I = int x x^T dA about the centre.
struct Moments {
  double a = 0.0, s1 = 0.0, s2 = 0.0, i11 = 0.0, i12 = 0.0, i22 = 0.0;
};

// The annular sector ra <= r <= rb, aa <= angle <= aa + da (angle from e1 towards e2). The
// width is passed, not the end angle, so that equal sectors have bitwise equal areas.
inline Moments sector(double ra, double rb, double aa, double da) noexcept {
  Moments m;
  const double ab = aa + da;
  m.a = 0.5 * (rb * rb - ra * ra) * da;
  const double r3 = (rb * rb * rb - ra * ra * ra) / 3.0;
  m.s1 = r3 * (std::sin(ab) - std::sin(aa));
  m.s2 = r3 * (std::cos(aa) - std::cos(ab));
  const double r4 = 0.25 * (rb * rb * rb * rb - ra * ra * ra * ra);
  const double sin2 = std::sin(2.0 * ab) - std::sin(2.0 * aa);
  m.i11 = r4 * (0.5 * da + 0.25 * sin2);
  m.i22 = r4 * (0.5 * da - 0.25 * sin2);
  m.i12 = r4 * 0.5 * (std::sin(ab) * std::sin(ab) - std::sin(aa) * std::sin(aa));
  return m;
}

// The segment sa <= x1 <= sb of unit thickness (2D).
inline Moments segment(double sa, double sb) noexcept {
  Moments m;
  m.a = sb - sa;
  m.s1 = 0.5 * (sb * sb - sa * sa);
  m.i11 = (sb * sb * sb - sa * sa * sa) / 3.0;
  return m;
}

// An element at unit radius: its integrals, those of its cells, and a bound on the distance from
// its centroid to any of its points (which decides when the cells are needed).
struct ElementShape {
  Moments whole;
  std::array<Moments, kCells> cells{};
  double reach = 0.0;
};

// The gap over the interface in unit coordinates xi = x / R: g = gs + b1 xi1 + b2 xi2.
struct Field {
  double gs = 0.0, b1 = 0.0, b2 = 0.0;
  double at(const Moments& m) const noexcept { return gs * m.a + b1 * m.s1 + b2 * m.s2; }
};

// int g dA, int g xi dA and int g^2 dA over (part of) an element, in unit coordinates.
struct GapIntegrals {
  double n = 0.0, q1 = 0.0, q2 = 0.0, e2 = 0.0;
  void add(const Moments& m, const Field& f) noexcept {
    n += f.at(m);
    q1 += f.gs * m.s1 + m.i11 * f.b1 + m.i12 * f.b2;
    q2 += f.gs * m.s2 + m.i12 * f.b1 + m.i22 * f.b2;
    e2 += f.gs * f.gs * m.a + 2.0 * f.gs * (f.b1 * m.s1 + f.b2 * m.s2) + f.b1 * f.b1 * m.i11 +
          2.0 * f.b1 * f.b2 * m.i12 + f.b2 * f.b2 * m.i22;
  }
};

// The closed part (g < 0) of an element: all of it, none of it, or (when the gap's zero line
// crosses it) the cells whose centroid is closed. A cell enters when its mean gap is zero, so the
// normal force stays continuous; only its own small moment about its centroid appears at once.
inline GapIntegrals closed_part(const ElementShape& e, const Field& f) noexcept {
  GapIntegrals out;
  const double gc = f.at(e.whole) / e.whole.a;
  const double spread = std::sqrt(f.b1 * f.b1 + f.b2 * f.b2) * e.reach;
  if (gc + spread <= 0.0) {
    out.add(e.whole, f);
  } else if (gc - spread < 0.0) {
    for (const Moments& c : e.cells)
      if (f.at(c) < 0.0) out.add(c, f);
  }
  return out;
}

enum ElementBond : std::uint8_t {
  kBonded = 0,
  kUnbonded = 1,     // never bonded, or broken in tension
  kShearBroken = 2,  // broken in shear: keeps the residual cohesion
};

}  // namespace flat

struct FlatJoint {
  static constexpr std::string_view name = "flat_joint";
  static constexpr std::string_view summary =
      "Potyondy flat joint: a flat interface of bonded or frictional elements that break one by "
      "one (tension, then Mohr-Coulomb shear); broken interfaces keep resisting rotation.";
  static constexpr bool needs_frames = false;  // incremental: velocities suffice
  // An element's break is a crack that leaves the interface in place (BondOutcome).
  static constexpr bool breaks_by_element = true;
  static constexpr int kMaxElements = flat::kMaxElements;

  struct Params {
    double radius_multiplier = 1.0;  // lambda
    double modulus = 10e9;           // E*: k_n = E* / (R1 + R2) per unit area
    double stiffness_ratio = 2.5;    // kappa* = k_n / k_s
    double tensile_strength = 20e6;  // sigma_b
    double tensile_strength_sd = 0;
    double cohesion = 40e6;  // c_b
    double cohesion_sd = 0;
    double friction_angle_deg = 0;        // phi_b of bonded elements
    double friction = 0.5;                // mu of unbonded elements
    double residual_cohesion = 0;         // c_r of elements broken in shear
    double radial_elements = 1;           // N_r
    double circumferential_elements = 3;  // N_alpha (3D)
    double bonded_fraction = 1;           // phi_B: interfaces installed bonded
    double gapped_fraction = 0;           // phi_G: unbonded, faces g_0 apart
    double installation_gap = 0;          // g_0, m
    // Derived by prepare(), not input.
    double tan_friction = 0.0, shear_fraction = 0.4;
    int elements = 3;
    std::uint8_t unused[4]{};  // named, not padding (core/archive.hpp)
    std::array<flat::ElementShape, flat::kMaxElements> shapes{};
    RunGeometry run;  // set by the engine: disc (3D) or segment across the thickness (2D)
  };

  static void prepare(Params& p) noexcept {
    p.tan_friction = std::tan(p.friction_angle_deg * kDegree);
    p.shear_fraction = 1.0 / p.stiffness_ratio;
    // The table and check() refuse counts past 8 before any run (files and Simulation alike);
    // the bounds here only keep the arrays safe.
    const int nr = std::clamp(static_cast<int>(p.radial_elements), 1, flat::kMaxElements);
    const int na = p.run.planar ? 1 : std::max(1, static_cast<int>(p.circumferential_elements));
    p.elements = std::min(nr * na, flat::kMaxElements);
    for (int e = 0; e < p.elements; ++e) p.shapes[e] = shape_of(p.run.planar, nr, na, e);
  }

  // Element e of N_r x N_alpha (ring e / N_alpha, sector e % N_alpha) or of N_r segments.
  static flat::ElementShape shape_of(bool planar, int nr, int na, int e) noexcept {
    flat::ElementShape s;
    if (planar) {
      const double sa = -1.0 + 2.0 * e / nr, sb = -1.0 + 2.0 * (e + 1) / nr;
      s.whole = flat::segment(sa, sb);
      for (int c = 0; c < flat::kCells; ++c)
        s.cells[c] = flat::segment(sa + (sb - sa) * c / flat::kCells,
                                   sa + (sb - sa) * (c + 1) / flat::kCells);
      const double centre = s.whole.s1 / s.whole.a;
      s.reach = std::max(centre - sa, sb - centre);
      return s;
    }
    const int ring = e / na, sector = e % na;
    const double ra = static_cast<double>(ring) / nr, rb = static_cast<double>(ring + 1) / nr;
    const double da = 2.0 * std::numbers::pi / na, aa = da * sector;
    s.whole = flat::sector(ra, rb, aa, da);
    constexpr int m = flat::kCellsPerSide;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j)
        s.cells[i * m + j] = flat::sector(ra + (rb - ra) * i / m, ra + (rb - ra) * (i + 1) / m,
                                          aa + da * j / m, da / m);
    const double c1 = s.whole.s1 / s.whole.a, c2 = s.whole.s2 / s.whole.a;
    s.reach = rb + std::sqrt(c1 * c1 + c2 * c2);
    return s;
  }

  static constexpr std::array<ParamField<Params>, 15> fields() {
    return {{
        {"radius_multiplier", "-", &Params::radius_multiplier, 0, 1, false, true,
         "lambda: interface radius R = lambda min(R1, R2)"},
        {"modulus", "Pa", &Params::modulus, 0, kInf, false, true,
         "effective modulus E*: k_n = E* / (R1 + R2) per unit area"},
        {"stiffness_ratio", "-", &Params::stiffness_ratio, 0, kInf, false, true,
         "kappa* = k_n / k_s"},
        {"tensile_strength", "Pa", &Params::tensile_strength, 0, kInf, false, true,
         "mean tensile strength sigma_b of a bonded element"},
        {"tensile_strength_sd", "Pa", &Params::tensile_strength_sd, 0, kInf, true, true,
         "standard deviation of sigma_b over interfaces (normal, redrawn when <= 0)"},
        {"cohesion", "Pa", &Params::cohesion, 0, kInf, false, true,
         "mean cohesion c_b of a bonded element"},
        {"cohesion_sd", "Pa", &Params::cohesion_sd, 0, kInf, true, true,
         "standard deviation of c_b over interfaces (normal, redrawn when <= 0)"},
        {"friction_angle_deg", "deg", &Params::friction_angle_deg, 0, 90, true, false,
         "phi_b of bonded elements: tau_c = c_b - sigma tan(phi_b), sigma tension-positive"},
        {"friction", "-", &Params::friction, 0, kInf, true, true,
         "mu of unbonded elements: their shear force is at most mu F_n (F_n on the closed part)"},
        {"residual_cohesion", "Pa", &Params::residual_cohesion, 0, kInf, true, true,
         "c_r kept by elements broken in shear while pressed: shear force at most c_r A + mu F_n"},
        {"radial_elements", "-", &Params::radial_elements, 1, flat::kMaxElements, true, true,
         "N_r: rings of the disc (3D) or segments of the interface (2D)", true},
        {"circumferential_elements", "-", &Params::circumferential_elements, 1, flat::kMaxElements,
         true, true, "N_alpha: sectors of each ring (3D only); N_r N_alpha <= 8", true},
        {"bonded_fraction", "-", &Params::bonded_fraction, 0, 1, true, true,
         "phi_B: fraction of interfaces installed bonded (each drawn by its bond tag)"},
        {"gapped_fraction", "-", &Params::gapped_fraction, 0, 1, true, true,
         "phi_G: fraction installed unbonded with faces installation_gap apart; the rest "
         "(1 - phi_B - phi_G) unbonded with touching faces (slit)"},
        {"installation_gap", "m", &Params::installation_gap, 0, kInf, true, true,
         "g_0: opening of the gapped interfaces' faces at installation"},
    }};
  }

  // Combinations the field table cannot refuse on its own.
  static void check(const Params& p, const std::string& where, std::int64_t dimension) {
    if (dimension == 3 && p.radial_elements * p.circumferential_elements > flat::kMaxElements)
      throw InputError(where, "bond.circumferential_elements", num(p.circumferential_elements),
                       "radial_elements x circumferential_elements must be at most 8 (now " +
                           num(p.radial_elements) + " x " + num(p.circumferential_elements) + ")");
    if (p.bonded_fraction + p.gapped_fraction > 1.0 + 1e-12)
      throw InputError(where, "bond.gapped_fraction", num(p.gapped_fraction),
                       "bonded_fraction + gapped_fraction must be at most 1 (bonded_fraction = " +
                           num(p.bonded_fraction) + "); the rest are slit interfaces");
    if (p.gapped_fraction > 0.0 && !(p.installation_gap > 0.0))
      throw InputError(where, "bond.installation_gap", num(p.installation_gap),
                       "gapped interfaces (gapped_fraction = " + num(p.gapped_fraction) +
                           ") need installation_gap > 0 m; without a gap they are slit");
  }

  static Params example_params() {
    Params p;
    prepare(p);
    return p;
  }
  static BondModuli moduli(const Params& p) noexcept {
    return {p.modulus, p.modulus / p.stiffness_ratio};
  }
  // The interface itself carries compression: no contact between its grains while it exists.
  static bool contact_while_bonded(const Params&) noexcept { return false; }

  struct State {
    Vec3 n_old;  // normal of the previous step; zero until the first step after install
    Vec3 e1;     // the interface frame's first in-plane axis (3D)
    Vec3 bend;   // theta_b: relative bend rotation of grain 2, in the interface plane
    std::array<Vec3, flat::kMaxElements> shear{};  // elements' shear forces on grain 2
    double d0 = 0.0;                               // centre distance at which the faces touch
    double gap = 0.0;                              // g_s at the centre, at the last step
    double radius = 0.0;                           // R
    double kn = 0.0;                               // k_n per unit area
    double tensile_strength = 0.0, cohesion = 0.0;
    double gap0 = 0.0;  // the faces' opening at installation (gapped interfaces)
    std::array<std::uint8_t, flat::kMaxElements> bond{};  // flat::ElementBond
  };

  // The elements still bonded: each can break once, as one crack.
  static int bonded_sites(const Params& p, const State& s) noexcept {
    int n = 0;
    for (int e = 0; e < p.elements; ++e) n += s.bond[e] == flat::kBonded;
    return n;
  }

  static State install(const Params& p, const PairGeometry& g, const BodyFrames& fr,
                       std::uint64_t seed, std::uint64_t bond_tag) noexcept {
    State s;
    s.radius = p.radius_multiplier * std::min(g.R1, g.R2);
    s.kn = p.modulus / (g.R1 + g.R2);
    constexpr std::uint64_t kTensileStream = 0xf17e, kCohesionStream = 0xf1c0, kKindStream = 0xf1d5;
    s.tensile_strength =
        positive_normal(p.tensile_strength, p.tensile_strength_sd, seed, kTensileStream, bond_tag);
    s.cohesion = positive_normal(p.cohesion, p.cohesion_sd, seed, kCohesionStream, bond_tag);
    const double u = uniform01(seed, kKindStream, bond_tag);
    const bool bonded = u < p.bonded_fraction;
    const bool gapped = !bonded && u < p.bonded_fraction + p.gapped_fraction;
    s.gap0 = gapped ? p.installation_gap : 0.0;
    s.d0 = g.d - s.gap0;
    s.gap = s.gap0;
    s.bond.fill(bonded ? flat::kBonded : flat::kUnbonded);
    // The elements' layout starts from grain 1's body x axis (its y axis when x is within 26
    // degrees of n) in the interface plane, so that it turns with the sample.
    const Vec3 n = g.n;
    Vec3 axis = rotate(fr.q1, Vec3{1, 0, 0});
    if (std::abs(dot(axis, n)) > 0.9) axis = rotate(fr.q1, Vec3{0, 1, 0});
    s.e1 = unit(axis - n * dot(axis, n));
    return s;
  }

  // The interface's area A, its second moment about a diameter I (the bending stiffness is
  // k_n I) and its polar moment J (the twisting stiffness is k_s J).
  struct Section {
    double area, inertia, polar;
  };
  static Section section(const Params& p, const State& s) noexcept {
    const double r = s.radius;
    if (p.run.planar)
      return {2.0 * r * p.run.thickness, 2.0 / 3.0 * r * r * r * p.run.thickness, 0};
    const double i = 0.25 * std::numbers::pi * r * r * r * r;
    return {std::numbers::pi * r * r, i, 2.0 * i};
  }
  static double max_stiffness(const Params& p, const State& s, const BondRadii&) noexcept {
    return s.kn * std::max(1.0, p.shear_fraction) * section(p, s).area;
  }
  static double normal_stiffness(const Params& p, const State& s, const BondRadii&) noexcept {
    return s.kn * section(p, s).area;
  }
  static double shear_stiffness(const Params& p, const State& s, const BondRadii&) noexcept {
    return s.kn * p.shear_fraction * section(p, s).area;
  }
  static double max_moment_stiffness(const Params& p, const State& s, const BondRadii&) noexcept {
    const Section c = section(p, s);
    return s.kn * std::max(c.inertia, p.shear_fraction * c.polar);
  }

  // Scales from unit coordinates: areas by area_scale, first moments by area_scale R.
  struct Frame {
    Vec3 e1, e2;
    double area_scale, r;
  };
  static Frame frame(const Params& p, const State& s, const Vec3& n) noexcept {
    Frame f;
    if (p.run.planar) {
      f.e1 = Vec3{-n.y, n.x, 0.0};  // z x n
      f.e2 = Vec3{0.0, 0.0, 1.0};
      f.area_scale = s.radius * p.run.thickness;
    } else {
      f.e1 = s.e1;
      f.e2 = cross(n, s.e1);
      f.area_scale = s.radius * s.radius;
    }
    f.r = s.radius;
    return f;
  }
  // The gap field in unit coordinates: gradient n x theta_b, times R.
  static flat::Field field(const State& s, const Vec3& n, const Frame& f) noexcept {
    const Vec3 grad = cross(n, s.bend) * f.r;
    return {s.gap, dot(grad, f.e1), dot(grad, f.e2)};
  }

  // One element's loads on grain 2 in this step.
  struct ElementLoad {
    double fn = 0.0;  // normal force, compression-positive
    Vec3 shear;       // shear force
    Vec3 couple;      // moment of its normal stresses about the interface centre
    double normal_energy = 0.0;
    double sigma = 0.0;  // mean normal stress, tension-positive
    Vec3 centroid;       // in space, from the interface centre
  };
  static ElementLoad normal_load(const Params& p, const State& s, int e, const flat::Field& fld,
                                 const Frame& f, const Vec3& n) noexcept {
    const flat::ElementShape& shape = p.shapes[e];
    flat::GapIntegrals gi;
    if (s.bond[e] == flat::kBonded)
      gi.add(shape.whole, fld);
    else
      gi = flat::closed_part(shape, fld);
    ElementLoad l;
    const double area = shape.whole.a * f.area_scale;
    l.fn = -s.kn * gi.n * f.area_scale;
    l.sigma = -l.fn / area;
    const Vec3 q = (f.e1 * gi.q1 + f.e2 * gi.q2) * (f.area_scale * f.r);
    l.couple = cross(q, n) * -s.kn;  // int x x (-k_n g n) dA
    l.normal_energy = 0.5 * s.kn * gi.e2 * f.area_scale;
    l.centroid = (f.e1 * shape.whole.s1 + f.e2 * shape.whole.s2) * (f.r / shape.whole.a);
    return l;
  }
  static double element_area(const Params& p, int e, const Frame& f) noexcept {
    return p.shapes[e].whole.a * f.area_scale;
  }

  // A bonded element's loads against its strength.
  struct ElementJudgement {
    double ratio_t, ratio_s, index, tau;
    bool tensile, shear;
  };
  static ElementJudgement judge(const Params& p, const State& s, const ElementLoad& l,
                                double area) noexcept {
    ElementJudgement j;
    j.tau = norm(l.shear) / area;
    const double tau_c = s.cohesion - l.sigma * p.tan_friction;
    j.tensile = l.sigma >= s.tensile_strength;
    j.shear = j.tau >= tau_c;
    j.ratio_t = l.sigma / s.tensile_strength;
    j.ratio_s = tau_c > 0.0 ? j.tau / tau_c : std::numeric_limits<double>::quiet_NaN();
    j.index = larger_ratio(j.ratio_t, j.ratio_s);
    return j;
  }

  // The crack record of element e breaking under load l.
  static BondFailure element_record(const Params& p, const ElementLoad& l,
                                    const ElementJudgement& j, double area) noexcept {
    BondFailure f;
    f.broken = true;
    f.outcome = BondOutcome::ElementBroken;
    f.mode = j.tensile || !j.shear ? CrackMode::Tensile : CrackMode::Shear;
    f.Fn = l.fn;
    f.Fs = norm(l.shear);
    f.Mb = norm(l.couple);
    f.sigma = l.sigma;
    f.tau = j.tau;
    f.ratio_t = j.ratio_t;
    f.ratio_s = j.ratio_s;
    f.index = j.index;
    // The radius of a disc (3D) or the half-length of a strip (2D) of the element's area.
    f.bond_radius =
        p.run.planar ? 0.5 * area / p.run.thickness : std::sqrt(area / std::numbers::pi);
    f.point_offset = l.centroid;
    return f;
  }

  // An unbonded element's shear force: Coulomb-limited on its closed part (residual cohesion
  // after a shear break), the slip booked.
  static Vec3 limit_shear(const Params& p, const State& s, int e, const Vec3& trial,
                          const ElementLoad& l, double area, PairDissipation& dis) noexcept {
    const double k = s.kn * p.shear_fraction * area;
    const double cohesive = s.bond[e] == flat::kShearBroken ? p.residual_cohesion * area : 0.0;
    const double limit = p.friction * std::max(0.0, l.fn) + (l.fn > 0.0 ? cohesive : 0.0);
    return coulomb_shear(trial, Vec3{}, k, 0.0, limit, dis).force;
  }

  // One step: the interface's force and couple on grain 2. An element that breaks is reported
  // through `fail` (outcome ElementBroken) and the force is applied all the same; an interface
  // with no bonded element whose faces have parted beyond their installation gap everywhere is
  // released (outcome Released): the pair becomes an ordinary contact.
  static PairForce compute(const Params& p, State& s, const PairGeometry& g, const BodyFrames&,
                           double dt, PairDissipation& dis, BondFailure& fail) noexcept {
    const bool fresh = s.n_old.x == 0.0 && s.n_old.y == 0.0 && s.n_old.z == 0.0;
    if (fresh) dt = 0.0;
    // 1. Carry the frame, the bend rotation and the elements' shear forces into the present plane.
    if (!fresh) {
      const PlaneCarry carry(s.n_old, g.n, 0.5 * dot(g.w1 + g.w2, g.n) * dt);
      s.bend = carry.apply(s.bend);
      s.e1 = unit(carry.apply(s.e1));
      for (int e = 0; e < p.elements; ++e) s.shear[e] = carry.apply(s.shear[e]);
    }
    s.n_old = g.n;
    // 2. Increments: the relative bend rotation, the gap, the shear at each element's centroid
    // (the relative sliding plus the twist about n).
    const Vec3 wr = g.w2 - g.w1;
    const double twist_rate = p.run.planar ? 0.0 : dot(wr, g.n);
    s.bend += (wr - g.n * dot(wr, g.n)) * dt;
    s.gap = g.d - s.d0;
    const Vec3 vt = g.vt();
    const Frame f = frame(p, s, g.n);
    const flat::Field fld = field(s, g.n, f);
    PairForce total;
    int worst = -1;
    double worst_index = 0.0;
    bool any_bonded = false;
    for (int e = 0; e < p.elements; ++e) {
      ElementLoad l = normal_load(p, s, e, fld, f, g.n);
      const double area = element_area(p, e, f);
      const Vec3 slide = vt + cross(g.n, l.centroid) * twist_rate;
      const Vec3 trial = s.shear[e] - slide * (s.kn * p.shear_fraction * area * dt);
      if (s.bond[e] == flat::kBonded) {
        any_bonded = true;
        l.shear = trial;
        const ElementJudgement j = judge(p, s, l, area);
        if ((j.tensile || j.shear) && (worst < 0 || j.index > worst_index)) {
          worst = e;
          worst_index = j.index;
        }
      } else {
        l.shear = limit_shear(p, s, e, trial, l, area, dis);
      }
      s.shear[e] = l.shear;
      total.force += g.n * l.fn + l.shear;
      total.couple += l.couple + cross(l.centroid, l.shear);
    }
    if (worst >= 0) {
      break_element(p, s, worst, fld, f, g.n, total, fail);
    } else if (!any_bonded && s.gap - std::sqrt(fld.b1 * fld.b1 + fld.b2 * fld.b2) > s.gap0) {
      fail.broken = true;
      fail.outcome = BondOutcome::Released;
      return {};
    }
    return total;
  }

  // Breaks element e (the most overloaded of the step): its crack record with the energy it
  // releases, and its loads replaced in `total` by those of an unbonded element.
  static void break_element(const Params& p, State& s, int e, const flat::Field& fld,
                            const Frame& f, const Vec3& n, PairForce& total,
                            BondFailure& fail) noexcept {
    const double area = element_area(p, e, f);
    const double ks = s.kn * p.shear_fraction * area;
    ElementLoad before = normal_load(p, s, e, fld, f, n);
    before.shear = s.shear[e];
    const ElementJudgement j = judge(p, s, before, area);
    fail = element_record(p, before, j, area);
    s.bond[e] = j.tensile || !j.shear ? flat::kUnbonded : flat::kShearBroken;
    ElementLoad after = normal_load(p, s, e, fld, f, n);
    PairDissipation released;  // the excess shear is part of the crack's energy, not slip
    after.shear = limit_shear(p, s, e, before.shear, after, area, released);
    s.shear[e] = after.shear;
    total.force += n * (after.fn - before.fn) + (after.shear - before.shear);
    total.couple +=
        after.couple - before.couple + cross(before.centroid, after.shear - before.shear);
    const double normal = before.normal_energy - after.normal_energy;
    (before.sigma > 0.0 ? fail.energy.tension : fail.energy.compression) = normal;
    fail.energy.shear = 0.5 * (norm2(before.shear) - norm2(after.shear)) / ks;
  }

  // The most loaded bonded element against its strength (what snapshots show); index 0 when no
  // element is bonded.
  static BondFailure assess(const Params& p, const State& s, const BondRadii&) noexcept {
    const Vec3 n = s.n_old;
    BondFailure worst;
    if (n.x == 0.0 && n.y == 0.0 && n.z == 0.0) return worst;
    const Frame f = frame(p, s, n);
    const flat::Field fld = field(s, n, f);
    bool found = false;
    for (int e = 0; e < p.elements; ++e) {
      if (s.bond[e] != flat::kBonded) continue;
      ElementLoad l = normal_load(p, s, e, fld, f, n);
      l.shear = s.shear[e];
      const double area = element_area(p, e, f);
      const ElementJudgement j = judge(p, s, l, area);
      if (!found || j.index > worst.index) {
        worst = element_record(p, l, j, area);
        worst.broken = j.tensile || j.shear;
        found = true;
      }
    }
    if (!found) return BondFailure{};
    worst.outcome = BondOutcome::ElementBroken;
    return worst;
  }

  // Stored elastic energy: k_n/2 int g^2 dA over the loaded area, |F_s|^2 / (2 k_s A) per element.
  static BondEnergy energy(const Params& p, const State& s, const BondRadii&) noexcept {
    BondEnergy out;
    const Vec3 n = s.n_old;
    if (n.x == 0.0 && n.y == 0.0 && n.z == 0.0) return out;
    const Frame f = frame(p, s, n);
    const flat::Field fld = field(s, n, f);
    for (int e = 0; e < p.elements; ++e) {
      const ElementLoad l = normal_load(p, s, e, fld, f, n);
      (l.sigma > 0.0 ? out.tension : out.compression) += l.normal_energy;
      const double ks = s.kn * p.shear_fraction * element_area(p, e, f);
      out.shear += 0.5 * norm2(s.shear[e]) / ks;
    }
    return out;
  }

  static constexpr double kDegree = std::numbers::pi / 180.0;
};

}  // namespace breccia
