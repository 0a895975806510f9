// Constructive insertion (docs/physics.md §7.4; Place & Mora 2001, ESyS-Particle's GenGeo
// InsertGenerator): no dynamics. A few grains are seeded at random, then each new grain is fitted
// into the hole nearest a random point, tangent to the D + 1 nearest grains, or to D grains and
// the nearest vessel wall; it is kept when its radius lies in [r_min, r_max] and it overlaps
// nothing. The packing ends after `insertion_failures` consecutive misses. Dense, stress-free,
// with a high coordination; the radii are emergent within the bounds, not drawn from a
// distribution.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/sample/packing_methods.hpp"
#include "breccia/sample/sphere_grid.hpp"
#include "breccia/sample/tangent_fit.hpp"

namespace breccia::packing {

namespace {

constexpr std::uint64_t kInsertStream = 0x696e736572740000ull;  // "insert"
constexpr double kOverlapTolerance = 1e-9;  // relative: fitted grains touch, round-off aside

struct Bounds {
  double r_min, r_max;
};

Bounds radius_bounds(const PackingSettings& s) {
  if (s.radii.kind == RadiusDistribution::Kind::Classes) {
    const auto [lo, hi] =
        std::minmax_element(s.radii.class_radius.begin(), s.radii.class_radius.end());
    return {*lo, *hi};
  }
  return {s.radii.r_min, s.radii.r_max};
}

class Inserter {
 public:
  Inserter(const PackingSettings& s, const Region& region)
      : s_(s),
        region_(region),
        b_(radius_bounds(s)),
        grid_(region.lower(), region.upper(), 2.0 * b_.r_max, region.planar()),
        planar_(region.planar()),
        dim_(region.dimension()) {}

  // Seeds: grains drawn from the distribution at random positions without overlap, until they
  // fill 5 % of the vessel (GenGeo seeds before fitting, so the first fits have neighbours).
  void seed() {
    RadiusDistribution dist = s_.radii;
    dist.planar = planar_;
    double solid = 0.0;
    for (std::uint64_t k = 0; solid < 0.05 * region_.volume() && k < 100000; ++k) {
      const double r = dist.draw(s_.seed, k);
      const Vec3 x = region_.draw(r, s_.seed, kInsertStream, counter_);
      if (grid_.overlaps(x, r, all_)) continue;
      add({x, r});
      solid += planar_ ? std::numbers::pi * r * r * region_.thickness
                       : 4.0 / 3.0 * std::numbers::pi * r * r * r;
    }
    seeds_ = all_.size();
  }

  // Fits grains until `max_failures` consecutive random points gave none.
  void fill(std::uint64_t max_failures, std::size_t max_particles) {
    std::uint64_t failures = 0;
    while (failures < max_failures) {
      if (all_.size() >= max_particles)
        throw InputError("sample generation", "particle count",
                         "> " + std::to_string(max_particles),
                         "the insertion packing needs more particles than sample.max_particles; "
                         "use larger grains, a smaller sample or raise the limit");
      if (++tries_ % 1024 == 0) throw_if_interrupted("packing the sample (insertion)");
      if (try_one())
        failures = 0;
      else
        ++failures;
    }
  }

  std::size_t seeds() const { return seeds_; }
  std::uint64_t tries() const { return tries_; }
  const std::vector<PosRad>& particles() const { return all_; }

 private:
  bool try_one() {
    Vec3 x = region_.draw(0.0, s_.seed, kInsertStream, counter_);
    // A point inside a grain moves to its surface (fitter i of §7.4).
    auto near = grid_.nearest(x, static_cast<std::size_t>(dim_ + 1), 1, all_);
    if (!near.empty() && near.front().first < 0.0) {
      const PosRad& q = all_[near.front().second];
      const Vec3 d = x - q.x;
      x = q.x + (norm(d) > 0.0 ? unit(d) : Vec3{1, 0, 0}) * q.r;
      near = grid_.nearest(x, static_cast<std::size_t>(dim_ + 1), 1, all_);
    }
    std::vector<Surface> spheres;
    for (const auto& [gap, i] : near) {
      const PosRad& q = all_[i];
      spheres.push_back({false, q.x, {}, q.r});
    }
    // Tangent to D + 1 grains (fitter ii).
    if (static_cast<int>(spheres.size()) == dim_ + 1 && accept(fit_free_radius(spheres, planar_)))
      return true;
    // Tangent to D grains and the nearest wall (fitter iii).
    if (static_cast<int>(spheres.size()) >= dim_) {
      std::vector<Surface> walls = region_.wall_surfaces(x);
      std::sort(walls.begin(), walls.end(), [&](const Surface& a, const Surface& b) {
        return dot(x - a.point, a.normal) < dot(x - b.point, b.normal);
      });
      std::vector<Surface> chosen(spheres.begin(), spheres.begin() + dim_);
      chosen.push_back(walls.front());
      std::vector<FittedSphere> fits = fit_free_radius(chosen, planar_);
      if (region_.round() && walls.front().normal.z == 0.0)
        for (FittedSphere& f : fits) f = on_cylinder(f, chosen);
      if (accept(fits)) return true;
    }
    return false;
  }

  // The side of a cylinder is met through its tangent plane: refit with the plane taken at the
  // candidate's own centre until it stays put (exact tangency to the cylinder).
  FittedSphere on_cylinder(FittedSphere f, std::vector<Surface> chosen) const {
    for (int it = 0; it < 5; ++it) {
      chosen.back() = region_.wall_surfaces(f.centre)[0];
      const auto again = fit_free_radius(chosen, planar_);
      if (again.empty()) return f;
      f = again.front();
    }
    return f;
  }

  bool accept(const std::vector<FittedSphere>& fits) {
    for (const FittedSphere& f : fits) {
      if (f.radius < b_.r_min || f.radius > b_.r_max) continue;
      if (region_.wall_distance(f.centre) < f.radius * (1.0 - kOverlapTolerance)) continue;
      if (grid_.overlaps(f.centre, f.radius, all_, SphereGrid::kNone, kOverlapTolerance)) continue;
      add({f.centre, f.radius});
      return true;
    }
    return false;
  }

  void add(const PosRad& q) {
    grid_.insert(static_cast<std::uint32_t>(all_.size()), q.x);
    all_.push_back(q);
  }

  const PackingSettings& s_;
  const Region& region_;
  Bounds b_;
  SphereGrid grid_;
  std::vector<PosRad> all_;
  bool planar_;
  int dim_;
  std::uint64_t counter_ = 0, tries_ = 0;
  std::size_t seeds_ = 0;
};

}  // namespace

PackedState pack_by_insertion(const PackingSettings& s, const Log& log) {
  PackedState st;
  st.region = packing_region(s);
  StageClock clock;
  Inserter ins(s, st.region);
  ins.seed();
  st.report.stages.push_back(clock.done("seeds", fmt::format("{} grains", ins.seeds())));
  ins.fill(s.insertion_failures, s.max_particles);
  st.report.stages.push_back(clock.done(
      "insertion",
      fmt::format("{} grains fitted in {} tries (ends after {} misses in a row)",
                  ins.particles().size() - ins.seeds(), ins.tries(), s.insertion_failures)));
  log(fmt::format("packing: {} grains inserted in a {} of {:.4g} m^3", ins.particles().size(),
                  shape_name(s.shape), st.region.volume()));
  st.particles = ins.particles();
  st.report.converged = true;
  return st;
}

}  // namespace breccia::packing
