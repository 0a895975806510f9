#pragma once
// One sample split over the ranks of an MPI launch (ARCHITECTURE.md, "Ranks (MPI)"). Each rank
// owns a contiguous range of particle indexes cut at multiples of kDomainGrain, whole blocks of
// the pair pass and of the integrator, so that a rank walks the blocks and pairs that one process
// walks, in the same order, and its sums come out to the same bits. After its own particles a rank
// keeps its ghosts: the particles of later ranks that its own can touch, in index order, so that
// its local order is the global order. Particles of earlier ranks it needs no copy of: a pair
// belongs to the block of its first (lower) particle, whose rank sends the share of the second.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "breccia/core/ranks.hpp"
#include "breccia/state/pair_list.hpp"
#include "breccia/state/particle_store.hpp"

namespace breccia {

// The pair pass's blocks (512) and the integrator's (1,024) both end at its multiples.
inline constexpr std::size_t kDomainGrain = 2 * kParticleBlock;

struct IndexRange {
  std::size_t begin = 0, end = 0;
  std::size_t size() const noexcept { return end - begin; }
  bool contains(std::size_t i) const noexcept { return i >= begin && i < end; }
};

// n particle indexes over `ranks` ranges: contiguous, in rank order, cut at multiples of
// kDomainGrain and as equal as that allows (the counts differ by one grain at most, the last
// range ending at n). When n has fewer grains than there are ranks, the first ranks own none.
std::vector<IndexRange> split_indexes(std::size_t n, int ranks);

// Whether particles a and b (a the lower index) come within the neighbour list's range,
// R_a + R_b + skin, or exactly to it: the test the ghosts are chosen by, never narrower than the
// list's own (engine/neighbour_grid.cpp).
inline bool within_reach(const PosRad& a, const PosRad& b, double skin) noexcept {
  const double cut = a.r + b.r + skin;
  return norm2(b.x - a.x) <= cut * cut;
}

// The ghosts of `own` when one process knows every particle: the indexes at or past own.end of
// the particles within reach of one of own's, ascending. The reference the ranks' plan is
// checked against.
std::vector<std::uint32_t> ghosts_of(const std::vector<PosRad>& all, IndexRange own, double skin);

// This rank's ghosts and what it sends, worked out by the ranks together (collective), each
// knowing its own particles only.
struct GhostPlan {
  std::vector<std::uint32_t> ghosts;  // global indexes, ascending
  std::vector<PosRad> ghost_pos_rad;  // theirs when the plan was made
  // Per rank: the local indexes (0 = this rank's first particle) of this rank's particles that
  // it keeps as ghosts, ascending, the order it keeps them in.
  std::vector<std::vector<std::uint32_t>> send;
};
// `own_particles` are those of ranges[rank()]. Each rank sends every earlier rank the particles
// whose centres lie in that rank's bounding box widened by 2 R_max + skin; the receiver keeps
// those within reach of one of its own (a cell grid over its own particles) and tells each
// sender which. `required` (global indexes of later ranks' particles, ascending) are kept
// wherever they lie: the partners of bonds stretched beyond the reach.
GhostPlan plan_ghosts(const std::vector<PosRad>& own_particles,
                      const std::vector<IndexRange>& ranges, double skin,
                      const std::vector<std::uint32_t>& required = {});

// The ghosts' values from their owners, in the plan's order (collective): each rank sends the
// values of its particles in plan.send[r] to rank r. `own` holds this rank's particles' values.
template <class T>
std::vector<T> ghost_values(const GhostPlan& plan, const std::vector<T>& own) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<std::string> out(plan.send.size());
  for (std::size_t r = 0; r < out.size(); ++r) {
    out[r].resize(plan.send[r].size() * sizeof(T));
    for (std::size_t k = 0; k < plan.send[r].size(); ++k)
      std::memcpy(out[r].data() + k * sizeof(T), &own[plan.send[r][k]], sizeof(T));
  }
  std::vector<T> ghosts;
  ghosts.reserve(plan.ghosts.size());
  for (const std::string& from : ranks::exchange(out))  // later ranks, in rank order
    for (std::size_t at = 0; at + sizeof(T) <= from.size(); at += sizeof(T)) {
      T v;
      std::memcpy(&v, from.data() + at, sizeof(T));
      ghosts.push_back(v);
    }
  return ghosts;
}

// The blocks of `block_size` particles that a rank owns: those whose first particle it owns.
inline IndexRange owned_blocks(IndexRange own, std::size_t block_size) noexcept {
  return {(own.begin + block_size - 1) / block_size, (own.end + block_size - 1) / block_size};
}

// Per-block partial sums, each rank having filled those of its own blocks, made whole on every
// rank (collective): `partials` holds `segments` runs of the same blocks one after the other
// (one per wall, say). Every rank then adds all the blocks in block order, as one process does.
template <class T>
void complete_block_partials(std::vector<T>& partials, std::size_t block_size,
                             const std::vector<IndexRange>& ranges, std::size_t segments = 1) {
  static_assert(std::is_trivially_copyable_v<T>);
  if (ranges.size() < 2) return;
  const std::size_t blocks = partials.size() / segments;
  const auto slice = [&](std::size_t r) { return owned_blocks(ranges[r], block_size); };
  const IndexRange mine = slice(static_cast<std::size_t>(ranks::rank()));
  std::string out;
  out.reserve(segments * mine.size() * sizeof(T));
  for (std::size_t s = 0; s < segments; ++s)
    out.append(reinterpret_cast<const char*>(partials.data() + s * blocks + mine.begin),
               mine.size() * sizeof(T));
  std::vector<std::size_t> sizes(ranges.size());
  for (std::size_t r = 0; r < sizes.size(); ++r) sizes[r] = segments * slice(r).size() * sizeof(T);
  const std::vector<std::string> all = ranks::all_gather(out, sizes);
  for (std::size_t r = 0; r < all.size(); ++r) {
    const IndexRange theirs = slice(r);
    for (std::size_t s = 0; s < segments; ++s)
      std::memcpy(partials.data() + s * blocks + theirs.begin,
                  all[r].data() + s * theirs.size() * sizeof(T), theirs.size() * sizeof(T));
  }
}

// A load a rank computed for a particle another rank owns (the second particle of a pair whose
// first is its own): the particle's global index and the value.
template <class T>
struct Share {
  std::uint32_t particle = 0;
  T value{};
};

// The shares each own particle received, in rank order and, from each rank, in the order that
// rank computed them: particle k's (k local) are values[offsets[k] ... offsets[k + 1]). Ranks
// own ascending index ranges and walk their pairs in pair order, so this is the order of the
// cross slots that one process adds for the same pairs.
template <class T>
struct IncomingShares {
  std::vector<std::uint32_t> offsets;
  std::vector<T> values;
};

template <class T>
void arrange_shares(IndexRange own, const std::vector<Share<T>>& all, IncomingShares<T>& r);

// Sends every share to the rank owning its particle (collective); `shares` in the order this
// rank computed them.
template <class T>
IncomingShares<T> return_shares(const std::vector<IndexRange>& ranges,
                                const std::vector<Share<T>>& shares) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<std::string> out(ranges.size());
  for (const Share<T>& s : shares) {
    const auto owner =
        std::upper_bound(ranges.begin(), ranges.end(), s.particle,
                         [](std::uint32_t g, const IndexRange& r) { return g < r.end; }) -
        ranges.begin();
    std::string& to = out[static_cast<std::size_t>(owner)];
    to.append(reinterpret_cast<const char*>(&s), sizeof(Share<T>));
  }
  const std::vector<std::string> in = ranks::exchange(out);
  std::vector<Share<T>> all;
  for (const std::string& from : in)
    for (std::size_t at = 0; at + sizeof(Share<T>) <= from.size(); at += sizeof(Share<T>)) {
      Share<T> s;
      std::memcpy(&s, from.data() + at, sizeof(Share<T>));
      all.push_back(s);
    }
  IncomingShares<T> r;
  arrange_shares(ranges[static_cast<std::size_t>(ranks::rank())], all, r);
  return r;
}

// The shares received (`all`, in the order they came) arranged by the own particle they load.
template <class T>
void arrange_shares(IndexRange own, const std::vector<Share<T>>& all, IncomingShares<T>& r) {
  r.offsets.assign(own.size() + 1, 0);
  for (const Share<T>& s : all) ++r.offsets[s.particle - own.begin + 1];
  for (std::size_t k = 0; k < own.size(); ++k) r.offsets[k + 1] += r.offsets[k];
  r.values.resize(all.size());
  std::vector<std::uint32_t> fill(r.offsets.begin(), r.offsets.end() - 1);
  for (const Share<T>& s : all) r.values[fill[s.particle - own.begin]++] = s.value;
}

}  // namespace breccia
