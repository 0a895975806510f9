// The pass over wall contacts (docs/physics.md §6.1): forces on the grains in a fixed order,
// the walls' resultants and their work.
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

// Wall contact k's loads on its grain of this step (zero for an open contact without history).
template <class CL>
void load_wall_contact(const Wall& w, const ParticleStore& p, const typename CL::Params& params,
                       double dt, WallContacts<CL>& wc, std::size_t k, PairDissipation& dis) {
  const std::uint32_t i = wc.particle[k];
  const PosRad& q = p.pos_rad[i];
  Vec3 nrm;
  const double gap = w.gap(q.x, q.r, nrm);
  if (gap >= 0.0 && !has_history(wc.state[k].n_old)) {
    wc.force[k] = {};
    wc.torque[k] = {};
    wc.normal_force[k] = 0.0;
    wc.stiffness[k] = 0.0;
    return;
  }
  PairGeometry g;
  g.n = nrm;
  g.delta = -gap;
  g.d = q.r - g.delta;
  g.r2 = nrm * -(q.r - 0.5 * g.delta);
  g.r1 = {};
  g.vc = p.vel[i] + cross(p.angvel[i], g.r2) - w.surface_velocity(nrm);
  g.w1 = {};
  g.w2 = p.angvel[i];
  g.R1 = w.convex_radius(p.planar());
  g.R2 = q.r;
  g.m2 = p.mass[i];
  g.wall = true;
  g.planar = p.planar();
  g.thickness = p.thickness();
  const PairForce pf = CL::compute(params, wc.state[k], g, dt, dis);
  wc.force[k] = pf.force;
  wc.torque[k] = cross(g.r2, pf.force) + pf.couple;
  wc.normal_force[k] = dot(pf.force, nrm);
  double kn = 0.0, ks = 0.0;
  if (g.delta > 0.0) CL::timestep_stiffness(params, g, kn, ks);
  wc.stiffness[k] = kn;
}

}  // namespace

// Each wall's contacts first, their partial sums kept per block of the particles touched
// (parallel.hpp, particle_block_starts); then, wall after wall, the sums in block order, the
// loads on the grains and the wall's work.
template <class CL>
void Simulation::compute_walls_for(ContactSet<CL>& c) {
  auto& wall_sets = std::get<std::vector<WallContacts<CL>>>(wall_contacts_);
  const double dt = dt_;
  const std::size_t nb = block_count(p_.size());
  wall_blocks_.assign(walls_.size() * nb, WallBlock{});
  for (std::size_t wi = 0; wi < walls_.size(); ++wi) {
    const Wall& w = walls_[wi];
    WallContacts<CL>& wc = wall_sets[wi];
    std::vector<std::size_t>& starts = wall_block_starts_;
    particle_block_starts(wc.particle, p_.size(), starts);
    WallBlock* const blocks = wall_blocks_.data() + wi * nb;
    for_item_blocks(starts, [&](std::size_t begin, std::size_t end, std::size_t blk) {
      WallBlock sum;
      for (std::size_t k = begin; k < end; ++k) {
        load_wall_contact(w, p_, c.wall_params, dt, wc, k, sum.dissipation);
        sum.force += wc.force[k];
        sum.radial += wc.normal_force[k];
        sum.touching += wc.normal_force[k] != 0.0 ? 1 : 0;
        sum.stiffness += wc.stiffness[k];
      }
      blocks[blk] = sum;
    });
  }
  if (split_) {
    // One exchange for the step's loads (the pair pass's shares, dissipation and cracks, and the
    // walls' sums), then the pair pass's sums, which come first in one process.
    exchange_step_loads(c.pairs);
    add_pair_dissipation();
  }
  for (std::size_t wi = 0; wi < walls_.size(); ++wi) {
    Wall& w = walls_[wi];
    const WallContacts<CL>& wc = wall_sets[wi];
    const WallBlock* const blocks = wall_blocks_.data() + wi * nb;
    PairDissipation dissipation;
    for (std::size_t blk = 0; blk < nb; ++blk) dissipation += blocks[blk].dissipation;
    d_pairs_ += dissipation;
    for (std::size_t k = 0; k < wc.particle.size(); ++k) {
      const std::uint32_t i = wc.particle[k];
      p_.force[i] += wc.force[k];  // after the pair pass's sum, in wall and particle order
      p_.torque[i] += wc.torque[k];
    }
    WallBlock sum;
    for (std::size_t blk = 0; blk < nb; ++blk) {
      sum.force += blocks[blk].force;
      sum.radial += blocks[blk].radial;
      sum.stiffness += blocks[blk].stiffness;
      sum.touching += blocks[blk].touching;
    }
    // Trapezoidal work over the wall's last displacement (matches the leapfrog kinetic energy):
    // the motion that made it, not the one a servo has set for the next step.
    const double dw = w.shape != WallShape::Cylinder
                          ? 0.5 * dot(w.force_prev + sum.force, w.advanced_velocity) * dt
                          : 0.5 * (w.radial_force_prev + sum.radial) * w.advanced_radial_speed * dt;
    w.work += dw;
    w_walls_ += dw;
    w.force = sum.force;
    w.radial_force = sum.radial;
    w.force_prev = sum.force;
    w.radial_force_prev = sum.radial;
    w.contacts = sum.touching;
    w.contact_stiffness = sum.stiffness;
  }
}

void Simulation::compute_walls() {
  std::visit([&](auto& contacts) { compute_walls_for(contacts); }, contact_);
}

}  // namespace breccia
