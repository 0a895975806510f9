// Fuzz target: a sweep plan (sweep-plan.json) as `breccia resume` checks it before any run: its
// JSON, format and kind, the resolved experiment it carries and the values of what varies.
#include "breccia/run/run.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_one(data, size, [](const std::string& text) {
    breccia::check_sweep_plan(text, "fuzz/sweep-plan.json");
  });
}
