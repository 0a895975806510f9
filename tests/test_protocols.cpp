// The lab-test registry (every registered test documented and run on a tiny sample) and the
// Brazilian test: sigma_t from the platen force by the ISRM formula, a split along the loaded
// diameter, bad discs refused.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "breccia/core/error.hpp"
#include "breccia/spec/experiment.hpp"
#include "cli_harness.hpp"

namespace fs = std::filesystem;
using namespace breccia;
using namespace breccia::testing;

namespace {

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  std::string cell;
  while (std::getline(in, cell, ',')) out.push_back(cell);
  return out;
}

// One column of a run's history.csv, row by row (empty when the column is missing).
std::vector<double> history_column(const fs::path& folder, const std::string& name) {
  std::ifstream in(folder / "history.csv");
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split_csv(line);
  const auto col =
      static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  std::vector<double> out;
  if (col == header.size()) return out;
  while (std::getline(in, line)) out.push_back(std::stod(split_csv(line).at(col)));
  return out;
}

// A tiny experiment of each registered test kind: about 300-850 grains, fast loading.
std::string tiny_experiment(std::string_view kind) {
  const std::string common =
      "[output]\nplot = false\nsnapshot_strain_interval = 0\n"
      "[engine]\ndensity_scaling = 100\n";
  if (kind == "biaxial")
    return common +
           "dimension = 2\n[contact]\nlaw = \"linear\"\nmodulus = 8e9\nfriction = 0.4\n"
           "[sample]\nshape = \"rectangle\"\nwidth = 0.003\nheight = 0.006\nthickness = 2e-4\n"
           "radius_min = 0.1e-3\nradius_max = 0.15e-3\nporosity = 0.16\n"
           "[test]\nkind = \"biaxial\"\nplaten_speed = 0.1\nmax_strain = 0.003\n"
           "confining_stress = 1e6\n";
  // The Brazilian disc keeps the bonds it was written for (c = 10 T: every early crack
  // tensile), whatever the default preset: the test checks the protocol, not the rock.
  if (kind == "brazilian")
    return common +
           "[material]\npreset = \"custom\"\n[contact]\nlaw = \"hertz_mindlin\"\n"
           "shear_modulus = 29e9\npoisson_ratio = 0.33\nfriction = 0.4\n"
           "[bond]\nmodulus = 8e9\ntensile_strength = 30e6\ncohesion = 300e6\n"
           "[sample]\nshape = \"cylinder\"\ndiameter = 0.004\nheight = 0.002\n"
           "radius_min = 0.12e-3\nradius_max = 0.2e-3\n"
           "[test]\nkind = \"brazilian\"\nplaten_speed = 0.1\n";
  // A ball of 1 mm at 20 m/s on a slab 2 x 3 x 3 grains thick; no mass scaling (refused).
  if (kind == "impact")
    return "[output]\nplot = false\nsnapshot_strain_interval = 0\n"
           "[engine]\ndensity_scaling = 1\nlocal_damping = 0\n"
           "[sample]\nshape = \"slab\"\nwidth = 0.004\ndepth = 0.004\nslab_thickness = 0.0015\n"
           "radius_min = 0.2e-3\nradius_max = 0.3e-3\n"
           "[test]\nkind = \"impact\"\nprojectile_diameter = 1e-3\nimpact_speed = 20\n"
           "standoff = 0.02e-3\nduration = 6e-6\n";
  // The bottom face of a 4 x 4 x 1.5 mm slab shaken along its normal: 3 cycles at 100 kHz.
  if (kind == "vibration")
    return "[output]\nplot = false\nsnapshot_strain_interval = 0\n"
           "[engine]\ndensity_scaling = 1\n"
           "[sample]\nshape = \"slab\"\nwidth = 0.004\ndepth = 0.004\nslab_thickness = 0.0015\n"
           "radius_min = 0.2e-3\nradius_max = 0.3e-3\n"
           "[test]\nkind = \"vibration\"\nfrequency = 1e5\namplitude = 5e-6\ncycles = 3\n"
           "grip_length = 0\nramp_cycles = 0\n";
  // A plate at 1 MPa slid 0.1 mm over a 4 x 4 x 1.5 mm slab held at its base.
  if (kind == "abrasion")
    return common +
           "[sample]\nshape = \"slab\"\nwidth = 0.004\ndepth = 0.004\nslab_thickness = 0.0015\n"
           "radius_min = 0.2e-3\nradius_max = 0.3e-3\n"
           "[test]\nkind = \"abrasion\"\nnormal_stress = 1e6\nsliding_speed = 0.1\n"
           "slide_distance = 0.1e-3\n";
  // A slab 8 x 3 x 1.5 mm, 3 mm in the vice, pushed by a rod 1 mm from its free end.
  if (kind == "cantilever")
    return "[output]\nplot = false\nsnapshot_strain_interval = 0\nhistory_interval = 50\n"
           "[engine]\ndensity_scaling = 100\n"
           "[sample]\nshape = \"slab\"\nwidth = 0.008\ndepth = 0.003\nslab_thickness = 0.0015\n"
           "radius_min = 0.2e-3\nradius_max = 0.3e-3\n"
           "[test]\nkind = \"cantilever\"\nclamp_length = 3e-3\nload_distance = 1e-3\n"
           "nose_radius = 0.5e-3\npusher_speed = 0.1\nmax_deflection = 0.2e-3\n";
  std::string s = common +
                  "[sample]\nwidth = 0.0024\ndepth = 0.0024\nheight = 0.0048\n"
                  "radius_min = 0.2e-3\nradius_max = 0.3e-3\n"
                  "[test]\nkind = \"" +
                  std::string(kind) + "\"\nplaten_speed = 0.1\nmax_strain = 0.003\n";
  if (kind == "triaxial") s += "confining_stress = 1e6\n";
  return s;
}

// Runs an experiment file through the command; the run folder's summary (and the folder).
nlohmann::json run_file(const fs::path& dir, const std::string& name, const std::string& toml,
                        fs::path* folder_out = nullptr) {
  fs::create_directories(dir);
  const fs::path file = dir / (name + ".toml");
  std::ofstream(file) << toml;
  const Result r = run("run --quiet --output " + (dir / "runs").string() + " " + file.string());
  EXPECT_EQ(r.code, 0) << r.out;
  const fs::path folder = last_line(r.out);
  if (folder_out) *folder_out = folder;
  return nlohmann::json::parse(read(folder / "summary.json"));
}

// A fresh folder `dir` holding tiny.toml, the tiny experiment of `kind` named "tiny" (sweeps).
fs::path tiny_file(const fs::path& dir, std::string_view kind) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path file = dir / "tiny.toml";
  std::ofstream(file) << "name = \"tiny\"\n" + tiny_experiment(kind);
  return file;
}

}  // namespace

// Every registered test is documented, runs, and continues exactly from a checkpoint.
TEST(Protocols, EveryRegisteredTestIsDocumentedRunsATinyCaseAndResumesExactly) {
  const std::string docs = experiment_docs();
  const fs::path dir = fs::temp_directory_path() / "breccia_protocols";
  fs::remove_all(dir);
  std::vector<std::string> kinds;
  for_each_lab_test([&]<class T>() { kinds.emplace_back(T::name); });
  EXPECT_EQ(kinds,
            (std::vector<std::string>{"ucs", "triaxial", "biaxial", "brazilian", "direct_tension",
                                      "impact", "cantilever", "vibration", "abrasion"}));
  for_each_lab_test([&]<class T>() {
    const std::string name(T::name);
    EXPECT_NE(docs.find("`test` kind `\"" + name + "\"`"), std::string::npos) << name;
    for (const auto& f : T::fields())
      EXPECT_NE(docs.find("| `" + std::string(f.key) + "` |"), std::string::npos) << f.key;
    fs::path whole;
    const nlohmann::json s = run_file(dir, name, tiny_experiment(T::name), &whole);
    EXPECT_EQ(s["test_kind"], name);
    EXPECT_EQ(s["status"], "complete") << name;
    EXPECT_GT(s["steps"].get<int>(), 100) << name;
    // Stopped halfway and resumed from its checkpoint (the test's own save_state and restore),
    // it writes the uninterrupted run's rows and cracks byte for byte and reports the same.
    const Result stopped =
        run(fmt::format("run --quiet --output {} {} --stop-at-step {}", (dir / "split").string(),
                        (dir / (name + ".toml")).string(), s["steps"].get<int>() / 2));
    ASSERT_EQ(stopped.code, 130) << name << ": " << stopped.out;
    const fs::path split = last_line(stopped.out);
    const Result resumed = run("resume --quiet " + split.string());
    ASSERT_EQ(resumed.code, 0) << name << ": " << resumed.out;
    EXPECT_EQ(read(whole / "history.csv"), read(split / "history.csv")) << name;
    EXPECT_EQ(read(whole / "cracks.csv"), read(split / "cracks.csv")) << name;
    const auto r = nlohmann::json::parse(read(split / "summary.json"));
    for (const std::string& key :
         std::vector<std::string>{"steps", "energy", "bonds_broken", "crack_pattern", name})
      EXPECT_EQ(s.value(key, nlohmann::json()), r.value(key, nlohmann::json())) << name << key;
    // The resolved experiment names the test and reads back as the same kind.
    const ExperimentSpec spec = parse_experiment(tiny_experiment(T::name), "tiny", {});
    EXPECT_EQ(spec.test_kind(), name);
    EXPECT_NE(to_toml(spec).find("kind = \"" + name + "\""), std::string::npos);
  });
  fs::remove_all(dir);
}

TEST(Impact, TheBallsLostEnergyAndMomentumGoIntoTheSlab) {
  // The tiny slab on its floor, hit at 20 m/s by a 1 mm ball of 11,000 kg/m^3, undamped.
  const fs::path dir = fs::temp_directory_path() / "breccia_impact";
  fs::remove_all(dir);
  fs::path folder;
  const nlohmann::json s = run_file(dir, "impact", tiny_experiment("impact"), &folder);
  ASSERT_EQ(s["status"], "complete");
  const nlohmann::json& im = s["impact"];
  const nlohmann::json& ball = im["projectile"];
  // Hand numbers: m = 11000 x (4/3) pi (0.5 mm)^3 = 5.760e-6 kg; E = m v^2 / 2 = 1.152e-3 J.
  const double m = 11000.0 * 4.0 / 3.0 * std::numbers::pi * std::pow(0.5e-3, 3);
  EXPECT_NEAR(ball["mass_kg"].get<double>(), m, 1e-12 * m);
  EXPECT_NEAR(ball["kinetic_energy_in_j"].get<double>(), 0.5 * m * 400.0, 1e-12);
  EXPECT_NEAR(ball["momentum_in_kg_m_s"].get<double>(), m * 20.0, 1e-15);
  // It cannot touch before its 0.02 mm flight to the slab's highest point is over (1 us at
  // 20 m/s); the grains under its axis lie at most one grain diameter (0.6 mm) lower.
  const double first = im["first_contact_s"].get<double>();
  EXPECT_GE(first, 1e-6 - s["time_step_s"].get<double>());
  EXPECT_LE(first, (0.02e-3 + 0.6e-3) / 20.0);
  EXPECT_GT(im["contact_time_s"].get<double>(), 0.0);
  EXPECT_GT(im["max_indentation_m"].get<double>(), 0.0);
  // Energy: what the ball lost is the work its contacts did, to the leapfrog's O(dt) at the
  // contact's start and end (below 1e-3 of the energy at about 100 steps per contact).
  const double lost =
      ball["kinetic_energy_in_j"].get<double>() - ball["kinetic_energy_out_j"].get<double>();
  EXPECT_GT(lost, 0.0);
  EXPECT_NEAR(ball["work_on_slab_j"].get<double>(), lost, 1e-3 * lost);
  // The slab's own ledger closes with that work as its input (the floor does none: it stays).
  EXPECT_NEAR(s["energy"]["boundary_work_j"].get<double>(), ball["work_on_slab_j"].get<double>(),
              1e-9);
  EXPECT_LT(std::abs(s["energy"]["residual_relative"].get<double>()), 1e-2);
  // The history has the ball's columns, its velocity starting at -20 m/s (down the z axis).
  const std::string history = read(folder / "history.csv");
  EXPECT_NE(history.find(",projectile_velocity_m_s,"), std::string::npos);
  EXPECT_NE(history.find(",-20,"), std::string::npos);
  // Not a stress-strain test: no moduli, its own headline instead.
  EXPECT_FALSE(s.contains("youngs_modulus_pa"));
  EXPECT_FALSE(im["headline"].empty());
  fs::remove_all(dir);
}

TEST(Cantilever, TheSlabBreaksAtTheVicesEdgeUnderTheBendingStressOfBeamTheory) {
  const fs::path dir = fs::temp_directory_path() / "breccia_cantilever";
  fs::remove_all(dir);
  fs::path folder;
  const nlohmann::json s = run_file(dir, "cantilever", tiny_experiment("cantilever"), &folder);
  ASSERT_EQ(s["status"], "complete");
  const nlohmann::json& c = s["cantilever"];
  // It broke: the force fell from its peak once bonds had broken.
  EXPECT_NE(s["stop_reason"].get<std::string>().find("fell below"), std::string::npos);
  const double f = c["max_force_n"].get<double>(), L = c["lever_m"].get<double>();
  const double b = c["slab_width_m"].get<double>(), h = c["slab_thickness_m"].get<double>();
  EXPECT_GT(f, 0.0);
  // The lever is the slab's length less the vice and the rod's distance from the end (8 - 3 - 1
  // mm, to a grain's roughness of the ends); the strength is the root's bending stress.
  EXPECT_NEAR(L, 4e-3, 0.3e-3);
  EXPECT_NEAR(c["flexural_strength_pa"].get<double>(), 6.0 * f * L / (b * h * h), 1e-9 * f);
  // The bending moment is largest at the vice's edge: most cracks lie in the lever's first
  // third there (cracks spread along the slab would put about a sixth of them there).
  EXPECT_GT(c["cracks_near_root_share"].get<double>(), 0.6);
  // The rod's and the vice's forces are columns of the history.
  const std::string history = read(folder / "history.csv");
  EXPECT_NE(history.find(",rod_travel_m,rod_force_n,vice_force_n"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Vibration, TheShakenFaceFollowsTheSineAndTheShakerWorkFeedsTheSlab) {
  const fs::path dir = fs::temp_directory_path() / "breccia_vibration";
  fs::remove_all(dir);
  fs::path folder;
  const nlohmann::json s = run_file(dir, "vibration", tiny_experiment("vibration"), &folder);
  ASSERT_EQ(s["status"], "complete");
  const nlohmann::json& v = s["vibration"];
  // Hand numbers: A = 5 um at f = 100 kHz: peak speed A 2 pi f = 3.14 m/s, acceleration
  // A (2 pi f)^2 = 1.97e6 m/s^2.
  EXPECT_NEAR(v["peak_velocity_m_s"].get<double>(), 5e-6 * 2 * std::numbers::pi * 1e5, 1e-12);
  EXPECT_NEAR(v["peak_acceleration_m_s2"].get<double>(),
              5e-6 * std::pow(2 * std::numbers::pi * 1e5, 2), 1e-3);
  // The face's displacement is A sin(2 pi f t) at every step; the rows (40 a cycle) sample the
  // sine at phases no further than 2 pi / 80 from its crest: at least A cos(pi / 40).
  const double followed = v["amplitude_followed_m"].get<double>();
  EXPECT_LE(followed, 5e-6 * (1 + 1e-9));
  EXPECT_GE(followed, 5e-6 * std::cos(std::numbers::pi / 40.0));
  EXPECT_NEAR(v["cycles"].get<double>(), 3.0, 0.1);
  // Every row's face displacement lies on the sine of the row's time.
  const std::string history = read(folder / "history.csv");
  std::istringstream in(history);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  for (std::istringstream h(line); std::getline(h, line, ',');) names.push_back(line);
  const auto column = [&](const std::string& n) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
  };
  const std::size_t ct = column("time_s"), cd = column("face_displacement_m");
  ASSERT_LT(cd, names.size());
  std::size_t rows = 0;
  double t0 = 0.0;
  while (std::getline(in, line)) {
    std::vector<double> x;
    for (std::istringstream r(line); std::getline(r, line, ',');) x.push_back(std::stod(line));
    if (rows == 0) t0 = x[ct] - s["time_step_s"].get<double>();  // the first row is step 1
    EXPECT_NEAR(x[cd], 5e-6 * std::sin(2 * std::numbers::pi * 1e5 * (x[ct] - t0)), 1e-12);
    ++rows;
  }
  EXPECT_GT(rows, 100u);
  // The shaker's work is what the slab's ledger takes in.
  EXPECT_GT(v["shaker_work_j"].get<double>(), 0.0);
  EXPECT_LT(std::abs(s["energy"]["residual_relative"].get<double>()), 1e-2);
  fs::remove_all(dir);
}

TEST(Abrasion, AnUnbreakableSlabSlidesAtThePlatesFrictionCoefficient) {
  // Bonds that cannot break keep the top face whole: every contact under the plate slides once
  // the plate moves, each carrying mu F_n, so shear over normal force is the plate's friction.
  const fs::path dir = fs::temp_directory_path() / "breccia_abrasion";
  fs::remove_all(dir);
  const std::string toml = tiny_experiment("abrasion") + "flat_plate = true\n" +
                           "[contact]\nwall_friction = 0.3\n"
                           "[bond]\ntensile_strength = 1e10\ncohesion = 1e10\n";
  fs::path folder;
  const nlohmann::json s = run_file(dir, "abrasion", toml, &folder);
  ASSERT_EQ(s["status"], "complete");
  const nlohmann::json& a = s["abrasion"];
  EXPECT_TRUE(a["settled"].get<bool>());
  EXPECT_EQ(s["bonds_broken"].get<int>(), 0);
  // 2 %: contacts that stick for a step while the plate's servo adjusts its normal force.
  EXPECT_NEAR(a["bulk_friction_mean"].get<double>(), 0.3, 0.006);
  EXPECT_GE(a["slid_m"].get<double>(), 0.1e-3);
  EXPECT_EQ(a["worn_mass_kg"].get<double>(), 0.0);
  // The normal force the servo held, over the face's area, is the normal stress (2 %).
  const std::string history = read(folder / "history.csv");
  EXPECT_NE(history.find(",abrader_normal_force_n,abrader_shear_force_n,bulk_friction"),
            std::string::npos);
  fs::remove_all(dir);
}

namespace {

// The grit layer on a slab whose bonds cannot break, slid 0.5 mm (about one row pitch of the
// grit) at 0.2 m/s under 1 MPa, with the grains' friction `mu`. Returns the summary; `folder`
// gets the run's folder.
nlohmann::json grit_run(const fs::path& dir, double mu, fs::path* folder) {
  std::string toml = tiny_experiment("abrasion") + fmt::format("[contact]\nfriction = {}\n", mu) +
                     "[bond]\ntensile_strength = 1e10\ncohesion = 1e10\n";
  const std::string tiny = "sliding_speed = 0.1\nslide_distance = 0.1e-3\n";
  toml.replace(toml.find(tiny), tiny.size(), "sliding_speed = 0.2\nslide_distance = 0.5e-3\n");
  return run_file(dir, "abrasion", toml, folder);
}

}  // namespace

TEST(Abrasion, AFrictionlessGritLayerDoesNoNetWorkOnAnElasticSlab) {
  // Without friction every grit-grain contact is a conservative spring: riding up over a grain
  // takes the work that riding down gives back, so over the slide the shear force averages out
  // (the rows' spread is the roughness, +/- 0.04 here; 0.03 allows for the half-row the second
  // half of the slide does not complete). With the grains' friction the layer drags.
  const fs::path dir = fs::temp_directory_path() / "breccia_abrasion_grit";
  fs::remove_all(dir);
  fs::path folder;
  const nlohmann::json s = grit_run(dir, 0.0, &folder);
  ASSERT_EQ(s["status"], "complete");
  const nlohmann::json& a = s["abrasion"];
  EXPECT_EQ(a["abrader"], "grit layer");
  EXPECT_TRUE(a["settled"].get<bool>());
  EXPECT_EQ(s["bonds_broken"].get<int>(), 0);
  EXPECT_NEAR(a["bulk_friction_mean"].get<double>(), 0.0, 0.03);
  EXPECT_GT(a["bulk_friction_sd"].get<double>(), 0.01);  // the roughness is felt
  // The servo holds the normal force through the slide (2 %).
  const std::string history = read(folder / "history.csv");
  std::istringstream rows(history);
  std::string line;
  std::getline(rows, line);
  const auto columns = split_csv(line);
  const auto col = std::find(columns.begin(), columns.end(), "abrader_normal_force_n");
  ASSERT_NE(col, columns.end());
  const auto k = static_cast<std::size_t>(col - columns.begin());
  const double target = a["normal_force_target_n"].get<double>();
  int n = 0;
  while (std::getline(rows, line)) {
    EXPECT_NEAR(std::stod(split_csv(line)[k]), target, 0.02 * target) << line;
    ++n;
  }
  EXPECT_GT(n, 10);
  // The grit is apparatus: fragments.csv holds the rock's grains only, and none wore off.
  const std::size_t grit = a["grit_grains"].get<std::size_t>();
  EXPECT_GT(grit, 20u);
  std::istringstream frags(read(folder / "fragments.csv"));
  std::getline(frags, line);
  std::size_t grains = 0;
  while (std::getline(frags, line)) grains += std::stoul(split_csv(line)[1]);
  EXPECT_EQ(grains, s["sample"]["particles"].get<std::size_t>());
  EXPECT_EQ(grains + grit, s["particles"].get<std::size_t>());
  EXPECT_EQ(a["worn_mass_kg"].get<double>(), 0.0);
  fs::remove_all(dir);
}

TEST(Abrasion, AGritLayerDragsWithTheGrainsFriction) {
  // With friction 0.5 every sliding contact carries 0.5 of its normal force along its tangent
  // plane, and the conservative part still averages out: the bulk coefficient is the grains'
  // friction to within the same 0.03 plus the 10 % by which contacts that stick for a while
  // (the servo moving the layer, grains rolling) carry less than mu F_n.
  const fs::path dir = fs::temp_directory_path() / "breccia_abrasion_grit_mu";
  fs::remove_all(dir);
  fs::path folder;
  const nlohmann::json s = grit_run(dir, 0.5, &folder);
  ASSERT_EQ(s["status"], "complete");
  EXPECT_NEAR(s["abrasion"]["bulk_friction_mean"].get<double>(), 0.5, 0.08);
  fs::remove_all(dir);
}

TEST(Impact, DensityScalingAndOtherShapesAreRefused) {
  EXPECT_NO_THROW(parse_experiment(tiny_experiment("impact"), "impact.toml", {}));
  try {
    parse_experiment(tiny_experiment("impact"), "impact.toml", {"engine.density_scaling=10"});
    ADD_FAILURE() << "density scaling accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("engine.density_scaling"), std::string::npos);
  }
  try {
    parse_experiment(tiny_experiment("impact"), "impact.toml", {"sample.shape=\"cylinder\""});
    ADD_FAILURE() << "cylinder accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("slab"), std::string::npos);
  }
}

// A confining-stress sweep picks the registered test that runs at each sigma_3 and carries the
// loading across; a biaxial test kept at its kind keeps its other keys; a test without platens
// is refused, naming the tests that can be swept.
TEST(Protocols, ConfiningSweepChoosesTheTestFromItsTraits) {
  ExperimentSpec s = parse_experiment("[test]\nkind = \"ucs\"\nplaten_speed = 0.07\n", "x", {});
  set_confining_stress(s, 3e6, "sweep");
  EXPECT_EQ(s.test_kind(), "triaxial");
  EXPECT_EQ(std::get<TriaxialTest::Params>(s.test).platen_speed, 0.07);
  EXPECT_EQ(confining_stress(s), 3e6);
  set_confining_stress(s, 0.0, "sweep");
  EXPECT_EQ(s.test_kind(), "ucs");
  EXPECT_EQ(std::get<UcsTest::Params>(s.test).platen_speed, 0.07);
  ExperimentSpec bi = parse_experiment(
      "[engine]\ndimension = 2\n[sample]\nshape = \"rectangle\"\n[test]\nkind = \"biaxial\"\n"
      "membrane = false\n",
      "x", {});
  set_confining_stress(bi, 7e6, "sweep");
  EXPECT_FALSE(std::get<BiaxialTest::Params>(bi.test).membrane);
  EXPECT_EQ(confining_stress(bi), 7e6);
  ExperimentSpec slab = parse_experiment(tiny_experiment("impact"), "x", {});
  try {
    set_confining_stress(slab, 1e6, "sweep");
    ADD_FAILURE() << "impact accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("\"ucs\", \"triaxial\" or \"biaxial\""), std::string::npos)
        << e.what();
  }
}

TEST(Protocols, OldLoadingTableStillReadsAsTheTestItMeant) {
  const ExperimentSpec ucs = parse_experiment("[loading]\nplaten_speed = 0.07\n", "old.toml", {});
  EXPECT_EQ(ucs.test_kind(), "ucs");
  EXPECT_EQ(std::get<UcsTest::Params>(ucs.test).platen_speed, 0.07);
  const ExperimentSpec tri =
      parse_experiment("[loading]\nconfining_stress = 5e6\nmax_strain = 0.01\n", "old.toml", {});
  EXPECT_EQ(tri.test_kind(), "triaxial");
  EXPECT_EQ(std::get<TriaxialTest::Params>(tri.test).confining_stress, 5e6);
  EXPECT_EQ(confining_stress(tri), 5e6);
  const ExperimentSpec bi = parse_experiment(
      "[engine]\ndimension = 2\n[contact]\nlaw = \"linear\"\n[sample]\nshape = \"rectangle\"\n",
      "old.toml", {"loading.confining_stress=2e6"});
  EXPECT_EQ(bi.test_kind(), "biaxial");
  // Both layouts at once, a key of another kind, a test on the wrong sample: refused, by name.
  EXPECT_THROW(parse_experiment("[loading]\nplaten_speed = 1\n[test]\nkind = \"ucs\"\n", "x", {}),
               InputError);
  try {
    parse_experiment("[test]\nkind = \"ucs\"\nconfining_stress = 1e6\n", "x.toml", {});
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("for test kind \"ucs\""), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_experiment("[test]\nkind = \"biaxial\"\n", "x", {}), InputError);
  EXPECT_THROW(parse_experiment("[test]\nkind = \"shear_box\"\n", "x", {}), InputError);
}

TEST(Brazilian, TensileStrengthFromThePlatenForceAndACentralSplit) {
  const fs::path dir = fs::temp_directory_path() / "breccia_brazilian";
  fs::remove_all(dir);
  fs::path folder;
  const nlohmann::json s = run_file(dir, "disc", tiny_experiment("brazilian"), &folder);
  ASSERT_EQ(s["status"], "complete");
  const double d = s["disc_diameter_m"].get<double>(), t = s["disc_thickness_m"].get<double>();
  EXPECT_NEAR(d, 0.004, 1e-4);  // the disc as packed: its extent between the platens
  EXPECT_NEAR(t, 0.002, 1e-4);
  // sigma_t = 2 F / (pi D t) with F the peak mean platen force: recomputed from history.csv.
  std::ifstream hist(folder / "history.csv");
  std::string line;
  std::getline(hist, line);
  std::vector<std::string> cols;
  for (std::size_t a = 0, e; a <= line.size(); a = e + 1) {
    e = line.find(',', a);
    if (e == std::string::npos) e = line.size();
    cols.push_back(line.substr(a, e - a));
  }
  auto col = [&](const char* n) {
    return static_cast<std::size_t>(std::find(cols.begin(), cols.end(), n) - cols.begin());
  };
  const std::size_t fb = col("platen_force_bottom_n"), ft = col("platen_force_top_n");
  const std::size_t sq = col("deviatoric_stress_pa");
  ASSERT_LT(sq, cols.size());
  double f_peak = 0.0, s_peak = 0.0;
  while (std::getline(hist, line)) {
    std::vector<double> v;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) v.push_back(std::atof(c.c_str()));
    const double f = 0.5 * (v[fb] + v[ft]);
    // Each row's stress is the formula applied to its own forces.
    EXPECT_NEAR(v[sq], 2.0 * f / (std::numbers::pi * d * t), 1e-6 * std::abs(v[sq]) + 1e-3);
    if (v[sq] > s_peak) {
      s_peak = v[sq];
      f_peak = f;
    }
  }
  // history.csv keeps 9 significant digits: a relative rounding of up to 5e-9.
  EXPECT_NEAR(s["tensile_strength_pa"].get<double>(), s_peak, 5e-9 * s_peak);
  EXPECT_NEAR(s["peak_force_n"].get<double>(), f_peak, 1e-6 * f_peak);
  EXPECT_GT(s_peak, 1e6);
  // The first cracks open in tension along the loaded diameter: a uniform scatter over the disc
  // would put 31 % of them within R / 4 of it.
  const auto& b = s["crack_pattern"]["brazilian"];
  EXPECT_GE(b["early_tensile_share"].get<double>(), 0.9);
  EXPECT_GE(b["early_in_band_share"].get<double>(), 0.7);
  EXPECT_GE(b["all_in_band_share"].get<double>(), 0.6);
  fs::remove_all(dir);
}

TEST(Brazilian, BadDiscsAreRefused) {
  auto refused = [](const std::string& toml, const char* fragment) {
    try {
      parse_experiment(toml, "disc.toml", {});
      ADD_FAILURE() << "no error for:\n" << toml;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  const std::string test = "[test]\nkind = \"brazilian\"\n";
  refused(test, "needs a \"cylinder\"");  // the default prism
  refused(test + "[sample]\nshape = \"cylinder\"\ndiameter = 0.01\nheight = 0.02\n",
          "0.2 <= t / D <= 1");
  refused(test +
              "[sample]\nshape = \"cylinder\"\ndiameter = 0.01\nheight = 0.0025\n"
              "radius_min = 0.3e-3\nradius_max = 0.5e-3\n",
          "too thin for its grains");
  refused(test +
              "[sample]\nshape = \"cylinder\"\ndiameter = 0.004\nheight = 0.002\n"
              "radius_min = 0.2e-3\nradius_max = 0.3e-3\n",
          "too small for its grains");
  refused(test +
              "[engine]\ndimension = 2\n[contact]\nlaw = \"linear\"\n"
              "[sample]\nshape = \"rectangle\"\n",
          "needs a \"disk\"");
  // A sweep over confining stress needs a compression test.
  ExperimentSpec disc = parse_experiment(
      test + "[sample]\nshape = \"cylinder\"\ndiameter = 0.01\nheight = 0.005\n", "d", {});
  EXPECT_THROW(set_confining_stress(disc, 5e6, "sweep"), InputError);
}

TEST(Protocols, EveryBondLawRunsATinyTestIn3DAnd2D) {
  // The registry's bond laws through the whole command: built from the experiment file, run
  // (orientations reach the total formulations in 3D and, as angles about z, in 2D), cracks
  // recorded under the law's name.
  const fs::path dir = fs::temp_directory_path() / "breccia_bond_laws";
  fs::remove_all(dir);
  for_each_type<BondLaws>([&]<class Law>() {
    const std::string name(Law::name);
    for (const char* kind : {"ucs", "biaxial"}) {
      if (planar_only_law<Law> && std::string(kind) == "ucs") continue;  // 2D laws: biaxial only
      fs::path folder;
      std::string toml = tiny_experiment(kind) + "[bond]\nlaw = \"" + name + "\"\n";
      // To the peak (about 1.2 % for the Berea parallel bonds) and past it.
      toml.replace(toml.find("max_strain = 0.003"), 18, "max_strain = 0.03");
      const nlohmann::json s = run_file(dir, name + "-" + kind, toml, &folder);
      EXPECT_EQ(s["status"], "complete") << name << " " << kind;
      EXPECT_GT(s["bonds_initial"].get<int>(), 100) << name << " " << kind;
      if (std::string(kind) == "ucs") {
        EXPECT_GT(s["bonds_broken"].get<int>(), 0) << name;
        std::ifstream cracks(folder / "cracks.csv");
        std::string header, first;
        std::getline(cracks, header);
        std::getline(cracks, first);
        EXPECT_NE(first.find("," + name + ","), std::string::npos) << first;
      }
    }
  });
  fs::remove_all(dir);
}

TEST(Biaxial, MembranesHoldSigma3ThroughThePeakAndTheShearBand) {
  // The tiny biaxial (about 300 disks at sigma_3 = 1 MPa) loaded to 4 % strain, far past its
  // peak: the membranes' applied confining stress (their inward force per unit height) stays at
  // sigma_3 in every row. By construction it is exact to rounding whatever shape the chains
  // take, so 1e-9 tells a lost or broken chain from rounding; the side walls it replaces
  // strayed by 8 % before the peak and 180 % after it.
  const fs::path dir = fs::temp_directory_path() / "breccia_membrane";
  fs::remove_all(dir);
  std::string toml = tiny_experiment("biaxial");
  toml.replace(toml.find("max_strain = 0.003"), 18, "max_strain = 0.04\nstop_fraction = 0");
  fs::path folder;
  const nlohmann::json s = run_file(dir, "membrane", toml, &folder);
  ASSERT_EQ(s["status"], "complete");
  EXPECT_GT(s["bonds_broken"].get<int>(), 20) << "the sample must fail";
  const std::vector<double> confining = history_column(folder, "confining_stress_pa");
  const std::vector<double> strain = history_column(folder, "axial_strain");
  for (std::size_t row = 0; row < confining.size(); ++row)
    EXPECT_NEAR(confining[row], 1e6, 1e-3) << "row " << row;
  EXPECT_GT(confining.size(), 20u);
  ASSERT_FALSE(strain.empty());
  EXPECT_GT(strain.back(), 0.039);
  // The membranes' work is recorded beside the platens' (physics.md §2.4): with both, history's
  // own columns close the balance to the residual the engine wrote, to the rounding of their 9
  // printed digits; the membranes' work is thousands of times that, so a record without it could
  // not close.
  const auto col = [&](const char* name) { return history_column(folder, name); };
  const std::vector<double> platens = col("boundary_work_j"), loads = col("external_load_work_j");
  std::vector<double> stored(platens.size(), 0.0), lost(platens.size(), 0.0);
  for (const char* c : {"kinetic_j", "bond_tension_j", "bond_compression_j", "bond_shear_j",
                        "bond_bending_j", "bond_twisting_j", "contact_strain_j"}) {
    const std::vector<double> v = col(c);
    for (std::size_t r = 0; r < v.size(); ++r) stored[r] += v[r];
  }
  for (const char* c : {"friction_j", "local_damping_j", "viscous_damping_j", "deleted_springs_j",
                        "released_by_breaks_j"}) {
    const std::vector<double> v = col(c);
    for (std::size_t r = 0; r < v.size(); ++r) lost[r] += v[r];
  }
  const std::vector<double> residual = col("energy_residual_j");
  const std::size_t last = platens.size() - 1;
  // Both ends against the first row: the residual column is taken against the engine's first
  // sample, which is the first row's baseline or earlier.
  const double closure = (platens[last] + loads[last] - platens[0] - loads[0]) -
                         (stored[last] - stored[0]) - (lost[last] - lost[0]);
  const double rounding = 1e-7 * std::abs(platens[last] - platens[0]);
  EXPECT_NEAR(closure, residual[last] - residual[0], rounding);
  EXPECT_GT(std::abs(loads[last] - loads[0]), 1000 * rounding);
  EXPECT_NEAR(s["energy"]["external_load_work_j"].get<double>(), loads[last],
              1e-9 * std::abs(loads[last]));
  fs::remove_all(dir);
}

TEST(Triaxial, AMembraneHoldsSigma3PastThePeakAndResumesExactly) {
  // A tiny cylinder (3 x 6 mm, about 220 grains) at sigma_3 = 1 MPa with the 3D membrane,
  // loaded to 3 % strain, past its peak: the membrane's confining stress (inward radial force
  // over its faces' radial area) is sigma_3 to rounding in every row, whatever shape the
  // surface takes; 1e-3 Pa tells a lost face from rounding. Its nodes are found again from the
  // grains every step and not checkpointed, so a run stopped halfway and resumed must write the
  // uninterrupted rows byte for byte.
  const fs::path dir = fs::temp_directory_path() / "breccia_membrane_3d";
  fs::remove_all(dir);
  std::string toml = tiny_experiment("triaxial");
  toml.replace(toml.find("width = 0.0024\ndepth = 0.0024"), 29,
               "shape = \"cylinder\"\ndiameter = 0.003");
  toml.replace(toml.find("height = 0.0048"), 15, "height = 0.006");
  toml.replace(toml.find("max_strain = 0.003"), 18,
               "max_strain = 0.03\nstop_fraction = 0\nmembrane = true");
  fs::path folder;
  const nlohmann::json s = run_file(dir, "membrane", toml, &folder);
  ASSERT_EQ(s["status"], "complete");
  EXPECT_GT(s["bonds_broken"].get<int>(), 20) << "the sample must fail";
  EXPECT_EQ(s.value("lateral_boundary", ""), "flexible membrane on the outermost grains all round");
  const std::vector<double> confining = history_column(folder, "confining_stress_pa");
  for (std::size_t row = 0; row < confining.size(); ++row)
    EXPECT_NEAR(confining[row], 1e6, 1e-3) << "row " << row;
  EXPECT_GT(confining.size(), 20u);
  const Result stopped =
      run(fmt::format("run --quiet --output {} {} --stop-at-step {}", (dir / "split").string(),
                      (dir / "membrane.toml").string(), s["steps"].get<int>() / 2));
  ASSERT_EQ(stopped.code, 130) << stopped.out;
  const fs::path split = last_line(stopped.out);
  const Result resumed = run("resume --quiet " + split.string());
  ASSERT_EQ(resumed.code, 0) << resumed.out;
  EXPECT_EQ(read(folder / "history.csv"), read(split / "history.csv"));
  EXPECT_EQ(read(folder / "cracks.csv"), read(split / "cracks.csv"));
  fs::remove_all(dir);
}

TEST(Sweep, ParallelProcessesGiveWhatOneRunAfterAnotherGives) {
  // The tiny biaxial at 0 and 1 MPa, swept as two child processes of one thread each and then in
  // this process one after the other (with the machine's threads): the engine is deterministic
  // whatever the thread count, so both sweeps give the same peaks to the last digit.
  const fs::path dir = fs::temp_directory_path() / "breccia_sweep";
  const fs::path file = tiny_file(dir, "biaxial");
  std::map<int, nlohmann::json> sweeps;
  for (const int jobs : {2, 1}) {
    // The parallel sweep also writes its report: the trend table and figures.
    const Result r = run(fmt::format("sweep --jobs {} --confining-mpa 0 1 --output {} {}{}", jobs,
                                     (dir / std::to_string(jobs)).string(), file.string(),
                                     jobs == 2 ? " --set output.plot=true" : ""));
    ASSERT_EQ(r.code, 0) << r.out;
    const fs::path folder = last_line(r.out);
    sweeps[jobs] = nlohmann::json::parse(read(folder / "sweep.json"));
    if (jobs == 2) {
      EXPECT_NE(r.out.find("2 at a time"), std::string::npos) << r.out;
      EXPECT_TRUE(fs::exists(folder / "experiments" / "tiny-confining-1MPa.toml"));
      EXPECT_TRUE(fs::exists(folder / "report" / "trends.png"));
      std::ifstream trends(folder / "trends.csv");
      std::string header, line;
      std::getline(trends, header);
      for (const char* c : {"confining_stress_mpa", "peak_q_mpa", "shear_fraction_end",
                            "damage_index_at_peak", "fracture_share", "strain_energy_share",
                            "b_value_at_peak", "d2_at_peak", "crack_initiation_mpa"})
        EXPECT_NE(header.find(c), std::string::npos) << c << " in " << header;
      int rows = 0;
      while (std::getline(trends, line)) ++rows;
      EXPECT_EQ(rows, 2);
    }
  }
  ASSERT_EQ(sweeps[2]["runs"].size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto &a = sweeps[2]["runs"][i], &b = sweeps[1]["runs"][i];
    EXPECT_EQ(a["status"], "complete");
    EXPECT_EQ(a["confining_stress_pa"], b["confining_stress_pa"]);
    EXPECT_EQ(a["peak_deviatoric_stress_pa"], b["peak_deviatoric_stress_pa"]) << i;
    EXPECT_EQ(a["cracks"], b["cracks"]) << i;
  }
  EXPECT_EQ(sweeps[2]["status"], "complete");
  fs::remove_all(dir);
}

TEST(Sweep, StrainRatesSetThePlatenSpeedFromTheSampleLength) {
  // The tiny UCS at 20 and 200 /s without density scaling: each run's measured strain rate
  // (2 v / h0, h0 between the platens at the start of loading) is the one asked for, to the
  // gap between the grains' extent and the platens; two rates give no rate fit, and say so.
  const fs::path dir = fs::temp_directory_path() / "breccia_rate_sweep";
  const fs::path file = tiny_file(dir, "ucs");
  // Density scaling would scale the inertia the study measures: refused before any folder.
  const Result refused = run(fmt::format("sweep --jobs 1 --strain-rates 20 200 --output {} {}",
                                         (dir / "out").string(), file.string()));
  EXPECT_NE(refused.code, 0);
  EXPECT_NE(refused.out.find("engine.density_scaling"), std::string::npos) << refused.out;
  EXPECT_FALSE(fs::exists(dir / "out"));
  const Result r = run(fmt::format(
      "sweep --jobs 2 --strain-rates 20 200 --output {} {} --set engine.density_scaling=1 "
      "--set output.plot=true",
      (dir / "out").string(), file.string()));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto sweep = nlohmann::json::parse(read(fs::path(last_line(r.out)) / "sweep.json"));
  EXPECT_EQ(sweep["variable"], "strain_rate");
  ASSERT_EQ(sweep["runs"].size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& run_i = sweep["runs"][i];
    ASSERT_EQ(run_i["status"], "complete");
    const double target = run_i["strain_rate_target_per_s"];
    EXPECT_NEAR(run_i["strain_rate_per_s"].get<double>(), target, 0.02 * target);
    EXPECT_TRUE(run_i["failure_plane"].contains("method"));
    // Read back from the child's summary: the damage ratio is that of its bonds.
    ASSERT_GT(run_i["bonds_initial"].get<double>(), 0.0);
    EXPECT_DOUBLE_EQ(run_i["damage_ratio_percent"].get<double>(),
                     100.0 * run_i["cracks"].get<double>() / run_i["bonds_initial"].get<double>());
  }
  EXPECT_NEAR(sweep["runs"][1]["platen_speed_m_per_s"].get<double>() /
                  sweep["runs"][0]["platen_speed_m_per_s"].get<double>(),
              10.0, 1e-9);
  EXPECT_FALSE(sweep["rate_dependence"]["valid"]);
  EXPECT_EQ(sweep["rate_dependence"]["flag"], "too_few_rates");
  // Its report: UCS against the rate, the curves and damage ratios, the failure plane, and the
  // table of the rates.
  const fs::path folder = last_line(r.out);
  for (const char* f : {"report/rate_dependence.png", "report/rate_curves.png",
                        "report/failure_plane.png", "rates.csv", "report.html"})
    EXPECT_TRUE(fs::exists(folder / f)) << f;
  EXPECT_NE(r.out.find("damage ratio"), std::string::npos) << r.out;
  // Resumed quietly, a finished sweep runs nothing and keeps its results. (Without a logger,
  // measuring the generated sample's length once threw std::bad_function_call.)
  const Result quiet = run("resume --quiet " + folder.string());
  EXPECT_EQ(quiet.code, 0) << quiet.out;
  EXPECT_EQ(nlohmann::json::parse(read(folder / "sweep.json"))["runs"], sweep["runs"]);
  fs::remove_all(dir);
}

TEST(Biaxial, RicebalLaboratoryRunsEndToEnd) {
  // Seed 002's test on a tiny sample: planar spheres with Hertz-Mindlin contacts, preconsolidated
  // to 10 MPa between particle rows, RICEBAL bonds, membranes at 2 MPa, history rows every 0.001
  // strain (the platens' full speed; the ramp makes the first rows closer).
  const fs::path dir = fs::temp_directory_path() / "breccia_ricebal";
  fs::remove_all(dir);
  const std::string toml =
      "[output]\nplot = false\nsnapshot_strain_interval = 0\nhistory_strain_interval = 0.001\n"
      "[engine]\ndimension = 2\ndensity_scaling = 100\n"
      "[material]\npreset = \"custom\"\n"
      "[contact]\nlaw = \"hertz_mindlin\"\nshear_modulus = 10e9\npoisson_ratio = 0.2\n"
      "friction = 0.5\n"
      "[bond]\nlaw = \"ricebal_bond\"\nmodulus = 10e9\ntensile_strength = 20e6\ncohesion = 40e6\n"
      "[sample]\nshape = \"rectangle\"\npacking = \"preconsolidation\"\nwidth = 1.2e-3\n"
      "height = 2.4e-3\nradius_min = 30e-6\nradius_max = 70e-6\nporosity = 0.18\n"
      "bond_gap_tolerance = 0.2e-6\n"
      "[test]\nkind = \"biaxial\"\nconfining_stress = 2e6\nplaten_speed = 0.05\n"
      "max_strain = 0.02\n";
  fs::path folder;
  const nlohmann::json s = run_file(dir, "ricebal", toml, &folder);
  ASSERT_EQ(s["status"], "complete");
  EXPECT_GT(s["bonds_initial"].get<int>(), 200);
  EXPECT_GT(s["bonds_broken"].get<int>(), 0) << "the sample must crack";
  EXPECT_EQ(s["sample"]["locked_in_stress"]["contact_law"], "hertz_mindlin");
  const std::string resolved = read(folder / "experiment.toml");
  EXPECT_NE(resolved.find("planar_body = \"planar_sphere\""), std::string::npos);
  // Rows about 0.001 strain apart once the platens are at full speed.
  std::ifstream in(folder / "history.csv");
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  for (std::stringstream ss(line); std::getline(ss, line, ',');) header.push_back(line);
  const auto strain_col = static_cast<std::size_t>(
      std::find(header.begin(), header.end(), "axial_strain") - header.begin());
  std::vector<double> strain;
  while (std::getline(in, line)) {
    std::vector<std::string> v;
    for (std::stringstream ss(line); std::getline(ss, line, ',');) v.push_back(line);
    strain.push_back(std::stod(v[strain_col]));
  }
  ASSERT_GE(strain.size(), 15u);
  EXPECT_LE(strain.size(), 25u);
  EXPECT_NEAR(strain.back() - strain[strain.size() - 2], 0.001, 1e-4);
  fs::remove_all(dir);
}
