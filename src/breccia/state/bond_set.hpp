#pragma once
// The bonds of one law: contiguous arrays sorted by particle index pair (ARCHITECTURE.md). Broken
// bonds are flagged in the step and compacted at the next neighbour rebuild. Bonds are evaluated in
// the engine's single pass over interacting pairs (one geometry, one result slot per pair), through
// `bond_of_pair`, rebuilt with the neighbour list.
#include <cstdint>
#include <vector>

#include "breccia/state/pair_list.hpp"

namespace breccia {

template <class Law>
struct BondSet {
  typename Law::Params params;
  PairList pairs;                  // particle indices, first < second (index order)
  std::vector<std::uint64_t> tag;  // stable bond tags
  std::vector<typename Law::State> state;
  std::vector<std::uint8_t> intact;
  std::vector<std::uint32_t> bond_of_pair;  // per interacting pair: bond index or kNoBond
  std::size_t broken_since_compaction = 0;

  static constexpr std::uint32_t kNoBond = 0xffffffffu;
  // What each bond holds (run/memory_budget.cpp): its pair, tag, state and flag.
  static constexpr std::size_t kBytesPerBond = 2 * sizeof(std::uint32_t) + sizeof(std::uint64_t) +
                                               sizeof(typename Law::State) + sizeof(std::uint8_t);

  std::size_t size() const noexcept { return tag.size(); }
  std::size_t intact_count() const noexcept { return size() - broken_since_compaction; }
};

// Contact history of one contact law, one entry per neighbour pair. It survives neighbour-list
// rebuilds: the engine merges the old entries into the new sorted list.
template <class Law>
struct ContactSet {
  typename Law::Params params;       // particle-particle
  typename Law::Params wall_params;  // particle-wall (wall friction differs)
  PairList pairs;
  std::vector<typename Law::State> state;
  std::vector<PairSlot> slot;
};

}  // namespace breccia
