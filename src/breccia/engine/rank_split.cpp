// One sample split over the ranks of an MPI launch (ARCHITECTURE.md, "Ranks (MPI)"). Each rank
// steps the particles of its index range (engine/domain.hpp) and the pairs, bonds and wall
// contacts whose first grain is its own; its ghosts come from their owners every step, the loads
// of its pairs on other ranks' grains go back to them as shares, and every per-block partial sum
// is made whole on every rank before it is added in block order. The ranks thus walk the blocks
// and pairs one process walks, and add the same numbers in the same order: the results are those
// of one process to the bit.
#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "breccia/core/byte_text.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/core/type_list.hpp"
#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/engine/pair_lists.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

using namespace engine_detail;

namespace {

// What a pair pass reads of a ghost.
struct GhostState {
  PosRad pos_rad;
  Vec3 vel, angvel;
  Quat orientation;
  double angle = 0.0;
};

// The bond and joint laws by their position (a crack names its law by a pointer to static
// storage, which differs from process to process: ranks send the position).
std::vector<std::string_view> law_names() {
  std::vector<std::string_view> names;
  for_each_type<BondLaws>([&]<class L>() { names.push_back(L::name); });
  for_each_type<JointLaws>([&]<class L>() { names.push_back(L::name); });
  return names;
}

// Keeps the elements of a bond-layout set whose first grain is in `own`, in their order.
template <class Law>
void keep_own_elements(BondSet<Law>& set, IndexRange own) {
  std::size_t w = 0, broken = 0;
  for (std::size_t k = 0; k < set.size(); ++k) {
    if (!own.contains(set.pairs.first[k])) continue;
    set.pairs.first[w] = set.pairs.first[k];
    set.pairs.second[w] = set.pairs.second[k];
    set.tag[w] = set.tag[k];
    set.state[w] = set.state[k];
    set.intact[w] = set.intact[k];
    broken += set.intact[k] ? 0 : 1;
    ++w;
  }
  set.pairs.first.resize(w);
  set.pairs.second.resize(w);
  set.tag.resize(w);
  set.state.resize(w);
  set.intact.resize(w);
  set.broken_since_compaction = broken;
  set.bond_of_pair.clear();
}

// Keeps the pairs of a contact set whose first grain is in `own`, with their histories (kept in
// their blocks' stores, which are the own blocks'); the other blocks' stores are freed.
template <class CL>
void keep_own_pairs(ContactSet<CL>& c, IndexRange own, std::size_t particles) {
  PairList kept;
  std::vector<std::uint32_t> history;
  std::vector<Vec3> forces;
  for (std::size_t k = 0; k < c.pairs.size(); ++k) {
    if (!own.contains(c.pairs.first[k])) continue;
    kept.first.push_back(c.pairs.first[k]);
    kept.second.push_back(c.pairs.second[k]);
    history.push_back(c.history[k]);
    if (!c.kept_force.empty()) forces.push_back(c.kept_force[k]);
  }
  const IndexRange blocks = owned_blocks(own, kParticleBlock);
  for (std::size_t b = 0; b < c.stores.size(); ++b)
    if (!blocks.contains(b)) std::vector<typename CL::State>().swap(c.stores[b]);
  kept.build_offsets(particles);
  kept.build_cross_index(particles);
  c.pairs = std::move(kept);
  c.history = std::move(history);
  c.kept_force = std::move(forces);
}

// Keeps a wall's contacts with grains in `own`.
template <class CL>
void keep_own_wall_contacts(WallContacts<CL>& wc, IndexRange own) {
  WallContacts<CL> kept;
  for (std::size_t k = 0; k < wc.particle.size(); ++k) {
    if (!own.contains(wc.particle[k])) continue;
    kept.particle.push_back(wc.particle[k]);
    kept.state.push_back(wc.state[k]);
    kept.force.push_back(wc.force[k]);
    kept.torque.push_back(wc.torque[k]);
    kept.normal_force.push_back(wc.normal_force[k]);
    kept.stiffness.push_back(wc.stiffness[k]);
  }
  wc = std::move(kept);
}

// Every rank's values of its own particles, on every rank (collective).
template <class T>
void complete_particle_values(std::vector<T>& values, const std::vector<IndexRange>& ranges) {
  static_assert(std::is_trivially_copyable_v<T>);
  if (values.empty()) return;
  const IndexRange own = ranges[static_cast<std::size_t>(ranks::rank())];
  const std::string mine(reinterpret_cast<const char*>(values.data() + own.begin),
                         own.size() * sizeof(T));
  std::vector<std::size_t> sizes(ranges.size());
  for (std::size_t r = 0; r < sizes.size(); ++r) sizes[r] = ranges[r].size() * sizeof(T);
  const std::vector<std::string> all = ranks::all_gather(mine, sizes);
  for (std::size_t r = 0; r < all.size(); ++r)
    std::memcpy(values.data() + ranges[r].begin, all[r].data(), ranges[r].size() * sizeof(T));
}

// Every rank's values, concatenated in rank order, on every rank (collective).
template <class T>
std::vector<T> concatenated(const std::vector<T>& mine) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::string out;
  bytes::put_range(out, mine.data(), mine.size());
  std::vector<T> all;
  for (const std::string& from : ranks::all_gather(out)) {
    const std::size_t at = all.size(), n = from.size() / sizeof(T);
    all.resize(at + n);
    if (n > 0) std::memcpy(static_cast<void*>(all.data() + at), from.data(), n * sizeof(T));
  }
  return all;
}

// A bond-layout set made whole, without its pair index: every rank's elements in rank order are
// one process's order (a set is sorted by pair, and the ranks own ascending grain ranges).
template <class Law>
void concatenate_elements(BondSet<Law>& set) {
  std::size_t broken = 0;
  for (const std::string& b : ranks::all_gather(std::to_string(set.broken_since_compaction)))
    broken += std::stoull(b);
  set.pairs.first = concatenated(set.pairs.first);
  set.pairs.second = concatenated(set.pairs.second);
  set.tag = concatenated(set.tag);
  set.state = concatenated(set.state);
  set.intact = concatenated(set.intact);
  set.broken_since_compaction = broken;
  set.bond_of_pair.clear();
}

// The same with its pair index made anew from the whole list, as one process made it.
template <class Law>
void gather_elements(BondSet<Law>& set, const PairList& pairs) {
  concatenate_elements(set);
  map_bonds_to_pairs(set, pairs);
}

// The pairs and histories made whole: the lists in rank order (one process's: sorted by first
// grain), each block's store from the rank that owns the block.
template <class CL>
void gather_contacts(ContactSet<CL>& c, const std::vector<IndexRange>& ranges,
                     std::size_t particles) {
  PairList whole;
  whole.first = concatenated(c.pairs.first);
  whole.second = concatenated(c.pairs.second);
  c.history = concatenated(c.history);
  c.kept_force = concatenated(c.kept_force);
  const std::size_t blocks = (particles + kParticleBlock - 1) / kParticleBlock;
  const IndexRange mine =
      owned_blocks(ranges[static_cast<std::size_t>(ranks::rank())], kParticleBlock);
  std::string out;
  for (std::size_t b = mine.begin; b < mine.end; ++b) {
    bytes::put(out, static_cast<std::uint64_t>(c.stores[b].size()));
    bytes::put_range(out, c.stores[b].data(), c.stores[b].size());
    bytes::put(out, c.packed[b]);
  }
  c.stores.resize(blocks);
  c.packed.resize(blocks);
  const std::vector<std::string> all = ranks::all_gather(out);
  for (std::size_t r = 0; r < all.size(); ++r) {
    std::size_t at = 0;
    const IndexRange theirs = owned_blocks(ranges[r], kParticleBlock);
    for (std::size_t b = theirs.begin; b < theirs.end; ++b) {
      c.stores[b].resize(bytes::take<std::uint64_t>(all[r], at));
      bytes::take_range(all[r], at, c.stores[b].data(), c.stores[b].size());
      c.packed[b] = bytes::take<std::uint32_t>(all[r], at);
    }
  }
  whole.build_offsets(particles);
  whole.build_cross_index(particles);
  c.pairs = std::move(whole);
}

// A wall's contacts made whole: each rank's are its grains', ascending.
template <class CL>
void gather_wall_contacts(WallContacts<CL>& wc) {
  wc.particle = concatenated(wc.particle);
  wc.state = concatenated(wc.state);
  wc.force = concatenated(wc.force);
  wc.torque = concatenated(wc.torque);
  wc.normal_force = concatenated(wc.normal_force);
  wc.stiffness = concatenated(wc.stiffness);
}

}  // namespace

// The split keeps the lists of the last rebuild, each rank its own part of them, so that the
// next steps (and the next rebuild) are those of one process whenever the split is made.
void Simulation::split_over_ranks() {
  if (ranks::size() < 2 || split_) return;
  if (retired_)
    throw std::logic_error(
        "Simulation::split_over_ranks: the simulation's interactions are retired");
  if (!initialised_) initialise();
  split_ = std::make_unique<RankSplit>();
  RankSplit& s = *split_;
  s.ranges = split_indexes(p_.size(), ranks::size());
  s.own = s.ranges[static_cast<std::size_t>(ranks::rank())];
  std::apply([&](auto&... set) { (keep_own_elements(set, s.own), ...); }, bonds_);
  std::apply([&](auto&... set) { (keep_own_elements(set, s.own), ...); }, joints_);
  std::visit(
      [&]<class CL>(ContactSet<CL>& c) {
        keep_own_pairs(c, s.own, p_.size());
        std::apply([&](auto&... set) { (map_bonds_to_pairs(set, c.pairs), ...); }, bonds_);
        std::apply([&](auto&... set) { (map_bonds_to_pairs(set, c.pairs), ...); }, joints_);
        for (auto& wc : std::get<std::vector<WallContacts<CL>>>(wall_contacts_))
          keep_own_wall_contacts(wc, s.own);
        // Every ghost the kept pairs reach, planned from the positions of the last rebuild.
        std::vector<std::uint32_t> reached;
        for (const std::uint32_t j : c.pairs.second)
          if (j >= s.own.end) reached.push_back(j);
        std::sort(reached.begin(), reached.end());
        reached.erase(std::unique(reached.begin(), reached.end()), reached.end());
        std::vector<PosRad> built(s.own.size());
        for (std::size_t k = 0; k < built.size(); ++k)
          built[k] = {x_at_build_[s.own.begin + k], p_.pos_rad[s.own.begin + k].r};
        s.plan = plan_ghosts(built, s.ranges, skin_, reached);
        s.shares_from.clear();
      },
      contact_);
  cross_slots_.clear();
  std::vector<std::vector<Failure>>().swap(block_failures_);
  note_bonds_anywhere();
  refresh_ghosts();
}

bool Simulation::bonds_here() const noexcept {
  bool any = false;
  std::apply([&](const auto&... set) { ((any = any || set.size() > 0), ...); }, bonds_);
  std::apply([&](const auto&... set) { ((any = any || set.size() > 0), ...); }, joints_);
  return any;
}

bool Simulation::bonds_anywhere() const noexcept {
  return split_ ? split_->bonds_anywhere : bonds_here();
}

void Simulation::note_bonds_anywhere() {
  const std::vector<std::string> all = ranks::all_gather(bonds_here() ? "1" : "0");
  split_->bonds_anywhere = std::find(all.begin(), all.end(), "1") != all.end();
}

const std::vector<IndexRange>& Simulation::rank_ranges() const noexcept {
  static const std::vector<IndexRange> none;
  return split_ ? split_->ranges : none;
}

std::vector<std::uint32_t> Simulation::bond_partners_beyond() const {
  std::vector<std::uint32_t> out;
  const auto add = [&](const auto& set) {
    for (const std::uint32_t j : set.pairs.second)
      if (j >= split_->own.end) out.push_back(j);
  };
  std::apply([&](const auto&... set) { (add(set), ...); }, bonds_);
  std::apply([&](const auto&... set) { (add(set), ...); }, joints_);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void Simulation::build_own_pairs(PairList& out) {
  RankSplit& s = *split_;
  std::vector<PosRad> local(p_.pos_rad.begin() + static_cast<std::ptrdiff_t>(s.own.begin),
                            p_.pos_rad.begin() + static_cast<std::ptrdiff_t>(s.own.end));
  s.plan = plan_ghosts(local, s.ranges, skin_, bond_partners_beyond());
  s.shares_from.clear();
  refresh_ghosts();
  local.insert(local.end(), s.plan.ghost_pos_rad.begin(), s.plan.ghost_pos_rad.end());
  PairList found;
  build_neighbour_pairs(local, skin_, p_.planar(), found, PairIndex::OffsetsOnly, s.own.size());
  // Local order is global order (the ghosts lie past the own range, ascending): the list stays
  // sorted.
  const auto n_own = static_cast<std::uint32_t>(s.own.size());
  const auto global = [&](std::uint32_t k) {
    return k < n_own ? static_cast<std::uint32_t>(s.own.begin + k) : s.plan.ghosts[k - n_own];
  };
  out = PairList{};
  out.first.resize(found.size());
  out.second.resize(found.size());
  for (std::size_t k = 0; k < found.size(); ++k) {
    out.first[k] = global(found.first[k]);
    out.second[k] = global(found.second[k]);
  }
}

void Simulation::refresh_ghosts(bool with_integration) {
  const RankSplit& s = *split_;
  const bool turns = !p_.orientation.empty(), angles = !p_.angle.empty();
  const auto int_blocks = [&](std::size_t r) { return owned_blocks(s.ranges[r], kBlock); };
  std::string partials;  // to every rank
  if (with_integration) {
    const IndexRange mine = int_blocks(static_cast<std::size_t>(ranks::rank()));
    partials.assign(reinterpret_cast<const char*>(block_int_.data() + mine.begin),
                    mine.size() * sizeof(IntegrateBlock));
  }
  std::vector<std::string> out(s.plan.send.size());
  for (std::size_t r = 0; r < out.size(); ++r) {
    out[r].resize(s.plan.send[r].size() * sizeof(GhostState));
    for (std::size_t k = 0; k < s.plan.send[r].size(); ++k) {
      const std::size_t i = s.own.begin + s.plan.send[r][k];
      GhostState g{p_.pos_rad[i], p_.vel[i], p_.angvel[i], turns ? p_.orientation[i] : Quat{},
                   angles ? p_.angle[i] : 0.0};
      std::memcpy(out[r].data() + k * sizeof(GhostState), &g, sizeof(GhostState));
    }
    out[r] += partials;
  }
  std::vector<std::size_t> ghost_bytes(out.size(), 0), expected(out.size(), 0);
  std::size_t owner = 0;
  for (const std::uint32_t g : s.plan.ghosts) {
    while (!s.ranges[owner].contains(g)) ++owner;
    ghost_bytes[owner] += sizeof(GhostState);
  }
  for (std::size_t r = 0; r < out.size(); ++r)
    expected[r] =
        ghost_bytes[r] + (with_integration ? int_blocks(r).size() * sizeof(IntegrateBlock) : 0);
  const std::vector<std::string> in = ranks::exchange(out, expected);
  std::size_t next = 0;
  for (std::size_t r = 0; r < in.size(); ++r) {
    const std::string& from = in[r];
    for (std::size_t at = 0; at < ghost_bytes[r]; at += sizeof(GhostState)) {
      GhostState g;
      std::memcpy(&g, from.data() + at, sizeof(GhostState));
      const std::uint32_t i = s.plan.ghosts[next++];
      p_.pos_rad[i] = g.pos_rad;
      p_.vel[i] = g.vel;
      p_.angvel[i] = g.angvel;
      if (turns) p_.orientation[i] = g.orientation;
      if (angles) p_.angle[i] = g.angle;
    }
    if (with_integration)
      std::memcpy(block_int_.data() + int_blocks(r).begin, from.data() + ghost_bytes[r],
                  int_blocks(r).size() * sizeof(IntegrateBlock));
  }
}

void Simulation::finish_integration() {
  if (!split_ || !split_->integration_pending) return;
  complete_block_partials(block_int_, kBlock, split_->ranges);
  split_->integration_pending = false;
  add_integration_totals(false);
}

void Simulation::request_stop(bool stop) noexcept {
  if (split_) split_->stop_here = stop;
}

bool Simulation::stop_requested_anywhere() const noexcept {
  return split_ && split_->stop_anywhere;
}

using bytes::put;
using bytes::put_range;
using bytes::take;
using bytes::take_range;

// To each rank: the cross slots of this rank's pairs whose second grain it owns (grain by grain,
// each grain's in slot order), then, the same to all, this rank's block partials of the pair and
// wall passes, its stop request and its count of the step's cracks. Every size is known to the
// receiver (the shares' counts are fixed between ghost plans, counted once after each), so one
// exchange carries it all. A receiver takes the shares in rank order (pair order) and fills the
// others' blocks; the cracks follow in a second exchange in the steps that have any.
void Simulation::exchange_step_loads(const PairList& pairs) {
  RankSplit& s = *split_;
  const std::size_t n_ranks = s.ranges.size(), walls = walls_.size();
  const std::size_t wall_nb = walls > 0 ? wall_blocks_.size() / walls : 0;
  const auto pair_blocks = [&](std::size_t r) { return owned_blocks(s.ranges[r], kParticleBlock); };
  const auto wall_blocks = [&](std::size_t r) { return owned_blocks(s.ranges[r], kBlock); };
  const auto common_bytes = [&](std::size_t r) {
    return pair_blocks(r).size() * (sizeof(block_dis_[0]) + sizeof(block_joint_dis_[0])) +
           walls * wall_blocks(r).size() * sizeof(WallBlock) + sizeof(std::uint32_t) +
           sizeof(std::uint64_t);
  };
  // What every rank gets.
  std::string common;
  const IndexRange pb = pair_blocks(static_cast<std::size_t>(ranks::rank()));
  const IndexRange wb = wall_blocks(static_cast<std::size_t>(ranks::rank()));
  put_range(common, block_dis_.data() + pb.begin, pb.size());
  put_range(common, block_joint_dis_.data() + pb.begin, pb.size());
  for (std::size_t w = 0; w < walls; ++w)
    put_range(common, wall_blocks_.data() + w * wall_nb + wb.begin, wb.size());
  put(common, static_cast<std::uint32_t>(s.stop_here ? 1 : 0));
  put(common, static_cast<std::uint64_t>(s.cracks.size()));
  // The shares, by owner.
  std::vector<std::string> out(n_ranks);
  std::size_t owner = 0;
  std::vector<std::uint64_t> count(n_ranks, 0);
  for (const std::uint32_t g : s.plan.ghosts) {
    while (!s.ranges[owner].contains(g)) ++owner;
    for (std::uint32_t m = pairs.cross_in_offsets[g]; m < pairs.cross_in_offsets[g + 1]; ++m) {
      put(out[owner], Share<CrossSlot>{g, cross_slots_[pairs.cross_in[m]]});
      ++count[owner];
    }
  }
  s.shares_sent = 0;
  for (std::size_t r = 0; r < n_ranks; ++r) {
    s.shares_sent += count[r];
    out[r] += common;
  }
  if (s.shares_from.empty()) {
    std::vector<std::string> counts(n_ranks);
    for (std::size_t r = 0; r < n_ranks; ++r) put(counts[r], count[r]);
    for (const std::string& from :
         ranks::exchange(counts, std::vector<std::size_t>(n_ranks, sizeof(std::uint64_t)))) {
      std::size_t at = 0;
      s.shares_from.push_back(take<std::uint64_t>(from, at));
    }
  }
  std::vector<std::size_t> expected(n_ranks);
  for (std::size_t r = 0; r < n_ranks; ++r)
    expected[r] = s.shares_from[r] * sizeof(Share<CrossSlot>) + common_bytes(r);
  const std::vector<std::string> in = ranks::exchange(out, expected);
  std::vector<Share<CrossSlot>>& shares = s.received;
  shares.clear();
  std::vector<std::uint64_t> crack_counts(n_ranks, 0);
  bool stop = false;
  for (std::size_t r = 0; r < n_ranks; ++r) {
    const std::string& from = in[r];
    std::size_t at = 0;
    for (auto k = s.shares_from[r]; k > 0; --k) shares.push_back(take<Share<CrossSlot>>(from, at));
    const IndexRange their_pb = pair_blocks(r), their_wb = wall_blocks(r);
    take_range(from, at, block_dis_.data() + their_pb.begin, their_pb.size());
    take_range(from, at, block_joint_dis_.data() + their_pb.begin, their_pb.size());
    for (std::size_t w = 0; w < walls; ++w)
      take_range(from, at, wall_blocks_.data() + w * wall_nb + their_wb.begin, their_wb.size());
    // Read whatever the others said: a short-circuit here would skip the field's bytes.
    const bool stop_there = take<std::uint32_t>(from, at) != 0;
    stop = stop || stop_there;
    crack_counts[r] = take<std::uint64_t>(from, at);
    if (at != from.size())
      throw std::logic_error(fmt::format(
          "Simulation::exchange_step_loads: a message of another layout at step {} (from rank {}: "
          "{} bytes, {} read)",
          step_, r, from.size(), at));
  }
  s.stop_anywhere = stop;
  arrange_shares(s.own, shares, s.incoming);
  if (std::any_of(crack_counts.begin(), crack_counts.end(), [](auto n) { return n > 0; }))
    exchange_step_cracks(crack_counts);
}

// Every rank's cracks of the step, to every rank, recorded in rank order (pair order).
void Simulation::exchange_step_cracks(const std::vector<std::uint64_t>& crack_counts) {
  RankSplit& s = *split_;
  static const std::vector<std::string_view> names = law_names();
  constexpr std::size_t kCrackBytes = sizeof(std::uint32_t) + sizeof(CrackRecord);
  std::string mine;
  mine.reserve(s.cracks.size() * kCrackBytes);
  for (CrackRecord r : s.cracks) {
    put(mine,
        static_cast<std::uint32_t>(std::find(names.begin(), names.end(), r.law) - names.begin()));
    r.law = {};
    put(mine, r);
  }
  s.cracks.clear();
  std::vector<std::size_t> sizes(crack_counts.size());
  for (std::size_t r = 0; r < sizes.size(); ++r) sizes[r] = crack_counts[r] * kCrackBytes;
  for (const std::string& from : ranks::all_gather(mine, sizes)) {
    std::size_t at = 0;
    while (at < from.size()) {
      const auto law = take<std::uint32_t>(from, at);
      CrackRecord record = take<CrackRecord>(from, at);
      record.law = names.at(law);
      released_ += record.energy;
      cracks_.push_back(record);
    }
  }
}

namespace {

// The fields a gather brings, in their order (empty fields, such as the 3D angles, carry none).
template <class Store, class F>
void for_each_gathered_field(Store& p, F&& f) {
  f(p.pos_rad);
  f(p.vel);
  f(p.angvel);
  f(p.force);
  f(p.torque);
  f(p.orientation);
  f(p.angle);
  f(p.displacement);
}

std::size_t gathered_bytes_per_grain(const ParticleStore& p) {
  std::size_t n = 0;
  for_each_gathered_field(p, [&](const auto& v) { n += v.empty() ? 0 : sizeof(v[0]); });
  return n;
}

}  // namespace

// One collective for every field (it may come after each step: its latency counts).
void Simulation::gather_particles() {
  if (!split_ || split_->particles_whole) return;
  const std::vector<IndexRange>& ranges = split_->ranges;
  const std::size_t grain_bytes = gathered_bytes_per_grain(p_);
  const IndexRange own = split_->own;
  std::string mine;
  mine.reserve(own.size() * grain_bytes);
  for_each_gathered_field(p_, [&](const auto& v) {
    if (!v.empty()) put_range(mine, v.data() + own.begin, own.size());
  });
  std::vector<std::size_t> sizes(ranges.size());
  for (std::size_t r = 0; r < ranges.size(); ++r) sizes[r] = ranges[r].size() * grain_bytes;
  const std::vector<std::string> all = ranks::all_gather(mine, sizes);
  for (std::size_t r = 0; r < all.size(); ++r) {
    if (r == static_cast<std::size_t>(ranks::rank())) continue;
    std::size_t at = 0;
    for_each_gathered_field(p_, [&](auto& v) {
      if (!v.empty()) take_range(all[r], at, v.data() + ranges[r].begin, ranges[r].size());
    });
  }
  split_->particles_whole = true;
}

// The listed grains' fields, grain by grain, from their owners in rank order.
void Simulation::gather_grains(const GrainReads& reads) {
  const std::span<const std::uint32_t> grains = reads.some;
  // Checked in one process too, where a reader's list is tested most.
  if (!std::is_sorted(grains.begin(), grains.end()) ||
      (!grains.empty() && grains.back() >= p_.size()))
    throw std::logic_error("Simulation::gather_grains: the grains are not ascending indexes");
  if (!split_ || split_->particles_whole) return;
  if (reads.all) {
    gather_particles();
    return;
  }
  if (grains.empty()) return;
  const std::vector<IndexRange>& ranges = split_->ranges;
  const std::size_t grain_bytes = gathered_bytes_per_grain(p_);
  // Each rank's part of the list: a run of it, as the list is ascending.
  std::vector<std::span<const std::uint32_t>> parts(ranges.size());
  std::size_t from = 0;
  for (std::size_t r = 0; r < ranges.size(); ++r) {
    std::size_t to = from;
    while (to < grains.size() && grains[to] < ranges[r].end) ++to;
    parts[r] = grains.subspan(from, to - from);
    from = to;
  }
  const auto me = static_cast<std::size_t>(ranks::rank());
  std::string mine;
  mine.reserve(parts[me].size() * grain_bytes);
  for (const std::uint32_t i : parts[me])
    for_each_gathered_field(p_, [&](const auto& v) {
      if (!v.empty()) put_range(mine, v.data() + i, 1);
    });
  std::vector<std::size_t> sizes(ranges.size());
  for (std::size_t r = 0; r < ranges.size(); ++r) sizes[r] = parts[r].size() * grain_bytes;
  const std::vector<std::string> all = ranks::all_gather(mine, sizes);
  for (std::size_t r = 0; r < all.size(); ++r) {
    if (r == me) continue;
    std::size_t at = 0;
    for (const std::uint32_t i : parts[r])
      for_each_gathered_field(p_, [&](auto& v) {
        if (!v.empty()) take_range(all[r], at, v.data() + i, 1);
      });
  }
}

void Simulation::unsplit() {
  if (!split_) return;
  finish_integration();
  const std::vector<IndexRange> ranges = split_->ranges;
  gather_particles();
  complete_particle_values(x_at_build_, ranges);
  if (!damped_less_until_.empty()) complete_particle_values(damped_less_until_, ranges);
  if (!drive_force_prev_.empty()) {
    // Two entries a grain.
    std::vector<IndexRange> twice(ranges.size());
    for (std::size_t r = 0; r < ranges.size(); ++r)
      twice[r] = {2 * ranges[r].begin, 2 * ranges[r].end};
    complete_particle_values(drive_force_prev_, twice);
  }
  std::visit(
      [&]<class CL>(ContactSet<CL>& c) {
        gather_contacts(c, ranges, p_.size());
        std::apply([&](auto&... set) { (gather_elements(set, c.pairs), ...); }, bonds_);
        std::apply([&](auto&... set) { (gather_elements(set, c.pairs), ...); }, joints_);
        for (auto& wc : std::get<std::vector<WallContacts<CL>>>(wall_contacts_))
          gather_wall_contacts(wc);
      },
      contact_);
  split_.reset();
  cross_slots_.clear();
}

void Simulation::pair_loads_around(const std::vector<std::uint32_t>& grains,
                                   std::vector<std::uint32_t>& offsets,
                                   std::vector<PairLoad>& loads) const {
  // This rank's part: per grain, the pairs where it is first, and those where it is second.
  std::vector<std::vector<PairLoad>> rows(grains.size()), in(grains.size());
  std::visit(
      [&](const auto& c) {
        const PairList& l = c.pairs;
        if (l.offsets.empty()) return;
        for (std::size_t a = 0; a < grains.size(); ++a)
          for (std::uint32_t k = l.offsets[grains[a]]; k < l.offsets[grains[a] + 1]; ++k)
            rows[a].push_back({l.second[k], pair_force(c, k)});
        for (std::size_t k = 0; k < l.size(); ++k) {
          const auto at = std::lower_bound(grains.begin(), grains.end(), l.second[k]);
          if (at != grains.end() && *at == l.second[k])
            in[static_cast<std::size_t>(at - grains.begin())].push_back(
                {l.first[k], -pair_force(c, k)});
        }
      },
      contact_);
  offsets.assign(1, 0);
  loads.clear();
  if (!split_) {
    for (std::size_t a = 0; a < grains.size(); ++a) {
      loads.insert(loads.end(), rows[a].begin(), rows[a].end());
      loads.insert(loads.end(), in[a].begin(), in[a].end());
      offsets.push_back(static_cast<std::uint32_t>(loads.size()));
    }
    return;
  }
  // Every rank's parts: a grain's first-grain pairs come from its owner alone; its second-grain
  // pairs from the ranks in rank order, which is slot order.
  std::string mine;
  for (std::size_t a = 0; a < grains.size(); ++a) {
    put(mine, static_cast<std::uint64_t>(rows[a].size()));
    put_range(mine, rows[a].data(), rows[a].size());
    put(mine, static_cast<std::uint64_t>(in[a].size()));
    put_range(mine, in[a].data(), in[a].size());
  }
  const std::vector<std::string> all = ranks::all_gather(mine);
  std::vector<std::size_t> at(all.size(), 0);
  std::vector<PairLoad> second;
  for (std::size_t a = 0; a < grains.size(); ++a) {
    second.clear();
    for (std::size_t r = 0; r < all.size(); ++r) {
      const auto n_rows = take<std::uint64_t>(all[r], at[r]);
      const std::size_t begin = loads.size();
      loads.resize(begin + n_rows);
      take_range(all[r], at[r], loads.data() + begin, n_rows);
      const auto n_in = take<std::uint64_t>(all[r], at[r]);
      const std::size_t in_begin = second.size();
      second.resize(in_begin + n_in);
      take_range(all[r], at[r], second.data() + in_begin, n_in);
    }
    loads.insert(loads.end(), second.begin(), second.end());
    offsets.push_back(static_cast<std::uint32_t>(loads.size()));
  }
}

BondSets Simulation::whole_bonds() const {
  BondSets out = bonds_;
  const auto whole = [&](auto& set) {
    set.bond_of_pair.clear();
    if (split_) concatenate_elements(set);
  };
  std::apply([&](auto&... set) { (whole(set), ...); }, out);
  return out;
}

Simulation::SampleCounts Simulation::sample_counts() const {
  SampleCounts c{intact_bonds(), active_contacts()};
  if (!split_) return c;
  std::string mine;
  put(mine, c);
  c = {};
  for (const std::string& from :
       ranks::all_gather(mine, std::vector<std::size_t>(split_->ranges.size(), mine.size()))) {
    std::size_t at = 0;
    const auto theirs = take<SampleCounts>(from, at);
    c.intact_bonds += theirs.intact_bonds;
    c.active_contacts += theirs.active_contacts;
  }
  return c;
}

bool Simulation::lead_rank() const noexcept {
  return !split_ || ranks::root();
}

}  // namespace breccia
