#pragma once
#include <functional>
#include <optional>
// A bonded FCC block between two platens, the small standard system of several tests.
#include <cmath>

#include "breccia/engine/simulation.hpp"
#include "breccia/law/registry.hpp"
#include "breccia/sample/lattice.hpp"

namespace breccia::test {

inline Simulation compressed_block(int nx, int ny, int nz, double platen_speed,
                                   double bond_strength, double damping = 0.7,
                                   const std::function<void(Simulation&)>& before_start = {},
                                   bool keep_pair_forces = false,
                                   std::optional<InstructionSet> instruction_set = {}) {
  const double R = 0.5e-3;
  ParticleStore ps = fcc_block(nx, ny, nz, R, 2650);
  EngineConfig cfg;
  cfg.local_damping = damping;
  cfg.energy_interval = 50;
  cfg.keep_pair_forces = keep_pair_forces;
  cfg.instruction_set = instruction_set;
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

// A block bonded with law BL (example parameters) and touching through CL, squeezed by two
// platens: spheres in an FCC block, or disks in a hexagonal one for a law made for 2D.
// `size` scales the block's edges: 64 size^3 spheres, or 60 size^2 disks.
template <class CL, class BL>
Simulation law_block(bool keep_pair_forces = false, int size = 1,
                     std::optional<InstructionSet> instruction_set = {}) {
  const double R = 0.5e-3;
  ParticleStore ps = planar_only_law<BL> ? hex_block(6 * size, 10 * size, R, 2650, 1e-3)
                                         : fcc_block(2 * size, 2 * size, 4 * size, R, 2650);
  for (std::size_t i = 0; i < ps.size(); ++i)
    ps.vel[i] = Vec3{1e-3 * std::sin(1.7 * static_cast<double>(i)),
                     1e-3 * std::cos(0.3 * static_cast<double>(i)),
                     planar_only_law<BL> ? 0.0 : 1e-3 * std::sin(0.9 * static_cast<double>(i))};
  EngineConfig cfg;
  cfg.energy_interval = 20;
  cfg.keep_pair_forces = keep_pair_forces;
  cfg.instruction_set = instruction_set;
  // A contact layout with the rolling moments runs with rolling and twisting resistance on.
  typename CL::Params cp = CL::example_params();
  if constexpr (CL::rolling) {
    cp.rolling_friction = 0.2;
    cp.twisting_friction = 0.1;
    cp.rolling_damping_ratio = 0.3;
  }
  Simulation sim(std::move(ps), cfg, make_contact_model<CL>(cp, cp));
  sim.set_bond_params<BL>(BL::example_params());
  sim.bond_touching_pairs<BL>(1e-9);
  const int axis = planar_only_law<BL> ? 1 : 2;
  double top = 0.0;
  for (const auto& q : sim.particles().pos_rad) top = std::max(top, q.x[axis] + q.r);
  Vec3 up{}, down{}, at_top{};
  up[axis] = 1.0;
  down[axis] = -1.0;
  at_top[axis] = top;
  Wall bottom = Wall::plane("bottom", {}, up);
  Wall lid = Wall::plane("top", at_top, down);
  bottom.target_velocity = up * 0.5;
  lid.target_velocity = down * 0.5;
  bottom.ramp = lid.ramp = {0.0, 1e-5};
  sim.add_wall(bottom);
  sim.add_wall(lid);
  sim.initialise();
  return sim;
}

}  // namespace breccia::test
