#include "breccia/run/session.hpp"

#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>

#include "breccia/core/checksum.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/version.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr const char* kCheckpointMagic = "breccia-checkpoint";
// 2: commit and trailing hash; 3: strain gauges; 4, 5: brittle-beam and quaternion bond sets;
// 6: smooth joints; 7: the 2D side-wall servo's integral terms; 8: RICEBAL bond set; 13: the
// recorders in registry order, the next snapshot's strain with the snapshots; 14: the contact law
// and the bond and joint sets by law name. A new law, lab test or recorder needs no new number:
// laws and tests are found by name, and each recorder checks its own label.
constexpr std::uint32_t kCheckpointFormat = 14;

// Layout: magic, format, version, commit, the resolved experiment, the state of every part, and
// last the FNV-1a hash of all bytes before it, so that a damaged file is refused before any of
// it is trusted.
void write_checkpoint(const fs::path& folder, const ExperimentSpec& spec, Session& s) {
  const fs::path path = folder / kCheckpointFile;
  std::ostringstream body(std::ios::binary);
  {
    ArchiveWriter a(body);
    a.string(kCheckpointMagic);
    a.value(kCheckpointFormat);
    a.string(kVersion);
    a.string(kCommit);
    a.string(to_toml(spec));
    s.loop.save(a);
    s.sim.save_state(a);
    s.test->save_state(a);
    save_recorders(s.recorders, a);
    a.label("end of checkpoint");
  }
  const std::string bytes = std::move(body).str();
  const std::uint64_t hash = fnv1a64(bytes);
  std::string file = bytes;
  file.append(reinterpret_cast<const char*>(&hash), sizeof hash);
  // The last complete checkpoint stays until this one is written whole.
  write_file_atomically(path, file);
}

std::string read_checkpoint_bytes(const fs::path& cpath) {
  require_regular_file(cpath.string(), "a checkpoint");
  std::ifstream in(cpath, std::ios::binary);
  if (!in) throw InputError(cpath.string(), "", "", "cannot read the checkpoint");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  {
    std::istringstream head(bytes, std::ios::binary);
    ArchiveReader a(head, cpath.string());
    if (a.string() != kCheckpointMagic)
      throw InputError(cpath.string(), "header", "", "not a Breccia checkpoint");
    const auto format = a.get<std::uint32_t>();
    const std::string version = a.string();
    if (format != kCheckpointFormat || version != kVersion)
      throw InputError(cpath.string(), "version",
                       version + " (format " + std::to_string(format) + ")",
                       std::string("this is breccia ") + kVersion + " (format " +
                           std::to_string(kCheckpointFormat) +
                           "): resume with the version that wrote the checkpoint");
  }
  std::uint64_t stored = 0;
  if (bytes.size() < sizeof stored)
    throw InputError(cpath.string(), "length", std::to_string(bytes.size()) + " bytes",
                     "the checkpoint is truncated");
  std::memcpy(&stored, bytes.data() + bytes.size() - sizeof stored, sizeof stored);
  bytes.resize(bytes.size() - sizeof stored);
  if (fnv1a64(bytes) != stored)
    throw InputError(cpath.string(), "checksum", fmt::format("{:016x}", stored),
                     fmt::format("the file's bytes hash to {:016x}: the checkpoint is damaged "
                                 "or truncated and cannot be resumed",
                                 fnv1a64(bytes)));
  return bytes;
}

}  // namespace breccia
