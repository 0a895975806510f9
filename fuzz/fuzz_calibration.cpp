// Fuzz target: the calibration file (its own tables, then the [experiment] it carries, the free
// parameters' bounds and the ties checked against the experiment's key tables).
#include "breccia/calibrate/calibration_file.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_one(data, size, [](const std::string& text) {
    (void)breccia::parse_calibration(text, "fuzz-calibration.toml");
  });
}
