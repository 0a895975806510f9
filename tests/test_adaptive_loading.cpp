// Adaptive quasi-static loading (boundary/adaptive_loading.hpp, docs/physics.md §6.1): the
// controller's speeds against hand numbers, and whole runs against constant-speed runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "breccia/boundary/adaptive_loading.hpp"
#include "breccia/protocol/compression.hpp"
#include "breccia/spec/experiment.hpp"
#include "cli_harness.hpp"

using namespace breccia;
using namespace breccia::testing;
namespace fs = std::filesystem;

namespace {

// A floor of 0.01 m/s, a bar wave of 1000 m/s through 0.01 m at a step of 1e-7 s: a transit of 100
// steps, a check every 25; 1,000 intact bonds; a ceiling of 8 times the floor.
AdaptiveLoading controller() {
  return AdaptiveLoading({8.0, 2e-4, 2.5e-4}, 0.01, 1000.0, 0.01, 1e-7, 1000.0, 0.0);
}

// Quiet checks (no cracks, no kinetic energy, balanced platens) that strain the sample by
// `strain_per_check` at the current speed factor, from `strain`.
double quiet_checks(AdaptiveLoading& a, int n, double& strain, double strain_per_check) {
  for (int k = 0; k < n; ++k) {
    strain += strain_per_check * a.factor();
    a.update({.strain = strain});
  }
  return a.factor();
}

}  // namespace

TEST(AdaptiveLoading, ChecksFourTimesATransitOnceTheRampIsOver) {
  const AdaptiveLoading a = controller();
  EXPECT_EQ(a.check_steps(), 25u);
  EXPECT_TRUE(a.due(25, 0.0));
  EXPECT_FALSE(a.due(26, 0.0));
  EXPECT_TRUE(a.due_next(24, 0.0)) << "the step before a check samples the stored energy";
  const AdaptiveLoading late({8.0, 2e-4, 2.5e-4}, 0.01, 1000.0, 0.01, 1e-7, 1000.0, 1e-3);
  EXPECT_FALSE(late.due(25, 0.5e-3)) << "not during the start-up ramp";
  EXPECT_TRUE(late.due(10025, 1.0025e-3));
  const AdaptiveLoading off({1.0, 2e-4, 2.5e-4}, 0.01, 1000.0, 0.01, 1e-7, 1000.0, 0.0);
  EXPECT_FALSE(off.on());
  EXPECT_FALSE(off.due(25, 0.0));
}

TEST(AdaptiveLoading, AQuietSampleDoublesItsSpeedEveryTwoTransitsUpToTheCeiling) {
  AdaptiveLoading a = controller();
  double strain = 0.0;
  EXPECT_NEAR(quiet_checks(a, 8, strain, 1e-5), 2.0, 1e-12);  // 8 checks = 2 transits
  EXPECT_NEAR(quiet_checks(a, 8, strain, 1e-5), 4.0, 1e-12);
  EXPECT_NEAR(quiet_checks(a, 7, strain, 1e-5), 4.0 * std::pow(2.0, 7.0 / 8.0), 1e-12);
  EXPECT_EQ(quiet_checks(a, 1, strain, 1e-5), 8.0) << "the ceiling";
  EXPECT_EQ(quiet_checks(a, 10, strain, 1e-5), 8.0);
  EXPECT_EQ(a.max_factor(), 8.0);
}

TEST(AdaptiveLoading, CrackingHoldsEachTransitToItsBudgetOfBrokenBonds) {
  // At 8 times the floor, 1e-4 strain a check (2 v dt 25 / L at 0.08 m/s = 4e-5: any strain
  // does, the rule reads cracks per strain). One crack every 4 checks is 2 cracks over the
  // window of 8 checks and 8e-4 strain: phi = 2 / (1000 x 8e-4) = 2.5 per unit strain, so a
  // transit at speed v breaks 2.5 x 2 v / 1000 of the bonds, 2e-4 at v = 0.04 m/s: a factor of 4.
  AdaptiveLoading a = controller();
  double strain = 0.0;
  ASSERT_EQ(quiet_checks(a, 30, strain, 1e-5), 8.0);
  double cracks = 0.0, last = a.factor();
  for (int k = 1; k <= 40; ++k) {
    strain += 1e-4;
    if (k % 4 == 0) cracks += 1.0;
    const double f = a.update({.strain = strain, .cracks = cracks});
    EXPECT_GE(f, last / AdaptiveLoading::kDownPerCheck * (1 - 1e-15))
        << "at most a halving a transit, check " << k;
    last = f;
  }
  EXPECT_NEAR(a.factor(), 4.0, 1e-12);
  // Twice the rate, twice as slow; eight times, the floor (never below it).
  for (int k = 1; k <= 40; ++k) {
    strain += 1e-4;
    if (k % 2 == 0) cracks += 1.0;
    a.update({.strain = strain, .cracks = cracks});
  }
  EXPECT_NEAR(a.factor(), 2.0, 1e-12);
  for (int k = 1; k <= 40; ++k) {
    strain += 1e-4;
    cracks += 2.0;
    a.update({.strain = strain, .cracks = cracks});
  }
  EXPECT_EQ(a.factor(), 1.0);
}

TEST(AdaptiveLoading, KineticEnergyAndPlatenImbalanceScaleTheSpeedDown) {
  AdaptiveLoading a = controller();
  double strain = 0.0;
  ASSERT_EQ(quiet_checks(a, 30, strain, 1e-5), 8.0);
  // E'_kin / E_strain at 1.5625e-4 is the target over 1.6: the speed may rise by sqrt(1.6), but
  // not past the ceiling; at 4 times the target it should halve, by 2^(1/4) at most a check.
  strain += 1e-5;
  EXPECT_EQ(a.update({.strain = strain, .kinetic_ratio = 1.5625e-4}), 8.0);
  strain += 1e-5;
  EXPECT_NEAR(a.update({.strain = strain, .kinetic_ratio = 1e-3}),
              8.0 / AdaptiveLoading::kDownPerCheck, 1e-12);
  // Between the limits: E'_kin at 1.0 x the target over (1.05)^2 lets it rise by 1.05 only.
  strain += 1e-5;
  const double f = a.factor();
  EXPECT_NEAR(a.update({.strain = strain, .kinetic_ratio = 2.5e-4 / (1.05 * 1.05)}), 1.05 * f,
              1e-12);
  // The platens' imbalance 0.025 (twice the target 0.0125): a halving, limited to 2^(1/4).
  strain += 1e-5;
  const double g = a.factor();
  EXPECT_NEAR(a.update({.strain = strain, .imbalance = 0.025}), g / AdaptiveLoading::kDownPerCheck,
              1e-12);
  strain += 1e-5;
  const double h = a.factor();
  EXPECT_NEAR(a.update({.strain = strain, .imbalance = 0.0125 / 1.02}), 1.02 * h, 1e-12);
}

namespace {

// A UCS of 308 grains (a 3 x 3 x 6 mm prism of the tiny calibration's rock) at 0.03 m/s and
// density scaling 10: quasi-static, about 20,000 steps at a constant speed.
const std::string kTinyUcs =
    " --quiet --set engine.density_scaling=10 --set material.preset=\"custom\""
    " --set sample.width=3e-3 --set sample.depth=3e-3 --set sample.height=6e-3"
    " --set contact.law=\"hertz_mindlin\" --set contact.shear_modulus=29e9"
    " --set contact.poisson_ratio=0.33 --set contact.friction=0.4 --set bond.modulus=8e9"
    " --set bond.tensile_strength=30e6 --set bond.cohesion=60e6 --set output.plot=false";

fs::path run_tiny(const fs::path& out, const std::string& extra) {
  const Result r = run("run --output " + out.string() + kTinyUcs + extra);
  EXPECT_EQ(r.code, 0) << r.out;
  return last_line(r.out);
}

// One column of history.csv.
std::vector<double> column(const fs::path& history, const std::string& name) {
  std::istringstream in(read(history));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> cols;
  std::stringstream header(line);
  for (std::string c; std::getline(header, c, ',');) cols.push_back(c);
  const auto at =
      static_cast<std::size_t>(std::find(cols.begin(), cols.end(), name) - cols.begin());
  std::vector<double> v;
  while (std::getline(in, line)) {
    std::stringstream row(line);
    std::string cell;
    for (std::size_t k = 0; k <= at && std::getline(row, cell, ','); ++k) {
    }
    v.push_back(std::stod(cell));
  }
  return v;
}

}  // namespace

// The same test at a constant speed and adaptively (up to 8 times the floor): under half the
// steps for the same peak, modulus and crack count (within the 2 % the loading's results must
// keep; measured on this sample: +0.3 % in the peak and the modulus), with the rows of the
// constant-speed run (a row every 200 paced steps) and the speed it used in history.csv. The
// figures are this packing's, made in the baseline instruction set on every machine: on this
// tiny sample (about ten grains across, its gauges on single grain layers) other packings move
// further (engine.seed 2 and 3, and this seed packed in x86-64-v3: the peak within 1.0 %, the
// modulus -6.7 %, +0.5 % and -11 %, the steps 0.50, 0.55 and 0.61 of the constant speed's);
// the larger samples' figures are in validation/adaptive-loading.
TEST(AdaptiveLoading, AWholeRunTakesUnderHalfTheStepsForTheSameResults) {
  const fs::path out = fs::temp_directory_path() / "breccia_adaptive_loading";
  fs::remove_all(out);
  const std::string pinned = " --set engine.threads=1 --set engine.instruction_set=\"baseline\"";
  const fs::path a = run_tiny(out / "constant", pinned + " --set test.adaptive_speed_ratio=1");
  const fs::path b = run_tiny(out / "adaptive", pinned + " --set test.adaptive_speed_ratio=8");
  const auto sa = nlohmann::json::parse(read(a / "summary.json"));
  const auto sb = nlohmann::json::parse(read(b / "summary.json"));
  const double steps_a = sa["steps"].get<double>(), steps_b = sb["steps"].get<double>();
  EXPECT_LT(steps_b, 0.55 * steps_a) << steps_a << " against " << steps_b;
  for (const char* key : {"peak_deviatoric_stress_pa", "youngs_modulus_pa"})
    EXPECT_NEAR(sb[key].get<double>() / sa[key].get<double>(), 1.0, 0.02) << key;
  const double cracks_a = column(a / "history.csv", "broken_bonds").back();
  EXPECT_GT(cracks_a, 100.0) << "the test must break bonds";
  EXPECT_TRUE(sb["quasi_static"]["ok"].get<bool>()) << sb["quasi_static"].dump();
  EXPECT_FALSE(sa.contains("adaptive_loading"));
  const auto& rule = sb["adaptive_loading"];
  EXPECT_EQ(rule["speed_ratio"], 8.0);
  EXPECT_NEAR(rule["largest_speed_m_per_s"].get<double>(), 8 * 0.03, 1e-12)
      << "the elastic phase reaches the ceiling";
  const std::vector<double> va = column(a / "history.csv", "platen_speed_m_per_s");
  const std::vector<double> vb = column(b / "history.csv", "platen_speed_m_per_s");
  EXPECT_NEAR(*std::max_element(va.begin(), va.end()), 0.03, 1e-12);
  EXPECT_NEAR(*std::max_element(vb.begin(), vb.end()), 0.24, 1e-3);
  EXPECT_NEAR(vb.back(), 0.03, 1e-12) << "at the floor after the peak";
  const double rows_a = static_cast<double>(va.size()), rows_b = static_cast<double>(vb.size());
  EXPECT_NEAR(rows_b / rows_a, 1.0, 0.05) << "rows every 200 steps at the floor's pace";
  fs::remove_all(out);
}

// The controller's state is the run's: stopped mid-run and resumed on another thread count, the
// adaptive run writes the uninterrupted run's history and crack catalogue byte for byte.
TEST(AdaptiveLoading, AResumedRunOnAnotherThreadCountIsTheUninterruptedRun) {
  const fs::path out = fs::temp_directory_path() / "breccia_adaptive_resume";
  fs::remove_all(out);
  const std::string adaptive = " --set test.adaptive_speed_ratio=8";
  const fs::path whole = run_tiny(out / "whole", adaptive + " --set engine.threads=1");
  const Result first = run("run --output " + (out / "split").string() + kTinyUcs + adaptive +
                           " --set engine.threads=2 --stop-at-step 5301");
  EXPECT_EQ(first.code, 130) << first.out;
  const fs::path split = last_line(first.out);
  const Result rest = run("resume --quiet --threads 1 " + split.string());
  ASSERT_EQ(rest.code, 0) << rest.out;
  for (const char* f : {"history.csv", "cracks.csv", "events.csv"})
    EXPECT_EQ(read(whole / f), read(split / f)) << f;
  fs::remove_all(out);
}

// The Brazilian test loads adaptively too: a 4 mm disc (1,067 grains) at 0.02 m/s up to 8 times
// that, stopped in its elastic phase at 0.6 % of the diameter, gets there in well under the time a
// constant speed needs (strain x D / 2 v after the ramp), at over five times the floor's speed.
TEST(AdaptiveLoading, TheBrazilianTestSpeedsUpWhileItsDiscIsElastic) {
  const fs::path out = fs::temp_directory_path() / "breccia_adaptive_brazilian";
  fs::remove_all(out);
  fs::create_directories(out);
  std::ofstream(out / "disc.toml")
      << "name = \"disc\"\n[material]\npreset = \"berea\"\n[sample]\nshape = \"cylinder\"\n"
         "diameter = 0.004\nheight = 0.002\nradius_min = 0.12e-3\nradius_max = 0.18e-3\n"
         "[test]\nkind = \"brazilian\"\nplaten_speed = 0.02\nadaptive_speed_ratio = 8\n"
         "max_strain = 0.006\n[output]\nplot = false\n";
  const Result r = run("run " + (out / "disc.toml").string() + " --quiet --threads 1 --output " +
                       (out / "runs").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const fs::path folder = last_line(r.out);
  const auto s = nlohmann::json::parse(read(folder / "summary.json"));
  EXPECT_EQ(s["stop_reason"], "reached the maximum strain 0.006");
  // The disc's kinetic energy (all of it counts in a Brazilian test) holds it below the ceiling.
  const double fastest = s["adaptive_loading"]["largest_speed_m_per_s"].get<double>();
  EXPECT_GT(fastest, 0.1);
  EXPECT_LE(fastest, 0.16);
  const std::vector<double> v = column(folder / "history.csv", "platen_speed_m_per_s");
  EXPECT_GT(*std::max_element(v.begin(), v.end()), 0.1);
  const double constant_time = 0.006 * 0.004 / (2 * 0.02);
  EXPECT_LT(s["simulated_time_s"].get<double>(), 0.6 * constant_time);
  fs::remove_all(out);
}

// The direct tension test's grips load adaptively too: the tiny prism pulled at 0.02 m/s up to 8
// times that breaks at the constant-speed run's strength (within the 2 % the loading must keep)
// in fewer steps.
TEST(AdaptiveLoading, TheDirectTensionTestKeepsItsStrengthInFewerSteps) {
  const fs::path out = fs::temp_directory_path() / "breccia_adaptive_tension";
  fs::remove_all(out);
  const std::string tension = " --set engine.threads=1 --set test.kind=\"direct_tension\"";
  const fs::path a = run_tiny(out / "constant", tension);
  const fs::path b = run_tiny(out / "adaptive", tension + " --set test.adaptive_speed_ratio=8");
  const auto sa = nlohmann::json::parse(read(a / "summary.json"));
  const auto sb = nlohmann::json::parse(read(b / "summary.json"));
  EXPECT_GT(sa["bonds_broken"].get<int>(), 10) << "the test must break bonds";
  EXPECT_NEAR(sb["tensile_strength_pa"].get<double>() / sa["tensile_strength_pa"].get<double>(),
              1.0, 0.02);
  EXPECT_LT(sb["steps"].get<double>(), 0.8 * sa["steps"].get<double>());
  EXPECT_GT(sb["adaptive_loading"]["largest_speed_m_per_s"].get<double>(), 0.04);
  const std::vector<double> v = column(b / "history.csv", "grip_speed_m_per_s");
  EXPECT_NEAR(v.back(), 0.02, 1e-12) << "at the floor once the sample breaks";
  fs::remove_all(out);
}

// Which loadings are adaptive: the UCS by default, not the confined tests; two-speed loading
// replaces it; strain-rate sweeps and calibrations load at a constant speed.
TEST(AdaptiveLoading, TheUcsLoadsAdaptivelyByDefaultAndSweepsOfTheRateDoNot) {
  EXPECT_EQ(UcsTest::Params{}.adaptive_speed_ratio, 8.0);
  EXPECT_EQ(TriaxialTest::Params{}.adaptive_speed_ratio, 1.0);
  EXPECT_EQ(BiaxialTest::Params{}.adaptive_speed_ratio, 1.0);
  UcsTest::Params two_speed;
  two_speed.elastic_speed = 0.1;
  EXPECT_EQ(platen_settings(platen_loading(two_speed)).adaptive_speed_ratio, 1.0);
  EXPECT_EQ(platen_settings(platen_loading(UcsTest::Params{})).adaptive_speed_ratio, 8.0);
  const auto ratio = [](const ExperimentSpec& s) {
    return std::get<UcsTest::Params>(s.test).adaptive_speed_ratio;
  };
  ExperimentSpec spec = default_experiment();
  EXPECT_EQ(ratio(spec), 8.0);
  set_platen_speed(spec, 0.1, "test");
  EXPECT_EQ(ratio(spec), 1.0) << "a strain-rate sweep's test";
  ExperimentSpec calibrated = default_experiment();
  load_at_constant_speed(calibrated);
  EXPECT_EQ(ratio(calibrated), 1.0) << "a calibration's test";
  EXPECT_EQ(std::get<UcsTest::Params>(calibrated.test).platen_speed, 0.03);
}
