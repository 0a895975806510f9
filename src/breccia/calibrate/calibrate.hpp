#pragma once
// `breccia calibrate`: fits the free micro-parameters of a calibration file to its lab targets
// with a staged scheme (elastic, then strength, then friction; ARCHITECTURE.md "Calibration")
// driven by NLopt's COBYLA over small samples, then verifies the result over several packing
// seeds. Writes a calibration folder: every trial, the convergence table and figure, the
// parameter set as an experiment fragment and a verdict per target.
#include <functional>
#include <string>
#include <vector>

#include "breccia/calibrate/calibration_file.hpp"

namespace breccia {

class RankPool;

struct CalibrationOptions {
  std::string output_directory = "calibrations";  // receives <output>/<name>/
  std::string command_line;
  std::function<void(const std::string&)> log;  // progress and messages
  // Root of an MPI launch: each trial's tests run at once over the ranks (RankPool::serve on the
  // others).
  RankPool* pool = nullptr;
};

struct TargetVerdict {
  Target target;
  double calibrated = 0.0;      // on the calibration sample (NaN when not measured)
  double mean = 0.0, sd = 0.0;  // over the verification seeds (the calibration sample when none)
  int samples = 0;
  double error = 0.0;  // mean - target, relative for relative targets
  bool met = false;
};

struct CalibrationResult {
  std::string folder;
  std::string status;  // complete | interrupted
  std::vector<double> values;
  std::vector<TargetVerdict> verdicts;
  int evaluations = 0, test_runs = 0;
  double wall_seconds = 0.0;
};

CalibrationResult run_calibration(const CalibrationSpec& spec, const CalibrationOptions& options);

// Every check a calibration can fail before its first trial (what `calibrate --check` runs):
// the samples of every set are packed in a scratch folder and each test is built on them at the
// start and at the corners of the free parameters' box. Throws InputError.
void check_calibration(const CalibrationSpec& spec,
                       const std::function<void(const std::string&)>& log);

// The calibrated rock as an experiment fragment (a preset's material.toml without its header):
// [sample] density, and the bond installation gap where the calibration freed it (the gap
// sets how many bonds each grain has, so the rock depends on it), then [contact] and [bond].
std::string material_fragment(const CalibrationSpec& spec, const std::vector<double>& values);

// The calibration record's verdict table as text (for the command's output).
std::string verdict_table(const CalibrationResult& r);

}  // namespace breccia
