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

// A wall's resultant over its contacts: force, normal force, touching contacts and stiffness.
struct WallResultant {
  Vec3 force;
  double radial = 0.0, stiffness = 0.0;
  std::size_t touching = 0;
  WallResultant& operator+=(const WallResultant& o) noexcept {
    force += o.force;
    radial += o.radial;
    stiffness += o.stiffness;
    touching += o.touching;
    return *this;
  }
};

// The resultant summed per block of the particles touched, then in block order.
template <class Contacts>
WallResultant wall_resultant(const Contacts& wc, const std::vector<std::size_t>& starts) {
  WallResultant total;
  for (std::size_t blk = 0; blk + 1 < starts.size(); ++blk) {
    WallResultant block;
    for (std::size_t k = starts[blk]; k < starts[blk + 1]; ++k) {
      block.force += wc.force[k];
      block.radial += wc.normal_force[k];
      block.touching += wc.normal_force[k] != 0.0 ? 1 : 0;
      block.stiffness += wc.stiffness[k];
    }
    total += block;
  }
  return total;
}

}  // namespace

template <class CL>
void Simulation::compute_walls_for(ContactSet<CL>& c) {
  auto& wall_sets = std::get<std::vector<WallContacts<CL>>>(wall_contacts_);
  const double dt = dt_;
  for (std::size_t wi = 0; wi < walls_.size(); ++wi) {
    Wall& w = walls_[wi];
    WallContacts<CL>& wc = wall_sets[wi];
    const std::size_t n = wc.particle.size();
    // Grouped by blocks of the particles they touch (parallel.hpp, particle_block_starts).
    std::vector<std::size_t>& starts = wall_block_starts_;
    particle_block_starts(wc.particle, p_.size(), starts);
    const std::size_t nb = starts.size() - 1;
    block_dis_.assign(nb, PairDissipation{});
    for_item_blocks(starts, [&](std::size_t begin, std::size_t end, std::size_t blk) {
      PairDissipation dis;
      for (std::size_t k = begin; k < end; ++k) {
        const std::uint32_t i = wc.particle[k];
        const PosRad& q = p_.pos_rad[i];
        Vec3 nrm;
        const double gap = w.gap(q.x, q.r, nrm);
        if (gap >= 0.0 && !has_history(wc.state[k].n_old)) {
          wc.force[k] = {};
          wc.torque[k] = {};
          wc.normal_force[k] = 0.0;
          wc.stiffness[k] = 0.0;
          continue;
        }
        PairGeometry g;
        g.n = nrm;
        g.delta = -gap;
        g.d = q.r - g.delta;
        g.r2 = nrm * -(q.r - 0.5 * g.delta);
        g.r1 = {};
        g.vc = p_.vel[i] + cross(p_.angvel[i], g.r2) - w.surface_velocity(nrm);
        g.w1 = {};
        g.w2 = p_.angvel[i];
        g.R1 = w.convex_radius(p_.planar());
        g.R2 = q.r;
        g.m2 = p_.mass[i];
        g.wall = true;
        g.planar = p_.planar();
        g.thickness = p_.thickness();
        const PairForce pf = CL::compute(c.wall_params, wc.state[k], g, dt, dis);
        wc.force[k] = pf.force;
        wc.torque[k] = cross(g.r2, pf.force) + pf.couple;
        wc.normal_force[k] = dot(pf.force, nrm);
        double kn = 0.0, ks = 0.0;
        if (g.delta > 0.0) CL::timestep_stiffness(c.wall_params, g, kn, ks);
        wc.stiffness[k] = kn;
      }
      block_dis_[blk] = dis;
    });
    d_pairs_ += ordered_sum(block_dis_);
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t i = wc.particle[k];
      p_.force[i] += wc.force[k];  // after the pair pass's sum, in wall and particle order
      p_.torque[i] += wc.torque[k];
    }
    const WallResultant sum = wall_resultant(wc, starts);
    const Vec3 total = sum.force;
    const double radial = sum.radial;
    // Trapezoidal work over the wall's last displacement (matches the leapfrog kinetic energy):
    // the motion that made it, not the one a servo has set for the next step.
    const double dw = w.shape != WallShape::Cylinder
                          ? 0.5 * dot(w.force_prev + total, w.advanced_velocity) * dt
                          : 0.5 * (w.radial_force_prev + radial) * w.advanced_radial_speed * dt;
    w.work += dw;
    w_walls_ += dw;
    w.force = total;
    w.radial_force = radial;
    w.force_prev = total;
    w.radial_force_prev = radial;
    w.contacts = sum.touching;
    w.contact_stiffness = sum.stiffness;
  }
}

void Simulation::compute_walls() {
  std::visit([&](auto& contacts) { compute_walls_for(contacts); }, contact_);
}

}  // namespace breccia
