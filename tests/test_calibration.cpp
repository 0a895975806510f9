// `breccia calibrate`: a tiny calibration recovers targets made by a known parameter set, resumes
// without re-running a test, and bad calibration files are refused before anything runs.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "breccia/calibrate/affine_elasticity.hpp"
#include "breccia/calibrate/calibrate.hpp"
#include "breccia/calibrate/laboratory.hpp"
#include "breccia/core/error.hpp"
#include "breccia/material/library.hpp"
#include "breccia/run/run.hpp"
#include "cli_harness.hpp"

namespace fs = std::filesystem;
using namespace breccia;

namespace {

// About 330 grains of 0.22-0.36 mm in a 3 x 3 x 6 mm prism: a UCS test takes a few seconds on
// one thread (one thread: ctest runs tests side by side, and OpenMP teams that share cores
// wait on each other).
std::string tiny_experiment(double modulus, double tensile) {
  return fmt::format(R"(
[experiment]
name = "tiny"
[experiment.engine]
threads = 1
local_damping = 0.7
density_scaling = 10.0
[experiment.material]
preset = "custom"
[experiment.sample]
width = 3e-3
depth = 3e-3
height = 6e-3
radius_min = 0.22e-3
radius_max = 0.36e-3
[experiment.contact]
law = "hertz_mindlin"
shear_modulus = 29e9
poisson_ratio = 0.33
friction = 0.4
wall_friction = 0.3
[experiment.bond]
modulus = {:.17g}
tensile_strength = {:.17g}
cohesion = {:.17g}
[experiment.test]
kind = "ucs"
platen_speed = 0.03
)",
                     modulus, tensile, 2 * tensile);
}

std::string tiny_calibration(double e_target, double ucs_target, double modulus, double tensile) {
  return fmt::format(R"([calibration]
name = "tiny"
trials_per_stage = 8
passes = 2
verify_seeds = []
[targets]
youngs_modulus = {{ value = {:.17g}, tolerance = 0.05 }}
uniaxial_strength = {{ value = {:.17g}, tolerance = 0.05 }}
[free]
"bond.modulus" = [1e9, 50e9]
"bond.tensile_strength" = [5e6, 300e6]
[tied]
"bond.cohesion" = {{ follows = "bond.tensile_strength", factor = 2.0 }}
)",
                     e_target, ucs_target) +
         tiny_experiment(modulus, tensile);
}

std::size_t lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::size_t n = 0;
  for (std::string l; std::getline(in, l);) n += !l.empty();
  return n;
}

}  // namespace

// The targets are what a known parameter set gives on the same sample; the calibration starts
// a factor 2 away in both parameters and must meet both targets (5 %) within its trial budget,
// and land near the known set (the map from (E_b, sigma_c) to (E, UCS) is close to diagonal,
// so the answer is close to unique: 20 % allows for the tolerance band and the weak coupling).
TEST(Calibration, TinyCalibrationRecoversTargetsOfAKnownParameterSet) {
  const fs::path dir = fs::temp_directory_path() / "breccia_calibration_tiny";
  fs::remove_all(dir);
  const double known_modulus = 6e9, known_tensile = 25e6;
  const CalibrationSpec truth =
      parse_calibration(tiny_calibration(1e9, 1e6, known_modulus, known_tensile), "truth.toml");
  Laboratory lab(truth, dir / "truth", [](const std::string&) {});
  const Measurement m = lab.measure("calibration", {known_modulus, known_tensile}, TestPlan{});
  ASSERT_TRUE(m.properties.count(Property::YoungsModulus));
  ASSERT_TRUE(m.properties.count(Property::UniaxialStrength));
  const double e = m.properties.at(Property::YoungsModulus);
  const double ucs = m.properties.at(Property::UniaxialStrength);

  const std::string text = tiny_calibration(e, ucs, 0.5 * known_modulus, 2.0 * known_tensile);
  const CalibrationSpec spec = parse_calibration(text, "tiny.toml");
  CalibrationOptions opt;
  opt.output_directory = (dir / "out").string();
  const CalibrationResult r = run_calibration(spec, opt);
  ASSERT_EQ(r.status, "complete");
  ASSERT_EQ(r.verdicts.size(), 2u);
  for (const auto& v : r.verdicts)
    EXPECT_TRUE(v.met) << info(v.target.property).key << " " << v.error;
  EXPECT_NEAR(r.values[0] / known_modulus, 1.0, 0.2);
  EXPECT_NEAR(r.values[1] / known_tensile, 1.0, 0.2);
  for (const char* f : {"convergence.csv", "material.toml", "record.json", "trials.jsonl",
                        "manifest.json", "calibration.toml"})
    EXPECT_TRUE(fs::exists(fs::path(r.folder) / f)) << f;
  const std::string fragment = breccia::testing::read(fs::path(r.folder) / "material.toml");
  EXPECT_NE(fragment.find("[bond]"), std::string::npos);
  EXPECT_EQ(fragment.find("wall_friction"), std::string::npos);  // the platens' property

  // Run again: every test is read back from trials.jsonl, the answer is the same.
  const std::size_t runs = lines_of(fs::path(r.folder) / "trials.jsonl");
  const CalibrationResult again = run_calibration(spec, opt);
  EXPECT_EQ(again.values, r.values);
  EXPECT_EQ(again.evaluations, r.evaluations);
  EXPECT_EQ(lines_of(fs::path(r.folder) / "trials.jsonl"), runs);

  // Other targets continue in that folder (the tests measured the same sample); another
  // sample or other start values may not.
  const CalibrationResult retargeted = run_calibration(
      parse_calibration(tiny_calibration(e, 1.001 * ucs, 0.5 * known_modulus, 2.0 * known_tensile),
                        "retargeted.toml"),
      opt);
  EXPECT_EQ(retargeted.status, "complete");
  EXPECT_THROW(
      run_calibration(parse_calibration(tiny_calibration(e, ucs, 4e9, 40e6), "other.toml"), opt),
      InputError);
  fs::remove_all(dir);
}

// A size correction meets the targets where the verification measures them. The targets are
// what a known parameter set gives on the verification's sample, which differs from the
// calibration sample by more than the tolerances (another packing with frictionless platens
// stands in for another size: both shift E and the UCS by several per cent, at a fraction of a
// larger sample's cost). The search meets them on the calibration sample and so misses them on
// the verification's (the first round says so); the correction shifts its aims and meets them
// there, near the known set. The search starts at the known set, which misses the targets on
// the calibration sample by the gap between the samples: it moves away, the correction back.
TEST(Calibration, SizeCorrectionMeetsTheTargetsAtTheVerificationSize) {
  const fs::path dir = fs::temp_directory_path() / "breccia_calibration_size";
  fs::remove_all(dir);
  const double known_modulus = 6e9, known_tensile = 25e6;
  auto with_correction = [](std::string text, int rounds) {
    text.replace(text.find("verify_seeds = []"), 17,
                 fmt::format("verify_seeds = [1]\nverify_set = [\"contact.wall_friction=0.0\"]\n"
                             "size_corrections = {}",
                             rounds));
    return text;
  };
  const CalibrationSpec truth = parse_calibration(
      with_correction(tiny_calibration(1e9, 1e6, known_modulus, known_tensile), 2), "truth.toml");
  Laboratory lab(truth, dir / "truth", [](const std::string&) {});
  const Measurement m = lab.measure("verify-1", {known_modulus, known_tensile}, TestPlan{});
  ASSERT_TRUE(m.properties.count(Property::YoungsModulus));
  ASSERT_TRUE(m.properties.count(Property::UniaxialStrength));
  const double e = m.properties.at(Property::YoungsModulus);
  const double ucs = m.properties.at(Property::UniaxialStrength);

  CalibrationOptions opt;
  opt.output_directory = (dir / "out").string();
  const CalibrationSpec spec = parse_calibration(
      with_correction(tiny_calibration(e, ucs, known_modulus, known_tensile), 2), "size.toml");
  const CalibrationResult r = run_calibration(spec, opt);
  ASSERT_EQ(r.status, "complete");
  for (const auto& v : r.verdicts)
    EXPECT_TRUE(v.met) << info(v.target.property).key << " " << v.error;
  const auto record =
      nlohmann::json::parse(breccia::testing::read(fs::path(r.folder) / "record.json"));
  const auto& rounds = record.at("size_corrections");
  ASSERT_GE(rounds.size(), 1u);
  EXPECT_FALSE(rounds[0].at("met").get<bool>())
      << "the search's parameters must miss at the verification's sample, or the test shows "
         "nothing";
  // The aims moved the way the gap says: where the verification's sample reads lower, the
  // search aims higher.
  for (const auto& t : rounds[0].at("targets")) {
    const double small = t.at("calibration_sample"), large = t.at("verification_mean");
    if (t.at("met_at_verification").get<bool>()) continue;
    EXPECT_EQ(t.at("next_aim").get<double>() > t.at("lab").get<double>(), small > large)
        << t.dump();
  }
  EXPECT_NEAR(r.values[0] / known_modulus, 1.0, 0.2);
  EXPECT_NEAR(r.values[1] / known_tensile, 1.0, 0.2);
  fs::remove_all(dir);
}

// With fit_seeds the search judges a trial on the mean over one packing per seed: the two
// packings differ, and measure_fit() returns their mean, reading both tests back.
TEST(Calibration, FitSeedsJudgeATrialOnTheMeanOverTheirPackings) {
  const fs::path dir = fs::temp_directory_path() / "breccia_calibration_fit_seeds";
  fs::remove_all(dir);
  std::string text = tiny_calibration(8e9, 60e6, 6e9, 25e6);
  text.replace(text.find("verify_seeds = []"), 17, "verify_seeds = []\nfit_seeds = [1, 2]");
  const CalibrationSpec spec = parse_calibration(text, "fit.toml");
  ASSERT_EQ(spec.fit_sets(), (std::vector<std::string>{"fit-1", "fit-2"}));
  Laboratory lab(spec, dir, [](const std::string&) {});
  const std::vector<double> values{6e9, 25e6};
  const Measurement one = lab.measure("fit-1", values, TestPlan{});
  const Measurement two = lab.measure("fit-2", values, TestPlan{});
  const Measurement mean = lab.measure_fit(values, TestPlan{});
  EXPECT_EQ(mean.new_runs, 0) << "both tests are read back";
  for (int seed : {1, 2})
    EXPECT_NE(lab.sample_report(fmt::format("fit-{}", seed), values)
                  .value("settings", std::string())
                  .find(fmt::format("\nseed = {}\n", seed)),
              std::string::npos)
        << "packed with seed " << seed;
  for (Property p : {Property::YoungsModulus, Property::UniaxialStrength}) {
    ASSERT_TRUE(one.properties.count(p) && two.properties.count(p));
    EXPECT_NE(one.properties.at(p), two.properties.at(p)) << "two packings, two results";
    EXPECT_EQ(mean.properties.at(p), (one.properties.at(p) + two.properties.at(p)) / 2.0);
  }
  EXPECT_EQ(mean.run_folders.size(), one.run_folders.size() + two.run_folders.size());
  fs::remove_all(dir);
}

// With calibration.tensile_test = "direct_tension" the tensile target is measured by pulling the
// compression prism apart in grips at the calibration's grip speed: no disc is packed, the
// Brazilian test does not run, and the property is the test's own sigma_t = F / A.
TEST(Calibration, DirectTensionMeasuresTheTensileTargetOnTheCompressionPrism) {
  const fs::path dir = fs::temp_directory_path() / "breccia_calibration_direct_tension";
  fs::remove_all(dir);
  std::string text = tiny_calibration(8e9, 60e6, 6e9, 25e6);
  text.replace(text.find("verify_seeds = []"), 17,
               "verify_seeds = []\ntensile_test = \"direct_tension\"\ngrip_speed = 0.015");
  text.replace(text.find("[free]"), 6, "tensile_strength = 10e6\n[free]");
  const CalibrationSpec spec = parse_calibration(text, "direct.toml");
  const TestPlan plan = tests_for(spec, CalibrationStage::Strength);
  ASSERT_TRUE(plan.tensile);
  Laboratory lab(spec, dir, [](const std::string&) {});
  const Measurement m = lab.measure("calibration", {6e9, 25e6}, plan);
  ASSERT_TRUE(m.tests.contains("direct_tension")) << m.tests.dump();
  EXPECT_FALSE(m.tests.contains("brazilian"));
  for (const auto& f : fs::directory_iterator(dir / "samples"))
    EXPECT_EQ(f.path().filename().string().find("-disc"), std::string::npos) << f.path();
  fs::path folder;
  for (const std::string& f : m.run_folders)
    if (f.find("direct_tension") != std::string::npos) folder = f;
  ASSERT_FALSE(folder.empty());
  const std::string resolved = breccia::testing::read(folder / "experiment.toml");
  EXPECT_NE(resolved.find("kind = \"direct_tension\""), std::string::npos);
  EXPECT_NE(resolved.find("platen_speed = 0.015"), std::string::npos);
  EXPECT_NE(resolved.find("-prism.geom\""), std::string::npos);
  const auto summary = nlohmann::json::parse(breccia::testing::read(folder / "summary.json"));
  ASSERT_TRUE(summary.value("peak_reached", false));
  ASSERT_TRUE(m.properties.count(Property::TensileStrength));
  EXPECT_EQ(m.properties.at(Property::TensileStrength),
            summary["tensile_strength_pa"].get<double>());
  fs::remove_all(dir);
}

// The bond installation gap is part of the sample's genesis: each gap value a trial asks for
// gets its own packing, bonded as a run with that gap bonds it, so a wider gap gives more bonds
// per grain and a stiffer rock (docs/physics.md §7.6: E grows with the coordination). The
// calibrated rock's fragment carries the gap, and a file that reads it back bonds the same way.
TEST(Calibration, FreeBondGapPacksAndBondsASampleForEachGap) {
  const fs::path dir = fs::temp_directory_path() / "breccia_calibration_gap";
  fs::remove_all(dir);
  std::string text = tiny_calibration(8e9, 60e6, 6e9, 25e6);
  text.replace(text.find("[tied]"), 6, "\"sample.bond_gap_tolerance\" = [1e-6, 1e-4]\n[tied]");
  const CalibrationSpec spec = parse_calibration(text, "gap.toml");
  ASSERT_EQ(spec.free.size(), 3u);
  EXPECT_EQ(spec.free[2].stage, CalibrationStage::Elastic);
  EXPECT_DOUBLE_EQ(spec.free[2].start, 5e-6);  // the experiment's default gap
  Laboratory lab(spec, dir, [](const std::string&) {});
  const std::vector<double> narrow{6e9, 25e6, 1e-6}, wide{6e9, 25e6, 6e-5};
  const Measurement a = lab.measure("calibration", narrow, TestPlan{});
  const Measurement b = lab.measure("calibration", wide, TestPlan{});
  const auto bonds = [&](const std::vector<double>& v) {
    return lab.sample_report("calibration", v).value("bonds", 0);
  };
  ASSERT_GT(bonds(narrow), 0);
  // A gap of 60 um is a fifth of the mean grain radius: many more neighbours are bonded.
  EXPECT_GT(bonds(wide), bonds(narrow) * 5 / 4);
  EXPECT_TRUE(fs::exists(dir / "samples" / "calibration-bond_gap_tolerance=1e-06-prism.geom"));
  EXPECT_TRUE(fs::exists(dir / "samples" / "calibration-bond_gap_tolerance=6e-05-prism.geom"));
  ASSERT_TRUE(a.properties.count(Property::YoungsModulus) &&
              b.properties.count(Property::YoungsModulus));
  EXPECT_GT(b.properties.at(Property::YoungsModulus),
            1.1 * a.properties.at(Property::YoungsModulus));

  const std::string fragment = material_fragment(spec, wide);
  EXPECT_NE(fragment.find("bond_gap_tolerance = 6"), std::string::npos) << fragment;
  const ExperimentSpec back = parse_experiment(fragment, "material.toml", {});
  EXPECT_DOUBLE_EQ(back.bond_gap_tolerance, 6e-5);
  // Without the gap free, the fragment leaves it to the experiment that uses the rock.
  const CalibrationSpec fixed = parse_calibration(tiny_calibration(8e9, 60e6, 6e9, 25e6), "f.toml");
  EXPECT_EQ(material_fragment(fixed, {6e9, 25e6}).find("bond_gap_tolerance"), std::string::npos);
  fs::remove_all(dir);
}

// A file's [sample] keys override its preset's, the gap included (a preset applies first).
TEST(MaterialLibrary, AFilesBondGapOverridesThePresets) {
  const ExperimentSpec s = parse_experiment(
      "[material]\npreset = \"berea\"\n[sample]\nbond_gap_tolerance = 2e-5\n", "gap.toml", {});
  EXPECT_DOUBLE_EQ(s.bond_gap_tolerance, 2e-5);
  EXPECT_DOUBLE_EQ(
      parse_experiment("[material]\npreset = \"berea\"\n", "p.toml", {}).bond_gap_tolerance,
      ExperimentSpec{}.bond_gap_tolerance);
}

namespace {

struct BadCalibration {
  const char* name;
  std::string text;
  std::vector<std::string> needles;
};

std::string with_experiment(const std::string& head) {
  return head + tiny_experiment(8e9, 30e6);
}

std::vector<BadCalibration> bad_calibrations() {
  const std::string e_target = "[targets]\nyoungs_modulus = 8e9\n";
  const std::string free_e = "[free]\n\"bond.modulus\" = [1e9, 50e9]\n";
  const std::string tensile_target = "[targets]\nyoungs_modulus = 8e9\ntensile_strength = 5e6\n";
  return {
      {"UnknownTarget",
       with_experiment("[targets]\nyoungs = 8e9\n" + free_e),
       {"bad.toml:2", "targets.youngs", "unknown target", "youngs_modulus"}},
      {"LowerAboveUpper",
       with_experiment(e_target + "[free]\n\"bond.modulus\" = [5e9, 1e9]\n"),
       {"bad.toml:4", "free.\"bond.modulus\"", "impossible bounds"}},
      {"BoundTheLawRefuses",
       with_experiment("[targets]\nfriction_angle_deg = 30\n[calibration]\nconfining_stresses = "
                       "[5e6]\n[free]\n\"contact.friction\" = { lower = -1, upper = 1, scale = "
                       "\"linear\" }\n"),
       {"bad.toml:6", "contact.friction", "bound not accepted"}},
      {"LogScaleThroughZero",
       with_experiment("[targets]\nfriction_angle_deg = 30\n[calibration]\nconfining_stresses = "
                       "[5e6]\n[free]\n\"contact.friction\" = { lower = 0, upper = 1, scale = "
                       "\"log\" }\n"),
       {"bad.toml:6", "log-scale parameter needs bounds above 0"}},
      {"StartOutsideBounds",
       with_experiment(e_target + "[free]\n\"bond.modulus\" = [20e9, 50e9]\n"),
       {"bad.toml:4", "start value 8000000000", "outside the bounds"}},
      {"TargetTheTestsCannotMeasure",
       with_experiment("[targets]\ncohesion = 30e6\n[free]\n\"contact.friction\" = { lower = "
                       "0.1, upper = 1, scale = \"linear\" }\n"),
       {"bad.toml:2", "targets.cohesion", "without triaxial tests", "confining_stresses"}},
      {"FreeParameterWithoutATarget",
       with_experiment(e_target + free_e +
                       "\"contact.friction\" = { lower = 0.1, upper = 1, "
                       "scale = \"linear\" }\n"),
       {"bad.toml:5", "free.\"contact.friction\"", "friction stage", "none of that stage"}},
      {"NotAMicroParameter",
       with_experiment(e_target + "[free]\n\"sample.width\" = [1e-3, 1e-2]\n"),
       {"bad.toml:4", "not a micro-parameter", "bond.modulus"}},
      {"TiedToAFixedKey",
       with_experiment(e_target + free_e +
                       "[tied]\n\"bond.cohesion\" = { follows = \"bond.tensile_strength\" }\n"),
       {"bad.toml:6", "must name a free parameter"}},
      {"ZeroTolerance",
       with_experiment("[targets]\nyoungs_modulus = { value = 8e9, tolerance = 0 }\n" + free_e),
       {"bad.toml:2", "tolerance", "above 0"}},
      {"FrictionAngleOutOfRange",
       with_experiment("[targets]\nfriction_angle_deg = 95\n[calibration]\nconfining_stresses = "
                       "[5e6]\n[free]\n\"contact.friction\" = { lower = 0.1, upper = 1, scale = "
                       "\"linear\" }\n"),
       {"bad.toml:2", "friction_angle_deg", "0 < phi < 90"}},
      {"NoFreeParameter", with_experiment(e_target), {"[free]", "at least one free parameter"}},
      {"UnknownTable",
       with_experiment(e_target + free_e + "[target]\nx = 1\n"),
       {"bad.toml:5", "unknown table", "[targets]"}},
      {"BadExperimentKey",
       e_target + free_e + "[experiment.sample]\nwidth = -1e-3\n",
       {"bad.toml:6", "sample.width", "-0.001"}},
      {"NegativeConfiningStress",
       with_experiment(e_target + free_e + "[calibration]\nconfining_stresses = [-5e6]\n"),
       {"bad.toml:6", "calibration.confining_stresses", "above 0"}},
      {"FitSeedTwice",
       with_experiment(e_target + free_e + "[calibration]\nfit_seeds = [4, 4]\n"),
       {"bad.toml:6", "calibration.fit_seeds", "seed 4 twice"}},
      {"NegativeFitSeed",
       with_experiment(e_target + free_e + "[calibration]\nfit_seeds = [-1]\n"),
       {"bad.toml:6", "calibration.fit_seeds", "allowed: 0 to"}},
      {"AimAboveTheTolerance",
       with_experiment(e_target + free_e + "[calibration]\naim = 1.5\n"),
       {"bad.toml:6", "calibration.aim", "1.5", "from 0.1 to 1"}},
      {"TooManySizeCorrections",
       with_experiment(e_target + free_e + "[calibration]\nsize_corrections = 9\n"),
       {"bad.toml:6", "calibration.size_corrections", "9"}},
      {"UnknownTensileTest",
       with_experiment(e_target + free_e + "[calibration]\ntensile_test = \"pull\"\n"),
       {"bad.toml:6", "calibration.tensile_test", "pull", "direct_tension"}},
      {"GripSpeedOfATestThatDoesNotRun",
       with_experiment(tensile_target + free_e + "[calibration]\ngrip_speed = 0.01\n"),
       {"bad.toml:7", "calibration.grip_speed", "0.01", "direct tension test, which does not run",
        "\"brazilian\""}},
      {"DiscOfATestThatDoesNotRun",
       with_experiment(tensile_target + free_e +
                       "[calibration]\ntensile_test = \"direct_tension\"\nbrazilian_diameter = "
                       "0.01\n"),
       {"bad.toml:8", "calibration.brazilian_diameter", "Brazilian test, which does not run"}},
      {"TensileTestWithoutATensileTarget",
       with_experiment(e_target + free_e +
                       "[calibration]\ntensile_test = \"direct_tension\"\ngrip_speed = 0.01\n"),
       {"bad.toml:6", "calibration.tensile_test", "runs only for a targets.tensile_strength"}},
      {"ConfinementWithoutAnEnvelopeTarget",
       with_experiment(e_target + free_e + "[calibration]\nconfining_stresses = [5e6]\n"),
       {"bad.toml:6", "calibration.confining_stresses", "targets.friction_angle_deg"}},
      {"GripsNotMoving",
       with_experiment(e_target + free_e +
                       "[calibration]\ntensile_test = \"direct_tension\"\ngrip_speed = 0\n"),
       {"bad.toml:7", "calibration.grip_speed", "above 0 m/s"}},
      {"SizeCorrectionWithoutVerification",
       with_experiment(e_target + free_e +
                       "[calibration]\nsize_corrections = 1\nverify_seeds = []\n"),
       {"calibration.size_corrections", "verify_seeds"}},
  };
}

class BadCalibrationFile : public ::testing::TestWithParam<BadCalibration> {};

}  // namespace

// Refused with file, line, key and what is allowed; the command exits 2 and writes nothing.
TEST_P(BadCalibrationFile, IsRefusedBeforeAnyRunStarts) {
  const BadCalibration& c = GetParam();
  try {
    (void)parse_calibration(c.text, "bad.toml");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    for (const auto& n : c.needles)
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what() << "\nlacks " << n;
  }
  const fs::path dir = fs::temp_directory_path() / ("breccia_badcal_" + std::string(c.name));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "bad.toml") << c.text;
  const auto r = breccia::testing::run("calibrate '" + (dir / "bad.toml").string() +
                                       "' --output '" + (dir / "out").string() + "'");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("error: "), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "out")) << r.out;
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Cases, BadCalibrationFile, ::testing::ValuesIn(bad_calibrations()),
                         [](const ::testing::TestParamInfo<BadCalibration>& i) {
                           return std::string(i.param.name);
                         });

// Every preset ships with the record of the calibration that made it (targets with sources,
// achieved mean and spread over at least three packing seeds, the command); one without is
// refused here.
TEST(MaterialLibrary, EveryPresetShipsWithItsCalibrationRecord) {
  ASSERT_FALSE(embedded_materials().empty());
  for (const auto& m : embedded_materials()) {
    const auto r = nlohmann::json::parse(m.record, nullptr, false);
    ASSERT_TRUE(r.is_object()) << m.name << ": no calibration record (materials/" << m.name
                               << "/record.json)";
    EXPECT_EQ(r.value("name", ""), std::string(m.name));
    EXPECT_NE(r.value("command", "").find(" calibrate "), std::string::npos) << m.name;
    EXPECT_FALSE(r.value("calibration_file", "").empty()) << m.name;
    EXPECT_GE(r.value("verify_seeds", nlohmann::json::array()).size(), 3u) << m.name;
    ASSERT_TRUE(r.contains("verdicts") && !r["verdicts"].empty()) << m.name;
    for (const auto& v : r["verdicts"]) {
      EXPECT_TRUE(v["mean"].is_number()) << m.name << " " << v.dump();
      EXPECT_FALSE(v.value("source", "").empty()) << m.name << " " << v.dump();
    }
  }
  // ... and passes the honesty checks (both crack modes, no crushed end).
  for (const auto& m : embedded_materials())
    for (const auto& f : honesty_failures(m)) ADD_FAILURE() << m.name << ": " << f;
  // The built-in default experiment uses a calibrated rock.
  const ExperimentSpec d = default_experiment();
  bool found = false;
  for (const auto& m : embedded_materials()) found |= m.name == d.preset;
  EXPECT_TRUE(found) << d.preset;
}

// The honesty checks catch what they name: a UCS without shear cracks, a crushed end, and a
// triaxial test without shear cracks; a record that meets them passes, whatever its Brazilian
// disc's crack modes.
TEST(MaterialLibrary, HonestyChecksCatchMissingShearCracksAndCrushedEnds) {
  auto record = [](double ucs_shear, double ucs_end, double triaxial_shear) {
    nlohmann::json seed = {
        {"tests",
         {{"ucs", {{"shear_crack_fraction", ucs_shear}, {"largest_end_quarter_share", ucs_end}}},
          {"triaxial-10MPa",
           {{"shear_crack_fraction", triaxial_shear}, {"largest_end_quarter_share", 0.3}}}}}};
    return nlohmann::json{{"verification", {seed, seed, seed}}}.dump();
  };
  const std::string good = record(0.05, 0.3, 0.2), no_shear = record(0.0004, 0.3, 0.2),
                    crushed = record(0.05, 0.55, 0.2), triaxial = record(0.05, 0.3, 0.005);
  EXPECT_TRUE(honesty_failures({"good", "", good}).empty());
  const auto a = honesty_failures({"no_shear", "", no_shear});
  ASSERT_EQ(a.size(), 1u);
  EXPECT_NE(a[0].find("ucs: shear share of the microcracks 0.04 %"), std::string::npos) << a[0];
  const auto b = honesty_failures({"crushed", "", crushed});
  ASSERT_EQ(b.size(), 1u);
  EXPECT_NE(b[0].find("55 % of the cracks in one end quarter"), std::string::npos) << b[0];
  const auto c = honesty_failures({"triaxial", "", triaxial});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_NE(c[0].find("triaxial-10MPa"), std::string::npos) << c[0];
  EXPECT_FALSE(honesty_failures({"empty", "", "{}"}).empty());
  // A Brazilian disc splits in tension: a record whose disc broke no bond in shear passes.
  auto with_disc = nlohmann::json::parse(good);
  for (auto& seed : with_disc["verification"])
    seed["tests"]["brazilian"] = {{"shear_crack_fraction", 0.0},
                                  {"largest_end_quarter_share", 0.5}};
  EXPECT_TRUE(honesty_failures({"disc", "", with_disc.dump()}).empty());
}

// Each preset loads, validates and runs a tiny UCS (an FCC block of 64 grains, its masses scaled
// so that it takes about a third of the steps: a second or so).
TEST(MaterialLibrary, EveryPresetRunsATinyUcs) {
  const fs::path dir = fs::temp_directory_path() / "breccia_presets";
  fs::remove_all(dir);
  for (const auto& m : embedded_materials()) {
    // A 2D preset (its record says so) runs on a hexagonal block of planar spheres.
    const bool planar = nlohmann::json::parse(m.record).value("dimension", 3) == 2;
    const ExperimentSpec spec = parse_experiment(
        fmt::format("[material]\npreset = \"{}\"\n[sample]\nsource = \"lattice\"\n"
                    "cells = {}\n[engine]\nthreads = 1\ndimension = {}\ndensity_scaling = 100\n"
                    "[output]\nplot = false\nsnapshot_strain_interval = 0\ndirectory = \"{}\"\n",
                    m.name, planar ? "[6, 10, 1]" : "[2, 2, 4]", planar ? 2 : 3, dir.string()),
        "preset-test", {});
    EXPECT_EQ(spec.preset, std::string(m.name));
    RunOptions opt;
    const RunResult r = run_experiment(spec, opt);
    EXPECT_EQ(r.status, "complete") << m.name << ": " << r.stop_reason;
    EXPECT_GT(r.peak_stress, 0.0) << m.name;
  }
  fs::remove_all(dir);
}

// docs/materials.md is generated from the records: regenerate it with
// `build/breccia materials --output docs/materials.md` when a preset changes.
TEST(MaterialLibrary, DocsTableIsUpToDate) {
  EXPECT_EQ(breccia::testing::read(fs::path(BRECCIA_SOURCE_DIR) / "docs" / "materials.md"),
            materials_docs());
}

// docs/calibration.md is generated from the tables that validate calibration files.
TEST(Calibration, DocsAreUpToDate) {
  EXPECT_EQ(breccia::testing::read(fs::path(BRECCIA_SOURCE_DIR) / "docs" / "calibration.md"),
            calibration_docs());
}

namespace {

// Lame constants of the uniform-strain average of kn n n n n + ks (d n n - n n n n) over evenly
// spread contact normals (a Fibonacci sphere, or a circle in 2D), up to a common factor.
struct Lame {
  double lambda, mu;
};
Lame averaged_contact_stiffness(int dimension, double kn, double ks) {
  const int n = 20000;
  double c1111 = 0.0, c1122 = 0.0;
  for (int i = 0; i < n; ++i) {
    double n1, n2;
    if (dimension == 2) {
      const double a = 2.0 * M_PI * (i + 0.5) / n;
      n1 = std::cos(a);
      n2 = std::sin(a);
    } else {
      const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z);
      const double a = M_PI * (3.0 - std::sqrt(5.0)) * i;
      n1 = r * std::cos(a);
      n2 = r * std::sin(a);
    }
    c1111 += kn * std::pow(n1, 4) + ks * (n1 * n1 - std::pow(n1, 4));
    c1122 += (kn - ks) * n1 * n1 * n2 * n2;
  }
  return {c1122 / n, 0.5 * (c1111 - c1122) / n};
}

}  // namespace

// The scaling law the elastic stage uses for nu is the affine average itself, derived here by
// summing the contact stiffness over directions; 1e-3 is far above the quadrature error of 20,000
// directions (about 1e-7) and far below the effect of kappa (0.13 to 0.22 for kappa 2.5 to 10).
TEST(AffineElasticity, MatchesTheDirectionAverageOfTheContactStiffness) {
  for (int dim : {2, 3}) {
    const AffineElasticity affine{dim};
    auto measured = [&](double kappa) {
      const Lame l = averaged_contact_stiffness(dim, 1.0, 1.0 / kappa);
      const double nu =
          dim == 2 ? l.lambda / (l.lambda + 2 * l.mu) : l.lambda / (2 * (l.lambda + l.mu));
      const double e = dim == 2 ? 4 * l.mu * (l.lambda + l.mu) / (l.lambda + 2 * l.mu)
                                : l.mu * (3 * l.lambda + 2 * l.mu) / (l.lambda + l.mu);
      return std::pair{nu, e};
    };
    for (double kappa : {1.0, 2.5, 10.0}) {
      EXPECT_NEAR(measured(kappa).first, affine.poisson(kappa), 1e-3) << dim << "D " << kappa;
      EXPECT_NEAR(affine.stiffness_ratio(affine.poisson(kappa)), kappa, 1e-9 * kappa);
    }
    EXPECT_NEAR(measured(10.0).second / measured(2.5).second,
                affine.modulus_factor(10.0) / affine.modulus_factor(2.5), 1e-3);
    EXPECT_NEAR(affine.poisson(1e9), affine.poisson_limit(), 1e-6);
    EXPECT_TRUE(std::isinf(affine.stiffness_ratio(affine.poisson_limit())));
  }
  EXPECT_NEAR(AffineElasticity{3}.poisson_limit(), 0.25, 1e-15);
  EXPECT_NEAR(AffineElasticity{2}.poisson_limit(), 1.0 / 3.0, 1e-15);
}
