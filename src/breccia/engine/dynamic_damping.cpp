// Dynamic damping (docs/physics.md §2.1): local damping is lowered around each fresh crack for
// the time its waves take to leave the source, so a bonded-particle model radiates where it
// breaks and stays quasi-static elsewhere. The grains a crack reaches are found in a grid of the
// rank's own grains binned at the last neighbour rebuild; no grain has moved more than half the
// skin since, so a search reaching the skin beyond the radius finds every one.
#include <algorithm>
#include <cmath>
#include <limits>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

namespace {

constexpr double kNotDamped = -std::numeric_limits<double>::infinity();

std::int64_t cell_coord(double v, double lo, double inv_h, std::int64_t n) noexcept {
  const auto c = static_cast<std::int64_t>(std::floor((v - lo) * inv_h));
  return std::clamp<std::int64_t>(c, 0, n - 1);
}

}  // namespace

void Simulation::set_dynamic_damping(double alpha, double radius, double time) {
  const std::string where = "engine settings";
  if (!(alpha >= 0.0 && alpha < 1.0))
    throw InputError(where, "dynamic_damping_alpha", num(alpha), "allowed: 0 <= value < 1");
  if (!(radius >= 0.0) || !std::isfinite(radius))
    throw InputError(where, "dynamic_damping_radius", num(radius), "must be >= 0 m (0 = off)");
  if (!(time >= 0.0) || !std::isfinite(time))
    throw InputError(where, "dynamic_damping_time", num(time), "must be >= 0 s (0 = off)");
  cfg_.dynamic_damping_alpha = alpha;
  cfg_.dynamic_damping_radius = radius;
  cfg_.dynamic_damping_time = time;
  if (!(radius > 0.0 && time > 0.0)) std::vector<double>().swap(damped_less_until_);
}

double Simulation::dynamically_damped_until(std::size_t i) const noexcept {
  return i < damped_less_until_.size() ? damped_less_until_[i] : kNotDamped;
}

void Simulation::build_dynamic_damping_grid() {
  RegionGrid& g = region_grid_;
  const IndexRange own = owned_particles();
  g.own_begin = own.begin;
  g.own_end = own.end;
  g.built_at = rebuilds_;
  const bool planar = p_.planar();
  const double inf = std::numeric_limits<double>::infinity();
  Vec3 lo{inf, inf, inf}, hi = -lo;
  for (std::size_t i = own.begin; i < own.end; ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], x_at_build_[i][k]);
      hi[k] = std::max(hi[k], x_at_build_[i][k]);
    }
  if (own.begin >= own.end) lo = hi = Vec3{};
  // Cells about the size of the region, fewer than four a grain.
  double h = cfg_.dynamic_damping_radius + skin_;
  auto cells = [&](double hh) {
    double c = 1.0;
    for (int k = 0; k < (planar ? 2 : 3); ++k) c *= std::floor((hi[k] - lo[k]) / hh) + 1.0;
    return c;
  };
  while (cells(h) > 4.0 * static_cast<double>(own.size()) + 64.0) h *= 1.26;
  g.lo = lo;
  g.inv_h = 1.0 / h;
  g.nx = static_cast<std::int64_t>(std::floor((hi.x - lo.x) / h)) + 1;
  g.ny = static_cast<std::int64_t>(std::floor((hi.y - lo.y) / h)) + 1;
  g.nz = planar ? 1 : static_cast<std::int64_t>(std::floor((hi.z - lo.z) / h)) + 1;
  const auto ncell = static_cast<std::size_t>(g.nx * g.ny * g.nz);
  auto cell_of = [&](const Vec3& x) {
    return static_cast<std::size_t>(
        (cell_coord(x.z, g.lo.z, g.inv_h, g.nz) * g.ny + cell_coord(x.y, g.lo.y, g.inv_h, g.ny)) *
            g.nx +
        cell_coord(x.x, g.lo.x, g.inv_h, g.nx));
  };
  g.start.assign(ncell + 1, 0);
  for (std::size_t i = own.begin; i < own.end; ++i) ++g.start[cell_of(x_at_build_[i]) + 1];
  for (std::size_t c = 0; c < ncell; ++c) g.start[c + 1] += g.start[c];
  g.items.resize(own.size());
  std::vector<std::uint32_t> fill(g.start.begin(), g.start.end() - 1);
  for (std::size_t i = own.begin; i < own.end; ++i)
    g.items[fill[cell_of(x_at_build_[i])]++] = static_cast<std::uint32_t>(i);
}

// Each crack of the step lowers the damping of the own free grains whose centres lie within the
// radius of its contact point until its time plus the window; a grain near several keeps the
// latest. The marks are a maximum, so their order (and the thread or rank count) does not matter.
void Simulation::mark_dynamic_damping(std::size_t first_crack) {
  if (!(cfg_.dynamic_damping_radius > 0.0 && cfg_.dynamic_damping_time > 0.0) ||
      cracks_.size() <= first_crack)
    return;
  const std::size_t n = p_.size();
  if (damped_less_until_.size() != n) damped_less_until_.resize(n, kNotDamped);
  const IndexRange own = owned_particles();
  RegionGrid& g = region_grid_;
  if (g.built_at != rebuilds_ || g.own_begin != own.begin || g.own_end != own.end ||
      g.items.size() != own.size())
    build_dynamic_damping_grid();
  const double radius = cfg_.dynamic_damping_radius, r2 = radius * radius;
  const double reach = radius + skin_;
  const std::int64_t nz_reach = p_.planar() ? 0 : 1;
  cracks_.visit(first_crack, [&](const CrackRecord& c) {
    const double until = c.time + cfg_.dynamic_damping_time;
    const Vec3& x = c.position;
    const std::int64_t x0 = cell_coord(x.x - reach, g.lo.x, g.inv_h, g.nx),
                       x1 = cell_coord(x.x + reach, g.lo.x, g.inv_h, g.nx),
                       y0 = cell_coord(x.y - reach, g.lo.y, g.inv_h, g.ny),
                       y1 = cell_coord(x.y + reach, g.lo.y, g.inv_h, g.ny),
                       z0 = nz_reach ? cell_coord(x.z - reach, g.lo.z, g.inv_h, g.nz) : 0,
                       z1 = nz_reach ? cell_coord(x.z + reach, g.lo.z, g.inv_h, g.nz) : 0;
    for (std::int64_t cz = z0; cz <= z1; ++cz)
      for (std::int64_t cy = y0; cy <= y1; ++cy)
        for (std::int64_t cx = x0; cx <= x1; ++cx) {
          const auto cell = static_cast<std::size_t>((cz * g.ny + cy) * g.nx + cx);
          for (std::uint32_t m = g.start[cell]; m < g.start[cell + 1]; ++m) {
            const std::uint32_t i = g.items[m];
            if (norm2(p_.pos_rad[i].x - x) <= r2)
              damped_less_until_[i] = std::max(damped_less_until_[i], until);
          }
        }
  });
}

}  // namespace breccia
