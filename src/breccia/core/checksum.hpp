#pragma once
// FNV-1a, 64 bit: a fast hash of bytes for cache keys and for detecting damaged checkpoints
// (accidental corruption, not tampering).
#include <cstdint>
#include <string_view>

namespace breccia {

inline std::uint64_t fnv1a64(std::string_view bytes,
                             std::uint64_t h = 1469598103934665603ull) noexcept {
  for (const unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  return h;
}

}  // namespace breccia
