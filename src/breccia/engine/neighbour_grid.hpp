#pragma once
// Neighbour search: particles are binned in a uniform cell grid (cell edge >= 2 R_max + skin) and
// every pair closer than R_i + R_j + skin is listed once (i < j), sorted by (i, j). Cost is linear
// in the particle count; the result does not depend on the thread count.
#include <vector>

#include "breccia/state/pair_list.hpp"
#include "breccia/state/particle_store.hpp"

namespace breccia {

// What build_neighbour_pairs indexes: both indexes, or only the pairs where a particle is first
// (a rebuild builds the rest once the old list's contact history is merged and freed).
enum class PairIndex { Full, OffsetsOnly };

// Fills `out.first/second` (sorted) with all pairs within R_i + R_j + skin and builds its index.
// Only pairs whose first particle lies below `firsts` are listed (a rank's own particles, before
// its ghosts).
void build_neighbour_pairs(const std::vector<PosRad>& particles, double skin, bool planar,
                           PairList& out, PairIndex index = PairIndex::Full,
                           std::size_t firsts = static_cast<std::size_t>(-1));

}  // namespace breccia
