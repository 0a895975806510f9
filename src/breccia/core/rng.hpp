#pragma once
// Counter-based random numbers: a value is a pure function of (seed, stream, counter), so per-bond
// strengths do not depend on creation order, thread count or how many draws came before.
#include <cmath>
#include <cstdint>
#include <numbers>

namespace breccia {

constexpr std::uint64_t splitmix64(std::uint64_t x) noexcept {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

constexpr std::uint64_t hash3(std::uint64_t seed, std::uint64_t stream,
                              std::uint64_t counter) noexcept {
  return splitmix64(splitmix64(splitmix64(seed) ^ stream) ^ counter);
}

// Uniform in the open interval (0, 1).
constexpr double uniform01(std::uint64_t seed, std::uint64_t stream,
                           std::uint64_t counter) noexcept {
  return (static_cast<double>(hash3(seed, stream, counter) >> 11) + 0.5) * 0x1.0p-53;
}

// Standard normal by Box-Muller from two counter-indexed uniforms.
inline double standard_normal(std::uint64_t seed, std::uint64_t stream,
                              std::uint64_t counter) noexcept {
  const double u1 = uniform01(seed, stream, 2 * counter);
  const double u2 = uniform01(seed, stream, 2 * counter + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

// Normal(mean, sd) truncated to positive values by redrawing (docs/physics.md §9 decision 4). With
// sd == 0 the mean itself is returned. Gives up after 1000 redraws, which only happens when the
// mean is many standard deviations below zero; callers validate mean > 0 beforehand.
inline double positive_normal(double mean, double sd, std::uint64_t seed, std::uint64_t stream,
                              std::uint64_t key) noexcept {
  if (sd <= 0.0) return mean;
  for (std::uint64_t k = 0; k < 1000; ++k) {
    const double v = mean + sd * standard_normal(seed, stream, key * 1000 + k);
    if (v > 0.0) return v;
  }
  return mean;
}

}  // namespace breccia
