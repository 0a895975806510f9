// Fuzz target: the x-y-z-r table reader (YADE / PFC exports), 3D and 2D.
#include <sstream>

#include "breccia/sample/sample_import.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_one(data, size, [](const std::string& text) {
    const auto dim =
        !text.empty() && (text.front() & 1) ? breccia::Dimension::Two : breccia::Dimension::Three;
    std::istringstream in(text);
    (void)breccia::parse_xyzr_table(in, "fuzz.txt", dim, 2650.0, 1e-3, kFuzzMaxParticles);
  });
}
