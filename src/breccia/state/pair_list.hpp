#pragma once
// A list of particle pairs (i, j) sorted by (i, j), with its indexes: the pairs where a particle is
// first (contiguous), where it is second (transposed), and the cross pairs of the pair pass's
// particle blocks.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "breccia/core/vec3.hpp"

namespace breccia {

// The pair pass walks the pairs in blocks of particles: block b owns particles [b kParticleBlock,
// (b + 1) kParticleBlock) and the pairs whose first particle it owns, and sums their loads into its
// own particles' totals directly. A pair whose second particle belongs to a later block is a cross
// pair: its second particle's share goes through a cross slot, which the integrator adds. The
// blocks depend on the particle count only, so the order of every sum, and with it every result,
// is the same for any number of threads.
inline constexpr std::size_t kParticleBlock = 512;

// A cross pair's loads on its second particle, written by the pair pass, read by the integrator.
struct CrossSlot {
  Vec3 force;   // on particle 2
  Vec3 torque;  // on particle 2, about its centre
};

struct PairList {
  std::vector<std::uint32_t> first, second;  // sorted by (first, second)
  std::vector<std::uint32_t> offsets;        // pairs with first == i: [offsets[i], offsets[i+1])
  // Pairs with second == i, ascending slot (build_transposed_index; empty in the engine's list).
  std::vector<std::uint32_t> in_offsets, in_slot;
  // Cross pairs (above): block b's are cross slots [cross_begin[b], cross_begin[b + 1]) in pair
  // order; particle i's, as the second particle, are cross_in[cross_in_offsets[i] ...
  // cross_in_offsets[i + 1]), ascending.
  std::vector<std::uint32_t> cross_begin, cross_in_offsets, cross_in;

  std::size_t size() const noexcept { return first.size(); }

  // Rebuilds the first index alone (the pairs where a particle is first) for n particles: all
  // that merging contact history reads. `first` must already be sorted.
  void build_offsets(std::size_t n) {
    offsets.assign(n + 1, 0);
    for (std::size_t k = 0; k < first.size(); ++k) ++offsets[first[k] + 1];
    for (std::size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
  }

  // Rebuilds both indexes for n particles. `first` must already be sorted.
  void build_index(std::size_t n) {
    build_offsets(n);
    build_transposed_index(n);
  }

  // Rebuilds the transposed index (the pairs where a particle is second) for n particles. The
  // engine's neighbour list keeps none (4 bytes a pair and a grain): its readers build one.
  void build_transposed_index(std::size_t n) { transposed_index(n, in_offsets, in_slot); }
  // The pairs where each of n particles is second, in ascending slot order: particle i's are
  // slots[offsets[i] ... offsets[i + 1]).
  void transposed_index(std::size_t n, std::vector<std::uint32_t>& offsets_out,
                        std::vector<std::uint32_t>& slots) const {
    offsets_out.assign(n + 1, 0);
    for (std::size_t k = 0; k < first.size(); ++k) ++offsets_out[second[k] + 1];
    for (std::size_t i = 0; i < n; ++i) offsets_out[i + 1] += offsets_out[i];
    slots.resize(first.size());
    std::vector<std::uint32_t> fill(offsets_out.begin(), offsets_out.end() - 1);
    for (std::size_t k = 0; k < first.size(); ++k)
      slots[fill[second[k]]++] = static_cast<std::uint32_t>(k);
  }

  std::size_t cross_slots() const noexcept { return cross_in.size(); }

  // Rebuilds the cross-pair index for n particles (after build_index).
  void build_cross_index(std::size_t n) {
    const std::size_t blocks = (n + kParticleBlock - 1) / kParticleBlock;
    cross_begin.assign(blocks + 1, 0);
    cross_in_offsets.assign(n + 1, 0);
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t end = std::min(n, (b + 1) * kParticleBlock);
      std::uint32_t count = 0;
      for (std::uint32_t k = offsets[b * kParticleBlock]; k < offsets[end]; ++k)
        if (second[k] >= end) {
          ++count;
          ++cross_in_offsets[second[k] + 1];
        }
      cross_begin[b + 1] = cross_begin[b] + count;
    }
    for (std::size_t i = 0; i < n; ++i) cross_in_offsets[i + 1] += cross_in_offsets[i];
    cross_in.resize(cross_begin[blocks]);
    std::vector<std::uint32_t> fill(cross_in_offsets.begin(), cross_in_offsets.end() - 1);
    std::uint32_t slot = 0;
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t end = std::min(n, (b + 1) * kParticleBlock);
      for (std::uint32_t k = offsets[b * kParticleBlock]; k < offsets[end]; ++k)
        if (second[k] >= end) cross_in[fill[second[k]]++] = slot++;
    }
  }
};

// Asks the cache for particle i's cross slots: they were written in pair order and are read in
// particle order, a gather that misses the cache as often as not.
inline void prefetch_cross(const PairList& list, const std::vector<CrossSlot>& slots,
                           std::size_t i) noexcept {
  for (std::uint32_t m = list.cross_in_offsets[i]; m < list.cross_in_offsets[i + 1]; ++m)
    __builtin_prefetch(slots.data() + list.cross_in[m]);
}

// Adds the cross slots of particle i (loads of pairs owned by earlier blocks) in a fixed order.
inline void gather_cross(const PairList& list, const std::vector<CrossSlot>& slots, std::size_t i,
                         Vec3& force, Vec3& torque) noexcept {
  for (std::uint32_t m = list.cross_in_offsets[i]; m < list.cross_in_offsets[i + 1]; ++m) {
    const CrossSlot& s = slots[list.cross_in[m]];
    force += s.force;
    torque += s.torque;
  }
}

}  // namespace breccia
