#pragma once
// Particle order in memory. A pair kernel reads both grains of a pair; when neighbours in space
// are neighbours in the arrays those reads hit the cache. Samples from other tools (GenGeo's
// insertion order, a file written by hand) come in no useful order, so the run sorts them along
// a space-filling curve before the engine sees them. Tags, not positions in the arrays, name the
// particles in every output, so the order changes no result but the rounding of sums.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "breccia/sample/geometry_file.hpp"

namespace breccia {

// The Morton (Z-order) key of a position inside the box [lo, hi]: 21 bits per axis, interleaved.
std::uint64_t morton_key(const Vec3& x, const Vec3& lo, const Vec3& hi) noexcept;

// The permutation that sorts the particles by Morton key over their bounding box (ties by their
// present order): entry k is the present index of the particle that goes to place k.
std::vector<std::size_t> spatial_order(const std::vector<ParticleSpec>& particles);

// Reorders the particles (and their file lines, when known) along the curve. Bonds name tags
// and are unchanged.
void sort_spatially(GeometryData& g);

}  // namespace breccia
