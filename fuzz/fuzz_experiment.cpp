// Fuzz target: the experiment parser (TOML, key tables, ranges, consistency checks).
#include "breccia/io/experiment.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_one(data, size, [](const std::string& text) {
    const breccia::ExperimentSpec spec = breccia::parse_experiment(text, "fuzz.toml", {});
    (void)breccia::to_toml(spec);  // the resolved spec must print
  });
}
