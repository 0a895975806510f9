#pragma once
// Pieces every frictional contact law shares (docs/physics.md §3.1, §3.2, §2.2, §3.6): carrying the
// shear spring into the current contact plane, the incremental shear update with the Coulomb
// limit, and the dashpots with the no-tension rule. Each books its losses into PairDissipation.
#include <cmath>

#include "breccia/law/pair.hpp"

namespace breccia {

// The rotation that carries a contact's stored shear force and moments from the previous contact
// plane (normal n_old) into the current one: exact tilt, then the spin of the pair about n.
inline PlaneCarry contact_carry(const Vec3& n_old, const PairGeometry& g, double dt) noexcept {
  return PlaneCarry(n_old, g.n, 0.5 * dot(g.w1 + g.w2, g.n) * dt);
}

struct ShearResult {
  Vec3 force;
  bool sliding = false;
};

// Incremental shear spring of stiffness k driven by the tangential velocity vt, limited to
// |F_s| <= limit; the slip dissipation |F_s| (|F*| - |F_s|) / k is booked (§3.6).
inline ShearResult coulomb_shear(const Vec3& fs, const Vec3& vt, double k, double dt, double limit,
                                 PairDissipation& dis) noexcept {
  ShearResult r{fs - vt * (k * dt), false};
  const double ft2 = norm2(r.force);
  if (ft2 > limit * limit) {
    const double ft = std::sqrt(ft2);
    dis.slip += limit * (ft - limit) / k;
    r.force *= limit / ft;
    r.sliding = true;
  }
  return r;
}

// Dashpot force with normal and shear coefficients cn, cs (N s/m). The total normal force never
// becomes attractive (no-tension rule, §2.2); the shear dashpot is off while sliding. Books the
// viscous loss.
inline Vec3 dashpot_force(const PairGeometry& g, double fn_spring, double vn, const Vec3& vt,
                          double cn, double cs, bool sliding, double dt,
                          PairDissipation& dis) noexcept {
  double fn_visc = -cn * vn;
  if (fn_spring + fn_visc < 0.0) fn_visc = -fn_spring;
  const Vec3 fs_visc = sliding ? Vec3{} : vt * -cs;
  dis.viscous -= (fn_visc * vn + dot(fs_visc, vt)) * dt;
  return g.n * fn_visc + fs_visc;
}

}  // namespace breccia
