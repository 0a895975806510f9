#pragma once
// Grains binned in a uniform grid for the geometric steps of sample generation (random placement,
// insertion, floater placement): which grains a sphere overlaps, and which lie nearest a point.
// With cells at least twice the largest radius, a sphere no larger than that can only touch
// grains in its own and the adjacent cells. The grid holds indices into a particle array that
// its caller owns and passes in.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "breccia/core/vec3.hpp"
#include "breccia/state/particle_store.hpp"

namespace breccia {

class SphereGrid {
 public:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  SphereGrid(Vec3 lo, Vec3 hi, double cell, bool planar) : lo_(lo), cell_(cell) {
    for (int k = 0; k < 3; ++k)
      n_[k] = (planar && k == 2) ? 1 : std::max(1, static_cast<int>((hi[k] - lo[k]) / cell) + 1);
    cells_.resize(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2]);
  }

  void insert(std::uint32_t i, const Vec3& x) { cells_[index(x)].push_back(i); }
  // Grain i moved from `from` to `to`.
  void move(std::uint32_t i, const Vec3& from, const Vec3& to) {
    auto& old = cells_[index(from)];
    old.erase(std::find(old.begin(), old.end(), i));
    insert(i, to);
  }

  // True when the sphere (x, r) overlaps a grain of `p` other than `self`, beyond a relative
  // round-off of `tolerance`.
  bool overlaps(const Vec3& x, double r, const std::vector<PosRad>& p, std::uint32_t self = kNone,
                double tolerance = 0.0) const {
    bool hit = false;
    visit(x, 1, [&](std::uint32_t j) {
      if (hit || j == self) return;
      const double reach = (p[j].r + r) * (1.0 - tolerance);
      hit = norm2(p[j].x - x) < reach * reach;
    });
    return hit;
  }

  // The `count` grains nearest to x by surface distance |x - c| - R (negative inside a grain),
  // searched within `rings` cells around x; nearest first.
  std::vector<std::pair<double, std::uint32_t>> nearest(const Vec3& x, std::size_t count, int rings,
                                                        const std::vector<PosRad>& p) const {
    std::vector<std::pair<double, std::uint32_t>> found;
    visit(x, rings, [&](std::uint32_t j) { found.push_back({norm(p[j].x - x) - p[j].r, j}); });
    const std::size_t keep = std::min(count, found.size());
    std::partial_sort(found.begin(), found.begin() + static_cast<long>(keep), found.end());
    found.resize(keep);
    return found;
  }

 private:
  std::array<int, 3> cell_of(const Vec3& x) const {
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k)
      c[static_cast<std::size_t>(k)] =
          std::clamp(static_cast<int>((x[k] - lo_[k]) / cell_), 0, n_[k] - 1);
    return c;
  }
  std::size_t index(const std::array<int, 3>& c) const {
    return (static_cast<std::size_t>(c[2]) * n_[1] + c[1]) * n_[0] + c[0];
  }
  std::size_t index(const Vec3& x) const { return index(cell_of(x)); }
  template <class F>
  void visit(const Vec3& x, int rings, F&& f) const {
    const auto c = cell_of(x);
    const int rz = n_[2] == 1 ? 0 : rings;
    for (int dz = -rz; dz <= rz; ++dz)
      for (int dy = -rings; dy <= rings; ++dy)
        for (int dx = -rings; dx <= rings; ++dx) {
          const std::array<int, 3> d{c[0] + dx, c[1] + dy, c[2] + dz};
          if (d[0] < 0 || d[1] < 0 || d[2] < 0 || d[0] >= n_[0] || d[1] >= n_[1] || d[2] >= n_[2])
            continue;
          for (std::uint32_t j : cells_[index(d)]) f(j);
        }
  }

  Vec3 lo_;
  double cell_;
  int n_[3];
  std::vector<std::vector<std::uint32_t>> cells_;
};

}  // namespace breccia
