// Fuzz target: the experiment parser (TOML, key tables, ranges, consistency checks). A spec that
// parses must print as TOML that parses back to the same text (the run manifest and checkpoints
// rely on it).
#include <cstdlib>

#include "breccia/spec/experiment.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_one(data, size, [](const std::string& text) {
    const breccia::ExperimentSpec spec = breccia::parse_experiment(text, "fuzz.toml", {});
    const std::string resolved = breccia::to_toml(spec);
    std::string again;
    try {
      again = breccia::to_toml(breccia::parse_experiment(resolved, "resolved.toml", {}));
    } catch (const breccia::InputError&) {
      std::abort();  // the resolved spec must always parse back
    }
    if (again != resolved) std::abort();
  });
}
