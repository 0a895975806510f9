#include "breccia/core/instruction_set.hpp"

namespace breccia {

std::string_view instruction_set_name(InstructionSet set) noexcept {
  switch (set) {
    case InstructionSet::x86_64_v3:
      return "x86-64-v3";
    case InstructionSet::baseline:
      break;
  }
  return "baseline";
}

std::optional<InstructionSet> instruction_set_from_name(std::string_view name) noexcept {
  for (InstructionSet set : kInstructionSets)
    if (instruction_set_name(set) == name) return set;
  return std::nullopt;
}

bool instruction_set_supported(InstructionSet set) noexcept {
#ifdef BRECCIA_MULTI_ISA
  __builtin_cpu_init();
  // The features the set's kernels are compiled with (instruction_set.hpp), as the CPU reports
  // them; the operating system's saving of the wide registers is part of GCC's check.
  const bool v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                  __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2") &&
                  __builtin_cpu_supports("popcnt") && __builtin_cpu_supports("sse4.2") &&
                  __builtin_cpu_supports("avx");
  switch (set) {
    case InstructionSet::x86_64_v3:
      return v3;
    case InstructionSet::baseline:
      return true;
  }
  return false;
#else
  return set == InstructionSet::baseline;
#endif
}

InstructionSet best_instruction_set() noexcept {
  InstructionSet best = InstructionSet::baseline;
  for (InstructionSet set : kInstructionSets)
    if (instruction_set_supported(set)) best = set;
  return best;
}

}  // namespace breccia
