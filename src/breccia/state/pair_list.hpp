#pragma once
// A list of particle pairs (i, j) sorted by (i, j), with the two indexes the gather pass needs:
// the pairs where a particle is first (contiguous) and where it is second (transposed).
#include <cstdint>
#include <vector>

#include "breccia/core/vec3.hpp"

namespace breccia {

// Per-pair result slot of the compute pass: force on particle 2 and the torques about both
// centres. Written by exactly one pair, read by the two particles in the gather pass.
struct PairSlot {
  Vec3 force;    // on particle 2
  Vec3 torque1;  // on particle 1
  Vec3 torque2;  // on particle 2
};

struct PairList {
  std::vector<std::uint32_t> first, second;  // sorted by (first, second)
  std::vector<std::uint32_t> offsets;        // pairs with first == i: [offsets[i], offsets[i+1])
  std::vector<std::uint32_t> in_offsets, in_slot;  // pairs with second == i, ascending slot

  std::size_t size() const noexcept { return first.size(); }

  // Rebuilds both indexes for n particles. `first` must already be sorted.
  void build_index(std::size_t n) {
    offsets.assign(n + 1, 0);
    in_offsets.assign(n + 1, 0);
    for (std::size_t k = 0; k < first.size(); ++k) {
      ++offsets[first[k] + 1];
      ++in_offsets[second[k] + 1];
    }
    for (std::size_t i = 0; i < n; ++i) {
      offsets[i + 1] += offsets[i];
      in_offsets[i + 1] += in_offsets[i];
    }
    in_slot.resize(first.size());
    std::vector<std::uint32_t> fill(in_offsets.begin(), in_offsets.end() - 1);
    for (std::size_t k = 0; k < first.size(); ++k)
      in_slot[fill[second[k]]++] = static_cast<std::uint32_t>(k);
  }
};

// Adds the contributions of all pairs of particle i to (force, torque), in a fixed order.
inline void gather_pairs(const PairList& list, const std::vector<PairSlot>& slots, std::size_t i,
                         Vec3& force, Vec3& torque) noexcept {
  for (std::uint32_t k = list.offsets[i]; k < list.offsets[i + 1]; ++k) {
    force -= slots[k].force;
    torque += slots[k].torque1;
  }
  for (std::uint32_t m = list.in_offsets[i]; m < list.in_offsets[i + 1]; ++m) {
    const PairSlot& s = slots[list.in_slot[m]];
    force += s.force;
    torque += s.torque2;
  }
}

}  // namespace breccia
