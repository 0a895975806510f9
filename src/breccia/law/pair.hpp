#pragma once
// What every pair law (contact or bond) receives and returns. The engine computes the geometry of
// a pair once (docs/physics.md §0.2); a law turns it into a force on particle 2 and a pure couple
// on particle 2 (§0.3). Particle 1 receives the opposite force and couple; torques about the
// centres follow from the lever arms, which conserves linear and angular momentum exactly.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "breccia/core/quat.hpp"
#include "breccia/core/vec3.hpp"

namespace breccia {

struct PairGeometry {
  Vec3 n;              // unit normal from body 1 to body 2
  double d = 0.0;      // centre distance (for a wall: distance from the wall plane)
  double delta = 0.0;  // overlap R1 + R2 - d (> 0 in contact)
  Vec3 r1, r2;         // lever arms from the centres to the contact point
  Vec3 vc;             // relative velocity of the contact point, 2 minus 1
  Vec3 w1, w2;         // angular velocities
  // Radii. Against a wall, R1 is the wall's convex curvature radius: a sphere wall's radius, 0
  // for a flat (or concave) one.
  double R1 = 0.0, R2 = 0.0;
  double m1 = 0.0, m2 = 0.0;   // masses (m1 unused against a wall)
  bool wall = false;           // body 1 is a rigid wall
  bool planar = false;         // 2D slab geometry
  bool planar_sphere = false;  // 2D run of spheres confined to the plane (§3.4), not disks
  double thickness = 1.0;

  double vn() const noexcept { return dot(vc, n); }
  Vec3 vt() const noexcept { return vc - n * vn(); }
  // Reduced mass, for dashpots only (the particle's mass against a wall).
  double m_star() const noexcept { return wall ? m2 : m1 * m2 / (m1 + m2); }
};

// The radii of a bond's two grains. A bond's section follows from them (a grain's radius cannot
// change while it holds a bond), so a bond law derives its radius and stiffness per unit area
// from them instead of keeping them in every bond's state; where no pair is at hand (stored
// energy, time step, snapshots) the engine passes them from the particle store.
struct BondRadii {
  double R1 = 0.0, R2 = 0.0;
};
inline BondRadii radii_of(const PairGeometry& g) noexcept {
  return {g.R1, g.R2};
}

// The run's geometry, as a bond's section needs it where no pair is at hand (stored energy, time
// step, snapshots): 2D or 3D, the disks' thickness, planar spheres. The engine sets it on a
// law's parameters (`Params::run`) before any bond is installed; it is not input.
struct RunGeometry {
  bool planar = false;
  bool planar_sphere = false;
  std::uint8_t unused[6]{};  // named, not padding: checkpoints copy the bytes (core/archive.hpp)
  double thickness = 1.0;
};

// The shape of a particle pair from centres and radii (§0.2): normal, distance, overlap and the
// lever arms to the contact point in the middle of the overlap (or gap). Total-formulation bonds
// need nothing more.
[[gnu::always_inline]] inline PairGeometry pair_shape(const Vec3& x1, double R1, const Vec3& x2,
                                                      double R2, bool planar,
                                                      double thickness) noexcept {
  PairGeometry g;
  const Vec3 dvec = x2 - x1;
  g.d = norm(dvec);
  g.n = dvec * (1.0 / g.d);
  g.delta = R1 + R2 - g.d;
  const Vec3 xc_rel = g.n * (R1 - 0.5 * g.delta);  // x_c - x_1
  g.r1 = xc_rel;
  g.r2 = xc_rel - dvec;
  g.R1 = R1;
  g.R2 = R2;
  g.planar = planar;
  g.thickness = thickness;
  return g;
}

// Adds the motion of the pair to its shape: the relative velocity of the contact point, the
// angular velocities and the masses (contacts and incremental bonds).
[[gnu::always_inline]] inline void add_pair_motion(PairGeometry& g, const Vec3& v1, const Vec3& w1,
                                                   const Vec3& v2, const Vec3& w2, double m1,
                                                   double m2) noexcept {
  g.vc = (v2 + cross(w2, g.r2)) - (v1 + cross(w1, g.r1));
  g.w1 = w1;
  g.w2 = w2;
  g.m1 = m1;
  g.m2 = m2;
}

// Geometry of a particle pair from centres, radii and velocities (§0.2): its shape and motion.
[[gnu::always_inline]] inline PairGeometry pair_geometry(const Vec3& x1, double R1, const Vec3& x2,
                                                         double R2, const Vec3& v1, const Vec3& w1,
                                                         const Vec3& v2, const Vec3& w2, double m1,
                                                         double m2, bool planar,
                                                         double thickness) noexcept {
  PairGeometry g = pair_shape(x1, R1, x2, R2, planar, thickness);
  add_pair_motion(g, v1, w1, v2, w2, m1, m2);
  return g;
}

// Orientations (body to world) of the two bodies, for the total bond formulations that need them
// (§4.2, §4.3; a law says so with `needs_frames`). In 2D, rotations about z by the disks' angles.
struct BodyFrames {
  Quat q1, q2;
};

// What a law produces for one pair in one step.
struct PairForce {
  Vec3 force;   // on particle 2
  Vec3 couple;  // pure couple on particle 2
};

// Energy that left the elastic springs of one item in one step (booked by the engine, §2.4).
struct PairDissipation {
  double slip = 0.0;      // Coulomb sliding
  double viscous = 0.0;   // dashpots
  double deleted = 0.0;   // spring energy lost without work (contact separated with shear load,
                          // Hertz stiffness change)
  double dilation = 0.0;  // work put into smooth joints' normal springs by dilation (§5): an
                          // input, not a loss
  PairDissipation& operator+=(const PairDissipation& o) noexcept {
    slip += o.slip;
    viscous += o.viscous;
    deleted += o.deleted;
    dilation += o.dilation;
    return *this;
  }
};

// Stored elastic energy of a bond by component (§4.0).
struct BondEnergy {
  double tension = 0.0;      // normal part while F_n < 0
  double compression = 0.0;  // normal part while F_n >= 0
  double shear = 0.0;
  double bending = 0.0;
  double twisting = 0.0;
  double total() const noexcept { return tension + compression + shear + bending + twisting; }
  BondEnergy& operator+=(const BondEnergy& o) noexcept {
    tension += o.tension;
    compression += o.compression;
    shear += o.shear;
    bending += o.bending;
    twisting += o.twisting;
    return *this;
  }
};

// A bond law's elastic moduli as the papers use them: the bar-wave speed sqrt(E / rho) of a
// sample and the crack energy sigma^2 V / (2 E) or tau^2 V / (2 G) (docs/analysis.md §2.3).
struct BondModuli {
  double young = 0.0;  // Pa
  double shear = 0.0;  // Pa
};

enum class CrackMode : std::uint8_t { Tensile = 0, Shear = 1 };

// What a failure does to the bond: it breaks (a crack; the bond is removed), one of its elements
// breaks (a crack; the bond stays and its force of the step is applied: the flat joint), or it is
// released without a crack (a fully broken interface whose faces have parted).
enum class BondOutcome : std::uint8_t { Broken = 0, ElementBroken = 1, Released = 2 };

// A bond's loads against its strength, as its law judges them (each bond law's `assess` reads its
// state after the step's update): the failure decision of one step with the quantities the
// crack record needs (§4.0), and what snapshots show of intact bonds.
struct BondFailure {
  bool broken = false;
  BondOutcome outcome = BondOutcome::Broken;  // what `broken` does
  CrackMode mode = CrackMode::Tensile;
  double Fn = 0.0;  // compression-positive
  double Fs = 0.0;
  double Mt = 0.0;                      // signed twisting moment M . n
  double Mb = 0.0;                      // |bending moment|
  double sigma = 0.0, tau = 0.0;        // peak stresses, sigma tension-positive
  double ratio_t = 0.0, ratio_s = 0.0;  // criterion ratios; NaN where undefined
  // How close the bond is to its strength: 1 or more when it breaks (the larger criterion ratio;
  // the quaternion bond's breakage index B).
  double index = 0.0;
  double bond_radius = 0.0;
  // From the §0.2 contact point to the law's own point on the branch, along n (beam bonds act
  // at x1 + d R1 / (R1 + R2), §4.2 step 8): where the crack record places the crack.
  double point_shift = 0.0;
  Vec3 point_offset;  // and from there across the interface (the flat joint's element)
  BondEnergy energy;  // released energy by component
};

// The breakage index of a criterion tested as "tensile, else shear": the larger of its two ratios.
// A shear ratio of NaN means the shear limit is used up (no strength left), so the bond is at or
// beyond its strength whatever the tensile ratio says.
inline double larger_ratio(double ratio_t, double ratio_s) noexcept {
  return std::isnan(ratio_s) ? std::max(ratio_t, 1.0) : std::max(ratio_t, ratio_s);
}

}  // namespace breccia
