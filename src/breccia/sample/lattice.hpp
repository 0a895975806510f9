#pragma once
// Regular packings for verification and benchmarks (docs/physics.md §7.5): face-centred cubic
// blocks of equal spheres and hexagonal blocks of equal disks, touching exactly. Tags run from 1 in
// storage order, which is spatial (rows, then layers), so neighbours are close in memory.
#include "breccia/state/particle_store.hpp"

namespace breccia {

// nx x ny x nz cubic cells of edge 2 sqrt(2) R, four spheres per cell, lowest corner at origin.
ParticleStore fcc_block(int nx, int ny, int nz, double radius, double density, Vec3 origin = {});

// nx disks per row, ny rows, rows sqrt(3) R apart and every other row shifted by R.
ParticleStore hex_block(int nx, int ny, double radius, double density, double thickness,
                        Vec3 origin = {});

}  // namespace breccia
