#pragma once
// A run in progress as a checkpoint holds it: the engine, the lab test, the recorders
// (observe/registry.hpp) and the loading loop's own state; and checkpoint.bin, which saves and
// restores it exactly.
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "breccia/analysis/compression.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/observe/registry.hpp"
#include "breccia/protocol/protocol.hpp"
#include "breccia/spec/experiment.hpp"

namespace breccia {

inline constexpr const char* kCheckpointFile = "checkpoint.bin";
// The crack records a run no longer holds in memory (engine/crack_catalogue.hpp), in the order
// recorded: the checkpoint's companion, gone with it when the run completes.
inline constexpr const char* kCrackCatalogueFile = "checkpoint-cracks.bin";

// What the loading loop carries from one row to the next besides the engine, the protocol and
// the recorders: the analysed series, the quality monitors and the run's bookkeeping.
struct LoopState {
  analysis::CompressionSeries series;
  std::vector<double> imbalance, ke_ratio, confine_err;
  double wall_seconds = 0.0;  // spent in earlier sessions of this run (updated when saved)
  std::uint64_t consolidation_steps = 0;
  std::uint64_t bonds_initial = 0;
  std::uint64_t bond_sites_initial = 0;  // Simulation::intact_bond_sites at the start
  std::vector<std::string> warnings;     // those of the set-up
  // Reference state of the loading stage for the failure analysis.
  double volume0 = 0.0, porosity0 = 0.0, length_min = 0.0;
  std::string wave_speed_method;

  template <class Archive>
  void transfer(Archive& a) {
    a.label("loop");
    a.vector(series.axial_strain);
    a.vector(series.deviatoric);
    a.vector(series.lateral_strain);
    a.vector(series.volumetric_strain);
    a.vector(series.gauge_axial_strain);
    a.vector(series.gauge_lateral_strain);
    a.vector(series.broken_bonds);
    a.value(series.confining_stress);
    a.vector(imbalance);
    a.vector(ke_ratio);
    a.vector(confine_err);
    a.value(wall_seconds);
    a.value(consolidation_steps);
    a.value(bonds_initial);
    a.value(bond_sites_initial);
    a.sized(warnings, 8);
    for (std::string& w : warnings) a.string(w);
    a.value(volume0);
    a.value(porosity0);
    a.value(length_min);
    a.string(wave_speed_method);
  }
  void save(ArchiveWriter& a) const { const_cast<LoopState*>(this)->transfer(a); }
  void load(ArchiveReader& a) {
    transfer(a);
    const std::size_t rows = series.axial_strain.size();
    for (std::size_t m :
         {series.deviatoric.size(), series.lateral_strain.size(), series.volumetric_strain.size(),
          series.gauge_axial_strain.size(), series.gauge_lateral_strain.size(),
          series.broken_bonds.size(), imbalance.size(), ke_ratio.size()})
      if (m != rows)
        throw InputError(a.where(), "series", std::to_string(m),
                         "series lengths differ: the checkpoint is corrupt");
  }
};

// One run in progress: everything a checkpoint holds.
struct Session {
  Simulation sim;
  std::unique_ptr<Protocol> test;
  LoopState loop;
  RecorderList recorders;  // in registry order
  AeMonitor& ae() const { return find_recorder<AeMonitor>(recorders); }
};

// Writes checkpoint.bin atomically (temporary file, then rename): a crash while writing leaves the
// previous checkpoint intact.
void write_checkpoint(const std::filesystem::path& folder, const ExperimentSpec& spec, Session& s);
// Checks checkpoint.bin's header and its hash (streamed through, never held whole) and returns the
// file opened at its first byte; throws InputError naming the file when either is wrong.
std::ifstream open_checkpoint(const std::filesystem::path& checkpoint);

}  // namespace breccia
