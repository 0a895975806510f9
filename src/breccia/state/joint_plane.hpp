#pragma once
// Where the joints of a sample lie (docs/physics.md §5, "Assigning smooth joints"): one plane
// through `point` with unit `normal`, limited to a disc of `radius` (a penny-shaped joint; a
// segment of half-length `radius` in 2D), or a set of parallel planes `spacing` apart. A particle
// pair is cut by the joint when its branch segment crosses a plane inside the plane's extent.
#include <cmath>
#include <limits>

#include "breccia/core/vec3.hpp"

namespace breccia {

struct JointPlane {
  Vec3 point;
  Vec3 normal{0, 0, 1};
  double radius = std::numeric_limits<double>::infinity();  // m; infinite: the whole plane
  double spacing = 0.0;  // m; > 0: planes through point + k spacing normal for every integer k

  // Whether the branch from x1 to x2 crosses the joint within its extent.
  bool cuts(const Vec3& x1, const Vec3& x2) const noexcept {
    const double s1 = dot(x1 - point, normal), s2 = dot(x2 - point, normal);
    double offset = 0.0;  // signed distance of the crossed plane from `point`
    if (spacing > 0.0) {
      const double k1 = std::floor(s1 / spacing), k2 = std::floor(s2 / spacing);
      if (k1 == k2) return false;
      offset = std::max(k1, k2) * spacing;
    } else if ((s1 < 0.0) == (s2 < 0.0)) {
      return false;
    }
    if (!std::isfinite(radius)) return true;
    const Vec3 p = x1 + (x2 - x1) * ((s1 - offset) / (s1 - s2));
    const Vec3 rel = p - (point + normal * offset);
    return norm2(rel - normal * dot(rel, normal)) <= radius * radius;
  }
};

}  // namespace breccia
