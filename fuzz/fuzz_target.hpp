#pragma once
// One fuzz target: bytes in, parsed or refused with an InputError. Anything else (another
// exception, a crash, a sanitizer report, a hang) is a finding. Built with libFuzzer under clang
// (scripts/fuzz), or with replay_main.cpp as a plain program that replays a corpus (CI, ctest).
#include <cstddef>
#include <cstdint>
#include <string>

#include "breccia/core/error.hpp"

// Small limits keep each input fast: a fuzzer that announces 1e8 particles must meet the count
// check, not an allocation.
inline constexpr std::uint64_t kFuzzMaxParticles = 10000;

template <class Parse>
int fuzz_one(const std::uint8_t* data, std::size_t size, Parse parse) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    parse(text);
  } catch (const breccia::InputError&) {
    // the expected answer to bad input
  }
  return 0;
}
