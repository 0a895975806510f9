// Fuzz target: the ESyS-Particle GenGeo (LSMGeometry 1.2) reader.
#include <sstream>

#include "breccia/sample/sample_import.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_one(data, size, [](const std::string& text) {
    std::istringstream in(text);
    (void)breccia::parse_gengeo(in, "fuzz.geo", 2650.0, 1e-3, kFuzzMaxParticles);
  });
}
