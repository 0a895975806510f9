#pragma once
// Operations on the engine's sorted pair lists, shared by its stages: carrying contact history
// from one neighbour list to the next, keeping every bonded pair in the list, and the index from
// pairs to the bonds of a law. Internal to engine/.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "breccia/core/parallel.hpp"
#include "breccia/core/vec3.hpp"
#include "breccia/state/bond_set.hpp"
#include "breccia/state/pair_list.hpp"

namespace breccia::engine_detail {

// Carries contact history from an old sorted pair list to a new one (same particle indexing):
// each new particle block's store gets the histories in force of its pairs, in pair order, with
// room for a quarter more contacts before it grows. Of the old list only the rows (offsets,
// second) are read; each old block's store is released once merged, so that the two stores never
// coexist whole.
template <class State>
void merge_history(const PairList& old_pairs, const std::vector<std::uint32_t>& old_history,
                   std::vector<std::vector<State>>& old_stores, const PairList& new_pairs,
                   std::vector<std::uint32_t>& new_history,
                   std::vector<std::vector<State>>& new_stores,
                   std::vector<std::uint32_t>& packed) {
  const std::size_t n = new_pairs.offsets.size() - 1;
  new_history.assign(new_pairs.size(), kNoHistory);
  new_stores.assign((n + kParticleBlock - 1) / kParticleBlock, {});
  packed.assign(new_stores.size(), 0);
  const bool carried = !old_pairs.offsets.empty();
  for_each_item(new_stores.size(), [&](std::size_t blk) {
    const std::size_t first = blk * kParticleBlock, last = std::min(n, first + kParticleBlock);
    std::vector<State>& store = new_stores[blk];
    if (!carried) {
      store.reserve(16);
      return;
    }
    std::vector<State> old = std::move(old_stores[blk]);
    std::size_t count = 0;
    for (const State& st : old) count += has_history(st.n_old) ? 1 : 0;
    store.reserve(count + count / 4 + 16);
    for (std::size_t i = first; i < last; ++i) {
      std::uint32_t a = old_pairs.offsets[i];
      const std::uint32_t ae = old_pairs.offsets[i + 1];
      for (std::uint32_t b = new_pairs.offsets[i]; b < new_pairs.offsets[i + 1]; ++b) {
        while (a < ae && old_pairs.second[a] < new_pairs.second[b]) ++a;
        if (a < ae && old_pairs.second[a] == new_pairs.second[b] && old_history[a] != kNoHistory &&
            has_history(old[old_history[a]].n_old)) {
          new_history[b] = static_cast<std::uint32_t>(store.size());
          store.push_back(old[old_history[a]]);
        }
      }
    }
    packed[blk] = static_cast<std::uint32_t>(store.size());
  });
}

// Frees what a rebuild no longer needs of an old pair list before the new one is built: all but
// the rows (offsets, second) that merge_history reads.
inline void keep_rows_only(PairList& l) {
  PairList rows;
  rows.offsets = std::move(l.offsets);
  rows.second = std::move(l.second);
  l = std::move(rows);
}

// Rewrites one block's contact histories in pair order, keeping only those in force: entries
// appended in the order of first touch, and those of contacts that opened, scatter a block's
// states in memory; packed, the pair pass reads them in order again. Where a state lies changes
// no result. Pairs [begin, end) are the block's.
template <class State>
void repack_history(std::size_t begin, std::size_t end, std::vector<std::uint32_t>& history,
                    std::vector<State>& store) {
  std::size_t count = 0;
  for (std::size_t k = begin; k < end; ++k)
    count += history[k] != kNoHistory && has_history(store[history[k]].n_old) ? 1 : 0;
  std::vector<State> packed;
  packed.reserve(count + count / 4 + 16);
  for (std::size_t k = begin; k < end; ++k) {
    std::uint32_t& h = history[k];
    if (h == kNoHistory) continue;
    if (!has_history(store[h].n_old)) {
      h = kNoHistory;
      continue;
    }
    packed.push_back(store[h]);
    h = static_cast<std::uint32_t>(packed.size() - 1);
  }
  store.swap(packed);
}

// Adds the pairs of `bonds` (sorted) that `pairs` (sorted) lacks. Rare: a bond stretched beyond
// R1 + R2 + skin. The index of `pairs` must be rebuilt afterwards.
inline void add_missing_pairs(const PairList& bonds, PairList& pairs) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> missing;
  std::size_t a = 0;
  for (std::size_t k = 0; k < bonds.size(); ++k) {
    const auto key = std::pair(bonds.first[k], bonds.second[k]);
    while (a < pairs.size() && std::pair(pairs.first[a], pairs.second[a]) < key) ++a;
    if (a == pairs.size() || std::pair(pairs.first[a], pairs.second[a]) != key)
      missing.push_back(key);
  }
  if (missing.empty()) return;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> all(pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) all[k] = {pairs.first[k], pairs.second[k]};
  all.insert(all.end(), missing.begin(), missing.end());
  std::sort(all.begin(), all.end());
  pairs.first.resize(all.size());
  pairs.second.resize(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    pairs.first[k] = all[k].first;
    pairs.second[k] = all[k].second;
  }
}

// For each interacting pair, the index of its bond in `set` (or kNoBond). Both lists are sorted.
// A law without bonds keeps no index (the pair pass does not read it): a run uses one bond law,
// and an index per law would cost 4 bytes per pair for each of the others.
template <class Law>
void map_bonds_to_pairs(BondSet<Law>& set, const PairList& pairs) {
  if (set.size() == 0) {
    set.bond_of_pair.clear();
    set.bond_of_pair.shrink_to_fit();
    return;
  }
  set.bond_of_pair.assign(pairs.size(), BondSet<Law>::kNoBond);
  std::size_t a = 0;
  for (std::size_t k = 0; k < set.size(); ++k) {
    const auto key = std::pair(set.pairs.first[k], set.pairs.second[k]);
    while (std::pair(pairs.first[a], pairs.second[a]) < key) ++a;
    set.bond_of_pair[a] = static_cast<std::uint32_t>(k);
  }
}

// Merges new elements (i < j, tag, state) into a sorted bond-layout set.
template <class Law>
void insert_sorted(
    BondSet<Law>& set,
    std::vector<std::tuple<std::uint32_t, std::uint32_t, BondTag, typename Law::State>>& added) {
  if (added.empty()) return;
  for (std::size_t k = 0; k < set.size(); ++k)
    added.emplace_back(set.pairs.first[k], set.pairs.second[k], set.tag[k], set.state[k]);
  std::sort(added.begin(), added.end(), [](const auto& a, const auto& b) {
    return std::pair(std::get<0>(a), std::get<1>(a)) < std::pair(std::get<0>(b), std::get<1>(b));
  });
  const std::size_t n = added.size();
  set.pairs = PairList{};
  set.pairs.first.resize(n);
  set.pairs.second.resize(n);
  set.tag.resize(n);
  set.state.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    std::tie(set.pairs.first[k], set.pairs.second[k], set.tag[k], set.state[k]) = added[k];
  set.intact.assign(n, 1);
  added.clear();
}

}  // namespace breccia::engine_detail
