#pragma once
// The virtual laboratory a calibration measures with: it packs the samples once (once per value
// of a free [sample] key), runs the lab tests a parameter set needs (UCS, Brazilian, triaxial at
// each confining stress) as ordinary run folders, and reads the properties back from their
// summaries. Every finished test is recorded in trials.jsonl under a key made of the sample,
// the test and the exact parameter values, so a calibration that is stopped and started again
// reads its finished tests back instead of re-running them (the optimiser is deterministic and
// asks for the same points again).
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "breccia/calibrate/calibration_file.hpp"
#include "breccia/run/rank_pool.hpp"

namespace breccia {

using Properties = std::map<Property, double>;

// Which tests a measurement needs.
struct TestPlan {
  bool ucs = true;
  bool tensile = false;   // the calibration's tensile test (Brazilian or direct tension)
  bool envelope = false;  // triaxial tests at the calibration's confining stresses
};
TestPlan tests_for(const CalibrationSpec& c, std::optional<CalibrationStage> stage);

struct Measurement {
  Properties properties;
  nlohmann::json tests = nlohmann::json::object();  // per test: everything it measured
  std::vector<std::string> run_folders;
  std::vector<std::string> problems;  // tests that did not give a property, and why
  int new_runs = 0;                   // tests run now (not read back from the record)
  double wall_seconds = 0.0;          // of the tests run now
};

class Laboratory {
 public:
  // `folder` is the calibration folder; samples/ and trials/ live under it. With a `pool` (root
  // of an MPI launch) the tests a measurement needs run at once over the ranks.
  Laboratory(const CalibrationSpec& c, std::filesystem::path folder,
             std::function<void(const std::string&)> log, RankPool* pool = nullptr);

  // The samples of a sample set: "calibration" (the [experiment] sample at the start values,
  // its seed), "fit-<seed>" (the same with that seed) or "verify-<seed>" (verify_set overrides,
  // that seed, packed with `values`). A free [sample] key (the bond installation gap) is part
  // of the sample's genesis: each of its values gets a packing of its own, made as a run with
  // that value would make it.
  void prepare_samples(const std::string& set, const std::vector<double>& values);
  Measurement measure(const std::string& set, const std::vector<double>& values,
                      const TestPlan& plan);
  // What the search judges a trial by: measure() on each of the calibration's fit sets
  // (CalibrationSpec::fit_sets), each property the mean over them; `tests` keyed by set.
  Measurement measure_fit(const std::vector<double>& values, const TestPlan& plan);
  // With a pool over several ranks: runs at once every test that measure() would run on these
  // sets at `values`, and records them; measure() then reads them back. Numbered in measure()'s
  // order. The runs it made, in new_runs and wall_seconds.
  Measurement prefetch(const std::vector<std::string>& sets, const std::vector<double>& values,
                       const TestPlan& plan);

  // Every check a trial can fail, before the first trial: the samples of every set (the
  // calibration's and each verification seed's) are packed, and each test the calibration will
  // run is built (not run) on them at each parameter set of `points` (the start and the corners
  // of the free parameters' box). Throws InputError naming the test, the set and the values.
  void preflight(const std::vector<std::vector<double>>& points);

  std::size_t recorded_tests() const noexcept { return book_.size(); }
  // The report of the set's sample packed for `values` (prepare_samples first).
  const nlohmann::json& sample_report(const std::string& set,
                                      const std::vector<double>& values) const;

 private:
  struct SamplePaths {
    std::string prism, disc;
    nlohmann::json report;
  };
  std::vector<std::string> set_overrides(const std::string& set) const;
  // The name of the set's packing for `values`: the set, and the values of its free [sample]
  // keys ("fit-1", or "fit-1-bond_gap_tolerance=2e-05").
  std::string packing_name(const std::string& set, const std::vector<double>& values) const;
  // The experiment of one test of one set at `values` on the packing `sample` (its run folder
  // under trials/).
  ExperimentSpec trial_spec(const std::string& set, const std::vector<double>& values,
                            const std::string& test, double sigma3,
                            const SamplePaths& sample) const;
  void read_trial_record();
  // A test to run: its record's key, its number and its experiment.
  struct PendingTest {
    std::string key, set, test;
    double sigma3 = 0.0;
    int run = 0;
    ExperimentSpec spec;
  };
  std::string test_key(const std::string& set, const std::vector<double>& values,
                       const std::string& test) const;
  PendingTest pending_test(const std::string& set, const std::vector<double>& values,
                           const std::string& test, double sigma3);
  // Records a finished test (trials.jsonl and the book) with what its summary says.
  nlohmann::json book_test(const PendingTest& t, const std::vector<double>& values,
                           const std::string& folder, const std::string& status,
                           const std::string& stop_reason, double wall, Measurement& m);
  nlohmann::json run_test(const std::string& set, const std::vector<double>& values,
                          const std::string& test, double sigma3, Measurement& m);

  const CalibrationSpec& c_;
  std::filesystem::path folder_;
  std::function<void(const std::string&)> log_;
  std::map<std::string, nlohmann::json> book_;  // key -> record of a finished test
  std::map<std::string, SamplePaths> samples_;  // by packing_name
  int next_run_ = 1;
  RankPool* pool_ = nullptr;
};

}  // namespace breccia
