#pragma once
// Deterministic parallel helpers. Work is cut into fixed-size blocks that do not depend on the
// thread count; partial sums are kept per block and added in block order, so every reduction is
// bitwise identical for any number of threads (ARCHITECTURE.md, "Determinism without atomics").
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace breccia {

inline constexpr std::size_t kBlock = 1024;

inline std::size_t block_count(std::size_t n) noexcept {
  return (n + kBlock - 1) / kBlock;
}

inline int max_threads() noexcept {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

inline void set_threads(int n) noexcept {
#ifdef _OPENMP
  if (n > 0) omp_set_num_threads(n);
#else
  (void)n;
#endif
}

// How many blocks a thread takes at a time: four where there are plenty (fewer trips to the
// shared counter), one where there are few, so that a small system's handful of blocks is shared
// among the threads rather than taken by the first to ask (four blocks on two threads in one
// chunk of four would leave the second thread idle).
inline int block_chunk(std::ptrdiff_t blocks) noexcept {
  const std::ptrdiff_t per_thread_quarter =
      blocks / (4 * static_cast<std::ptrdiff_t>(max_threads()));
  return static_cast<int>(std::clamp<std::ptrdiff_t>(per_thread_quarter, 1, 4));
}

// Calls body(begin, end, block) for each block of [0, n) in parallel. Blocks are handed out
// dynamically (a thread slowed by the machine does not hold the others at the barrier); results
// stay bitwise reproducible because each block's output depends only on the block. A single
// block runs on the calling thread: small systems pay no fork-join cost. for_blocks_in walks
// blocks [first, last) of [0, n) only (the blocks of one rank's particles).
template <class Body>
void for_blocks_in(std::size_t first, std::size_t last, std::size_t n, Body&& body) {
  const std::ptrdiff_t nb = static_cast<std::ptrdiff_t>(last - first);
  const int chunk = block_chunk(nb);
#pragma omp parallel for schedule(dynamic, chunk) if (nb > 1)
  for (std::ptrdiff_t k = 0; k < nb; ++k) {
    const std::size_t b = first + static_cast<std::size_t>(k);
    const std::size_t begin = b * kBlock;
    const std::size_t end = begin + kBlock < n ? begin + kBlock : n;
    body(begin, end, b);
  }
}

template <class Body>
void for_blocks(std::size_t n, Body&& body) {
  for_blocks_in(0, block_count(n), n, body);
}

// Calls body(k) for each k in [0, n) in parallel, one at a time: for items that are blocks of work
// already (the pair pass's particle blocks). The same reproducibility rule holds as above.
template <class Body>
void for_each_item(std::size_t n, Body&& body) {
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(dynamic, 1) if (count > 1)
  for (std::ptrdiff_t k = 0; k < count; ++k) body(static_cast<std::size_t>(k));
}

// Where each block of kBlock particles begins in a list of items sorted by the particle that owns
// them (a bond's or a pair's first grain, a wall contact's grain): block b's items are
// [starts[b], starts[b + 1]). A sum over such a list is grouped by these blocks, so that a rank
// that owns whole blocks of particles forms the same partials alone (ARCHITECTURE.md, "Ranks
// (MPI)"). The first form fills `starts` in the room it has (the per-step passes allocate
// nothing).
inline void particle_block_starts(const std::vector<std::uint32_t>& owner, std::size_t particles,
                                  std::vector<std::size_t>& starts) {
  const std::size_t blocks = block_count(particles);
  starts.assign(blocks + 1, owner.size());
  for (std::size_t b = 0; b < blocks; ++b)
    starts[b] = static_cast<std::size_t>(
        std::lower_bound(owner.begin(), owner.end(), static_cast<std::uint32_t>(b * kBlock)) -
        owner.begin());
}
inline std::vector<std::size_t> particle_block_starts(const std::vector<std::uint32_t>& owner,
                                                      std::size_t particles) {
  std::vector<std::size_t> starts;
  particle_block_starts(owner, particles, starts);
  return starts;
}

// Calls body(begin, end, block) for each block's items (particle_block_starts), in parallel.
template <class Body>
void for_item_blocks(const std::vector<std::size_t>& starts, Body&& body) {
  const std::ptrdiff_t nb = static_cast<std::ptrdiff_t>(starts.size()) - 1;
  const int chunk = block_chunk(nb);
#pragma omp parallel for schedule(dynamic, chunk) if (nb > 1)
  for (std::ptrdiff_t b = 0; b < nb; ++b)
    body(starts[static_cast<std::size_t>(b)], starts[static_cast<std::size_t>(b) + 1],
         static_cast<std::size_t>(b));
}

// Adds per-block partials in block order.
template <class T>
T ordered_sum(const std::vector<T>& partials) {
  T s{};
  for (const T& p : partials) s += p;
  return s;
}

}  // namespace breccia
