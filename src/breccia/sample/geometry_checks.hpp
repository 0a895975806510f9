#pragma once
// What every sample read from a file must satisfy before a simulation is built from it, whatever
// the reader (breccia-geometry, x-y-z-r table, GenGeo): a bounded count, finite values, unique
// tags, no grain whose centre lies inside another (coincident or deeply overlapping grains give
// infinite or NaN forces in the first step), bonds between two different existing grains, each
// once. Errors name the file and the line of the offending row.
#include <cstdint>
#include <string>

#include "breccia/sample/geometry_file.hpp"

namespace breccia {

// The most bonds per particle a file may announce (a polydisperse packing has at most a few tens).
inline constexpr std::uint64_t kMaxBondsPerParticle = 64;

// "source:line" of particle i (or bond k), or just the source when the line is not known.
std::string particle_where(const GeometryData& g, std::size_t i, const std::string& source);
std::string bond_where(const GeometryData& g, std::size_t k, const std::string& source);

// Throws InputError naming `source`, the line, the key, the value and what is allowed unless the
// count is within `max_particles`, every position, radius and density is finite and positive
// where it must be, the sample spans at most 1e9 of its largest radii, tags are unique, no two
// centres lie closer than the larger of their radii, and every bond joins two different
// existing tags once.
void check_geometry(const GeometryData& g, const std::string& source,
                    std::uint64_t max_particles = kMaxFileParticles);

// Throws InputError unless a count announced at `where` for `key` is at most `limit`.
void check_announced_count(std::uint64_t count, std::uint64_t limit, const std::string& where,
                           const char* key);

}  // namespace breccia
