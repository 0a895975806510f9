// The pass over interacting pairs: each pair's geometry once, its bonds' and contact's loads
// summed into the pair's slot, and the bonds that broke turned into crack records in pair order.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/engine/pair_lists.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

using namespace engine_detail;

namespace {

constexpr std::uint32_t kNoHeldBond = 0xffffffffu;  // no bond of the pair awaits judging

}  // namespace

// One pass over all interacting pairs: the bond(s) of the pair, then its contact, summed into one
// slot. Each pair's geometry is computed once; bonded pairs that overlap get the contact force in
// parallel (docs/physics.md §4.0). Breaks are collected per block and processed in pair order.
// It stays one function: split into member stages (bonds, joints, contact, the held bond) it ran
// 7-17 % slower on bench_engine's 100k-grain elastic case, whatever was inlined.
template <class CL>
void Simulation::compute_pairs_for(ContactSet<CL>& c) {
  const std::size_t n = c.pairs.size();
  const std::size_t nb = block_count(n);
  block_dis_.assign(nb, PairDissipation{});
  block_joint_dis_.assign(nb, PairDissipation{});
  if (block_failures_.size() < nb) block_failures_.resize(nb);
  const double dt = dt_;
  for_blocks(n, [&](std::size_t begin, std::size_t end, std::size_t blk) {
    PairDissipation dis, joint_dis;
    auto& fails = block_failures_[blk];
    fails.clear();
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t i = c.pairs.first[k], j = c.pairs.second[k];
      PairGeometry g;
      bool have_geometry = false, have_motion = false;
      // The shape first; the motion when a law reads it.
      auto need = [&](bool motion) {
        if (!have_geometry) {
          g = motion ? geometry(i, j) : shape(i, j);
        } else if (motion && !have_motion) {
          add_motion(g, i, j);
        }
        have_geometry = true;
        have_motion = have_motion || motion;
      };
      Vec3 force, couple;
      std::uint32_t law_index = 0;
      bool contact_off = false;  // an intact bond whose law excludes the contact (§4.0)
      // A bond judged on the interface totals (§4.4) waits for its pair's contact force.
      PairForce held;
      std::uint32_t held_law = kNoHeldBond, held_bond = 0;
      auto bond_part = [&]<class Law>(BondSet<Law>& set) {
        // A run uses one bond law: the others' sets are empty, and their index is not read.
        const std::uint32_t b = set.size() == 0 ? BondSet<Law>::kNoBond : set.bond_of_pair[k];
        if (b != BondSet<Law>::kNoBond && set.intact[b]) {
          need(law_needs_motion<Law>);
          if constexpr (judged_on_interface<Law>) {
            held = Law::loads(set.state[b], g, dt);
            held_law = law_index;
            held_bond = b;
            ++law_index;
            return;
          }
          BondFailure f;
          const PairForce pf = Law::compute(set.params, set.state[b], g, frames<Law>(i, j), dt, f);
          if (f.broken) {
            fails.push_back({law_index, b, f});
          } else {
            force += pf.force;
            couple += pf.couple;
            contact_off = contact_off || !Law::contact_while_bonded(set.params);
          }
        }
        ++law_index;
      };
      std::apply([&](auto&... set) { (bond_part(set), ...); }, bonds_);
      // A joint replaces the pair's contact law (docs/physics.md §5); a bonded joint that breaks
      // goes on unbonded, so its force of the step is applied.
      auto joint_part = [&]<class JL>(BondSet<JL>& set) {
        // Most samples have no joints: no load of the pair's index then.
        const std::uint32_t b = set.size() == 0 ? BondSet<JL>::kNoBond : set.bond_of_pair[k];
        if (b != BondSet<JL>::kNoBond) {
          need(law_needs_motion<JL>);
          contact_off = true;
          BondFailure f;
          const PairForce pf = JL::compute(set.params, set.state[b], g, dt, joint_dis, f);
          if (f.broken) fails.push_back({law_index, b, f});
          force += pf.force;
          couple += pf.couple;
        }
        ++law_index;
      };
      std::apply([&](auto&... set) { (joint_part(set), ...); }, joints_);
      if (!have_geometry) {
        const PosRad& a = p_.pos_rad[i];
        const PosRad& b = p_.pos_rad[j];
        const double reach = a.r + b.r;
        if (norm2(b.x - a.x) < reach * reach || has_history(c.state[k].n_old)) need(true);
      }
      PairSlot& s = c.slot[k];
      if (!have_geometry) {
        s = PairSlot{};
        continue;
      }
      if (contact_off && has_history(c.state[k].n_old)) {
        // Bonded under load with a law that excludes the contact: its spring energy is lost
        // without work (§4.0, D_del) and the contact starts afresh when the bond breaks.
        dis.deleted += CL::stored_energy(c.params, c.state[k]);
        c.state[k] = {};
      }
      Vec3 contact_force;
      if (!contact_off && (g.delta > 0.0 || has_history(c.state[k].n_old))) {
        need(true);
        const PairForce pf = CL::compute(c.params, c.state[k], g, dt, dis);
        force += pf.force;
        couple += pf.couple;
        contact_force = pf.force;
      }
      if (held_law != kNoHeldBond) {
        std::uint32_t li = 0;
        auto judge = [&]<class Law>(BondSet<Law>& set) {
          if constexpr (judged_on_interface<Law>) {
            if (li == held_law) {
              BondFailure f;
              Law::judge(set.params, set.state[held_bond], g, contact_force, f);
              if (f.broken) {
                fails.push_back({held_law, held_bond, f});
              } else {
                force += held.force;
                couple += held.couple;
              }
            }
          }
          ++li;
        };
        std::apply([&](auto&... set) { (judge(set), ...); }, bonds_);
      }
      s.force = force;
      s.torque1 = cross(g.r1, -force) - couple;
      s.torque2 = cross(g.r2, force) + couple;
    }
    block_dis_[blk] = dis;
    block_joint_dis_[blk] = joint_dis;
  });
  d_pairs_ += ordered_sum(block_dis_);
  const PairDissipation joint_dis = ordered_sum(block_joint_dis_);
  d_pairs_ += joint_dis;
  d_joint_slip_ += joint_dis.slip;
  // Breaks are processed as one batch in pair order (independent of the thread count).
  for (std::size_t blk = 0; blk < nb; ++blk)
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
  set.intact[bond] = 0;
  ++set.broken_since_compaction;
  record_crack(set, bond, info);
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
  r.position = p_.pos_rad[i].x + g.r1 + g.n * info.point_shift;
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
  released_ += info.energy;
  cracks_.push_back(r);
}

}  // namespace breccia
