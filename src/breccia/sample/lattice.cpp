#include "breccia/sample/lattice.hpp"

#include <cmath>

#include "breccia/core/error.hpp"

namespace breccia {

ParticleStore fcc_block(int nx, int ny, int nz, double radius, double density, Vec3 origin) {
  if (nx < 1 || ny < 1 || nz < 1)
    throw InputError("fcc lattice", "cells",
                     std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz),
                     "each count must be >= 1");
  ParticleStore s(Dimension::Three, 1.0);
  const double a = 2.0 * std::sqrt(2.0) * radius;
  const Vec3 basis[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  std::uint64_t tag = 1;
  for (int k = 0; k < nz; ++k)
    for (int b2 = 0; b2 < 2; ++b2)  // the two atomic layers of each cell, bottom first
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
          for (const Vec3& b : basis) {
            if ((b.z > 0.0) != (b2 == 1)) continue;
            ParticleSpec p;
            p.tag = tag++;
            p.position = origin + Vec3{(i + b.x) * a + radius, (j + b.y) * a + radius,
                                       (k + b.z) * a + radius};
            p.radius = radius;
            p.density = density;
            s.add(p);
          }
  return s;
}

ParticleStore hex_block(int nx, int ny, double radius, double density, double thickness,
                        Vec3 origin) {
  if (nx < 1 || ny < 1)
    throw InputError("hexagonal lattice", "cells", std::to_string(nx) + "x" + std::to_string(ny),
                     "each count must be >= 1");
  ParticleStore s(Dimension::Two, thickness);
  std::uint64_t tag = 1;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      ParticleSpec p;
      p.tag = tag++;
      p.position = origin + Vec3{2.0 * radius * (i + 0.5 * (j % 2)) + radius,
                                 std::sqrt(3.0) * radius * j + radius, 0.0};
      p.radius = radius;
      p.density = density;
      s.add(p);
    }
  return s;
}

}  // namespace breccia
