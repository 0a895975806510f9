#pragma once
// Import of packings made by other tools (issue: users of YADE, PFC and ESyS-Particle bring their
// samples). Both readers return particles without motion and, for GenGeo, the bond list; errors
// name the file, line, key, value and what is allowed.
//
// Table: one particle per row, `x y z radius` (3D) or `x y radius` / `x y z radius` (2D, z must
// be 0), separated by whitespace or commas; '#' starts a comment; one header row of words is
// skipped. Tags are the row numbers from 1.
//
// GenGeo: the `LSMGeometry 1.2` text that ESyS-Particle's GenGeo writes (MNTable::write): a
// Dimension line, particles `x y z radius id tag` between BeginParticles/EndParticles, and
// bonds `id1 id2 tag` between BeginConnect/EndConnect. Breccia tags are GenGeo ids + 1.
#include <istream>
#include <string>

#include "breccia/sample/geometry_file.hpp"

namespace breccia {

// Both readers refuse more than `max_particles` rows and samples that fail check_geometry
// (sample/geometry_checks.hpp).
GeometryData read_xyzr_table(const std::string& path, Dimension dim, double density,
                             double thickness, std::uint64_t max_particles = kMaxFileParticles);
GeometryData read_gengeo(const std::string& path, double density, double thickness,
                         std::uint64_t max_particles = kMaxFileParticles);
// The same from a stream; `source` names it in errors (the fuzzers feed these).
GeometryData parse_xyzr_table(std::istream& in, const std::string& source, Dimension dim,
                              double density, double thickness,
                              std::uint64_t max_particles = kMaxFileParticles);
GeometryData parse_gengeo(std::istream& in, const std::string& source, double density,
                          double thickness, std::uint64_t max_particles = kMaxFileParticles);

}  // namespace breccia
