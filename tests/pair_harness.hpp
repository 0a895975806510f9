#pragma once
// Drives one pair through a law kernel the way the engine does (geometry at x^n with velocities
// v^{n-1/2}, then x^{n+1} = x^n + v dt), and returns forces and torques on both particles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "breccia/law/registry.hpp"

namespace breccia::test {

template <class List>
struct GTypes;
template <class... Ts>
struct GTypes<TypeList<Ts...>> {
  using type = ::testing::Types<Ts...>;
};

struct Body {
  Vec3 x, v, w;
  Quat q;  // orientation, body to world
  double R = 0.5e-3;
  double m = 1.388e-6;
};

struct PairResult {
  Vec3 f1, f2, t1, t2, couple;
};

inline PairGeometry make_geometry(const Body& a, const Body& b, bool planar = false,
                                  double thickness = 1.0, bool planar_sphere = false) {
  PairGeometry g =
      pair_geometry(a.x, a.R, b.x, b.R, a.v, a.w, b.v, b.w, a.m, b.m, planar, thickness);
  g.planar_sphere = planar && planar_sphere;
  return g;
}

inline PairResult assemble(const PairGeometry& g, const PairForce& pf) {
  PairResult r;
  r.f2 = pf.force;
  r.f1 = -pf.force;
  r.t2 = cross(g.r2, pf.force) + pf.couple;
  r.t1 = cross(g.r1, -pf.force) - pf.couple;
  r.couple = pf.couple;
  return r;
}

// Joint laws (docs/physics.md §5) are installed with a joint-plane normal, not body frames.
template <class Law>
constexpr bool is_joint_law = requires {
  Law::starts_bonded;
};
template <class Law>
constexpr bool is_bond_law = !is_joint_law<Law> && requires {
  Law::install;
};

// One step of a pair: evaluates the law, then moves both bodies with their velocities.
template <class Law>
struct PairStepper {
  typename Law::Params params = Law::example_params();
  typename Law::State state{};
  Body a, b;
  double dt = 1e-8;
  // 2D laws (RICEBAL) run on planar spheres in the x-y plane; the tests keep their motion there
  // through in_plane() and about_z().
  bool planar = planar_only_law<Law>;
  bool planar_sphere = planar_only_law<Law>;
  double thickness = 1.0;
  BondFailure failure;
  PairDissipation dissipation;
  Vec3 joint_normal{1, 0, 0};  // joint laws: the plane's normal (tilted from most branches)

  void install(std::uint64_t seed = 1, std::uint64_t tag = 1) {
    // As the engine does: the run's geometry, then the derived parameters.
    if constexpr (requires { params.run; })
      params.run = {
          .planar = planar, .planar_sphere = planar && planar_sphere, .thickness = thickness};
    if constexpr (requires { Law::prepare(params); }) Law::prepare(params);
    if constexpr (is_joint_law<Law>)
      state = Law::install(params, make_geometry(a, b, planar, thickness, planar_sphere),
                           joint_normal, Law::starts_bonded(params));
    else if constexpr (is_bond_law<Law>)
      state = Law::install(params, make_geometry(a, b, planar, thickness, planar_sphere),
                           {a.q, b.q}, seed, tag);
  }
  PairResult evaluate() {
    const PairGeometry g = make_geometry(a, b, planar, thickness, planar_sphere);
    PairForce pf;
    if constexpr (is_joint_law<Law>)
      pf = Law::compute(params, state, g, dt, dissipation, failure);
    else if constexpr (is_bond_law<Law> && law_dissipates<Law>)
      pf = Law::compute(params, state, g, {a.q, b.q}, dt, dissipation, failure);
    else if constexpr (is_bond_law<Law>)
      pf = Law::compute(params, state, g, {a.q, b.q}, dt, failure);
    else
      pf = Law::compute(params, state, g, dt, dissipation);
    return assemble(g, pf);
  }
  void move() {
    a.x += a.v * dt;
    b.x += b.v * dt;
    a.q = integrate_orientation(a.q, a.w, dt);
    b.q = integrate_orientation(b.q, b.w, dt);
  }
  // The radii of the two grains, from which a bond's section follows.
  BondRadii radii() const { return {a.R, b.R}; }
  double energy() const {
    if constexpr (is_bond_law<Law> || is_joint_law<Law>)
      return Law::energy(params, state, radii()).total();
    else
      return Law::stored_energy(params, state);
  }
};

// A vector as a law's own dimension sees it: unchanged in 3D; for 2D laws the in-plane part of a
// position or velocity, and the z part of a rotation.
template <class Law>
Vec3 in_plane(const Vec3& v) {
  return planar_only_law<Law> ? Vec3{v.x, v.y, 0.0} : v;
}
template <class Law>
Vec3 about_z(const Vec3& w) {
  return planar_only_law<Law> ? Vec3{0.0, 0.0, w.z} : w;
}

// Rotation matrix applied through a quaternion.
inline Vec3 rot(const Quat& q, const Vec3& v) {
  return rotate(q, v);
}

}  // namespace breccia::test
