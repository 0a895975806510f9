// The stored energies of the energy ledger (docs/physics.md §2.4), sampled every energy_interval
// steps: contacts, bonds by component, joints, kinetic energy, and the balance residual.
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

// Every sum below is grouped by blocks of particles (a bond's or pair's first grain, a wall
// contact's grain), the blocks' partials added in block order (parallel.hpp,
// particle_block_starts); on a split sample each rank fills its own blocks' and the partials are
// made whole first (`ranges`, empty on one rank).
namespace {

template <class T>
T blocks_total(std::vector<T>& partials, const std::vector<IndexRange>& ranges) {
  complete_block_partials(partials, kBlock, ranges);
  return ordered_sum(partials);
}

// The intact bonds' stored energy, by component.
template <class Law>
BondEnergy bond_energy(const BondSet<Law>& s, const Simulation& sim,
                       const std::vector<IndexRange>& ranges) {
  const std::vector<std::size_t> starts =
      particle_block_starts(s.pairs.first, sim.particles().size());
  std::vector<BondEnergy> part(starts.size() - 1);
  for_item_blocks(starts, [&](std::size_t b, std::size_t e, std::size_t blk) {
    BondEnergy acc;
    for (std::size_t k = b; k < e; ++k)
      if (s.intact[k])
        acc +=
            Law::energy(s.params, s.state[k], sim.bond_radii(s.pairs.first[k], s.pairs.second[k]));
    part[blk] = acc;
  });
  return blocks_total(part, ranges);
}

// The particle contacts' stored energy, in pair order (where a state lies in its block's array is
// no part of any result).
template <class CL>
double pair_contact_energy(const ContactSet<CL>& c, std::size_t n,
                           const std::vector<IndexRange>& ranges) {
  std::vector<std::size_t> starts(block_count(n) + 1);
  for (std::size_t b = 0; b < starts.size(); ++b)
    starts[b] = c.pairs.offsets.empty() ? 0 : c.pairs.offsets[std::min(n, b * kBlock)];
  std::vector<double> part(starts.size() - 1);
  for_item_blocks(starts, [&](std::size_t b, std::size_t e, std::size_t blk) {
    double acc = 0.0;
    for (std::size_t k = b; k < e; ++k)
      if (c.history[k] != kNoHistory) acc += CL::stored_energy(c.params, c.state(k));
    part[blk] = acc;
  });
  return blocks_total(part, ranges);
}

// One wall's contacts' stored energy.
template <class CL>
double wall_contact_energy(const WallContacts<CL>& wc, const typename CL::Params& params,
                           std::size_t n, const std::vector<IndexRange>& ranges) {
  const std::vector<std::size_t> at = particle_block_starts(wc.particle, n);
  std::vector<double> part(at.size() - 1);
  for (std::size_t blk = 0; blk + 1 < at.size(); ++blk) {
    double acc = 0.0;
    for (std::size_t k = at[blk]; k < at[blk + 1]; ++k)
      acc += CL::stored_energy(params, wc.state[k]);
    part[blk] = acc;
  }
  return blocks_total(part, ranges);
}

// A joint law's springs: a bonded joint's are bond energy by component, an unbonded joint's are
// contact energy (it replaces a contact).
struct JointEnergy {
  BondEnergy bonded;
  double unbonded = 0.0;
  JointEnergy& operator+=(const JointEnergy& o) noexcept {
    bonded += o.bonded;
    unbonded += o.unbonded;
    return *this;
  }
};
template <class JL>
void add_joint_energy(const BondSet<JL>& s, const Simulation& sim,
                      const std::vector<IndexRange>& ranges, BondEnergy& bond, double& contact) {
  const std::vector<std::size_t> at = particle_block_starts(s.pairs.first, sim.particles().size());
  std::vector<JointEnergy> part(at.size() - 1);
  for (std::size_t blk = 0; blk + 1 < at.size(); ++blk)
    for (std::size_t k = at[blk]; k < at[blk + 1]; ++k) {
      const BondEnergy e =
          JL::energy(s.params, s.state[k], sim.bond_radii(s.pairs.first[k], s.pairs.second[k]));
      if (JL::is_bonded(s.state[k]))
        part[blk].bonded += e;
      else
        part[blk].unbonded += e.total();
    }
  const JointEnergy total = blocks_total(part, ranges);
  bond += total.bonded;
  contact += total.unbonded;
}

}  // namespace

template <class CL>
void Simulation::sample_stored_energy_for(ContactSet<CL>& c) {
  const std::vector<IndexRange>& ranges = rank_ranges();
  BondEnergy bond;
  std::apply([&](const auto&... sets) { ((bond += bond_energy(sets, *this, ranges)), ...); },
             bonds_);
  double contact = pair_contact_energy(c, p_.size(), ranges);
  for (const auto& wc : std::get<std::vector<WallContacts<CL>>>(wall_contacts_))
    contact += wall_contact_energy(wc, c.wall_params, p_.size(), ranges);
  std::apply(
      [&](const auto&... sets) { (add_joint_energy(sets, *this, ranges, bond, contact), ...); },
      joints_);

  EnergyLedger& L = ledger_;
  L.step = step_;
  L.time = time_;
  L.bond = bond;
  L.contact = contact;
  L.boundary_work = w_walls_ + w_drive_;
  L.body_force_work = w_gravity_;
  L.external_work = w_external_ - w_external_boundary_;
  L.joint_dilation = d_pairs_.dilation;
  L.friction = d_pairs_.slip;
  L.joint_slip = d_joint_slip_;
  L.local_damping = d_local_ - d_local_boundary_;
  L.viscous_damping = d_pairs_.viscous;
  L.deleted = d_pairs_.deleted;
  L.released = released_;
  L.broken_bonds = cracks_.size();
  if (!baseline_) baseline_ = L;
  const EnergyLedger& B = *baseline_;
  const double work = L.work_in() - B.work_in();
  const double d_stored = L.stored() - B.stored();
  const double d_dissipated = L.dissipated() - B.dissipated();
  L.residual = work - d_stored - d_dissipated;
  const double scale = std::max({std::abs(work), std::abs(d_stored), std::abs(d_dissipated),
                                 std::numeric_limits<double>::min()});
  L.residual_relative = L.residual / scale;
}

void Simulation::sample_stored_energy() {
  std::visit([&](auto& contacts) { sample_stored_energy_for(contacts); }, contact_);
}

}  // namespace breccia
