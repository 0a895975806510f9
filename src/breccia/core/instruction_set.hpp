#pragma once
// The instruction sets the hot kernels are built for, both in one binary: the build's own flags
// (the baseline: SSE2 for the portable x86-64 build) and x86-64-v3 (AVX2 with fused multiply-adds).
// A run picks one at its start (v3 where the CPU has it, or the one the experiment names) and every
// step of the pair pass and the integrator runs in it: within one set the results are the same to
// the bit at any thread and rank count; between sets they differ by the fused multiply-adds of v3,
// which round once where the baseline rounds twice (docs/physics.md §1.7). AVX-512 (x86-64-v4) is
// not among them: on the peers' cylinder its kernels ran 10 % slower than v3's (bench/RESULTS.md).
#include <cstdint>
#include <optional>
#include <string_view>

namespace breccia {

enum class InstructionSet : std::uint8_t { baseline, x86_64_v3 };

inline constexpr InstructionSet kInstructionSets[] = {InstructionSet::baseline,
                                                      InstructionSet::x86_64_v3};

// The names of docs and keys: "baseline", "x86-64-v3" (the GCC and psABI level).
std::string_view instruction_set_name(InstructionSet set) noexcept;
std::optional<InstructionSet> instruction_set_from_name(std::string_view name) noexcept;

// Whether this CPU runs the set's kernels (and this binary has them: built for x86-64 with GCC).
bool instruction_set_supported(InstructionSet set) noexcept;

// The fastest set this CPU runs.
InstructionSet best_instruction_set() noexcept;

// The v3 kernels are the baseline's source compiled again with v3's features added: GCC's target
// attribute with flatten, which inlines the body's calls into it, where they are compiled with
// those features (the stages flatten's early pass leaves out, such as the bond lanes, are marked
// always_inline). Only ISA features are added, never `arch=`: a function of another arch could not
// inline the engine's small helpers. The binary's own flags stay the floor: a native build's
// baseline is already native. What stays out of line (the pair shape, kept so on purpose) runs in
// the baseline: deterministic all the same.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define BRECCIA_MULTI_ISA 1
#define BRECCIA_TARGET_X86_64_V3                                                    \
  gnu::target(                                                                      \
      "sse3,ssse3,sse4.1,sse4.2,popcnt,cx16,sahf,avx,avx2,bmi,bmi2,f16c,fma,lzcnt," \
      "movbe,xsave"),                                                               \
      gnu::flatten

namespace isa_detail {
template <class Body>
[[BRECCIA_TARGET_X86_64_V3]] void run_x86_64_v3(Body& body) {
  body();
}
}  // namespace isa_detail
#endif

// Runs body() compiled for the set: the caller's loop over blocks stays outside, so that one call
// covers a block's work. The caller checks instruction_set_supported first (the engine refuses a
// set the CPU lacks).
template <class Body>
inline void with_instruction_set(InstructionSet set, Body&& body) {
#ifdef BRECCIA_MULTI_ISA
  switch (set) {
    case InstructionSet::x86_64_v3:
      isa_detail::run_x86_64_v3(body);
      return;
    case InstructionSet::baseline:
      break;
  }
#else
  (void)set;
#endif
  body();
}

}  // namespace breccia
