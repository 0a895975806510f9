// The neighbour list: when to rebuild it (the Verlet skin), and the rebuild itself: broken bonds
// compacted, the cell grid searched, every bonded pair kept, pairs mapped to bonds and contact
// history carried over.
#include <algorithm>
#include <cmath>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <limits>
#include <numeric>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/engine/pair_lists.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

using namespace engine_detail;

template <class Law>
void Simulation::compact_bonds(BondSet<Law>& set) {
  if (set.broken_since_compaction == 0) return;
  std::size_t w = 0;
  for (std::size_t k = 0; k < set.size(); ++k) {
    if (!set.intact[k]) continue;
    set.pairs.first[w] = set.pairs.first[k];
    set.pairs.second[w] = set.pairs.second[k];
    set.tag[w] = set.tag[k];
    set.state[w] = set.state[k];
    ++w;
  }
  set.pairs.first.resize(w);
  set.pairs.second.resize(w);
  set.tag.resize(w);
  set.state.resize(w);
  set.intact.assign(w, 1);
  set.broken_since_compaction = 0;
}

bool Simulation::needs_rebuild() const noexcept {
  const double d = std::sqrt(max_disp2_);
  double wall = 0.0;
  for (const Wall& w : walls_) wall = std::max(wall, w.moved);
  return 2.0 * (d + radius_growth_) > skin_ || d + radius_growth_ + wall > skin_;
}

namespace {

// Releases a vector's memory (clear() keeps it).
template <class T>
void release(std::vector<T>& v) {
  std::vector<T>().swap(v);
}

// Returns the heap's free pages to the system: a rebuild frees the old lists and the contact
// stores of every block, small allocations that glibc would otherwise keep resident.
void return_free_memory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

}  // namespace

template <class CL>
void Simulation::rebuild_for(ContactSet<CL>& contacts) {
  std::apply([&](auto&... set) { (compact_bonds(set), ...); }, bonds_);
  // What the new list replaces goes before it is built, so that old and new coexist only in the
  // parts the history merge reads (the peak memory of a run is a rebuild's).
  // The per-pair forces, the bonds' pair indexes and the cross slots are rewritten after it.
  release(contacts.kept_force);
  release(cross_slots_);
  std::apply([&](auto&... set) { (release(set.bond_of_pair), ...); }, bonds_);
  std::apply([&](auto&... set) { (release(set.bond_of_pair), ...); }, joints_);
  PairList old_pairs = std::move(contacts.pairs);
  keep_rows_only(old_pairs);
  std::vector<std::uint32_t> old_history = std::move(contacts.history);
  std::vector<std::vector<typename CL::State>> old_stores = std::move(contacts.stores);
  contacts.pairs = PairList{};
  if (split_)
    build_own_pairs(contacts.pairs);
  else
    build_neighbour_pairs(p_.pos_rad, skin_, p_.planar(), contacts.pairs, PairIndex::OffsetsOnly);
  // Every intact bond must be an interacting pair even if it stretched beyond the search range.
  std::apply([&](auto&... set) { (add_missing_pairs(set.pairs, contacts.pairs), ...); }, bonds_);
  std::apply([&](auto&... set) { (add_missing_pairs(set.pairs, contacts.pairs), ...); }, joints_);
  contacts.pairs.build_offsets(p_.size());
  merge_history(old_pairs, old_history, old_stores, contacts.pairs, contacts.history,
                contacts.stores, contacts.packed);
  old_pairs = PairList{};
  release(old_history);
  release(old_stores);
  // The pair pass's cross index, once the old list is gone.
  contacts.pairs.build_cross_index(p_.size());
  std::apply([&](auto&... set) { (map_bonds_to_pairs(set, contacts.pairs), ...); }, bonds_);
  std::apply([&](auto&... set) { (map_bonds_to_pairs(set, contacts.pairs), ...); }, joints_);
  assign_joints();
  if (split_) note_bonds_anywhere();
  keep_pair_forces_ = pair_forces_needed(contacts);
  // A split sample decides as one process would: a bond law somewhere needs them.
  if (split_) keep_pair_forces_ = ranks::any_flags(keep_pair_forces_ ? 1 : 0) != 0;
  if (keep_pair_forces_) contacts.kept_force.assign(contacts.pairs.size(), Vec3{});
  // Wall candidates: the rank's particles within the skin of each wall, history carried by
  // particle index.
  auto& wall_sets = std::get<std::vector<WallContacts<CL>>>(wall_contacts_);
  const IndexRange own = owned_particles();
  for (std::size_t wi = 0; wi < walls_.size(); ++wi) {
    WallContacts<CL>& wc = wall_sets[wi];
    WallContacts<CL> fresh;
    std::size_t a = 0;
    for (auto i = static_cast<std::uint32_t>(own.begin); i < own.end; ++i) {
      Vec3 nrm;
      if (walls_[wi].gap(p_.pos_rad[i].x, p_.pos_rad[i].r, nrm) >= skin_) continue;
      fresh.particle.push_back(i);
      while (a < wc.particle.size() && wc.particle[a] < i) ++a;
      fresh.state.push_back(a < wc.particle.size() && wc.particle[a] == i ? wc.state[a]
                                                                          : typename CL::State{});
    }
    fresh.force.assign(fresh.particle.size(), {});
    fresh.torque.assign(fresh.particle.size(), {});
    fresh.normal_force.assign(fresh.particle.size(), 0.0);
    fresh.stiffness.assign(fresh.particle.size(), 0.0);
    wc = std::move(fresh);
    walls_[wi].moved = 0.0;
  }
  x_at_build_.resize(p_.size());
  for (std::size_t i = own.begin; i < own.end; ++i) x_at_build_[i] = p_.pos_rad[i].x;
  max_disp2_ = 0.0;
  radius_growth_ = 0.0;
  ++rebuilds_;
  return_free_memory();
}

void Simulation::rebuild() {
  finish_integration();  // the totals hold the displacement since the last build
  std::visit([&](auto& contacts) { rebuild_for(contacts); }, contact_);
}

}  // namespace breccia
