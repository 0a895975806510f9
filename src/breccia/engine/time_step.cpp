// The critical time step (docs/physics.md §1.5): per-particle translational and rotational
// estimates from every stiffness that can act on the particle, times the safety factor.
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

// Bonds and joints (§1.5, §5): translational max(K_n, K_s); rotational max(K_b, K_t) + K_s |r|^2
// (a joint has no couple: its max_moment_stiffness is 0).
void Simulation::add_bond_stiffness(std::vector<double>& k_tr, std::vector<double>& k_rot) {
  auto add_set = [&]<class Law>(BondSet<Law>& s) {
    for (std::size_t k = 0; k < s.size(); ++k) {
      const auto i = s.pairs.first[k], j = s.pairs.second[k];
      const PairGeometry g = geometry(i, j);
      const auto& st = s.state[k];
      const BondRadii r = radii_of(g);
      const double kt = Law::max_stiffness(s.params, st, r);
      const double ks = Law::shear_stiffness(s.params, st, r);
      const double km = Law::max_moment_stiffness(s.params, st, r);
      k_tr[i] += kt;
      k_tr[j] += kt;
      k_rot[i] += km + ks * norm2(g.r1);
      k_rot[j] += km + ks * norm2(g.r2);
    }
  };
  std::apply([&](auto&... sets) { (add_set(sets), ...); }, bonds_);
  std::apply([&](auto&... sets) { (add_set(sets), ...); }, joints_);
}

// Contacts: every neighbour pair that touches or nearly touches (gap < 0.1 R_min) may carry a
// contact during loading; so does a particle near a wall. Each particle also gets at least one
// contact of its own size, so that free particles have a finite estimate.
double Simulation::add_contact_stiffness(std::vector<double>& k_tr, std::vector<double>& k_rot) {
  double dt_rayleigh = std::numeric_limits<double>::infinity();
  std::visit(
      [&]<class CL>(ContactSet<CL>& c) {
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const auto i = c.pairs.first[k], j = c.pairs.second[k];
          const PairGeometry g = geometry(i, j);
          if (-g.delta > 0.1 * std::min(g.R1, g.R2)) continue;
          double kn = 0.0, ks = 0.0;
          CL::timestep_stiffness(c.params, g, kn, ks);
          k_tr[i] += std::max(kn, ks);
          k_tr[j] += std::max(kn, ks);
          k_rot[i] += ks * g.R1 * g.R1;
          k_rot[j] += ks * g.R2 * g.R2;
        }
        for (std::size_t i = 0; i < p_.size(); ++i) {
          const PosRad& q = p_.pos_rad[i];
          PairGeometry g = pair_geometry({}, q.r, {2.0 * q.r, 0, 0}, q.r, {}, {}, {}, {}, 1, 1,
                                         p_.planar(), p_.thickness());
          double kn = 0.0, ks = 0.0;
          CL::timestep_stiffness(c.params, g, kn, ks);
          k_tr[i] += std::max(kn, ks);
          k_rot[i] += ks * q.r * q.r;
          for (const Wall& w : walls_) {
            Vec3 nrm;
            const double gap = w.gap(q.x, q.r, nrm);
            if (gap > 0.1 * q.r) continue;
            PairGeometry gw = g;
            gw.wall = true;
            gw.R1 = w.convex_radius(p_.planar());
            gw.delta = std::max(-gap, 0.0);
            CL::timestep_stiffness(c.wall_params, gw, kn, ks);
            k_tr[i] += std::max(kn, ks);
            k_rot[i] += ks * q.r * q.r;
          }
          if constexpr (requires { CL::rayleigh_time_step(c.params, 1.0, 1.0); })
            dt_rayleigh =
                std::min(dt_rayleigh, cfg_.hertz_rayleigh_factor *
                                          CL::rayleigh_time_step(c.params, q.r, p_.density[i]));
        }
      },
      contact_);
  return dt_rayleigh;
}

// The configured step, or the critical one times the safety factor (at most the Rayleigh
// bound); a configured step above that is kept with a warning.
void Simulation::adopt_time_step(double crit, double dt_rayleigh) {
  dt_crit_ = crit;
  const double recommended = std::min(cfg_.safety_factor * crit, dt_rayleigh);
  if (!std::isfinite(recommended) || !(recommended > 0.0))
    throw InputError("time step", "estimate", num(recommended),
                     "could not estimate a stable time step: check stiffnesses and masses");
  if (cfg_.time_step > 0.0) {
    dt_ = cfg_.time_step;
    if (dt_ > recommended)
      warnings_.push_back("time_step " + num(dt_) + " s is above the stable estimate " +
                          num(recommended) + " s (critical " + num(crit) +
                          " s times safety factor); the run may blow up");
  } else {
    dt_ = recommended;
  }
}

void Simulation::estimate_time_step() {
  const std::size_t n = p_.size();
  std::vector<double> k_tr(n, 0.0), k_rot(n, 0.0);
  add_bond_stiffness(k_tr, k_rot);
  const double dt_rayleigh = add_contact_stiffness(k_tr, k_rot);
  double crit = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    if (k_tr[i] > 0.0) crit = std::min(crit, std::sqrt(p_.mass[i] / k_tr[i]));
    if (k_rot[i] > 0.0) crit = std::min(crit, std::sqrt(p_.inertia[i] / k_rot[i]));
  }
  adopt_time_step(crit, dt_rayleigh);
}

void Simulation::refresh_time_step() {
  refuse_on_split_sample("refresh_time_step");
  if (intact_bonds() > 0)
    throw InputError("time step", "bonds", std::to_string(intact_bonds()),
                     "the time step is only re-estimated before bonds are installed");
  if (!initialised_) return;
  estimate_time_step();
  baseline_.reset();
  sample_requested_ = true;
}

}  // namespace breccia
