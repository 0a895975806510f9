// Floater elimination (docs/physics.md §7.2 step 5), with floaters counted by their bonded
// neighbours (other grains within the bond gap tolerance; vessel walls do not count, since the test
// removes them or turns them into platens). Potyondy & Cundall grow a floater in small radius
// steps, cycling in between, until it has N_f contacts; here each floater is placed at once where
// that growth ends: the largest sphere that fits its cage, i.e. tangent to D + 1 of the nearest
// grains and walls (the fitters of §7.4). It then touches them without overlap, so nothing else
// is disturbed. A grain whose cage is wider than the growth cap allows is placed at the cap,
// tangent to D of its nearest grains; one that fits no way is left and counted.
#include <algorithm>
#include <cmath>
#include <optional>
#include <tuple>

#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/sample/packing_methods.hpp"
#include "breccia/sample/sphere_grid.hpp"
#include "breccia/sample/tangent_fit.hpp"

namespace breccia::packing {

namespace {

// The surfaces around one grain: neighbours within reach and the vessel walls, nearest first.
struct Cage {
  std::vector<Surface> surfaces;     // sorted by gap to the grain as it is
  std::vector<std::uint32_t> grain;  // the neighbour's index, or SphereGrid::kNone for a wall
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

class FloaterFitter {
 public:
  FloaterFitter(Simulation& sim, const Region& region, double tol, int n_f, double max_growth,
                const std::vector<double>& nominal_radius)
      : sim_(sim),
        p_(sim.particles().pos_rad),
        region_(region),
        tol_(tol),
        n_f_(n_f),
        max_growth_(max_growth),
        nominal_(nominal_radius),
        planar_(region.planar()),
        dim_(region.dimension()) {
    double r_max = 0.0;
    for (const PosRad& q : p_) r_max = std::max(r_max, q.r);
    reach_ = 2.0 * max_growth * r_max + tol;
    build_neighbour_pairs(p_, reach_ * 1.0001 + 1e-300, planar_, near_);
    // Cells of twice the largest radius a grown floater can have.
    grid_.emplace(region.lower(), region.upper(), 2.0 * r_max * (1.0 + max_growth), planar_);
    for (std::uint32_t i = 0; i < p_.size(); ++i) grid_->insert(i, p_[i].x);
    contacts_.assign(p_.size(), 0);
    for (std::size_t k = 0; k < near_.size(); ++k) {
      const PosRad& a = p_[near_.first[k]];
      const PosRad& b = p_[near_.second[k]];
      if (norm(b.x - a.x) - a.r - b.r <= tol) {
        ++contacts_[near_.first[k]];
        ++contacts_[near_.second[k]];
      }
    }
  }

  // Walls do not count: a grain held against a platen by two bonds is the first to break there.
  bool is_floater(std::uint32_t i) const { return contacts_[i] < n_f_; }

  // Places floater i snug in its cage; false when no fit is found.
  bool place(std::uint32_t i, FloaterFix& out) {
    const Cage cage = cage_of(i);
    const std::optional<FittedSphere> best = snug_fit(i, cage);
    if (!best) return false;
    const Vec3 from = p_[i].x;
    // A hair over tangency, so that a zero bond gap tolerance still counts the contacts.
    sim_.place_particle(i, best->centre, best->radius * (1.0 + 1e-9));
    grid_->move(i, from, best->centre);
    out.largest_growth = std::max(out.largest_growth, best->radius / nominal_[i] - 1.0);
    // Its new contacts count for the floaters still to come.
    for (std::size_t k = 0; k < cage.surfaces.size(); ++k) {
      const Surface& s = cage.surfaces[k];
      if (!s.plane && norm(best->centre - s.point) - best->radius - s.radius <= tol_)
        ++contacts_[cage.grain[k]];
    }
    return true;
  }

 private:
  Cage cage_of(std::uint32_t i) const {
    std::vector<std::tuple<double, Surface, std::uint32_t>> around;
    auto add_neighbour = [&](std::uint32_t j) {
      const double gap = norm(p_[j].x - p_[i].x) - p_[i].r - p_[j].r;
      if (gap <= reach_) around.emplace_back(gap, Surface{false, p_[j].x, {}, p_[j].r}, j);
    };
    for (std::uint32_t k = near_.offsets[i]; k < near_.offsets[i + 1]; ++k)
      add_neighbour(near_.second[k]);
    for (std::uint32_t m = near_.in_offsets[i]; m < near_.in_offsets[i + 1]; ++m)
      add_neighbour(near_.first[near_.in_slot[m]]);
    for (const Surface& w : region_.wall_surfaces(p_[i].x)) {
      const double gap = dot(p_[i].x - w.point, w.normal) - p_[i].r;
      if (gap <= reach_) around.emplace_back(gap, w, SphereGrid::kNone);
    }
    std::sort(around.begin(), around.end(),
              [](const auto& a, const auto& b) { return std::get<0>(a) < std::get<0>(b); });
    Cage cage;
    for (const auto& [gap, surface, j] : around) {
      cage.surfaces.push_back(surface);
      cage.grain.push_back(j);
    }
    return cage;
  }

  // The fit with the least growth tangent to D + 1 of the nearest surfaces, touching N_f grains;
  // for a cage wider than the cap, the capped grain against D of the nearest grains.
  std::optional<FittedSphere> snug_fit(std::uint32_t i, const Cage& cage) const {
    const double r = p_[i].r;
    const double limit = nominal_[i] * (1.0 + max_growth_);
    const Vec3 from = p_[i].x;
    const int n = std::min<int>(static_cast<int>(cage.surfaces.size()), planar_ ? 7 : 9);
    auto grains_in = [&](const std::vector<int>& idx) {
      int g = 0;
      for (int k : idx) g += cage.surfaces[static_cast<std::size_t>(k)].plane ? 0 : 1;
      return g;
    };
    auto chosen = [&](const std::vector<int>& idx) {
      std::vector<Surface> c;
      for (int k : idx) c.push_back(cage.surfaces[static_cast<std::size_t>(k)]);
      return c;
    };
    auto ok = [&](const FittedSphere& f) {
      return fits(f, from, reach_, *grid_, p_, i, region_, r, limit);
    };
    std::optional<FittedSphere> best;
    if (n >= dim_ + 1)
      combinations(n, dim_ + 1, [&](const std::vector<int>& idx) {
        if (grains_in(idx) < std::min(n_f_, dim_ + 1)) return false;
        for (FittedSphere f : fit_free_radius(chosen(idx), planar_)) {
          f = refine_on_walls(f, idx, cage, region_, planar_);
          if (ok(f) && (!best || f.radius < best->radius)) best = f;
        }
        return false;
      });
    if (!best && n >= dim_)
      combinations(n, dim_, [&](const std::vector<int>& idx) {
        if (grains_in(idx) < std::min(n_f_, dim_)) return false;
        for (const Vec3& x : fit_fixed_radius(chosen(idx), limit, planar_, from))
          if (ok({x, limit})) {
            best = FittedSphere{x, limit};
            return true;
          }
        return false;
      });
    return best;
  }

  Simulation& sim_;
  const std::vector<PosRad>& p_;
  const Region& region_;
  double tol_;
  int n_f_;
  double max_growth_;
  const std::vector<double>& nominal_;
  bool planar_;
  int dim_;
  double reach_ = 0.0;
  PairList near_;
  std::optional<SphereGrid> grid_;
  std::vector<int> contacts_;
};

}  // namespace

FloaterFix fit_floaters(Simulation& sim, const Region& region, double tol, int n_f,
                        double max_growth, const std::vector<double>& nominal_radius,
                        std::size_t candidates) {
  FloaterFix out;
  FloaterFitter fitter(sim, region, tol, n_f, max_growth, nominal_radius);
  const std::size_t n = std::min(sim.particles().size(), candidates);
  for (std::uint32_t i = 0; i < n; ++i) {
    if (!fitter.is_floater(i)) continue;
    ++out.found;
    out.fitted += fitter.place(i, out) ? 1 : 0;
  }
  return out;
}

}  // namespace breccia::packing
