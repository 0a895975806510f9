// Bad input, as a new user makes it: experiment files, --set, the command line, every geometry
// format and damaged run folders. Each case must end with a non-zero exit (never a signal), a
// message naming the file, key or option and the value, and no run folder that looks whole.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "cli_harness.hpp"

namespace fs = std::filesystem;
using namespace breccia::testing;

namespace {

constexpr int kAnyError = -2;  // a CLI11 usage error: any non-zero exit code

struct BadCase {
  const char* name;
  std::vector<std::pair<const char*, const char*>> files;  // written into the case's folder
  std::string args;                                        // "{d}" is the case's folder
  int code;                                                // expected exit code
  std::vector<std::string> needles;                        // the message must contain each
};

// A tiny FCC lattice: runs that pass validation get past the sample in milliseconds.
const std::string kLattice =
    " --set sample.source=\"lattice\" --set sample.cells=[2,2,4] --set output.plot=false";

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = 0; (p = s.find(from, p)) != std::string::npos; p += to.size())
    s.replace(p, from.size(), to);
  return s;
}

// A folder under `root` that looks like a finished run: a summary, or a manifest saying complete.
bool has_whole_looking_run(const fs::path& root) {
  if (!fs::exists(root)) return false;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.path().filename() == "summary.json") return true;
    if (e.path().filename() == "manifest.json") {
      const auto m = nlohmann::json::parse(read(e.path()), nullptr, false);
      if (!m.is_discarded() && m.value("status", "") == "complete") return true;
    }
  }
  return false;
}

const char* kGeomHead = "breccia-geometry 1\ndimension 3\n";
// A case file with this text is made a FIFO (a reader that opened it would wait forever).
const char* kFifo = "\x01fifo";

// A calibration of a tiny generated prism (about 330 grains): a case that must be refused before
// the first trial gets there in a second or two, packing included.
const std::string kCalibrationHead =
    "[calibration]\nname = \"t\"\ntrials_per_stage = 1\npasses = 1\nverify_seeds = []\n";
const std::string kCalibrationExperiment = kTinyCalibrationExperiment;
const std::string kModulusOnly =
    "[targets]\nyoungs_modulus = 8e9\n[free]\n\"bond.modulus\" = [2e9, 60e9]\n";

// The plan a confining sweep of the tiny lattice writes (sweep-plan.json), with `edit` applied.
std::string lattice_plan(const std::string& kind, const std::string& values,
                         const std::string& experiment, const std::string& extra = "") {
  return "{\"format\": \"breccia-sweep-plan 1\", \"kind\": \"" + kind +
         "\", \"values\": " + values +
         (experiment.empty() ? "" : ", \"experiment\": \"" + experiment + "\"") + extra + "}";
}
const std::string kPlanLattice =
    "[sample]\\nsource = \\\"lattice\\\"\\ncells = [2, 2, 4]\\n[output]\\nplot = false\\n";

std::vector<BadCase> cases() {
  const std::string run = "run --quiet --output {d}/runs ";
  const std::string geom = " --set sample.source=\"file\" --set sample.file=\"{d}/s.geom\"";
  const std::string table = " --set sample.source=\"table\" --set sample.file=\"{d}/s.txt\"";
  const std::string gengeo = " --set sample.source=\"gengeo\" --set sample.file=\"{d}/s.geo\"";
  const std::string gg_head =
      "LSMGeometry 1.2\nBoundingBox 0 0 0 1 1 1\nPeriodicBoundaries 0 0 0\n"
      "Dimension 3D\nBeginParticles\nSimple\n";
  static std::vector<std::string> keep;  // owns the texts the cases point to
  auto txt = [&](std::string s) { return keep.emplace_back(std::move(s)).c_str(); };
  auto exp = [&](const char* body) {
    return std::vector<std::pair<const char*, const char*>>{{"e.toml", body}};
  };
  const std::string e = run + "{d}/e.toml";
  std::vector<BadCase> c = {
      // --- experiment files ---
      {"toml_syntax", exp("[engine\nthreads = 1\n"), e, 2, {"e.toml:1", "TOML syntax"}},
      {"unknown_table",
       exp("[engin]\nthreads = 1\n"),
       e,
       2,
       {"e.toml:1", "[engin]", "unknown table"}},
      {"unknown_key", exp("[engine]\nthreds = 1\n"), e, 2, {"e.toml:2", "engine.threds"}},
      {"unknown_top_key", exp("nmae = \"x\"\n"), e, 2, {"e.toml:1", "nmae"}},
      {"wrong_type",
       exp("[engine]\nthreads = \"x\"\n"),
       e,
       2,
       {"e.toml:2", "engine.threads", "integer"}},
      {"nan_porosity",
       exp("[sample]\nporosity = nan\n"),
       e,
       2,
       {"e.toml:2", "sample.porosity", "nan"}},
      {"inf_speed",
       exp("[test]\nplaten_speed = inf\n"),
       e,
       2,
       {"e.toml:2", "test.platen_speed", "inf"}},
      {"negative_radius",
       exp("[sample]\nradius_min = -1e-3\n"),
       e,
       2,
       {"sample.radius_min", "-0.001"}},
      {"radius_order",
       exp("[sample]\nradius_min = 5e-4\nradius_max = 4e-4\n"),
       e,
       2,
       {"sample.radius_max"}},
      {"dimension_4", exp("[engine]\ndimension = 4\n"), e, 2, {"engine.dimension", "4"}},
      {"unknown_test", exp("[test]\nkind = \"shear\"\n"), e, 2, {"test.kind", "shear"}},
      {"huge_confinement",
       exp("[test]\nkind = \"triaxial\"\nconfining_stress = 1e308\n"),
       e,
       2,
       {"e.toml:3", "test.confining_stress", "1e+308"}},
      {"membrane_on_a_prism",
       exp("[test]\nkind = \"triaxial\"\nconfining_stress = 1e6\nmembrane = true\n"),
       e,
       2,
       {"test.membrane", "cylinder", "membrane = false"}},
      {"hertz_2d",
       exp("[engine]\ndimension = 2\n[sample]\nshape = \"rectangle\"\nplanar_body = "
           "\"disk\"\n[contact]\nlaw = \"hertz_mindlin\"\n"),
       e,
       2,
       {"contact.law"}},
      {"huge_lattice",
       exp("[sample]\nsource = \"lattice\"\ncells = [1000, 1000, 1000]\n"),
       e,
       2,
       {"sample.cells", "max_particles"}},
      {"file_without_name", exp("[sample]\nsource = \"file\"\n"), e, 2, {"sample.file"}},
      {"missing_geometry",
       exp("[sample]\nsource = \"file\"\nfile = \"nowhere.geom\"\n"),
       e,
       2,
       {"nowhere.geom", "cannot open"}},
      {"missing_experiment", {}, run + "{d}/absent.toml", 2, {"absent.toml", "cannot open"}},
      {"folder_as_experiment", {}, run + "{d}", 2, {"is a folder"}},
      {"folder_as_experiment_check", {}, "check {d}", 2, {"is a folder"}},
      {"safety_factor", exp("[engine]\nsafety_factor = 2\n"), e, 2, {"engine.safety_factor", "2"}},
      {"classes_mismatch",
       exp("[sample]\ndistribution = \"classes\"\nclass_radii = [1e-4, 2e-4]\nclass_mass_fractions "
           "= [1.0]\n"),
       e,
       2,
       {"sample.class_radii"}},
      {"density_scaling_below_1",
       exp("[engine]\ndensity_scaling = 0.5\n"),
       e,
       2,
       {"engine.density_scaling"}},
      {"dynamic_damping_radius_without_the_switch",
       exp("[engine]\ndynamic_damping_radius = 1e-3\n"),
       e,
       2,
       {"engine.dynamic_damping_radius", "0.001", "engine.dynamic_damping = true"}},
      {"dynamic_damping_alpha_of_1",
       exp("[engine]\ndynamic_damping = true\ndynamic_damping_alpha = 1\n"),
       e,
       2,
       {"engine.dynamic_damping_alpha", "1"}},
      {"preconsolidation_3d",
       exp("[sample]\npacking = \"preconsolidation\"\n"),
       e,
       2,
       {"sample.packing"}},
      {"name_too_long",
       exp(txt("name = \"" + std::string(300, 'a') + "\"\n")),
       e,
       2,
       {"e.toml:1", "'name'", "at most 100 characters"}},
      {"negative_seed", exp("[engine]\nseed = -1\n"), e, 2, {"engine.seed", "-1"}},
      {"zero_max_particles", exp("[sample]\nmax_particles = 0\n"), e, 2, {"sample.max_particles"}},
      {"legacy_loading_bad", exp("[loading]\nmode = \"sideways\"\n"), e, 2, {"e.toml:2"}},
      // --- derived quantities (checked before a run folder exists) ---
      {"bin_width_tiny",
       {},
       run + kLattice + " --set ae.bin_width=1e-300",
       2,
       {"ae.bin_width", "1e-300"}},
      {"ramp_forever",
       {},
       run + kLattice + " --set test.ramp_time=1e308",
       2,
       {"test.ramp_time", "steps"}},
      {"platen_light_speed",
       {},
       run + kLattice + " --set test.platen_speed=1e300",
       2,
       {"test.platen_speed", "1e+300"}},
      {"platen_slow_forever",
       {},
       run + kLattice + " --set test.platen_speed=1e-300",
       2,
       {"test.platen_speed", "steps"}},
      {"snapshots_tiny",
       {},
       run + kLattice + " --set output.snapshot_strain_interval=1e-300",
       2,
       {"output.snapshot_strain_interval"}},
      {"lattice_radius_tiny",
       {},
       run + kLattice + " --set sample.radius=1e-308",
       2,
       {"sample.radius", "1e-308"}},
      {"time_step_tiny",
       {},
       run + kLattice + " --set engine.time_step=1e-300",
       2,
       {"steps", "time step"}},
      // --- --set ---
      {"set_without_equals",
       {},
       run + "--set engine.threads",
       2,
       {"--set engine.threads", "section.key=value"}},
      {"set_wrong_type",
       {},
       run + "--set engine.threads=x",
       2,
       {"--set engine.threads=x", "integer"}},
      {"set_out_of_range",
       {},
       run + "--set test.platen_speed=-1",
       2,
       {"--set test.platen_speed=-1", "> 0"}},
      {"set_section_as_value", {}, run + "--set engine=3", 2, {"--set engine=3"}},
      {"set_unknown_table", {}, run + "--set nosuch.key=1", 2, {"nosuch"}},
      {"set_bad_choice",
       {},
       run + "--set sample.shape=hexagon",
       2,
       {"--set sample.shape=hexagon", "hexagon"}},
      {"set_on_file_blames_set",
       exp("[engine]\nthreads = 1\n"),
       e + " --set engine.safety_factor=7",
       2,
       {"--set engine.safety_factor=7"}},
      // --- the command line ---
      {"unknown_command", {}, "frobnicate", 2, {"unknown command 'frobnicate'", "run"}},
      {"no_command", {}, "", kAnyError, {"subcommand"}},
      {"negative_threads", {}, run + "--threads -1", kAnyError, {"--threads", "-1"}},
      {"too_many_threads", {}, run + "--threads 100000", kAnyError, {"--threads"}},
      {"negative_stop_step", {}, run + "--stop-at-step -5", kAnyError, {"--stop-at-step", "-5"}},
      {"resume_bad_threads", {}, "resume --threads 5000 {d}", kAnyError, {"--threads", "5000"}},
      {"unknown_flag", {}, run + "--bogus-flag", kAnyError, {"--bogus-flag"}},
      {"sweep_without_stresses", {}, "sweep", kAnyError, {"--confining-mpa"}},
      {"sweep_bad_stress", {}, "sweep --confining-mpa abc", kAnyError, {"--confining-mpa"}},
      {"summarise_missing", {}, "summarise {d}/nothing", 2, {"nothing", "not a folder"}},
      {"report_empty", {}, "report {d}", 2, {"summary.json"}},
      {"resume_empty", {}, "resume {d}", 2, {"manifest.json"}},
      // --- breccia-geometry files ---
      {"geom_header", {{"s.geom", "breccia-geometri 1\n"}}, run + geom, 2, {"s.geom:1", "header"}},
      {"geom_version",
       {{"s.geom", "breccia-geometry 2\n"}},
       run + geom,
       2,
       {"s.geom:1", "version"}},
      {"geom_negative_radius",
       {{"s.geom", txt(std::string(kGeomHead) + "particles 1\n1 0 0 0 -1 2650\n")}},
       run + geom,
       2,
       {"s.geom:4", "radius", "-1"}},
      {"geom_nan_position",
       {{"s.geom", txt(std::string(kGeomHead) + "particles 1\n1 nan 0 0 1e-3 2650\n")}},
       run + geom,
       2,
       {"s.geom:4", "'x'", "nan"}},
      {"geom_duplicate_tags",
       {{"s.geom",
         txt(std::string(kGeomHead) + "particles 2\n1 0 0 0 1e-3 2650\n1 3e-3 0 0 1e-3 2650\n")}},
       run + geom,
       2,
       {"s.geom:5", "tag", "s.geom:4"}},
      {"geom_coincident",
       {{"s.geom",
         txt(std::string(kGeomHead) + "particles 2\n1 0 0 0 1e-3 2650\n2 0 0 0 1e-3 2650\n")}},
       run + geom,
       2,
       {"s.geom:5", "share a centre"}},
      {"geom_deep_overlap",
       {{"s.geom",
         txt(std::string(kGeomHead) + "particles 2\n1 0 0 0 1e-3 2650\n2 5e-4 0 0 1e-3 2650\n")}},
       run + geom,
       2,
       {"s.geom:5", "inside another grain"}},
      {"geom_bond_missing",
       {{"s.geom", txt(std::string(kGeomHead) +
                       "particles 2\n1 0 0 0 1e-3 2650\n2 2e-3 0 0 1e-3 2650\nbonds 1\n1 7\n")}},
       run + geom,
       2,
       {"s.geom:7", "7", "no particle"}},
      {"geom_self_bond",
       {{"s.geom", txt(std::string(kGeomHead) +
                       "particles 2\n1 0 0 0 1e-3 2650\n2 2e-3 0 0 1e-3 2650\nbonds 1\n2 2\n")}},
       run + geom,
       2,
       {"s.geom:7", "itself"}},
      {"geom_bond_twice",
       {{"s.geom",
         txt(std::string(kGeomHead) +
             "particles 2\n1 0 0 0 1e-3 2650\n2 2e-3 0 0 1e-3 2650\nbonds 2\n1 2\n2 1\n")}},
       run + geom,
       2,
       {"s.geom:8", "twice"}},
      {"geom_huge_count",
       {{"s.geom", txt(std::string(kGeomHead) + "particles 1000000000000\n")}},
       run + geom,
       2,
       {"s.geom:3", "particles", "1000000000000"}},
      {"geom_count_mismatch",
       {{"s.geom", txt(std::string(kGeomHead) + "particles 3\n1 0 0 0 1e-3 2650\n")}},
       run + geom,
       2,
       {"s.geom", "announced 3"}},
      {"geom_negative_tag",
       {{"s.geom", txt(std::string(kGeomHead) + "particles 1\n-1 0 0 0 1e-3 2650\n")}},
       run + geom,
       2,
       {"s.geom:4", "tag", "-1"}},
      {"geom_unknown_key",
       {{"s.geom", txt(std::string(kGeomHead) + "walls 2\n")}},
       run + geom,
       2,
       {"s.geom:3", "walls", "unknown key"}},
      {"geom_2d_with_z",
       {{"s.geom", "breccia-geometry 1\ndimension 2\nparticles 1\n1 0 0 1 1e-3 2650\n"}},
       run + geom + " --set engine.dimension=2 --set contact.law=\"linear\"",
       2,
       {"s.geom:4", "z"}},
      // --- x-y-z-r tables ---
      {"table_nan_first_row",
       {{"s.txt", "nan 0 0 1e-3\n3e-3 0 0 1e-3\n"}},
       run + table,
       2,
       {"s.txt:1", "finite"}},
      {"table_words_after_header", {{"s.txt", "x y z r\nx y z r\n"}}, run + table, 2, {"s.txt:2"}},
      {"table_five_columns",
       {{"s.txt", "0 0 0 1e-3 5\n"}},
       run + table,
       2,
       {"s.txt:1", "columns", "5"}},
      {"table_coincident",
       {{"s.txt", "0 0 0 1e-3\n0 0 0 1e-3\n"}},
       run + table,
       2,
       {"s.txt:2", "share a centre"}},
      {"table_empty", {{"s.txt", "# nothing\n"}}, run + table, 2, {"s.txt", "no rows"}},
      {"table_negative_radius",
       {{"s.txt", "0 0 0 -1e-3\n"}},
       run + table,
       2,
       {"s.txt:1", "radius"}},
      // --- GenGeo files ---
      {"gengeo_fractional_id",
       {{"s.geo", txt(gg_head + "1\n0 0 0 1e-3 0.5 0\nEndParticles\n")}},
       run + gengeo,
       2,
       {"s.geo:8", "id", "0.5"}},
      {"gengeo_negative_id",
       {{"s.geo", txt(gg_head + "1\n0 0 0 1e-3 -3 0\nEndParticles\n")}},
       run + gengeo,
       2,
       {"s.geo:8", "id", "-3"}},
      {"gengeo_bond_missing",
       {{"s.geo", txt(gg_head + "2\n0 0 0 1e-3 0 0\n2e-3 0 0 1e-3 1 "
                                "0\nEndParticles\nBeginConnect\n1\n0 9 0\nEndConnect\n")}},
       run + gengeo,
       2,
       {"s.geo:13", "10", "no particle"}},
      {"gengeo_header",
       {{"s.geo", "LSMGeometri 1.2\n"}},
       run + gengeo,
       2,
       {"s.geo:1", "LSMGeometry"}},
      {"gengeo_count_mismatch",
       {{"s.geo", txt(gg_head + "2\n0 0 0 1e-3 0 0\nEndParticles\n")}},
       run + gengeo,
       2,
       {"s.geo", "EndParticles"}},
      {"gengeo_huge_count",
       {{"s.geo", txt(gg_head + "1e15\n")}},
       run + gengeo,
       2,
       {"s.geo:7", "particle count"}},
      // --- damaged run folders ---
      {"summary_wrong_type",
       {{"summary.json",
         "{\"experiment\": \"x\", \"status\": \"complete\", \"test\": \"UCS\", "
         "\"quasi_static\": 3}"}},
       "summarise {d}",
       2,
       {"summary.json", "quasi_static", "3"}},
      {"summary_not_json",
       {{"summary.json", "{\"experiment\": "}},
       "summarise {d}",
       2,
       {"summary.json", "not valid JSON"}},
      {"summary_array",
       {{"summary.json", "[1, 2]"}},
       "summarise {d}",
       2,
       {"summary.json", "object"}},
      {"summary_bad_quarters",
       {{"summary.json",
         "{\"experiment\": \"x\", \"status\": \"complete\", \"test\": \"UCS\", "
         "\"crack_pattern\": {\"quarter_shares_along_axis\": [\"a\", 1, 2, 3]}}"}},
       "summarise {d}",
       2,
       {"crack_pattern.quarter_shares_along_axis[0]"}},
      {"sweep_runs_not_list",
       {{"sweep.json", "{\"experiment\": \"x\", \"status\": \"complete\", \"runs\": 5}"}},
       "summarise {d}",
       2,
       {"sweep.json", "runs", "5"}},
      {"sweep_run_missing_stress",
       {{"sweep.json", "{\"experiment\": \"x\", \"status\": \"complete\", \"runs\": [{}]}"}},
       "summarise {d}",
       2,
       {"sweep.json", "runs[0].confining_stress_pa", "missing"}},
      {"sweep_plan_bad_kind",
       {{"sweep-plan.json", "{\"format\": \"breccia-sweep-plan 1\", \"kind\": \"x\"}"}},
       "resume {d}",
       2,
       {"sweep-plan.json", "kind", "confining_stress, strain_rate or parameter"}},
      {"sweep_plan_value_not_text",
       {{"sweep-plan.json",
         "{\"format\": \"breccia-sweep-plan 1\", \"kind\": \"strain_rate\", "
         "\"experiment\": \"[engine]\\ndensity_scaling = 1\\n\", \"values\": [0.5]}"}},
       "resume {d}",
       2,
       {"sweep-plan.json", "values[0]"}},
      {"sweep_plan_rate_not_a_number",
       {{"sweep-plan.json",
         "{\"format\": \"breccia-sweep-plan 1\", \"kind\": \"strain_rate\", "
         "\"experiment\": \"[engine]\\ndensity_scaling = 1\\n\", \"values\": [\"fast\"]}"}},
       "resume {d}",
       2,
       {"sweep-plan.json", "values", "fast", "numbers"}},
      {"manifest_not_json",
       {{"manifest.json", "{{{"}},
       "resume {d}",
       2,
       {"manifest.json", "not valid JSON"}},
      {"manifest_status_type",
       {{"manifest.json", "{\"status\": 7}"}},
       "resume {d}",
       2,
       {"manifest.json", "status", "7"}},
      {"checkpoint_foreign",
       {{"manifest.json", "{\"status\": \"interrupted\"}"},
        {"checkpoint.bin", "hello world, not a checkpoint"}},
       "resume {d}",
       2,
       {"checkpoint.bin"}},
      {"complete_run",
       {{"manifest.json", "{\"status\": \"complete\"}"}},
       "resume {d}",
       2,
       {"nothing to resume"}},
      // --- calibration files: refused by `calibrate --check` and before the first trial ---
      {"calibration_tie_negative_factor",
       {{"c.toml",
         txt(kCalibrationHead + kModulusOnly +
             "[tied]\n\"bond.cohesion\" = { follows = \"bond.modulus\", factor = -1.0 }\n" +
             kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:", "tied.\"bond.cohesion\".factor", "-1", "above 0"}},
      {"calibration_tie_integer_key",
       {{"c.toml", txt(kCalibrationHead + kModulusOnly +
                       "[tied]\n\"engine.seed\" = { follows = \"bond.modulus\", factor = 1e-9 }\n" +
                       kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:", "tied.\"engine.seed\"", "integer"}},
      {"calibration_tie_out_of_range_at_a_bound",
       {{"c.toml", txt(kCalibrationHead + kModulusOnly +
                       "[tied]\n\"contact.poisson_ratio\" = { follows = \"bond.modulus\", factor = "
                       "1e-11 }\n" +
                       kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:", "tied.\"contact.poisson_ratio\"", "bound 60000000000", "contact.poisson_ratio"}},
      {"calibration_disc_too_small",
       {{"c.toml", txt(kCalibrationHead +
                       "[targets]\nyoungs_modulus = 8e9\ntensile_strength = 5e6\n[free]\n"
                       "\"bond.modulus\" = [2e9, 60e9]\n\"bond.tensile_strength\" = [1e6, 1e9]\n" +
                       kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml", "brazilian test", "too small for its grains", "calibration.brazilian_diameter"}},
      {"calibration_disc_too_small_run",
       {{"c.toml", txt(kCalibrationHead +
                       "[targets]\nyoungs_modulus = 8e9\ntensile_strength = 5e6\n[free]\n"
                       "\"bond.modulus\" = [2e9, 60e9]\n\"bond.tensile_strength\" = [1e6, 1e9]\n" +
                       kCalibrationExperiment)}},
       "calibrate {d}/c.toml --output {d}/runs",
       2,
       {"c.toml", "too small for its grains"}},
      {"calibration_negative_disc",
       {{"c.toml", txt(kCalibrationHead + "brazilian_diameter = -1e-3\n" + kModulusOnly +
                       kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:6", "calibration.brazilian_diameter", "-0.001", "above 0"}},
      {"calibration_without_experiment",
       {{"c.toml", txt(kCalibrationHead + kModulusOnly)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml", "[experiment]", "missing"}},
      {"calibration_absurd_tolerance",
       {{"c.toml", txt(replace_all(kCalibrationHead + kModulusOnly + kCalibrationExperiment,
                                   "youngs_modulus = 8e9\n",
                                   "youngs_modulus = 8e9\npoisson_ratio = { value = 0.25, "
                                   "tolerance = 100 }\n"))}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:", "targets.poisson_ratio.tolerance", "100", "at most 0.2"}},
      {"calibration_lattice_source",
       {{"c.toml", txt(replace_all(kCalibrationHead + kModulusOnly + kCalibrationExperiment,
                                   "width = 3e-3", "source = \"lattice\"\nwidth = 3e-3"))}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml", "experiment.sample.source", "lattice", "generate"}},
      {"calibration_folder_as_its_file",
       {{"c.toml", txt(kCalibrationHead + kModulusOnly + kCalibrationExperiment)},
        {"runs/t/calibration.toml/x", ""}},
       "calibrate {d}/c.toml --output {d}/runs",
       2,
       {"runs/t/calibration.toml", "is not a file"}},
      {"calibration_damaged_trial_record",
       {{"c.toml", txt(kCalibrationHead + kModulusOnly + kCalibrationExperiment)},
        {"runs/t/calibration.toml", txt(kCalibrationHead + kModulusOnly + kCalibrationExperiment)},
        {"runs/t/trials.jsonl", "{\"key\": 5, \"run\": 1}\n"}},
       "calibrate {d}/c.toml --output {d}/runs",
       2,
       {"trials.jsonl:1", "'key'", "5", "string"}},
      {"calibration_trial_record_not_json",
       {{"c.toml", txt(kCalibrationHead + kModulusOnly + kCalibrationExperiment)},
        {"runs/t/calibration.toml", txt(kCalibrationHead + kModulusOnly + kCalibrationExperiment)},
        {"runs/t/trials.jsonl", "{{{\n{\"key\": \"x\"}\n"}},
       "calibrate {d}/c.toml --output {d}/runs",
       2,
       {"trials.jsonl:1", "not valid JSON"}},
      // --- sweeps: every value checked before a folder is made ---
      {"sweep_duplicate_over",
       {},
       "sweep --output {d}/runs --over test.max_strain 0.01 1e-2" + kLattice,
       2,
       {"--over", "test.max_strain 1e-2", "same experiment"}},
      {"sweep_duplicate_confining",
       {},
       "sweep --output {d}/runs --confining-mpa 5 5" + kLattice,
       2,
       {"--confining-mpa", "5 MPa", "given twice"}},
      {"sweep_infinite_confining",
       {},
       "sweep --output {d}/runs --confining-mpa 5 inf" + kLattice,
       2,
       {"--confining-mpa", "inf", "finite"}},
      {"sweep_huge_confining",
       {},
       "sweep --output {d}/runs --confining-mpa 5 1e300" + kLattice,
       2,
       {"--confining-mpa", "1e+300 MPa", "<= 10000000000 Pa"}},
      {"sweep_duplicate_rates",
       {},
       "sweep --output {d}/runs --strain-rates 5 5 --set engine.density_scaling=1" + kLattice,
       2,
       {"--strain-rates", "5", "given twice"}},
      {"sweep_over_bad_value",
       {},
       "sweep --output {d}/runs --over engine.threads x" + kLattice,
       2,
       {"--over", "engine.threads x", "integer"}},
      {"sweep_over_old_loading_key",
       {{"e.toml", "[test]\nkind = \"ucs\"\n"}},
       "sweep {d}/e.toml --output {d}/runs --over loading.max_strain 0.01 0.02" + kLattice,
       2,
       {"loading.max_strain", "test.<key>"}},
      // --- sweep plans of a sweep being resumed: every error names the plan ---
      {"plan_without_experiment",
       {{"sweep-plan.json", txt(lattice_plan("confining_stress", "[\"0\"]", ""))}},
       "resume {d}",
       2,
       {"sweep-plan.json", "'experiment'", "missing"}},
      {"plan_experiment_bad",
       {{"sweep-plan.json",
         txt(lattice_plan("confining_stress", "[\"0\"]", "[engine]\\nthreads = \\\"x\\\"\\n"))}},
       "resume {d}",
       2,
       {"sweep-plan.json", "experiment.engine.threads", "integer", "plan's experiment"}},
      {"plan_duplicate_values",
       {{"sweep-plan.json", txt(lattice_plan("confining_stress", "[\"0\", \"0\"]", kPlanLattice))}},
       "resume {d}",
       2,
       {"sweep-plan.json", "'values'", "given twice"}},
      {"plan_huge_stress",
       {{"sweep-plan.json", txt(lattice_plan("confining_stress", "[\"1e30\"]", kPlanLattice))}},
       "resume {d}",
       2,
       {"sweep-plan.json", "'values'", "1e+30"}},
      {"plan_bad_parameter",
       {{"sweep-plan.json",
         txt(lattice_plan("parameter", "[\"x\"]", kPlanLattice, ", \"key\": \"engine.threads\""))}},
       "resume {d}",
       2,
       {"sweep-plan.json", "'values'", "engine.threads x", "integer"}},
      {"plan_experiment_from_a_missing_file",
       {{"sweep-plan.json",
         txt(lattice_plan("confining_stress", "[\"0\"]", "[sample]\\nsource = \\\"file\\\"\\n"))}},
       "resume {d}",
       2,
       {"sweep-plan.json", "experiment.sample.file"}},
      {"summary_empty_object",
       {{"summary.json", "{}"}},
       "summarise {d}",
       2,
       {"summary.json", "experiment", "missing"}},
      {"sweep_empty_object",
       {{"sweep.json", "{}"}},
       "summarise {d}",
       2,
       {"sweep.json", "experiment", "missing"}},
      {"report_damaged_summary",
       {{"summary.json", "{\"experiment\": \"x\", \"status\": \"complete\"}"}},
       "report {d}",
       2,
       {"summary.json", "'test'", "missing"}},
      {"checkpoint_is_a_folder",
       {{"manifest.json", "{\"status\": \"interrupted\"}"}, {"checkpoint.bin/x", ""}},
       "resume {d}",
       2,
       {"checkpoint.bin", "is a folder"}},
      {"geometry_fifo", {{"s.geom", kFifo}}, run + geom, 2, {"s.geom", "not a regular file"}},
      {"empty_experiment", exp(""), e, 2, {"e.toml", "empty"}},
      {"empty_experiment_comments", exp("# nothing here\n\n"), e, 2, {"e.toml", "empty"}},
      {"radius_underflow",
       {},
       run + "--set sample.radius_min=1e-308 --set sample.radius_max=2e-308",
       2,
       {"sample.radius_max", "2e-308", "1e-09"}},
      {"radius_overflow",
       {},
       run + "--set sample.radius_max=1e308",
       2,
       {"sample.radius_max", "1e+308"}},
      {"radius_too_large_for_the_sample",
       {},
       run + "--set sample.radius_min=1e-3 --set sample.radius_max=3e-3",
       2,
       {"sample.radius_max", "0.003"}},
      {"radius_too_many_grains",
       {},
       run + "--set sample.radius_min=1e-8 --set sample.radius_max=2e-8 "
             "--set sample.bond_gap_tolerance=1e-9",
       2,
       {"sample.radius_min", "sample.max_particles"}},
      // --- the experiment file and --set ---
      {"set_unknown_table_on_a_file",
       exp("[engine]\nthreads = 1\n"),
       e + " --set nosuch.key=1",
       2,
       {"--set nosuch.key=1", "[nosuch]", "unknown table"}},
      // --- options and values that were accepted, then ignored or misused ---
      {"resume_a_run_with_jobs",
       {{"manifest.json", "{\"status\": \"interrupted\"}"}},
       "resume {d} --jobs 3",
       2,
       {"'--jobs' = 3", "a sweep's option", "run folder"}},
      {"resume_a_run_with_ranks_per_run",
       {{"manifest.json", "{\"status\": \"interrupted\"}"}},
       "resume {d} --ranks-per-run 2",
       2,
       {"'--ranks-per-run' = 2", "a sweep's option"}},
      {"calibration_grip_speed_without_a_tensile_target",
       {{"c.toml", txt(kCalibrationHead + "tensile_test = \"direct_tension\"\ngrip_speed = 0.01\n" +
                       kModulusOnly + kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:6", "calibration.tensile_test", "direct_tension", "targets.tensile_strength"}},
      {"calibration_disc_without_a_tensile_target",
       {{"c.toml", txt(kCalibrationHead + "brazilian_diameter = 2e-3\n" + kModulusOnly +
                       kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:6", "calibration.brazilian_diameter", "targets.tensile_strength"}},
      {"calibration_confinement_without_an_envelope_target",
       {{"c.toml", txt(kCalibrationHead + "confining_stresses = [5e6]\n" + kModulusOnly +
                       kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:6", "calibration.confining_stresses", "targets.cohesion"}},
      {"calibration_verify_set_without_seeds",
       {{"c.toml", txt(kCalibrationHead + "verify_set = [\"sample.width=4e-3\"]\n" + kModulusOnly +
                       kCalibrationExperiment)}},
       "calibrate --check {d}/c.toml",
       2,
       {"c.toml:6", "calibration.verify_set", "verify_seeds = []"}},
      {"preset_2d_on_a_3d_sample",
       exp("[material]\npreset = \"lac_du_bonnet_2d_fj\"\n"),
       e,
       2,
       {"e.toml", "material.preset", "lac_du_bonnet_2d_fj", "calibrated in 2D",
        "\"lac_du_bonnet_fj\""}},
      {"preset_3d_on_a_2d_sample",
       exp("[engine]\ndimension = 2\n[material]\npreset = \"berea\"\n[sample]\n"
           "shape = \"rectangle\"\n"),
       e,
       2,
       {"e.toml", "material.preset", "calibrated in 3D", "\"berea_2d\""}},
      {"bond_gap_wider_than_the_grains",
       {},
       run + "--set sample.bond_gap_tolerance=5",
       2,
       {"sample.bond_gap_tolerance", "= 5", "sample.radius_min"}},
      {"bond_gap_wider_than_the_lattice",
       {},
       run + "--set sample.bond_gap_tolerance=1e-3" + kLattice,
       2,
       {"sample.bond_gap_tolerance", "0.001", "sample.radius = 0.0005"}},
      {"bond_gap_wider_than_the_file_grains",
       {{"s.txt", "0 0 0 1e-4\n2e-4 0 0 1e-4\n"}},
       run + table + " --set sample.bond_gap_tolerance=3e-4",
       2,
       {"sample.bond_gap_tolerance", "0.0003", "s.txt (0.0001 m)"}},
      {"confining_sweep_of_a_brazilian_test",
       {},
       "sweep --output {d}/runs --confining-mpa 0 5 --set test.kind=\"brazilian\"" + kLattice,
       2,
       {"--confining-mpa", "test.kind = \"brazilian\"", "loaded by platens"}},
      {"run_output_empty", {}, "run --output '' --quiet" + kLattice, kAnyError, {"--output", "''"}},
      {"sweep_output_empty",
       {},
       "sweep --output '' --confining-mpa 0" + kLattice,
       kAnyError,
       {"--output", "''"}},
  };
  return c;
}

void PrintTo(const BadCase& k, std::ostream* os) {
  *os << k.name;
}

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, FailsClearlyAndLeavesNoWholeLookingRun) {
  const BadCase& k = GetParam();
  const fs::path dir = fs::temp_directory_path() / (std::string("breccia_bad_") + k.name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const auto& [name, text] : k.files) {
    fs::create_directories((dir / name).parent_path());
    if (std::string(text) == kFifo)
      ASSERT_EQ(mkfifo((dir / name).c_str(), 0600), 0);
    else
      std::ofstream(dir / name) << text;
  }
  const Result r = run(replace_all(k.args, "{d}", dir.string()));
  ASSERT_NE(r.code, -1) << "killed by a signal\n" << r.out;
  if (k.code == kAnyError)
    EXPECT_NE(r.code, 0) << r.out;
  else
    EXPECT_EQ(r.code, k.code) << r.out;
  for (const std::string& needle : k.needles)
    EXPECT_NE(r.out.find(replace_all(needle, "{d}", dir.string())), std::string::npos)
        << "the message should name '" << needle << "':\n"
        << r.out;
  EXPECT_EQ(r.out.find("std::"), std::string::npos) << "a library message reached the user:\n"
                                                    << r.out;
  EXPECT_EQ(r.out.find("json.exception"), std::string::npos) << r.out;
  EXPECT_FALSE(has_whole_looking_run(dir / "runs")) << r.out;
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Cases, BadInput, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<BadCase>& i) {
                           return std::string(i.param.name);
                         });

// `breccia generate` never writes over a file it reads or one that is not a sample, and a refused
// or failed write leaves every file as it was and no temporary behind: each output path here is
// refused, naming the option, the path and why.
TEST(Generate, NeverWritesOverAnInputAndLeavesNoTemporary) {
  const fs::path dir = fs::temp_directory_path() / "breccia_generate_outputs";
  fs::remove_all(dir);
  fs::create_directories(dir / "adir");
  std::ofstream(dir / "lattice.toml") << "[sample]\nsource = \"lattice\"\ncells = [2, 2, 4]\n";
  const Result lattice =
      run("generate " + (dir / "lattice.toml").string() + " --output " + (dir / "s.geom").string());
  ASSERT_EQ(lattice.code, 0) << lattice.out;
  std::ofstream(dir / "e.toml") << "[sample]\nsource = \"file\"\nfile = \"s.geom\"\n";
  std::ofstream(dir / "notes.txt") << "a user's notes\n";
  std::ofstream(dir / "results.json") << "[1, 2]\n";
  // Every file's bytes before: none may change.
  std::vector<std::pair<fs::path, std::string>> before;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) before.emplace_back(e.path(), read(e.path()));
  const std::vector<std::pair<std::string, std::string>> outputs = {
      {"e.toml", "would replace the experiment file"},
      {"s.geom", "would replace the sample file the experiment reads"},
      {"s.geom.json", "would replace the report beside the sample file"},
      {"''", "the sample file to write"},
      {"adir", "a file to write, not a folder"},
      {"newdir/", "a file to write, not a folder"},
      {"notes.txt", "not a breccia-geometry sample"},
      {"results", "results.json exists and is not a sample's report"},
      {"notes.txt/s.geom", "cannot write the sample there"}};
  for (const auto& [output, why] : outputs) {
    const std::string path = output == "''" ? output : (dir / output).string();
    const Result r = run("generate " + (dir / "e.toml").string() + " --output " + path);
    EXPECT_EQ(r.code, 2) << output << "\n" << r.out;
    EXPECT_NE(r.out.find("'--output' = " + path), std::string::npos) << output << "\n" << r.out;
    EXPECT_NE(r.out.find(why), std::string::npos) << output << "\n" << r.out;
    EXPECT_EQ(r.out.find(".tmp"), std::string::npos) << output << "\n" << r.out;
  }
  for (const auto& [file, text] : before) EXPECT_EQ(read(file), text) << file;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    EXPECT_NE(e.path().extension(), ".tmp") << e.path();
    EXPECT_NE(e.path().filename(), "newdir") << "a folder was made for a refused output";
  }
  // A sample read from a file is written again as it was read; a lattice is written, not packed.
  const Result copy =
      run("generate " + (dir / "e.toml").string() + " --output " + (dir / "copy.geom").string());
  ASSERT_EQ(copy.code, 0) << copy.out;
  EXPECT_EQ(read(dir / "copy.geom"), read(dir / "s.geom"));
  EXPECT_NE(read(dir / "s.geom").find("\nparticles 64\n"), std::string::npos)
      << "2 x 2 x 4 FCC cells hold 64 grains";
  fs::remove_all(dir);
}

// A real checkpoint, damaged three ways: a flipped byte in the middle, a cut, and the hash
// trailer rewritten. Each is refused by name before any of it is used; none resumes to
// "complete".
TEST(BadCheckpoint, DamagedCheckpointsAreRefused) {
  const fs::path dir = fs::temp_directory_path() / "breccia_bad_checkpoint";
  fs::remove_all(dir);
  const Result first =
      run("run --quiet --output " + dir.string() + kLattice + " --stop-at-step 50");
  ASSERT_EQ(first.code, 130) << first.out;
  const fs::path folder = last_line(first.out);
  const fs::path cp = folder / "checkpoint.bin";
  ASSERT_TRUE(fs::exists(cp)) << first.out;
  const std::string good = read(cp);
  auto write = [&](const std::string& bytes) {
    std::ofstream(cp, std::ios::binary | std::ios::trunc) << bytes;
  };
  std::string flipped = good;
  flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 0x10);
  std::string rehashed = good;
  rehashed[rehashed.size() - 1] = static_cast<char>(rehashed[rehashed.size() - 1] ^ 0x01);
  for (const auto& [what, bytes, needle] :
       {std::tuple{"flipped byte", flipped, "checksum"},
        std::tuple{"cut in half", good.substr(0, good.size() / 2), "checksum"},
        std::tuple{"hash altered", rehashed, "checksum"},
        std::tuple{"empty", std::string(), "checkpoint.bin"}}) {
    write(bytes);
    const Result r = run("resume --quiet " + folder.string());
    EXPECT_EQ(r.code, 2) << what << ": " << r.out;
    EXPECT_NE(r.out.find("checkpoint.bin"), std::string::npos) << what << ": " << r.out;
    EXPECT_NE(r.out.find(needle), std::string::npos) << what << ": " << r.out;
    EXPECT_FALSE(fs::exists(folder / "summary.json") &&
                 read(folder / "manifest.json").find("\"complete\"") != std::string::npos)
        << what;
  }
  write(good);  // the intact one still resumes, to the end
  const Result ok = run("resume --quiet " + folder.string());
  EXPECT_EQ(ok.code, 0) << ok.out;
  fs::remove_all(dir);
}

}  // namespace
