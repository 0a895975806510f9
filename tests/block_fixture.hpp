#pragma once
#include <functional>
// A bonded FCC block between two platens, the small standard system of several tests.
#include <cmath>

#include "breccia/engine/simulation.hpp"
#include "breccia/sample/lattice.hpp"

namespace breccia::test {

inline Simulation compressed_block(int nx, int ny, int nz, double platen_speed,
                                   double bond_strength, double damping = 0.7,
                                   const std::function<void(Simulation&)>& before_start = {},
                                   bool keep_pair_forces = false) {
  const double R = 0.5e-3;
  ParticleStore ps = fcc_block(nx, ny, nz, R, 2650);
  EngineConfig cfg;
  cfg.local_damping = damping;
  cfg.energy_interval = 50;
  cfg.keep_pair_forces = keep_pair_forces;
  LinearContact::Params lp;
  LinearContact::Params wall = lp;
  wall.friction = 0.0;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>(lp, wall));
  ParallelBond::Params bp;
  bp.tensile_strength = bond_strength;
  bp.cohesion = bond_strength;
  bp.tensile_strength_sd = 0.2 * bond_strength;
  bp.cohesion_sd = 0.2 * bond_strength;
  sim.set_bond_params<ParallelBond>(bp);
  sim.bond_touching_pairs<ParallelBond>(1e-9);
  double zmax = 0.0;
  for (const auto& q : sim.particles().pos_rad) zmax = std::max(zmax, q.x.z + q.r);
  Wall bottom = Wall::plane("bottom", {0, 0, 0}, {0, 0, 1});
  Wall upper = Wall::plane("top", {0, 0, zmax}, {0, 0, -1});
  bottom.target_velocity = {0, 0, platen_speed};
  upper.target_velocity = {0, 0, -platen_speed};
  bottom.ramp = upper.ramp = {0.0, 2e-5};
  sim.add_wall(bottom);
  sim.add_wall(upper);
  if (before_start) before_start(sim);
  sim.initialise();
  return sim;
}

}  // namespace breccia::test
