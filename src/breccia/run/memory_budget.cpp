#include "breccia/run/memory_budget.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "breccia/core/error.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

namespace {

// Whether the pair pass keeps the array of pair forces for a law with these parameters: its state
// does not give its force back (Simulation::pair_force).
template <class Law>
bool keeps_pair_forces(const typename Law::Params& p) {
  if constexpr (has_state_force<Law>)
    return !Law::state_holds_force(p);
  else
    return true;
}

}  // namespace

MemoryEstimate estimate_memory(const ExperimentSpec& s, std::size_t particles, std::size_t bonds) {
  const bool planar = s.dimension == 2;
  const double n = static_cast<double>(particles);
  MemoryEstimate e;
  e.neighbour_pairs = n * (planar ? kPairsPerGrain2d : kPairsPerGrain3d);
  const double bond_count = bonds > 0 ? static_cast<double>(bonds) : n * (planar ? 2.0 : 3.0);
  e.particle_bytes = n * static_cast<double>(ParticleStore::kBytesPerParticle +
                                             Simulation::kScratchBytesPerParticle);
  // Dynamic damping's mark per grain (and its grid of the grains, a few bytes more).
  if (s.dynamic_damping) e.particle_bytes += n * static_cast<double>(sizeof(double) + 8);
  // The pair pass keeps an array of pair forces unless the laws' states give them back
  // (Simulation::pair_force): dashpots on the bonds or contacts, or a law without state forces.
  bool forces_kept = s.engine.bond_normal_damping_ratio > 0.0 ||
                     s.engine.bond_shear_damping_ratio > 0.0 || s.engine.keep_pair_forces;
  if (!s.joint_planes.empty())
    visit_params<JointLaws>(s.joint, [&]<class Law>(const typename Law::Params& p) {
      forces_kept = forces_kept || keeps_pair_forces<Law>(p);
    });
  visit_params<BondLaws>(s.bond, [&]<class Law>(const typename Law::Params& p) {
    e.bond_bytes = bond_count * static_cast<double>(BondSet<Law>::kBytesPerBond);
    forces_kept = forces_kept || keeps_pair_forces<Law>(p);
  });
  visit_params<ContactLaws>(s.contact, [&]<class Law>(const typename Law::Params& p) {
    // The state layout the engine will hold (with the rolling moments only when they are on).
    const double state_bytes = static_cast<double>(
        rolling_limits(p).on() ? sizeof(typename Law::template with_rolling<true>::State)
                               : sizeof(typename Law::State));
    // A pair's list entries (first, second), its history index and, while it
    // touches, a contact state with a quarter to spare; the estimate gives a state to every pair
    // (an FCC block's pairs all touch). A rebuild frees the forces and bond indexes before it
    // builds the new list, so the two lists coexist within that room.
    const double kept = 3.0 * sizeof(std::uint32_t) + 1.25 * state_bytes;
    // Every pair keeps one bond index, and its force where the states do not give it back; a
    // cross pair (pair_list.hpp) also a slot and its entry in the gather index.
    forces_kept = forces_kept || keeps_pair_forces<Law>(p);
    const double force = forces_kept ? sizeof(Vec3) : 0.0;
    const double cross = kCrossPairShare * (sizeof(CrossSlot) + sizeof(std::uint32_t));
    e.pair_bytes = e.neighbour_pairs * (kept + force + sizeof(std::uint32_t) + cross);
  });
  return e;
}

double available_memory_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string key;
    double kib = 0.0;
    if (words >> key >> kib && key == "MemAvailable:") return kib * 1024.0;
  }
  return 0.0;
}

std::string check_memory(const ExperimentSpec& s, std::size_t particles, std::size_t bonds,
                         double available) {
  const MemoryEstimate e = estimate_memory(s, particles, bonds);
  const double gib = 1024.0 * 1024.0 * 1024.0;
  const double per = e.total() / static_cast<double>(std::max<std::size_t>(particles, 1));
  const std::string parts = fmt::format(
      "{:.0f} bytes per grain: particles {:.2f} GiB, bonds {:.2f} GiB, about {:.3g} neighbour "
      "pairs {:.2f} GiB",
      per, e.particle_bytes / gib, e.bond_bytes / gib, e.neighbour_pairs, e.pair_bytes / gib);
  if (available > 0.0 && e.total() > available)
    throw InputError(
        s.source, "sample", fmt::format("{} grains", particles),
        fmt::format("the run needs about {:.1f} GiB ({}) and this machine has {:.1f} GiB "
                    "available: use fewer grains (larger sample.radius_min and radius_max, or a "
                    "smaller sample) or a "
                    "machine with more memory",
                    e.total() / gib, parts, available / gib));
  return fmt::format("memory: about {:.2f} GiB estimated ({}); {} available", e.total() / gib,
                     parts,
                     available > 0.0 ? fmt::format("{:.1f} GiB", available / gib) : "unknown");
}

}  // namespace breccia
