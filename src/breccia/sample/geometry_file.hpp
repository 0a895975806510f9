#pragma once
// Explicit geometry: a particle list and a bond list, from a text file or built in C++, so that
// users can import packings from other tools and tests can set up exact configurations.
//
// File format (`breccia-geometry 1`, one record per line, '#' starts a comment):
//
//   breccia-geometry 1
//   dimension 3                      # 3 (spheres) or 2 (disks in the x-y plane)
//   thickness 0.001                  # 2D only: disk thickness t in m (default 1)
//   particles 2
//   # tag x y z radius density [motion [vx vy vz [wx wy wz]]]
//   1 0     0 0 0.0005 2650
//   2 0.001 0 0 0.0005 2650 driven 0.001 0 0
//   bonds 1
//   # tag1 tag2
//   1 2
//
// SI units throughout. `motion` is free (default), fixed or driven; for free particles the
// velocities are initial values, for driven ones they are prescribed.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "breccia/state/particle_store.hpp"

namespace breccia {

// The most particles any file may announce or hold (the range of sample.max_particles).
inline constexpr std::uint64_t kMaxFileParticles = 100'000'000;

struct GeometryData {
  Dimension dimension = Dimension::Three;
  double thickness = 1.0;
  std::vector<ParticleSpec> particles;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> bonds;
  // Line of each particle and bond row in the file it was read from (empty when not read), for
  // error messages.
  std::vector<std::size_t> particle_lines, bond_lines;

  // Builds the particle store; throws InputError on duplicate tags and bad values.
  ParticleStore make_store(PlanarBody body = PlanarBody::Disk) const;
  // The particles of a store (tags, positions, radii, densities, velocities, motion), no bonds.
  static GeometryData of_store(const ParticleStore& ps);
};

// Reads a geometry file. Throws InputError naming the file, line, key, value and what is allowed,
// also when the sample fails check_geometry (sample/geometry_checks.hpp) or holds more than
// `max_particles`.
GeometryData read_geometry(const std::string& path,
                           std::uint64_t max_particles = kMaxFileParticles);
// Parses geometry text; `source` names it in error messages.
GeometryData parse_geometry(const std::string& text, const std::string& source,
                            std::uint64_t max_particles = kMaxFileParticles);
// Writes a geometry file that read_geometry reads back exactly (17 significant digits).
void write_geometry(const std::string& path, const GeometryData& g);

}  // namespace breccia
