// The direct tension test: a chain of bonded grains pulled by its end grains gives the modulus
// and the strength a hand calculation gives, and grips that leave too little of the sample free,
// or shapes the test cannot pull, are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "breccia/core/error.hpp"
#include "breccia/spec/experiment.hpp"
#include "cli_harness.hpp"

namespace fs = std::filesystem;
using namespace breccia;
using namespace breccia::testing;

namespace {

constexpr double kR = 0.5e-3;          // grain radius, m
constexpr int kGrains = 20;            // in a straight chain along z, touching
constexpr double kBondModulus = 10e9;  // E_b, Pa
constexpr double kBondTension = 10e6;  // sigma_c, Pa

// The chain as a table sample, and an experiment that pulls it with grips two grains long.
fs::path write_chain(const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream table(dir / "chain.txt");
  for (int i = 0; i < kGrains; ++i) table << "0 0 " << kR * (2 * i + 1) << " " << kR << "\n";
  const fs::path file = dir / "chain.toml";
  std::ofstream(file) << "name = \"chain\"\n"
                         "[output]\nplot = false\nsnapshot_strain_interval = 0\n"
                         "history_interval = 5\n"
                         "[engine]\ndensity_scaling = 100\n"
                         "[material]\npreset = \"custom\"\n"
                         "[contact]\nlaw = \"linear\"\nmodulus = 10e9\nfriction = 0.5\n"
                         "[bond]\nlaw = \"parallel_bond\"\nmodulus = 10e9\nstiffness_ratio = 2.5\n"
                         "tensile_strength = 10e6\ncohesion = 100e6\n"
                         "[sample]\nsource = \"table\"\nfile = \"chain.txt\"\n"
                         "[test]\nkind = \"direct_tension\"\nplaten_speed = 0.01\n"
                         "grip_length = 2e-3\nmax_strain = 0.01\n";
  return file;
}

}  // namespace

// Twenty touching grains along z; each grip holds two of them, so 17 bonds in series lie between
// the grips, over a free length of 20 - 4 = 16 mm. One bond's normal stiffness is
// K_n = E_b pi R^2 / 2R (docs/physics.md §4), the chain's cross-section is the square (2R)^2 it
// spans, and the strain is the grips' separation over the free length, so
//   E = K_n L_free / (17 (2R)^2),
// and the chain breaks when one bond's tension reaches sigma_c pi R^2 (no bending: nothing
// turns), sigma_t = sigma_c pi R^2 / (2R)^2 = sigma_c pi / 4.
TEST(DirectTension, AChainOfBondedGrainsHasTheModulusAndStrengthOfItsBonds) {
  const fs::path dir = fs::temp_directory_path() / "breccia_direct_tension_chain";
  const fs::path file = write_chain(dir);
  const Result r = run("run --quiet --output " + (dir / "runs").string() + " " + file.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const nlohmann::json s = nlohmann::json::parse(read(fs::path(last_line(r.out)) / "summary.json"));
  ASSERT_EQ(s["status"], "complete");
  EXPECT_EQ(s["gripped_grains"].get<int>(), 4);
  EXPECT_NEAR(s["free_length_m"].get<double>(), 16e-3, 1e-12);
  EXPECT_NEAR(s["cross_section_m2"].get<double>(), 4 * kR * kR, 1e-15);
  const double k_n = kBondModulus * std::numbers::pi * kR * kR / (2 * kR);
  const double e = k_n * 16e-3 / (17 * 4 * kR * kR);
  // The modulus is read on the rows around half the peak, where the chain is elastic and, after
  // the ramp, pulled at a steady rate: the tension varies along the chain only by the force that
  // accelerates its grains, which the ramp has made nil. 0.5 %: the rows' 9 significant digits
  // and the fit's rounding are far below that, the remaining dynamics of the ramp of the order.
  EXPECT_NEAR(s["youngs_modulus_pa"].get<double>(), e, 5e-3 * e);
  // The peak: the last row before the break, up to 5 steps of loading (each 2 v dt / 17 of
  // elongation per bond, under 0.2 % of the breaking elongation here) below the bond's strength.
  const double sigma_t = kBondTension * std::numbers::pi / 4.0;
  EXPECT_LE(s["tensile_strength_pa"].get<double>(), sigma_t * 1.002);
  EXPECT_GE(s["tensile_strength_pa"].get<double>(), sigma_t * 0.99);
  // The bonds break in tension and the chain comes apart: nothing turns or slides. Identical
  // bonds under one tension reach their strength within a step of one another, so that one or
  // all of the 17 break.
  EXPECT_GE(s["bonds_broken"].get<int>(), 1);
  EXPECT_LE(s["bonds_broken"].get<int>(), 17);
  EXPECT_EQ(s["cracks_tensile"], s["bonds_broken"]);
  // The chain's own stretch is the loading's: what is left of its motion is far below its strain
  // energy.
  EXPECT_TRUE(s["quasi_static"]["ok"].get<bool>());
  // A line of grains does not narrow: Poisson's ratio 0.
  EXPECT_NEAR(s["poisson_ratio"].get<double>(), 0.0, 1e-9);
  fs::remove_all(dir);
}

TEST(DirectTension, GripsThatLeaveTooLittleFreeAndShapesItCannotPullAreRefused) {
  auto refused = [](const std::string& toml, const char* key, const char* fragment) {
    try {
      parse_experiment(toml, "t.toml", {});
      ADD_FAILURE() << "no error for:\n" << toml;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(key), std::string::npos) << what;
      EXPECT_NE(what.find(fragment), std::string::npos) << what;
    }
  };
  const std::string test = "[test]\nkind = \"direct_tension\"\n";
  // An 8 x 8 x 16 mm prism: grips of 4.5 mm leave 7 mm free, under half of 16 mm.
  refused(test + "grip_length = 4.5e-3\n", "test.grip_length", "at least half");
  refused(test + "[sample]\nshape = \"slab\"\n", "sample.shape", "\"prism\" or a \"cylinder\"");
  refused(test +
              "[engine]\ndimension = 2\n[contact]\nlaw = \"linear\"\n[sample]\nshape = "
              "\"disk\"\n",
          "sample.shape", "\"rectangle\"");
  refused(test + "stop_fraction = 1\n", "test.stop_fraction", "");
  // The default grips (two largest grain diameters) and a cylinder are accepted.
  EXPECT_NO_THROW(parse_experiment(test, "t.toml", {}));
  EXPECT_NO_THROW(parse_experiment(test + "[sample]\nshape = \"cylinder\"\n", "t.toml", {}));
}
