#include "breccia/run/session.hpp"

#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "breccia/core/checksum.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/version.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr const char* kCheckpointMagic = "breccia-checkpoint";
// 2: commit and trailing hash; 3: strain gauges; 4, 5: brittle-beam and quaternion bond sets;
// 6: smooth joints; 7: the 2D side-wall servo's integral terms; 8: RICEBAL bond set; 13: the
// recorders in registry order, the next snapshot's strain with the snapshots; 14: the contact law
// and the bond and joint sets by law name; 15: bond states without their section (derived from
// the radius and the run's geometry, which the laws' parameters carry); 16: one force per pair
// instead of a result slot (the pair pass sums loads per particle block), no wall-load arrays; 17:
// a wall's velocity ramp starts from a factor (platens slowing down), and platen compression
// keeps its elastic-phase speed; 18: prescribed velocities, driver loads and 2D angles stored
// only where they exist (empty while every grain is free; angles in 2D only); 19: contact states
// with rolling and twisting springs; 20: parallel-bond and beam states without their radius and
// stiffness per unit area (derived from the grains' radii), bond tags in 32 bits; 21, 22: crack
// records and AE logs beyond the resident ones in the run folder; 23: pair forces kept only where
// the laws' states do not give them back; 24: the adaptive loading's controller; 25: the
// instruction set of the run's kernels. A new law, lab test or recorder needs no new number:
// laws and tests are found by name, and each recorder checks its own label.
constexpr std::uint32_t kCheckpointFormat = 25;

// Layout: magic, format, version, commit, the resolved experiment, the state of every part, and
// last the FNV-1a hash of all bytes before it, so that a damaged file is refused before any of
// it is trusted.
namespace {

void write_whole_checkpoint(const fs::path& folder, const ExperimentSpec& spec, Session& s) {
  // Streamed to a temporary renamed over the last complete checkpoint once whole.
  AtomicFileWriter file(folder / kCheckpointFile);
  {
    ArchiveWriter a(file.stream());
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
  const std::uint64_t hash = file.hash();
  file.stream().write(reinterpret_cast<const char*>(&hash), sizeof hash);
  file.commit();
}

}  // namespace

void write_checkpoint(const fs::path& folder, const ExperimentSpec& spec, Session& s) {
  if (!s.sim.split()) {
    write_whole_checkpoint(folder, spec, s);
    return;
  }
  // A split sample is saved as one process holds it: gathered whole, written by root (whose
  // failure every rank shares), and split again, which continues as before to the bit.
  s.sim.unsplit();
  ranks::on_root([&] {
    write_whole_checkpoint(folder, spec, s);
    return std::string();
  });
  s.sim.split_over_ranks();
}

std::ifstream open_checkpoint(const fs::path& cpath) {
  require_regular_file(cpath.string(), "a checkpoint");
  std::ifstream in(cpath, std::ios::binary);
  if (!in) throw InputError(cpath.string(), "", "", "cannot read the checkpoint");
  {
    ArchiveReader a(in, cpath.string());
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
  // The hash of every byte before the last eight, streamed (a checkpoint can be gigabytes).
  in.clear();
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  std::uint64_t stored = 0;
  if (size < sizeof stored)
    throw InputError(cpath.string(), "length", std::to_string(size) + " bytes",
                     "the checkpoint is truncated");
  in.seekg(0);
  std::vector<char> chunk(1 << 20);
  std::uint64_t hash = fnv1a64({}), left = size - sizeof stored;
  while (left > 0 && in) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, chunk.size()));
    in.read(chunk.data(), static_cast<std::streamsize>(n));
    hash = fnv1a64({chunk.data(), static_cast<std::size_t>(in.gcount())}, hash);
    left -= static_cast<std::uint64_t>(in.gcount());
  }
  in.read(reinterpret_cast<char*>(&stored), sizeof stored);
  if (!in) throw InputError(cpath.string(), "", "", "cannot read the checkpoint");
  if (hash != stored)
    throw InputError(cpath.string(), "checksum", fmt::format("{:016x}", stored),
                     fmt::format("the file's bytes hash to {:016x}: the checkpoint is damaged "
                                 "or truncated and cannot be resumed",
                                 hash));
  in.seekg(0);
  return in;
}

}  // namespace breccia
