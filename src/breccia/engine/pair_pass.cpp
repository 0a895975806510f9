// The pass over interacting pairs: each pair's geometry once, its bonds' and contact's loads summed
// into its two particles' totals (through a cross slot where the second particle belongs to a later
// block), and the bonds that broke turned into crack records in pair order.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>
#include <utility>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/engine/pair_lists.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/law/beam_lanes.hpp"

namespace breccia {

using namespace engine_detail;

namespace {

// No bond of the pair awaits judging.
constexpr std::uint32_t kNoHeldBond = 0xffffffffu;

// A bond law that evaluates four bonds at a time (law/beam_lanes.hpp).
template <class Law>
constexpr bool has_lane_kernel = requires(const typename Law::Params& p,
                                          const beam::LaneBond (&b)[beam::kLanes],
                                          beam::LaneResult (&out)[beam::kLanes]) {
  Law::compute_lanes(p, b, out);
};

// The lane results of one block's walk, reused from step to step (no allocation per step).
thread_local std::vector<beam::LaneResult> lane_results;

}  // namespace

// One particle block's walk over the pairs it owns. The pair in hand is worked through in stages:
// its bonds, its joint, whether it is touching, its contact, the bond judged on the interface
// totals, its loads on the two particles.
// The stages are inlined into the walk, and what a law writes through a reference (the geometry,
// the dissipation) lives outside the object, so that the object itself stays in registers: a
// split into out-of-line stages ran 7-17 % slower on bench_engine's 100k-grain elastic case, and
// this object with the geometry inside it 20 % slower.
template <class CL>
class Simulation::PairWalk {
 public:
  PairWalk(Simulation& sim, ContactSet<CL>& c, std::vector<Failure>& fails, PairGeometry& g,
           PairDissipation& dissipation, PairDissipation& joint_dissipation)
      : sim_(sim),
        c_(c),
        dt_(sim.dt_),
        contact_motion_(contact_needs_motion<CL>(c.params)),
        torques_(!sim.central_forces_only(c)),
        keep_forces_(sim.keep_pair_forces_),
        frames_ahead_(reads_frames(sim)),
        fails_(fails),
        g_(g),
        dissipation_(dissipation),
        joint_dissipation_(joint_dissipation) {}

  // Pairs [begin, end) of the block that owns particles up to owned_end; its cross pairs' loads
  // go to the cross slots from `next_cross` on. Each particle's sum runs in pair order.
  [[gnu::always_inline]] void walk(std::size_t begin, std::size_t end, std::uint32_t owned_end,
                                   std::uint32_t next_cross,
                                   std::vector<typename CL::State>& store) {
    store_ = &store;
    lanes_law_ = kNoHeldBond;
    if (frames_ahead_ && !bond_damped()) evaluate_lanes(begin, end, kBondLaws);
    Vec3* const force = sim_.p_.force.data();
    Vec3* const torque = sim_.p_.torque.data();
    const std::uint32_t* const second = c_.pairs.second.data();
    const PosRad* const pos_rad = sim_.p_.pos_rad.data();
    const Quat* const orientation = frames_ahead_ ? sim_.p_.orientation.data() : nullptr;
    for (std::size_t k = begin; k < end; ++k) {
      // The second grain of a pair a few ahead: its position (and orientation, for the total
      // bonds) is a gather the Morton order leaves to a cache miss as often as not.
      if (k + kAhead < end) {
        const std::uint32_t ahead = second[k + kAhead];
        __builtin_prefetch(pos_rad + ahead);
        if (orientation) __builtin_prefetch(orientation + ahead);
      }
      start(k);
      bond_parts(kBondLaws);
      joint_parts(kJointLaws);
      if (!have_geometry_ && !lane_loaded_ && !touching_or_loaded()) {
        if (keep_forces_) c_.kept_force[k] = {};
        if (j_ >= owned_end) sim_.cross_slots_[next_cross++] = CrossSlot{};
        continue;
      }
      const Vec3 contact_force = contact_part();
      if (held_law_ != kNoHeldBond) judge_held_bond(contact_force, kBondLaws);
      if (keep_forces_) c_.kept_force[k] = force_;
      force[i_] -= force_;
      Vec3 torque2;
      if (torques_) {
        torque[i_] += cross(g_.r1, -force_) - couple_;
        torque2 = cross(g_.r2, force_) + couple_;
      }
      if (j_ < owned_end) {
        force[j_] += force_;
        if (torques_) torque[j_] += torque2;
      } else {
        sim_.cross_slots_[next_cross++] = {force_, torque2};
      }
    }
  }

 private:
  // The laws by their position: a bond's failure names its law by it (joints after the bonds).
  static constexpr auto kBondLaws = std::make_index_sequence<std::tuple_size_v<BondSets>>{};
  static constexpr auto kJointLaws = std::make_index_sequence<std::tuple_size_v<JointSets>>{};
  static constexpr std::uint32_t kFirstJointLaw = std::tuple_size_v<BondSets>;
  // How many pairs ahead the second grain's data is prefetched: about one pair's work (a few
  // hundred cycles for a bonded pair) covers a miss to the last-level cache.
  static constexpr std::size_t kAhead = 4;

  // Whether the run reads 3D orientations in the pair pass: a bond set of a total law holds bonds.
  static bool reads_frames(const Simulation& sim) {
    if (sim.p_.planar() || sim.p_.orientation.empty()) return false;
    return std::apply(
        []<class... L>(const BondSet<L>&... set) {
          return ((L::needs_frames && set.size() > 0) || ...);
        },
        sim.bonds_);
  }

  // Unrolled over the laws without a lambda: GCC left the fold's lambda out of line, and the
  // walk's state then went through memory.
  template <std::size_t... L>
  [[gnu::always_inline]] void bond_parts(std::index_sequence<L...>) {
    (bond_part<L>(std::get<L>(sim_.bonds_)), ...);
  }
  template <std::size_t... L>
  [[gnu::always_inline]] void joint_parts(std::index_sequence<L...>) {
    (joint_part<kFirstJointLaw + L>(std::get<L>(sim_.joints_)), ...);
  }
  template <std::size_t... L>
  [[gnu::always_inline]] void judge_held_bond(const Vec3& contact_force,
                                              std::index_sequence<L...>) {
    (judge_held<L>(std::get<L>(sim_.bonds_), contact_force), ...);
  }

  [[gnu::always_inline]] void start(std::size_t k) {
    k_ = k;
    i_ = c_.pairs.first[k];
    j_ = c_.pairs.second[k];
    have_geometry_ = have_motion_ = contact_off_ = lane_loaded_ = false;
    force_ = couple_ = Vec3{};
    held_law_ = kNoHeldBond;
  }

  // The shape first; the motion when a law reads it.
  [[gnu::always_inline]] void need(bool motion) {
    if (!have_geometry_) {
      g_ = motion ? sim_.geometry(i_, j_) : sim_.shape(i_, j_);
    } else if (motion && !have_motion_) {
      sim_.add_motion(g_, i_, j_);
    }
    have_geometry_ = true;
    have_motion_ = have_motion_ || motion;
  }

  template <std::uint32_t LawIndex, class Law>
  [[gnu::always_inline]] void bond_part(BondSet<Law>& set) {
    // A run uses one bond law: the others' sets are empty, and keep no index.
    const std::uint32_t b = set.bond_at_pair(k_);
    if (b != BondSet<Law>::kNoBond && set.intact[b]) {
      if constexpr (has_lane_kernel<Law>) {
        if (lanes_law_ == LawIndex) {
          const beam::LaneResult& r = lane_results[lane_next_++];
          if (r.stands) {
            // Evaluated with the block's other bonds before the walk (evaluate_lanes): the
            // law's loads, and the lever arms of the pair's shape. A contact in parallel reads
            // the whole shape, so it is computed as compute() would have (the same numbers).
            force_ += r.force;
            couple_ += r.couple;
            if (Law::contact_while_bonded(set.params)) {
              need(law_needs_motion<Law>);
            } else {
              g_.r1 = r.r1;
              g_.r2 = r.r2;
              lane_loaded_ = true;
              contact_off_ = true;
            }
            return;
          }
        }
      }
      need(law_needs_motion<Law> || bond_damped());
      if constexpr (judged_on_interface<Law>) {
        // Judged on the interface totals (§4.4): it waits for the pair's contact force.
        held_ = Law::loads(set.state[b], g_, dt_);
        held_law_ = LawIndex;
        held_bond_ = b;
      } else {
        BondFailure f;
        PairForce pf;
        if constexpr (law_dissipates<Law>)
          pf = Law::compute(set.params, set.state[b], g_, sim_.frames<Law>(i_, j_), dt_,
                            dissipation_, f);
        else
          pf = Law::compute(set.params, set.state[b], g_, sim_.frames<Law>(i_, j_), dt_, f);
        if (f.broken) fails_.push_back({LawIndex, b, f});
        // A broken element leaves its bond in place (the flat joint): its force is applied.
        if (!f.broken || f.outcome == BondOutcome::ElementBroken) {
          force_ += pf.force;
          couple_ += pf.couple;
          if (bond_damped()) force_ += bond_dashpot<Law>(set.params, set.state[b]);
          contact_off_ = contact_off_ || !Law::contact_while_bonded(set.params);
        }
      }
    }
  }

  // Before the walk: the intact bonds of the block's pairs, in pair order, four at a time through
  // the lane kernel of the first law that has one and holds bonds. The walk takes the results in
  // the same order (and needs no shape for them where the law's contact is off between bonded
  // grains); a bond whose result does not stand goes through the law's compute().
  // Always inlined, with lanes_for and the laws' compute_lanes: GCC's flatten leaves them out of
  // the walk's x86-64-v3 copy otherwise (core/instruction_set.hpp), and there they are most of it.
  template <std::size_t... L>
  [[gnu::always_inline]] void evaluate_lanes(std::size_t begin, std::size_t end,
                                             std::index_sequence<L...>) {
    (void)((lanes_for<static_cast<std::uint32_t>(L)>(std::get<L>(sim_.bonds_), begin, end)) || ...);
  }
  template <std::uint32_t LawIndex, class Law>
  [[gnu::always_inline]] bool lanes_for(BondSet<Law>& set, std::size_t begin, std::size_t end) {
    if constexpr (!has_lane_kernel<Law>) {
      return false;
    } else {
      if (set.size() == 0 || set.params.run.planar) return false;
      lanes_law_ = LawIndex;
      lane_next_ = 0;
      lane_results.clear();
      const PosRad* const pos_rad = sim_.p_.pos_rad.data();
      const Quat* const orientation = sim_.p_.orientation.data();
      beam::LaneBond bonds[beam::kLanes];
      beam::LaneResult out[beam::kLanes];
      int filled = 0;
      for (std::size_t k = begin; k < end; ++k) {
        const std::uint32_t b = set.bond_at_pair(k);
        if (b == BondSet<Law>::kNoBond || !set.intact[b]) continue;
        const std::uint32_t i = c_.pairs.first[k], j = c_.pairs.second[k];
        bonds[filled++] = {pos_rad[i].x,   pos_rad[j].x,   pos_rad[i].r, pos_rad[j].r,
                           orientation[i], orientation[j], &set.state[b]};
        if (filled == beam::kLanes) {
          Law::compute_lanes(set.params, bonds, out);
          lane_results.insert(lane_results.end(), out, out + beam::kLanes);
          filled = 0;
        }
      }
      if (filled > 0) {
        // The empty lanes repeat the first bond on a copy of its state.
        typename Law::State spare = *bonds[0].state;
        for (int l = filled; l < beam::kLanes; ++l) {
          bonds[l] = bonds[0];
          bonds[l].state = &spare;
        }
        Law::compute_lanes(set.params, bonds, out);
        lane_results.insert(lane_results.end(), out, out + filled);
      }
      return true;
    }
  }

  // Whether intact bonds carry dashpots (read where used: the walk's own members stay few).
  [[gnu::always_inline]] bool bond_damped() const {
    return sim_.cfg_.bond_normal_damping_ratio > 0.0 || sim_.cfg_.bond_shear_damping_ratio > 0.0;
  }

  // The dashpots in parallel with an intact bond (docs/physics.md §2.2): c = 2 beta sqrt(m* k) on
  // the bond's normal and shear stiffness, against the relative velocity of the contact point. A
  // bond carries tension, so no no-tension rule; the loss is booked as viscous.
  template <class Law>
  [[gnu::always_inline]] Vec3 bond_dashpot(const typename Law::Params& p,
                                           const typename Law::State& s) {
    const double m = g_.m_star();
    const double cn = 2.0 * sim_.cfg_.bond_normal_damping_ratio *
                      std::sqrt(m * Law::normal_stiffness(p, s, radii_of(g_)));
    const double cs = 2.0 * sim_.cfg_.bond_shear_damping_ratio *
                      std::sqrt(m * Law::shear_stiffness(p, s, radii_of(g_)));
    const double vn = g_.vn();
    const Vec3 vt = g_.vc - g_.n * vn;
    dissipation_.viscous += (cn * vn * vn + cs * norm2(vt)) * dt_;
    return g_.n * (-cn * vn) - vt * cs;
  }

  // A joint replaces the pair's contact law (docs/physics.md §5); a bonded joint that breaks goes
  // on unbonded, so its force of the step is applied.
  template <std::uint32_t LawIndex, class JL>
  [[gnu::always_inline]] void joint_part(BondSet<JL>& set) {
    // Most samples have no joints: no load of the pair's index then.
    const std::uint32_t b = set.bond_at_pair(k_);
    if (b != BondSet<JL>::kNoBond) {
      need(law_needs_motion<JL>);
      contact_off_ = true;
      BondFailure f;
      const PairForce pf = JL::compute(set.params, set.state[b], g_, dt_, joint_dissipation_, f);
      if (f.broken) fails_.push_back({LawIndex, b, f});
      force_ += pf.force;
      couple_ += pf.couple;
    }
  }

  // An unbonded pair takes part when its grains overlap or its contact still holds history; the
  // test reads the two positions, and the pair's history only when it has touched since the
  // last rebuild.
  [[gnu::always_inline]] bool touching_or_loaded() {
    const PosRad& a = sim_.p_.pos_rad[i_];
    const PosRad& b = sim_.p_.pos_rad[j_];
    const double reach = a.r + b.r;
    if (norm2(b.x - a.x) >= reach * reach && !loaded()) return false;
    need(contact_motion_);
    return true;
  }

  [[gnu::always_inline]] bool loaded() const {
    const std::uint32_t h = c_.history[k_];
    return h != kNoHistory && has_history((*store_)[h].n_old);
  }

  // The contact's force, summed into the pair's (zero when the contact is off or open). A pair's
  // first touch since the last rebuild appends its history entry to the block's store.
  [[gnu::always_inline]] Vec3 contact_part() {
    std::uint32_t& h = c_.history[k_];
    const bool was_loaded = loaded();
    if (contact_off_ && was_loaded) {
      // Bonded under load with a law that excludes the contact: its spring energy is lost
      // without work (§4.0, D_del) and the contact starts afresh when the bond breaks.
      dissipation_.deleted += CL::stored_energy(c_.params, (*store_)[h]);
      (*store_)[h] = {};
    }
    if (contact_off_ || !(g_.delta > 0.0 || was_loaded)) return {};
    need(contact_motion_);
    if (h == kNoHistory) {
      h = static_cast<std::uint32_t>(store_->size());
      store_->emplace_back();
    }
    const PairForce pf = CL::compute(c_.params, (*store_)[h], g_, dt_, dissipation_);
    force_ += pf.force;
    couple_ += pf.couple;
    return pf.force;
  }

  template <std::uint32_t LawIndex, class Law>
  [[gnu::always_inline]] void judge_held(BondSet<Law>& set, const Vec3& contact_force) {
    if constexpr (judged_on_interface<Law>) {
      if (LawIndex != held_law_) return;
      BondFailure f;
      Law::judge(set.params, set.state[held_bond_], g_, contact_force, f);
      if (f.broken) {
        fails_.push_back({held_law_, held_bond_, f});
      } else {
        force_ += held_.force;
        couple_ += held_.couple;
        if (bond_damped()) force_ += bond_dashpot<Law>(set.params, set.state[held_bond_]);
      }
    }
  }

  Simulation& sim_;
  ContactSet<CL>& c_;
  const double dt_;
  const bool contact_motion_;  // whether the contact law reads the pair's velocities
  const bool torques_;         // false with central forces only (no torque but rounding)
  const bool keep_forces_;     // each pair's force goes to c_.kept_force (pair_force)
  const bool frames_ahead_;    // prefetch the second grain's orientation
  std::vector<Failure>& fails_;
  std::vector<typename CL::State>* store_ = nullptr;  // the block's contact histories
  PairGeometry& g_;                                   // the pair in hand's
  PairDissipation &dissipation_, &joint_dissipation_;
  // The pair in hand.
  std::size_t k_ = 0;
  std::uint32_t i_ = 0, j_ = 0;
  bool have_geometry_ = false, have_motion_ = false;
  bool contact_off_ = false;  // an intact bond whose law excludes the contact (§4.0)
  bool lane_loaded_ = false;  // a bond's loads came from the lanes (no shape in g_)
  // The law whose bonds went through the lanes before the walk, and the next result.
  std::uint32_t lanes_law_ = kNoHeldBond;
  std::size_t lane_next_ = 0;
  Vec3 force_, couple_;
  PairForce held_;
  std::uint32_t held_law_ = kNoHeldBond, held_bond_ = 0;
};

// One pass over all interacting pairs: the bond(s) of the pair, then its contact, summed into the
// two particles' totals. Each pair's geometry is computed once; bonded pairs that overlap get the
// contact force in parallel (docs/physics.md §4.0). The blocks are blocks of particles (a block
// owns the pairs of its particles as first), fixed by the particle count; breaks are collected
// per block and processed in pair order.
template <class CL>
void Simulation::compute_pairs_for(ContactSet<CL>& c) {
  const std::size_t n = p_.size();
  const std::size_t nb = (n + kParticleBlock - 1) / kParticleBlock;
  const IndexRange own = owned_blocks(owned_particles(), kParticleBlock);
  block_dis_.assign(nb, PairDissipation{});
  block_joint_dis_.assign(nb, PairDissipation{});
  if (block_failures_.size() < nb) block_failures_.resize(nb);
  cross_slots_.resize(c.pairs.cross_slots());
  // A split sample keeps the whole sample's decision of its last rebuild (the sets change there
  // only); one process decides each step.
  if (!split_) keep_pair_forces_ = pair_forces_needed(c);
  if (!keep_pair_forces_)
    std::vector<Vec3>().swap(c.kept_force);
  else if (c.kept_force.size() != c.pairs.size())
    c.kept_force.assign(c.pairs.size(), Vec3{});
  for_each_item(own.size(), [&](std::size_t k) {
    with_instruction_set(isa_, [&] { compute_pair_block(c, own.begin + k); });
  });
  process_failures(own.begin, own.end);
  // A split sample adds the sums once the wall pass has exchanged the partials.
  if (!split_) add_pair_dissipation();
}

// One particle block's pairs: its particles' loads zeroed, its walk, its contact states put back in
// pair order where new ones piled up.
template <class CL>
void Simulation::compute_pair_block(ContactSet<CL>& c, std::size_t blk) {
  const std::size_t n = p_.size();
  const std::size_t begin = blk * kParticleBlock, end = std::min(n, begin + kParticleBlock);
  std::fill(p_.force.begin() + static_cast<std::ptrdiff_t>(begin),
            p_.force.begin() + static_cast<std::ptrdiff_t>(end), Vec3{});
  std::fill(p_.torque.begin() + static_cast<std::ptrdiff_t>(begin),
            p_.torque.begin() + static_cast<std::ptrdiff_t>(end), Vec3{});
  block_failures_[blk].clear();
  PairGeometry g;
  PairDissipation dis, joint_dis;
  PairWalk<CL>(*this, c, block_failures_[blk], g, dis, joint_dis)
      .walk(c.pairs.offsets[begin], c.pairs.offsets[end], static_cast<std::uint32_t>(end),
            c.pairs.cross_begin[blk], c.stores[blk]);
  // New contacts append: once an eighth of the block's states came since it was last in pair
  // order, it is put back in order.
  std::vector<typename CL::State>& store = c.stores[blk];
  if (store.size() > c.packed[blk] + c.packed[blk] / 8 + 32) {
    repack_history(c.pairs.offsets[begin], c.pairs.offsets[end], c.history, store);
    c.packed[blk] = static_cast<std::uint32_t>(store.size());
  }
  block_dis_[blk] = dis;
  block_joint_dis_[blk] = joint_dis;
}

void Simulation::add_pair_dissipation() {
  d_pairs_ += ordered_sum(block_dis_);
  const PairDissipation joint_dis = ordered_sum(block_joint_dis_);
  d_pairs_ += joint_dis;
  d_joint_slip_ += joint_dis.slip;
}

// Breaks are processed as one batch in pair order (independent of the thread count).
void Simulation::process_failures(std::size_t first_block, std::size_t last_block) {
  for (std::size_t blk = first_block; blk < last_block; ++blk)
    for (const Failure& f : block_failures_[blk]) {
      std::uint32_t law_index = 0;
      std::apply(
          [&](auto&... set) {
            ((law_index++ == f.law ? process_failure(set, f.bond, f.info) : void()), ...);
          },
          bonds_);
      std::apply(
          [&](auto&... set) {
            ((law_index++ == f.law ? record_crack(set, f.bond, f.info) : void()), ...);
          },
          joints_);
    }
}

void Simulation::compute_pairs() {
  std::visit([&](auto& contacts) { compute_pairs_for(contacts); }, contact_);
}

template <class Law>
void Simulation::process_failure(BondSet<Law>& set, std::uint32_t bond, const BondFailure& info) {
  if (info.outcome != BondOutcome::ElementBroken) {
    set.intact[bond] = 0;
    ++set.broken_since_compaction;
  }
  if (info.outcome != BondOutcome::Released) record_crack(set, bond, info);
}

template <class Law>
void Simulation::record_crack(const BondSet<Law>& set, std::uint32_t bond,
                              const BondFailure& info) {
  const std::uint32_t i = set.pairs.first[bond], j = set.pairs.second[bond];
  const PairGeometry g = geometry(i, j);
  // The record names the pair by increasing tag with the normal from the first to the second
  // (§4.0); F_n, |F_s|, M_t = M . n and |M_b| do not depend on the orientation.
  const bool swap = p_.tag[i] > p_.tag[j];
  CrackRecord r;
  r.step = step_;
  r.time = time_;
  r.law = Law::name;
  r.bond_tag = set.tag[bond];
  r.id1 = p_.tag[swap ? j : i];
  r.id2 = p_.tag[swap ? i : j];
  r.R1 = swap ? g.R2 : g.R1;
  r.R2 = swap ? g.R1 : g.R2;
  r.position = p_.pos_rad[i].x + g.r1 + g.n * info.point_shift + info.point_offset;
  r.normal = swap ? -g.n : g.n;
  r.mode = info.mode;
  r.bond_radius = info.bond_radius;
  r.Fn = info.Fn;
  r.Fs = info.Fs;
  r.Mt = info.Mt;
  r.Mb = info.Mb;
  r.sigma = info.sigma;
  r.tau = info.tau;
  r.ratio_t = info.ratio_t;
  r.ratio_s = info.ratio_s;
  r.energy = info.energy;
  if (split_) {
    // Shared in pair order with the other ranks' (exchange_step_loads).
    split_->cracks.push_back(r);
    return;
  }
  released_ += info.energy;
  cracks_.push_back(r);
}

}  // namespace breccia
