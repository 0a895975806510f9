// Fuzz target: the breccia-geometry reader and the checks every sample passes.
#include "breccia/sample/geometry_file.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_one(data, size, [](const std::string& text) {
    (void)breccia::parse_geometry(text, "fuzz.geom", kFuzzMaxParticles);
  });
}
