#include "breccia/sample/geometry_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <unordered_map>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia {

namespace {

// Largest span of a sample in units of its largest radius: beyond it the grid keys of the
// overlap check (and the engine's neighbour grid) lose their meaning, and no connected sample
// is that sparse.
constexpr double kMaxSpanInRadii = 1e9;

void check_values(const GeometryData& g, const std::string& source) {
  for (std::size_t i = 0; i < g.particles.size(); ++i) {
    const ParticleSpec& p = g.particles[i];
    const auto where = [&] { return particle_where(g, i, source); };
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(p.position[k]))
        throw InputError(where(), std::string(1, "xyz"[k]), num(p.position[k]),
                         "expected a finite coordinate in m");
    if (!(std::isfinite(p.radius) && p.radius > 0.0))
      throw InputError(where(), "radius", num(p.radius), "expected a finite radius > 0 m");
    if (!(std::isfinite(p.density) && p.density > 0.0))
      throw InputError(where(), "density", num(p.density), "expected a finite density > 0 kg/m^3");
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(p.velocity[k]) || !std::isfinite(p.angular_velocity[k]))
        throw InputError(where(), "velocity", "non-finite", "expected finite velocities");
  }
}

void check_tags(const GeometryData& g, const std::string& source) {
  std::unordered_map<std::uint64_t, std::size_t> first;
  first.reserve(g.particles.size());
  for (std::size_t i = 0; i < g.particles.size(); ++i) {
    const auto [it, fresh] = first.emplace(g.particles[i].tag, i);
    if (!fresh)
      throw InputError(
          particle_where(g, i, source), "tag", std::to_string(g.particles[i].tag),
          "tags must be unique; the same tag is at " + particle_where(g, it->second, source));
  }
  std::set<std::pair<std::uint64_t, std::uint64_t>> seen;
  for (std::size_t k = 0; k < g.bonds.size(); ++k) {
    const auto [a, b] = g.bonds[k];
    const auto where = [&] { return bond_where(g, k, source); };
    for (const auto& [t, column] : {std::pair{a, "bond tag1"}, std::pair{b, "bond tag2"}})
      if (!first.count(t))
        throw InputError(where(), column, std::to_string(t), "no particle has this tag");
    if (a == b)
      throw InputError(where(), "bond", std::to_string(a) + " " + std::to_string(b),
                       "a particle cannot bond to itself");
    if (!seen.insert({std::min(a, b), std::max(a, b)}).second)
      throw InputError(where(), "bond", std::to_string(a) + " " + std::to_string(b),
                       "this pair is bonded twice; list each bond once");
  }
}

// No centre inside another grain: d >= max(r_i, r_j). Grains binned in cells of the largest
// radius; such a pair lies in the same or adjacent cells.
void check_overlaps(const GeometryData& g, const std::string& source) {
  double r_max = 0.0;
  Vec3 lo = g.particles.front().position, hi = lo;
  for (const ParticleSpec& p : g.particles) {
    r_max = std::max(r_max, p.radius);
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p.position[k]);
      hi[k] = std::max(hi[k], p.position[k]);
    }
  }
  for (int k = 0; k < 3; ++k)
    if (!((hi[k] - lo[k]) / r_max <= kMaxSpanInRadii))
      throw InputError(source, std::string(1, "xyz"[k]) + " extent", num(hi[k] - lo[k]) + " m",
                       "the sample spans more than 1e9 of its largest radii (" + num(r_max) +
                           " m): check the units of the coordinates and radii");
  using Cell = std::array<long long, 3>;
  const auto cell_of = [&](const Vec3& x) {
    Cell c;
    for (int k = 0; k < 3; ++k) c[k] = static_cast<long long>(std::floor((x[k] - lo[k]) / r_max));
    return c;
  };
  std::map<Cell, std::vector<std::size_t>> cells;
  for (std::size_t i = 0; i < g.particles.size(); ++i)
    cells[cell_of(g.particles[i].position)].push_back(i);
  for (std::size_t i = 0; i < g.particles.size(); ++i) {
    const ParticleSpec& p = g.particles[i];
    const Cell c = cell_of(p.position);
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          const auto it = cells.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == cells.end()) continue;
          for (const std::size_t j : it->second) {
            if (j <= i) continue;
            const ParticleSpec& q = g.particles[j];
            const double d = norm(q.position - p.position);
            if (d < std::max(p.radius, q.radius))
              throw InputError(particle_where(g, j, source), "position",
                               fmt::format("{} m from the centre of the grain at {}", num(d),
                                           particle_where(g, i, source)),
                               d == 0.0
                                   ? "two grains share a centre (a duplicated row?)"
                                   : "grains may touch or overlap a little, but no centre may lie "
                                     "inside another grain (radii " +
                                         num(p.radius) + " and " + num(q.radius) + " m)");
          }
        }
  }
}

}  // namespace

std::string particle_where(const GeometryData& g, std::size_t i, const std::string& source) {
  if (i < g.particle_lines.size() && g.particle_lines[i] > 0)
    return source + ":" + std::to_string(g.particle_lines[i]);
  return source + " (particle " + std::to_string(i + 1) + ")";
}

std::string bond_where(const GeometryData& g, std::size_t k, const std::string& source) {
  if (k < g.bond_lines.size() && g.bond_lines[k] > 0)
    return source + ":" + std::to_string(g.bond_lines[k]);
  return source + " (bond " + std::to_string(k + 1) + ")";
}

void check_announced_count(std::uint64_t count, std::uint64_t limit, const std::string& where,
                           const char* key) {
  if (count > limit)
    throw InputError(
        where, key, std::to_string(count),
        "at most " + std::to_string(limit) + " (raise sample.max_particles for larger samples)");
}

void check_geometry(const GeometryData& g, const std::string& source, std::uint64_t max_particles) {
  if (g.particles.empty())
    throw InputError(source, "particles", "0", "the sample has no particles");
  check_announced_count(g.particles.size(), max_particles, source, "particles");
  check_announced_count(g.bonds.size(), kMaxBondsPerParticle * max_particles, source, "bonds");
  check_values(g, source);
  check_tags(g, source);
  check_overlaps(g, source);
}

}  // namespace breccia
