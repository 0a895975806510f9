#pragma once
// The bonds of one law: contiguous arrays sorted by particle index pair (ARCHITECTURE.md). Broken
// bonds are flagged in the step and compacted at the next neighbour rebuild. Bonds are evaluated in
// the engine's single pass over interacting pairs (one geometry and one summed load per pair),
// through `bond_of_pair`, rebuilt with the neighbour list.
#include <cstdint>
#include <string_view>
#include <vector>

#include "breccia/state/pair_list.hpp"

namespace breccia {

// A bond's stable tag: numbered from 1 as bonds and joints are made, in 32 bits (4 bytes a bond
// fewer than 64; the engine refuses a run that would make more than 2^32 - 1 of them).
using BondTag = std::uint32_t;

template <class Law>
struct BondSet {
  typename Law::Params params;
  PairList pairs;            // particle indices, first < second (index order)
  std::vector<BondTag> tag;  // stable bond tags
  std::vector<typename Law::State> state;
  std::vector<std::uint8_t> intact;
  std::vector<std::uint32_t> bond_of_pair;  // per interacting pair: bond index or kNoBond
  std::size_t broken_since_compaction = 0;

  static constexpr std::uint32_t kNoBond = 0xffffffffu;
  // What each bond holds (run/memory_budget.cpp): its pair, tag, state and flag.
  static constexpr std::size_t kBytesPerBond = 2 * sizeof(std::uint32_t) + sizeof(BondTag) +
                                               sizeof(typename Law::State) + sizeof(std::uint8_t);

  std::size_t size() const noexcept { return tag.size(); }
  // The bond of interacting pair k, or kNoBond (a law without bonds keeps no index).
  std::uint32_t bond_at_pair(std::size_t k) const noexcept {
    return size() == 0 ? kNoBond : bond_of_pair[k];
  }
  std::size_t intact_count() const noexcept { return size() - broken_since_compaction; }
};

// A contact that has been in touch carries its previous normal (zero before the first touch).
inline bool has_history(const Vec3& n_old) noexcept {
  return n_old.x != 0.0 || n_old.y != 0.0 || n_old.z != 0.0;
}

// A pair without a contact-history entry.
inline constexpr std::uint32_t kNoHistory = 0xffffffffu;

// The contacts of one contact law over the neighbour pairs. Only a pair that has touched since
// the last neighbour-list rebuild has a state: a listed pair that never touches costs a 4-byte
// index, not a state (a neighbour list holds 1.5-2 times as many pairs as touch). The states live
// in one array per particle block of the pair pass (pair_list.hpp), which runs the block on one
// thread: a pair's first touch appends its entry without a lock, in an order fixed by the
// particle count. An entry whose contact opened is zeroed and stays the pair's until the next
// rebuild, which carries over only the histories in force, in pair order (a contact that opens
// and closes again keeps its place in memory).
template <class Law>
struct ContactSet {
  using State = typename Law::State;
  static constexpr std::string_view law_name() noexcept { return Law::name; }
  typename Law::Params params;       // particle-particle
  typename Law::Params wall_params;  // particle-wall (wall friction differs)
  PairList pairs;
  std::vector<std::uint32_t> history;      // per pair: its entry in its block's store
  std::vector<std::vector<State>> stores;  // per particle block of the pair pass
  std::vector<std::uint32_t> packed;       // per block: its store's size when last in order
  // Each pair's force on its second particle in the last step, where the pair pass keeps it
  // (empty where the laws' states give it back): read it through Simulation::pair_force.
  std::vector<Vec3> kept_force;

  // The state of pair k (which must have an entry).
  const State& state(std::size_t k) const noexcept {
    return stores[pairs.first[k] / kParticleBlock][history[k]];
  }
  // Whether pair k's contact holds history (it was in touch at the last step).
  bool has_history(std::size_t k) const noexcept {
    return history[k] != kNoHistory && breccia::has_history(state(k).n_old);
  }
  std::size_t active() const noexcept {
    std::size_t n = 0;
    for (const auto& store : stores)
      for (const State& st : store) n += breccia::has_history(st.n_old) ? 1 : 0;
    return n;
  }
};

}  // namespace breccia
