#pragma once
// A cloud of grains for the domain tests: n centres uniform in a 40 x 30 x 20 box of unit-order
// grains (radii 0.5-1), in the order of a space-filling curve as a run keeps them, or as drawn
// (every rank's particles then spread over the whole box).
#include <algorithm>
#include <numeric>
#include <vector>

#include "breccia/core/rng.hpp"
#include "breccia/sample/spatial_order.hpp"
#include "breccia/state/particle_store.hpp"

namespace breccia::testing {

inline std::vector<PosRad> domain_cloud(std::size_t n, bool curve_order) {
  std::vector<PosRad> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    p[i].x = {40.0 * uniform01(7, 1, i), 30.0 * uniform01(7, 2, i), 20.0 * uniform01(7, 3, i)};
    p[i].r = 0.5 + 0.5 * uniform01(7, 4, i);
  }
  if (!curve_order) return p;
  std::vector<std::uint64_t> key(n);
  for (std::size_t i = 0; i < n; ++i) key[i] = morton_key(p[i].x, {0, 0, 0}, {40, 30, 20});
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return key[a] < key[b]; });
  std::vector<PosRad> sorted(n);
  for (std::size_t k = 0; k < n; ++k) sorted[k] = p[order[k]];
  return sorted;
}

}  // namespace breccia::testing
