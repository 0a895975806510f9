#include "breccia/sample/spatial_order.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

namespace breccia {

namespace {

// Spreads the low 21 bits of v so that two zero bits separate each of them.
std::uint64_t spread_bits(std::uint64_t v) noexcept {
  v &= 0x1fffffu;
  v = (v | v << 32) & 0x1f00000000ffffu;
  v = (v | v << 16) & 0x1f0000ff0000ffu;
  v = (v | v << 8) & 0x100f00f00f00f00fu;
  v = (v | v << 4) & 0x10c30c30c30c30c3u;
  v = (v | v << 2) & 0x1249249249249249u;
  return v;
}

}  // namespace

std::uint64_t morton_key(const Vec3& x, const Vec3& lo, const Vec3& hi) noexcept {
  constexpr double cells = 2097151.0;  // 2^21 - 1
  std::uint64_t key = 0;
  for (int k = 0; k < 3; ++k) {
    const double span = hi[k] - lo[k];
    const double u = span > 0.0 ? std::clamp((x[k] - lo[k]) / span, 0.0, 1.0) : 0.0;
    key |= spread_bits(static_cast<std::uint64_t>(u * cells)) << k;
  }
  return key;
}

std::vector<std::size_t> spatial_order(const std::vector<ParticleSpec>& particles) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
  for (const ParticleSpec& p : particles)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p.position[k]);
      hi[k] = std::max(hi[k], p.position[k]);
    }
  std::vector<std::uint64_t> key(particles.size());
  for (std::size_t i = 0; i < particles.size(); ++i)
    key[i] = morton_key(particles[i].position, lo, hi);
  std::vector<std::size_t> order(particles.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return key[a] < key[b]; });
  return order;
}

void sort_spatially(GeometryData& g) {
  const std::vector<std::size_t> order = spatial_order(g.particles);
  std::vector<ParticleSpec> particles(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) particles[k] = g.particles[order[k]];
  g.particles = std::move(particles);
  if (g.particle_lines.size() == order.size()) {
    std::vector<std::size_t> lines(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) lines[k] = g.particle_lines[order[k]];
    g.particle_lines = std::move(lines);
  }
}

}  // namespace breccia
