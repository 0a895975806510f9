#include "breccia/engine/domain.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

#include "breccia/core/byte_text.hpp"
#include "breccia/core/ranks.hpp"

namespace breccia {

namespace {

using bytes::put;
using bytes::take;

// A rank's particles in brief: the box of their centres and their largest radius.
struct Extent {
  Vec3 lo, hi;
  double r_max = 0.0;
  std::uint8_t empty = 1;
};

Extent extent_of(const std::vector<PosRad>& p) {
  Extent e;
  const double inf = std::numeric_limits<double>::infinity();
  e.lo = Vec3{inf, inf, inf};
  e.hi = -e.lo;
  for (const PosRad& q : p) {
    for (int k = 0; k < 3; ++k) {
      e.lo[k] = std::min(e.lo[k], q.x[k]);
      e.hi[k] = std::max(e.hi[k], q.x[k]);
    }
    e.r_max = std::max(e.r_max, q.r);
  }
  e.empty = p.empty() ? 1 : 0;
  return e;
}

bool inside(const Extent& e, const Vec3& x, double widen) noexcept {
  for (int k = 0; k < 3; ++k)
    if (x[k] < e.lo[k] - widen || x[k] > e.hi[k] + widen) return false;
  return true;
}

// A cell grid over a rank's own particles with cells no narrower than any reach, so that every
// particle within reach of a point lies in the point's cell or a neighbouring one (a point
// outside the grid is taken to its nearest cell, which keeps that true).
class OwnGrid {
 public:
  OwnGrid(const std::vector<PosRad>& p, const Extent& e, double reach) : p_(p), lo_(e.lo) {
    double h = reach;
    const auto cells = [&](double hh) {
      double c = 1.0;
      for (int k = 0; k < 3; ++k) c *= std::floor((e.hi[k] - e.lo[k]) / hh) + 1.0;
      return c;
    };
    while (cells(h) > 4.0 * static_cast<double>(p.size()) + 64.0) h *= 1.26;
    inv_h_ = 1.0 / h;
    for (int k = 0; k < 3; ++k)
      n_[k] = static_cast<std::int64_t>(std::floor((e.hi[k] - e.lo[k]) / h)) + 1;
    start_.assign(static_cast<std::size_t>(n_[0] * n_[1] * n_[2]) + 1, 0);
    std::vector<std::size_t> cell(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
      cell[i] = index(coords(p[i].x));
      ++start_[cell[i] + 1];
    }
    for (std::size_t c = 0; c + 1 < start_.size(); ++c) start_[c + 1] += start_[c];
    items_.resize(p.size());
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < p.size(); ++i)
      items_[fill[cell[i]]++] = static_cast<std::uint32_t>(i);
  }

  // Whether `b` lies within reach of one of the particles.
  bool touches(const PosRad& b, double skin) const noexcept {
    const std::array<std::int64_t, 3> c = coords(b.x);
    for (std::int64_t z = std::max<std::int64_t>(c[2] - 1, 0); z <= std::min(c[2] + 1, n_[2] - 1);
         ++z)
      for (std::int64_t y = std::max<std::int64_t>(c[1] - 1, 0); y <= std::min(c[1] + 1, n_[1] - 1);
           ++y)
        for (std::int64_t x = std::max<std::int64_t>(c[0] - 1, 0);
             x <= std::min(c[0] + 1, n_[0] - 1); ++x) {
          const std::size_t cell = index({x, y, z});
          for (std::uint32_t m = start_[cell]; m < start_[cell + 1]; ++m)
            if (within_reach(p_[items_[m]], b, skin)) return true;
        }
    return false;
  }

 private:
  std::array<std::int64_t, 3> coords(const Vec3& x) const noexcept {
    std::array<std::int64_t, 3> c{};
    for (int k = 0; k < 3; ++k)
      c[static_cast<std::size_t>(k)] = std::clamp<std::int64_t>(
          static_cast<std::int64_t>(std::floor((x[k] - lo_[k]) * inv_h_)), 0, n_[k] - 1);
    return c;
  }
  std::size_t index(const std::array<std::int64_t, 3>& c) const noexcept {
    return static_cast<std::size_t>((c[2] * n_[1] + c[1]) * n_[0] + c[0]);
  }
  const std::vector<PosRad>& p_;
  Vec3 lo_;
  double inv_h_ = 1.0;
  std::int64_t n_[3] = {1, 1, 1};
  std::vector<std::uint32_t> start_, items_;
};

}  // namespace

std::vector<IndexRange> split_indexes(std::size_t n, int ranks) {
  const auto r = static_cast<std::size_t>(std::max(ranks, 1));
  const std::size_t grains = (n + kDomainGrain - 1) / kDomainGrain;
  std::vector<IndexRange> out(r);
  std::size_t grain = 0;
  for (std::size_t k = 0; k < r; ++k) {
    // The extra grains go to the last ranks, the last of which holds the partial grain.
    const std::size_t take_grains = grains / r + (k >= r - grains % r ? 1 : 0);
    out[k].begin = std::min(n, grain * kDomainGrain);
    grain += take_grains;
    out[k].end = std::min(n, grain * kDomainGrain);
  }
  return out;
}

std::vector<std::uint32_t> ghosts_of(const std::vector<PosRad>& all, IndexRange own, double skin) {
  std::vector<std::uint32_t> out;
  for (std::size_t j = own.end; j < all.size(); ++j)
    for (std::size_t i = own.begin; i < own.end; ++i)
      if (within_reach(all[i], all[j], skin)) {
        out.push_back(static_cast<std::uint32_t>(j));
        break;
      }
  return out;
}

namespace {

// The requests of `required` to their owners (collective): per rank, the local indexes of this
// rank's particles that it must offer to that rank whatever their place, ascending.
std::vector<std::vector<std::uint32_t>> requested_of_me(const std::vector<std::uint32_t>& required,
                                                        const std::vector<IndexRange>& ranges) {
  std::vector<std::string> asks(ranges.size());
  std::size_t r = 0;
  for (const std::uint32_t g : required) {
    while (r < ranges.size() && !ranges[r].contains(g)) ++r;
    if (r == ranges.size()) break;
    put(asks[r], g);
  }
  const std::vector<std::string> asked = ranks::exchange(asks);
  const IndexRange own = ranges[static_cast<std::size_t>(ranks::rank())];
  std::vector<std::vector<std::uint32_t>> out(ranges.size());
  for (std::size_t s = 0; s < asked.size(); ++s)
    for (std::size_t at = 0; at < asked[s].size();)
      out[s].push_back(static_cast<std::uint32_t>(take<std::uint32_t>(asked[s], at) - own.begin));
  return out;
}

}  // namespace

GhostPlan plan_ghosts(const std::vector<PosRad>& own_particles,
                      const std::vector<IndexRange>& ranges, double skin,
                      const std::vector<std::uint32_t>& required) {
  const auto n_ranks = static_cast<std::size_t>(ranks::size());
  const auto me = static_cast<std::size_t>(ranks::rank());
  GhostPlan plan;
  plan.send.resize(n_ranks);
  const std::vector<std::vector<std::uint32_t>> requested = requested_of_me(required, ranges);
  // Every rank's extent, and the widest reach any pair can have.
  std::string mine;
  put(mine, extent_of(own_particles));
  std::vector<Extent> extents;
  double r_max = 0.0;
  for (const std::string& text : ranks::all_gather(mine)) {
    std::size_t at = 0;
    extents.push_back(take<Extent>(text, at));
    r_max = std::max(r_max, extents.back().r_max);
  }
  const double reach = 2.0 * r_max + skin;
  // Offers to the earlier ranks: the particles in each one's widened box, in index order.
  std::vector<std::string> offers(n_ranks);
  std::vector<std::vector<std::uint32_t>> offered(n_ranks);
  for (std::size_t r = 0; r < me; ++r) {
    if (extents[r].empty) continue;
    auto ask = requested[r].begin();
    for (std::size_t k = 0; k < own_particles.size(); ++k) {
      const bool asked = ask != requested[r].end() && *ask == k;
      if (asked) ++ask;
      if (!asked && !inside(extents[r], own_particles[k].x, reach)) continue;
      offered[r].push_back(static_cast<std::uint32_t>(k));
      put(offers[r], static_cast<std::uint32_t>(ranges[me].begin + k));
      put(offers[r], static_cast<std::uint8_t>(asked));
      put(offers[r], own_particles[k]);
    }
  }
  const std::vector<std::string> received = ranks::exchange(offers);
  // Keep what lies within reach of an own particle; later ranks in order keep the index order.
  std::vector<std::string> kept(n_ranks);
  if (!own_particles.empty()) {
    const OwnGrid grid(own_particles, extents[me], reach);
    for (std::size_t s = me + 1; s < n_ranks; ++s) {
      std::size_t at = 0;
      for (std::uint32_t position = 0; at < received[s].size(); ++position) {
        const auto global = take<std::uint32_t>(received[s], at);
        const auto asked = take<std::uint8_t>(received[s], at);
        const auto q = take<PosRad>(received[s], at);
        if (!asked && !grid.touches(q, skin)) continue;
        plan.ghosts.push_back(global);
        plan.ghost_pos_rad.push_back(q);
        put(kept[s], position);
      }
    }
  }
  // Each sender learns which of its offers were kept.
  const std::vector<std::string> answers = ranks::exchange(kept);
  for (std::size_t r = 0; r < me; ++r) {
    std::size_t at = 0;
    while (at < answers[r].size())
      plan.send[r].push_back(offered[r][take<std::uint32_t>(answers[r], at)]);
  }
  return plan;
}

}  // namespace breccia
