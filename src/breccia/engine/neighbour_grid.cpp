#include "breccia/engine/neighbour_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "breccia/core/parallel.hpp"

namespace breccia {

namespace {

struct Grid {
  Vec3 lo;
  double inv_h = 0.0;
  std::int64_t nx = 1, ny = 1, nz = 1;
  std::vector<std::uint32_t> start;  // CSR over cells
  std::vector<std::uint32_t> items;

  std::int64_t coord(double v, double l, std::int64_t n) const noexcept {
    const auto c = static_cast<std::int64_t>((v - l) * inv_h);
    return std::clamp<std::int64_t>(c, 0, n - 1);
  }
  std::int64_t cell_of(const Vec3& x) const noexcept {
    return (coord(x.z, lo.z, nz) * ny + coord(x.y, lo.y, ny)) * nx + coord(x.x, lo.x, nx);
  }
};

Grid make_grid(const std::vector<PosRad>& p, double skin, bool planar) {
  Grid g;
  const double inf = std::numeric_limits<double>::infinity();
  Vec3 lo{inf, inf, inf}, hi = -lo;
  double rmax = 0.0;
  for (const PosRad& q : p) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], q.x[k]);
      hi[k] = std::max(hi[k], q.x[k]);
    }
    rmax = std::max(rmax, q.r);
  }
  double h = 2.0 * rmax + skin;
  // Keep the cell count near the particle count so that sparse systems stay cheap in memory.
  const double n = static_cast<double>(p.size());
  auto cells = [&](double hh) {
    double c = 1.0;
    for (int k = 0; k < (planar ? 2 : 3); ++k) c *= std::floor((hi[k] - lo[k]) / hh) + 1.0;
    return c;
  };
  while (cells(h) > 4.0 * n + 64.0) h *= 1.26;
  g.lo = lo;
  g.inv_h = 1.0 / h;
  g.nx = static_cast<std::int64_t>(std::floor((hi.x - lo.x) / h)) + 1;
  g.ny = static_cast<std::int64_t>(std::floor((hi.y - lo.y) / h)) + 1;
  g.nz = planar ? 1 : static_cast<std::int64_t>(std::floor((hi.z - lo.z) / h)) + 1;
  const std::size_t ncell = static_cast<std::size_t>(g.nx * g.ny * g.nz);
  g.start.assign(ncell + 1, 0);
  std::vector<std::uint32_t> cell(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    cell[i] = static_cast<std::uint32_t>(g.cell_of(p[i].x));
    ++g.start[cell[i] + 1];
  }
  for (std::size_t c = 0; c < ncell; ++c) g.start[c + 1] += g.start[c];
  g.items.resize(p.size());
  std::vector<std::uint32_t> fill(g.start.begin(), g.start.end() - 1);
  for (std::size_t i = 0; i < p.size(); ++i)
    g.items[fill[cell[i]]++] = static_cast<std::uint32_t>(i);
  return g;
}

}  // namespace

void build_neighbour_pairs(const std::vector<PosRad>& p, double skin, bool planar, PairList& out,
                           PairIndex index, std::size_t firsts) {
  const std::size_t n = p.size();
  out.first.clear();
  out.second.clear();
  if (n == 0) {
    out.build_index(0);
    return;
  }
  const Grid g = make_grid(p, skin, planar);
  const std::int64_t dz = planar ? 0 : 1;

  // Visits the candidates j > i of particle i; calls emit(j) for each pair within range.
  auto visit = [&](std::size_t i, auto&& emit) {
    const PosRad& a = p[i];
    const std::int64_t cx = g.coord(a.x.x, g.lo.x, g.nx), cy = g.coord(a.x.y, g.lo.y, g.ny),
                       cz = g.coord(a.x.z, g.lo.z, g.nz);
    for (std::int64_t z = std::max<std::int64_t>(cz - dz, 0); z <= std::min(cz + dz, g.nz - 1); ++z)
      for (std::int64_t y = std::max<std::int64_t>(cy - 1, 0); y <= std::min(cy + 1, g.ny - 1); ++y)
        for (std::int64_t x = std::max<std::int64_t>(cx - 1, 0); x <= std::min(cx + 1, g.nx - 1);
             ++x) {
          const std::size_t c = static_cast<std::size_t>((z * g.ny + y) * g.nx + x);
          for (std::uint32_t m = g.start[c]; m < g.start[c + 1]; ++m) {
            const std::uint32_t j = g.items[m];
            if (j <= i) continue;
            const double cut = a.r + p[j].r + skin;
            if (norm2(p[j].x - a.x) < cut * cut) emit(j);
          }
        }
  };

  // Two passes (count, then fill) so that each particle writes its own range: deterministic for
  // any thread count and free of atomics.
  std::vector<std::uint32_t> count(n + 1, 0);
  const std::ptrdiff_t sn = static_cast<std::ptrdiff_t>(std::min(n, firsts));
#pragma omp parallel for schedule(dynamic, 256) if (sn > 4096)
  for (std::ptrdiff_t i = 0; i < sn; ++i) {
    std::uint32_t c = 0;
    visit(static_cast<std::size_t>(i), [&](std::uint32_t) { ++c; });
    count[static_cast<std::size_t>(i) + 1] = c;
  }
  for (std::size_t i = 0; i < n; ++i) count[i + 1] += count[i];
  out.first.resize(count[n]);
  out.second.resize(count[n]);
#pragma omp parallel for schedule(dynamic, 256) if (sn > 4096)
  for (std::ptrdiff_t i = 0; i < sn; ++i) {
    const std::size_t ii = static_cast<std::size_t>(i);
    std::uint32_t k = count[ii];
    visit(ii, [&](std::uint32_t j) {
      out.first[k] = static_cast<std::uint32_t>(ii);
      out.second[k++] = j;
    });
    std::sort(out.second.begin() + count[ii], out.second.begin() + count[ii + 1]);
  }
  if (index == PairIndex::Full)
    out.build_index(n);
  else
    out.build_offsets(n);
}

}  // namespace breccia
