#pragma once
// Post-test failure analysis of a compression run (docs/analysis.md §2-§9), written into the run
// folder: the crack catalogue with its derived fields (strain, stage, event), the
// acoustic-emission event catalogue (events.csv), the indicator series over strain
// (indicators.csv), moving-window b-values and D2 (b_value_windows.csv, d2_windows.csv), the
// fragments (fragments.csv) and the energy budget at the test's landmarks. Returns the summary
// blocks for summary.json.
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>

#include "breccia/analysis/compression.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/observe/ae_monitor.hpp"
#include "breccia/spec/experiment.hpp"

namespace breccia {

struct FailureInputs {
  const ExperimentSpec& spec;
  const Simulation& sim;
  const AeMonitor& ae;  // finished (events closed)
  const analysis::CompressionSeries& series;
  const analysis::CompressionResult& result;
  double volume0 = 0.0;            // sample volume at the start of loading, m^3 (2D: x thickness)
  double initial_porosity = 0.0;   // n0 at the start of loading
  double sample_length_min = 0.0;  // smallest sample dimension (D2 upper radius 0.25 L)
  std::string wave_speed_method;   // how v_S was obtained
  // false for tests not read as a stress-strain curve (impact, ...): no deformation stages, and
  // the energy budget at the end only.
  bool stress_strain = true;
  // The rock's grains: the first this many of the store (a test's apparatus grains follow).
  std::size_t rock_particles = std::numeric_limits<std::size_t>::max();
  // Whether a signal stops the analysis (polled between its stages). Not after a loading that a
  // signal already stopped: that run's analysis of what it recorded is part of its stop.
  bool stoppable = true;
};

nlohmann::json write_failure_analysis(const std::filesystem::path& folder, const FailureInputs& in);

}  // namespace breccia
