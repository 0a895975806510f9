#include "breccia/analysis/fragments.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>

namespace breccia::analysis {

namespace {

// Union-find over particle indices (32-bit: a sample's particle count fits, and the analysis of a
// million-grain sample holds these arrays beside the engine's).
struct DisjointSets {
  std::vector<std::uint32_t> parent, size;
  explicit DisjointSets(std::size_t n) : parent(n), size(n, 1) {
    std::iota(parent.begin(), parent.end(), std::uint32_t{0});
  }
  std::uint32_t find(std::uint32_t a) {
    while (parent[a] != a) {
      parent[a] = parent[parent[a]];  // path halving
      a = parent[a];
    }
    return a;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (size[a] < size[b]) std::swap(a, b);
    parent[b] = a;
    size[a] += size[b];
  }
};

// The fragments of n particles whose mass, volume and position the accessors give; `bonds` calls
// its argument with each intact bond's particle indexes.
template <class Mass, class Volume, class Position, class Bonds>
FragmentResult fragments_of(std::size_t n, Mass&& mass, Volume&& volume, Position&& position,
                            Bonds&& bonds) {
  DisjointSets sets(n);
  bonds([&](std::uint32_t a, std::uint32_t b) { sets.unite(a, b); });
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> root_index(n, kNone);
  std::vector<Fragment> frags;
  std::vector<std::uint32_t> of(n);
  for (std::size_t p = 0; p < n; ++p) {
    const std::uint32_t r = sets.find(static_cast<std::uint32_t>(p));
    if (root_index[r] == kNone) {
      root_index[r] = static_cast<std::uint32_t>(frags.size());
      frags.emplace_back();
    }
    Fragment& f = frags[root_index[r]];
    const double m = mass(p);
    ++f.particles;
    f.mass += m;
    f.volume += volume(p);
    f.centroid += position(p) * m;
    of[p] = root_index[r];
  }
  // Free before the result's arrays are built: a million grains' worth each.
  std::vector<std::uint32_t>().swap(root_index);
  sets = DisjointSets(0);
  for (Fragment& f : frags)
    if (f.mass > 0.0) f.centroid = f.centroid * (1.0 / f.mass);
  // Largest first; ties by size then first particle (stable).
  std::vector<std::size_t> order(frags.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return frags[a].mass > frags[b].mass; });
  std::vector<std::size_t> rank(frags.size());
  FragmentResult r;
  for (std::size_t k = 0; k < order.size(); ++k) {
    rank[order[k]] = k;
    r.fragments.push_back(frags[order[k]]);
  }
  r.fragment_of.resize(n);
  for (std::size_t p = 0; p < n; ++p) r.fragment_of[p] = rank[of[p]];
  for (const Fragment& f : r.fragments) r.total_mass += f.mass;
  if (r.fragments.empty()) return r;
  r.largest_mass = r.fragments.front().mass;
  r.largest_fraction = r.largest_mass / r.total_mass;
  for (const Fragment& f : r.fragments) {
    const double frac = f.mass / r.largest_mass;
    const bool debris = f.particles == 1;
    if (debris) ++r.debris;
    ClassCount& c = frac < 0.1 ? r.smallest : frac > 0.9 ? r.biggest : r.intermediate;
    ++c.count;
    c.mass += f.mass;
    if (!debris) {
      ClassCount& d = frac < 0.1   ? r.smallest_no_debris
                      : frac > 0.9 ? r.biggest_no_debris
                                   : r.intermediate_no_debris;
      ++d.count;
      d.mass += f.mass;
    }
  }
  return r;
}

}  // namespace

FragmentResult find_fragments(const std::vector<double>& mass, const std::vector<double>& volume,
                              const std::vector<Vec3>& position,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& bonds) {
  return fragments_of(
      mass.size(), [&](std::size_t p) { return mass[p]; }, [&](std::size_t p) { return volume[p]; },
      [&](std::size_t p) { return position[p]; },
      [&](auto&& unite) {
        for (const auto& [a, b] : bonds) unite(a, b);
      });
}

FragmentResult find_fragments(const ParticleStore& p, const BondWalk& bonds, double density_scaling,
                              std::size_t count) {
  const std::size_t n = std::min(count, p.size());
  // Read from the store as the analysis goes (no copies of its arrays).
  auto mass = [&](std::size_t i) { return p.mass[i] / density_scaling; };
  auto volume = [&](std::size_t i) { return p.mass[i] / p.density[i]; };
  auto position = [&](std::size_t i) { return p.pos_rad[i].x; };
  // Bonds to particles beyond the first n are left out.
  return fragments_of(n, mass, volume, position, [&](auto&& unite) {
    bonds([&](std::uint32_t a, std::uint32_t b) {
      if (a < n && b < n) unite(a, b);
    });
  });
}

}  // namespace breccia::analysis
