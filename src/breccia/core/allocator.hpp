#pragma once
// How the process takes memory from the system. glibc serves a large block by mmap and, once
// such a block is freed, raises its threshold to that block's size (up to 32 MB), so that the
// engine's next arrays of that size come from the heap instead, where freed space stays resident
// until trimmed: a neighbour-list rebuild, which frees the pair forces and indexes and allocates
// the new list, then briefly held both (about 100 B a grain above the loop on a Tumlin cylinder).
// A fixed threshold keeps every block of 128 KiB or more in its own mapping, returned to the
// system when freed. Blocks that large are allocated at rebuilds and between rows, not per pair.
#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace breccia {

inline void configure_allocator() noexcept {
#ifdef __GLIBC__
  static const bool done = [] { return mallopt(M_MMAP_THRESHOLD, 128 * 1024) == 1; }();
  (void)done;
#endif
}

}  // namespace breccia
