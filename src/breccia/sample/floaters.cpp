// Floater elimination (physics.md §7.2 step 5), with floaters counted by their bonded neighbours
// (other grains within the bond gap tolerance; vessel walls do not count, since the test removes
// them or turns them into platens). Potyondy & Cundall grow a floater in small radius
// steps, cycling in between, until it has N_f contacts; here each floater is placed at once where
// that growth ends: the largest sphere that fits its cage, i.e. tangent to D + 1 of the nearest
// grains and walls (the fitters of §7.4). It then touches them without overlap, so nothing else
// is disturbed. A grain whose cage is wider than the growth cap allows is placed at the cap,
// tangent to D of its nearest grains; one that fits no way is left and counted.
#include <algorithm>
#include <cmath>

#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/sample/packing_methods.hpp"
#include "breccia/sample/sphere_grid.hpp"
#include "breccia/sample/tangent_fit.hpp"

namespace breccia::packing {

namespace {

// The surfaces around one grain: neighbours within reach and the vessel walls, nearest first.
struct Cage {
  std::vector<Surface> surfaces;  // sorted by gap to the grain as it is
};

// A candidate stays in its cage (it moves no further than the growth allows), inside the vessel,
// and clear of every grain.
bool fits(const FittedSphere& f, const Vec3& from, double max_move, const SphereGrid& grid,
          const std::vector<PosRad>& p, std::uint32_t self, const Region& region, double r_min,
          double r_max) {
  if (!(f.radius >= r_min && f.radius <= r_max)) return false;
  if (norm(f.centre - from) > max_move) return false;
  if (region.wall_distance(f.centre) < f.radius * (1.0 - 1e-9)) return false;
  return !grid.overlaps(f.centre, f.radius, p, self, 1e-9);
}

// Every choice of k of the first n surfaces, in lexicographic order (nearest sets first).
template <class F>
void combinations(int n, int k, F&& visit) {
  std::vector<int> idx(static_cast<std::size_t>(k));
  for (int i = 0; i < k; ++i) idx[static_cast<std::size_t>(i)] = i;
  while (true) {
    if (visit(idx)) return;
    int i = k - 1;
    while (i >= 0 && idx[static_cast<std::size_t>(i)] == n - k + i) --i;
    if (i < 0) return;
    ++idx[static_cast<std::size_t>(i)];
    for (int j = i + 1; j < k; ++j)
      idx[static_cast<std::size_t>(j)] = idx[static_cast<std::size_t>(j - 1)] + 1;
  }
}

// Refits with the vessel's tangent planes taken at the new centre (exact for the cylinder).
FittedSphere refine_on_walls(FittedSphere f, const std::vector<int>& idx, const Cage& cage,
                             const Region& region, bool planar) {
  if (!region.round()) return f;
  for (int it = 0; it < 4; ++it) {
    std::vector<Surface> chosen;
    for (int k : idx) {
      Surface s = cage.surfaces[static_cast<std::size_t>(k)];
      if (s.plane && s.normal.z == 0.0) s = region.wall_surfaces(f.centre)[0];
      chosen.push_back(s);
    }
    const auto again = fit_free_radius(chosen, planar);
    if (again.empty()) return f;
    f = again.front();
  }
  return f;
}

}  // namespace

FloaterFix fit_floaters(Simulation& sim, const Region& region, double tol, int n_f,
                        double max_growth, const std::vector<double>& nominal_radius,
                        std::size_t candidates) {
  FloaterFix out;
  const bool planar = region.planar();
  const int dim = region.dimension();
  const auto& p = sim.particles().pos_rad;
  double r_max = 0.0;
  for (const PosRad& q : p) r_max = std::max(r_max, q.r);
  const double reach = 2.0 * max_growth * r_max + tol;
  PairList near;
  build_neighbour_pairs(p, reach * 1.0001 + 1e-300, planar, near);
  // Cells of twice the largest radius a grown floater can have.
  SphereGrid grid(region.lower(), region.upper(), 2.0 * r_max * (1.0 + max_growth), planar);
  for (std::uint32_t i = 0; i < p.size(); ++i) grid.insert(i, p[i].x);
  std::vector<int> contacts(p.size(), 0);
  for (std::size_t k = 0; k < near.size(); ++k) {
    const PosRad& a = p[near.first[k]];
    const PosRad& b = p[near.second[k]];
    if (norm(b.x - a.x) - a.r - b.r <= tol) {
      ++contacts[near.first[k]];
      ++contacts[near.second[k]];
    }
  }
  // Walls do not count: a grain held against a platen by two bonds is the first to break there.
  auto is_floater = [&](std::uint32_t i) { return contacts[i] < n_f; };
  for (std::uint32_t i = 0; i < std::min(p.size(), candidates); ++i) {
    if (!is_floater(i)) continue;
    ++out.found;
    Cage cage;
    std::vector<std::pair<double, Surface>> around;
    auto add_neighbour = [&](std::uint32_t j) {
      const double gap = norm(p[j].x - p[i].x) - p[i].r - p[j].r;
      if (gap <= reach) around.push_back({gap, Surface{false, p[j].x, {}, p[j].r}});
    };
    for (std::uint32_t k = near.offsets[i]; k < near.offsets[i + 1]; ++k)
      add_neighbour(near.second[k]);
    for (std::uint32_t m = near.in_offsets[i]; m < near.in_offsets[i + 1]; ++m)
      add_neighbour(near.first[near.in_slot[m]]);
    for (const Surface& w : region.wall_surfaces(p[i].x)) {
      const double gap = dot(p[i].x - w.point, w.normal) - p[i].r;
      if (gap <= reach) around.push_back({gap, w});
    }
    std::sort(around.begin(), around.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& a : around) cage.surfaces.push_back(a.second);
    const double r = p[i].r;
    const double limit = nominal_radius[i] * (1.0 + max_growth);
    const Vec3 from = p[i].x;
    const double max_move = reach;
    const int n = std::min<int>(static_cast<int>(cage.surfaces.size()), planar ? 7 : 9);
    // Only fits that touch N_f grains end a floater (walls do not count).
    auto grains_in = [&](const std::vector<int>& idx) {
      int g = 0;
      for (int k : idx) g += cage.surfaces[static_cast<std::size_t>(k)].plane ? 0 : 1;
      return g;
    };
    // The snug fit with the least growth, tangent to D + 1 of the n nearest surfaces.
    std::optional<FittedSphere> best;
    if (n >= dim + 1)
      combinations(n, dim + 1, [&](const std::vector<int>& idx) {
        if (grains_in(idx) < std::min(n_f, dim + 1)) return false;
        std::vector<Surface> chosen;
        for (int k : idx) chosen.push_back(cage.surfaces[static_cast<std::size_t>(k)]);
        for (FittedSphere f : fit_free_radius(chosen, planar)) {
          f = refine_on_walls(f, idx, cage, region, planar);
          if (fits(f, from, max_move, grid, p, i, region, r, limit) &&
              (!best || f.radius < best->radius))
            best = f;
        }
        return false;
      });
    // A cage wider than the cap: the capped grain against D of the nearest grains.
    if (!best && n >= dim)
      combinations(n, dim, [&](const std::vector<int>& idx) {
        if (grains_in(idx) < std::min(n_f, dim)) return false;
        std::vector<Surface> chosen;
        for (int k : idx) chosen.push_back(cage.surfaces[static_cast<std::size_t>(k)]);
        for (const Vec3& x : fit_fixed_radius(chosen, limit, planar, p[i].x)) {
          const FittedSphere f{x, limit};
          if (fits(f, from, max_move, grid, p, i, region, r, limit)) {
            best = f;
            return true;
          }
        }
        return false;
      });
    if (!best) continue;
    // A hair over tangency, so that a zero bond gap tolerance still counts the contacts.
    sim.place_particle(i, best->centre, best->radius * (1.0 + 1e-9));
    grid.move(i, from, best->centre);
    out.largest_growth = std::max(out.largest_growth, best->radius / nominal_radius[i] - 1.0);
    ++out.fitted;
    // Its new contacts count for the floaters still to come.
    for (const Surface& s : cage.surfaces)
      if (!s.plane && norm(best->centre - s.point) - best->radius - s.radius <= tol) ++contacts[i];
  }
  return out;
}

}  // namespace breccia::packing
