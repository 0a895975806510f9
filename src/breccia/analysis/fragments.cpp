#include "breccia/analysis/fragments.hpp"

#include <algorithm>
#include <numeric>

namespace breccia::analysis {

namespace {

struct DisjointSets {
  std::vector<std::size_t> parent, size;
  explicit DisjointSets(std::size_t n) : parent(n), size(n, 1) {
    std::iota(parent.begin(), parent.end(), std::size_t{0});
  }
  std::size_t find(std::size_t a) {
    while (parent[a] != a) {
      parent[a] = parent[parent[a]];  // path halving
      a = parent[a];
    }
    return a;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (size[a] < size[b]) std::swap(a, b);
    parent[b] = a;
    size[a] += size[b];
  }
};

}  // namespace

FragmentResult find_fragments(const std::vector<double>& mass, const std::vector<double>& volume,
                              const std::vector<Vec3>& position,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& bonds) {
  const std::size_t n = mass.size();
  DisjointSets sets(n);
  for (const auto& [a, b] : bonds) sets.unite(a, b);
  std::vector<std::size_t> root_index(n, static_cast<std::size_t>(-1));
  std::vector<Fragment> frags;
  std::vector<std::size_t> of(n);
  for (std::size_t p = 0; p < n; ++p) {
    const std::size_t r = sets.find(p);
    if (root_index[r] == static_cast<std::size_t>(-1)) {
      root_index[r] = frags.size();
      frags.emplace_back();
    }
    Fragment& f = frags[root_index[r]];
    ++f.particles;
    f.mass += mass[p];
    f.volume += volume[p];
    f.centroid += position[p] * mass[p];
    of[p] = root_index[r];
  }
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

FragmentResult find_fragments(const ParticleStore& p,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& bonds,
                              double density_scaling, std::size_t count) {
  const std::size_t n = std::min(count, p.size());
  std::vector<double> mass(n), vol(n);
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    vol[i] = p.mass[i] / p.density[i];
    mass[i] = p.mass[i] / density_scaling;
    x[i] = p.pos_rad[i].x;
  }
  if (n == p.size()) return find_fragments(mass, vol, x, bonds);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> among;
  for (const auto& b : bonds)
    if (b.first < n && b.second < n) among.push_back(b);
  return find_fragments(mass, vol, x, among);
}

}  // namespace breccia::analysis
