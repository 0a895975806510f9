#pragma once
// One sample split over the ranks of an MPI launch (ARCHITECTURE.md, "Ranks (MPI)"). Each rank
// owns a contiguous range of particle indexes cut at multiples of kDomainGrain, whole blocks of
// the pair pass and of the integrator, so that a rank walks the blocks and pairs that one process
// walks, in the same order, and its sums come out to the same bits. After its own particles a rank
// keeps its ghosts: the particles of later ranks that its own can touch, in index order, so that
// its local order is the global order. Particles of earlier ranks it needs no copy of: a pair
// belongs to the block of its first (lower) particle, whose rank sends the share of the second.
#include <cstddef>
#include <cstdint>
#include <vector>

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
// sender which.
GhostPlan plan_ghosts(const std::vector<PosRad>& own_particles,
                      const std::vector<IndexRange>& ranges, double skin);

}  // namespace breccia
