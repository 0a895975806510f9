#pragma once
// The memory a run will hold, estimated from the sizes of the engine's arrays before any of them
// is allocated, so that a sample too large for the machine is refused with the figure and what
// to change instead of being killed by the kernel half-way through its test.
#include <cstddef>
#include <string>

#include "breccia/spec/experiment.hpp"

namespace breccia {

struct MemoryEstimate {
  double particle_bytes = 0.0;  // particle arrays and the engine's per-particle scratch
  double bond_bytes = 0.0;      // bond sets
  double pair_bytes = 0.0;      // neighbour pairs: lists, forces, contact history
  double neighbour_pairs = 0.0;
  double total() const noexcept { return particle_bytes + bond_bytes + pair_bytes; }
};

// Neighbour pairs per grain assumed by the estimate (half list, skin 0.4 mean radius): above
// the 4.2 of a packed and bonded 1.16M-grain cylinder, 4.4 on a bonded GenGeo cylinder and 5.9 on
// an FCC block (bench_engine), so that the estimate errs high.
inline constexpr double kPairsPerGrain3d = 6.0, kPairsPerGrain2d = 4.0;
// Share of the pairs that cross a particle block of the pair pass (state/pair_list.hpp), above the
// 21-23 % measured on 3D grains in spatial order (bench_engine: a 100k FCC block and a 97k random
// cylinder; 8 % on a 2D block).
inline constexpr double kCrossPairShare = 0.3;

// `bonds`: the sample's bond count, or 0 when the run bonds touching grains itself (then 3 per
// grain in 3D, 2 in 2D: a dense packing's coordination number halved).
MemoryEstimate estimate_memory(const ExperimentSpec& s, std::size_t particles, std::size_t bonds);

// The kernel's MemAvailable in bytes, or 0 where it cannot be read.
double available_memory_bytes();

// Throws InputError naming the sample when the estimate exceeds `available_bytes` (unchecked when
// 0: unknown); returns a line for the run's log otherwise.
std::string check_memory(const ExperimentSpec& s, std::size_t particles, std::size_t bonds,
                         double available_bytes);

}  // namespace breccia
