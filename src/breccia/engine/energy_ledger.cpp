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

template <class CL>
void Simulation::sample_stored_energy_for(ContactSet<CL>& c) {
  BondEnergy bond;
  std::apply(
      [&](auto&... sets) {
        auto one = [&]<class Law>(BondSet<Law>& s) {
          std::vector<BondEnergy> part(block_count(s.size()));
          for_blocks(s.size(), [&](std::size_t b, std::size_t e, std::size_t blk) {
            BondEnergy acc;
            for (std::size_t k = b; k < e; ++k)
              if (s.intact[k])
                acc += Law::energy(s.params, s.state[k],
                                   bond_radii(s.pairs.first[k], s.pairs.second[k]));
            part[blk] = acc;
          });
          bond += ordered_sum(part);
        };
        (one(sets), ...);
      },
      bonds_);
  // In pair order (where a state lies in its block's array is no part of any result).
  std::vector<double> part(block_count(c.pairs.size()));
  for_blocks(c.pairs.size(), [&](std::size_t b, std::size_t e, std::size_t blk) {
    double acc = 0.0;
    for (std::size_t k = b; k < e; ++k)
      if (c.history[k] != kNoHistory) acc += CL::stored_energy(c.params, c.state(k));
    part[blk] = acc;
  });
  double contact = ordered_sum(part);
  for (const auto& wc : std::get<std::vector<WallContacts<CL>>>(wall_contacts_))
    for (const auto& st : wc.state) contact += CL::stored_energy(c.wall_params, st);
  // Joints: a bonded joint's springs are bond energy by component, an unbonded joint's are
  // contact energy (it replaces a contact).
  std::apply(
      [&](auto&... sets) {
        auto one = [&]<class JL>(BondSet<JL>& s) {
          for (std::size_t k = 0; k < s.size(); ++k) {
            const BondEnergy e =
                JL::energy(s.params, s.state[k], bond_radii(s.pairs.first[k], s.pairs.second[k]));
            if (JL::is_bonded(s.state[k]))
              bond += e;
            else
              contact += e.total();
          }
        };
        (one(sets), ...);
      },
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
