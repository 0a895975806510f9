#pragma once
// Spheres (3D) and circles (2D, in the x-y plane) tangent to given spheres and planes: the
// Apollonius problem of docs/physics.md §7.4, as ESyS-Particle's GenGeo fitters pose it.
// Subtracting the tangency equation of one reference sphere from the others makes them linear in
// the centre (and the radius); the reference equation then gives a quadratic.
#include <optional>
#include <vector>

#include "breccia/core/vec3.hpp"

namespace breccia {

// A sphere to touch from outside, or a plane (point, unit normal toward the free side).
struct Surface {
  bool plane = false;
  Vec3 point;           // sphere centre, or a point of the plane
  Vec3 normal;          // plane only
  double radius = 0.0;  // sphere only
};

struct FittedSphere {
  Vec3 centre;
  double radius = 0.0;
};

// Spheres (circles) of free radius tangent to D + 1 surfaces, at least one of them a sphere.
// Every positive-radius solution, smallest radius first. Empty when the system is singular
// (condition number above 1e8, docs/physics.md §7.4).
std::vector<FittedSphere> fit_free_radius(const std::vector<Surface>& surfaces, bool planar);

// Centres of a sphere (circle) of the given radius tangent to D surfaces, at least one of them a
// sphere (two solutions in general, nearest to `near` first).
std::vector<Vec3> fit_fixed_radius(const std::vector<Surface>& surfaces, double radius, bool planar,
                                   const Vec3& near);

}  // namespace breccia
