#pragma once
// Fragments after a test (docs/analysis.md §9): connected components of the intact-bond graph by
// union-find; particles without an intact bond are single-particle debris. Classes relative to
// the largest fragment: smallest f < 0.1, biggest f > 0.9, intermediate otherwise.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "breccia/core/vec3.hpp"
#include "breccia/state/particle_store.hpp"

namespace breccia::analysis {

struct Fragment {
  std::size_t particles = 0;
  double mass = 0.0, volume = 0.0;
  Vec3 centroid;  // mass-weighted
};

struct ClassCount {
  std::size_t count = 0;
  double mass = 0.0;
};

struct FragmentResult {
  std::vector<Fragment> fragments;       // by mass, largest first
  std::vector<std::size_t> fragment_of;  // per particle: index into `fragments`
  double total_mass = 0.0, largest_mass = 0.0, largest_fraction = 0.0;
  std::size_t debris = 0;  // single-particle fragments
  // Classes with and without single-particle debris.
  ClassCount smallest, intermediate, biggest;
  ClassCount smallest_no_debris, intermediate_no_debris, biggest_no_debris;
};

// `bonds` are index pairs of intact bonds; masses, volumes and positions per particle.
FragmentResult find_fragments(const std::vector<double>& mass, const std::vector<double>& volume,
                              const std::vector<Vec3>& position,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& bonds);

// The fragments of the first `count` particles of a store (the rock; a test's apparatus grains
// follow them): volumes from mass and density, masses divided by the run's density scaling (the
// grains' own density). Bonds to particles beyond `count` are left out.
// `bonds` calls its argument with the particle indexes of each intact bond (a million-grain
// sample's bonds are walked where they lie, not copied).
using BondVisit = std::function<void(std::uint32_t, std::uint32_t)>;
using BondWalk = std::function<void(const BondVisit&)>;
FragmentResult find_fragments(const ParticleStore& p, const BondWalk& bonds, double density_scaling,
                              std::size_t count = std::numeric_limits<std::size_t>::max());

}  // namespace breccia::analysis
