#pragma once
// The 27 cells of a grid of cubes of side h around a point: the cells a search within h of the
// point must visit, whatever container holds the grid's cells.
#include <cmath>

#include "breccia/core/vec3.hpp"

namespace breccia {

// Calls f(a, b, c) for the cell of x and its 26 neighbours, by integer cell coordinates.
template <class F>
void for_each_cell_around(const Vec3& x, double h, F&& f) {
  const auto a = static_cast<long long>(std::floor(x.x / h));
  const auto b = static_cast<long long>(std::floor(x.y / h));
  const auto c = static_cast<long long>(std::floor(x.z / h));
  for (long long da = -1; da <= 1; ++da)
    for (long long db = -1; db <= 1; ++db)
      for (long long dc = -1; dc <= 1; ++dc) f(a + da, b + db, c + dc);
}

}  // namespace breccia
