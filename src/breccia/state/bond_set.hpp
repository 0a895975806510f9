#pragma once
// The bonds of one law: contiguous arrays sorted by particle index pair (ARCHITECTURE.md). Broken
// bonds are flagged in the step and compacted at the next neighbour rebuild. Bonds are evaluated in
// the engine's single pass over interacting pairs (one geometry and one summed load per pair),
// through `bond_of_pair`, rebuilt with the neighbour list.
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
  // The bond of interacting pair k, or kNoBond (a law without bonds keeps no index).
  std::uint32_t bond_at_pair(std::size_t k) const noexcept {
    return size() == 0 ? kNoBond : bond_of_pair[k];
  }
  std::size_t intact_count() const noexcept { return size() - broken_since_compaction; }
};

// The contact histories of one particle block of the pair pass (pair_list.hpp). A contact takes an
// entry at its first touch and frees it when it opens; freed entries are zeroed and reused last
// in, first out. The pass runs a block on one thread, so the block's entries are taken and freed
// without locks, in an order fixed by the particle count.
// A pair without contact history.
inline constexpr std::uint32_t kNoHistory = 0xffffffffu;

template <class State>
struct HistoryStore {
  std::vector<State> entries;
  std::vector<std::uint32_t> free;

  std::uint32_t take() {
    if (!free.empty()) {
      const std::uint32_t e = free.back();
      free.pop_back();
      return e;
    }
    entries.emplace_back();
    return static_cast<std::uint32_t>(entries.size() - 1);
  }
  void release(std::uint32_t e) {
    entries[e] = State{};
    free.push_back(e);
  }
  std::size_t in_use() const noexcept { return entries.size() - free.size(); }
};

// The contacts of one contact law over the neighbour pairs. Only a pair in touch (or holding
// history) has a state: a listed pair that does not touch costs a 4-byte index, not a state
// (a neighbour list holds 1.5-2 times as many pairs as touch). The histories survive
// neighbour-list rebuilds: the engine merges the old entries into the new sorted list.
template <class Law>
struct ContactSet {
  using State = typename Law::State;
  typename Law::Params params;       // particle-particle
  typename Law::Params wall_params;  // particle-wall (wall friction differs)
  PairList pairs;
  std::vector<std::uint32_t> history;       // per pair: its entry in its block's store, or none
  std::vector<HistoryStore<State>> stores;  // per particle block of the pair pass
  std::vector<Vec3> force;  // each pair's force on its second particle in the last step

  bool has_history(std::size_t k) const noexcept { return history[k] != kNoHistory; }
  // The state of pair k (which must have history).
  const State& state(std::size_t k) const noexcept {
    return stores[pairs.first[k] / kParticleBlock].entries[history[k]];
  }
  std::size_t active() const noexcept {
    std::size_t n = 0;
    for (const auto& s : stores) n += s.in_use();
    return n;
  }
};

}  // namespace breccia
