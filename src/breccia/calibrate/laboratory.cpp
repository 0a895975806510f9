#include "breccia/calibrate/laboratory.hpp"

#include <fmt/format.h>

#include <chrono>
#include <fstream>

#include "breccia/analysis/compression.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/io/json_view.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/run/run.hpp"
#include "breccia/run/sample_build.hpp"

namespace breccia {

namespace fs = std::filesystem;
using nlohmann::json;

TestPlan tests_for(const CalibrationSpec& c, std::optional<CalibrationStage> stage) {
  TestPlan p;
  const bool all = !stage.has_value();
  p.brazilian = c.needs_brazilian() && (all || *stage == CalibrationStage::Strength);
  p.envelope = c.needs_envelope() && (all || *stage == CalibrationStage::Friction);
  return p;
}

Laboratory::Laboratory(const CalibrationSpec& c, fs::path folder,
                       std::function<void(const std::string&)> log)
    : c_(c), folder_(std::move(folder)), log_(std::move(log)) {
  if (!log_) log_ = [](const std::string&) {};
  fs::create_directories(folder_ / "samples");
  fs::create_directories(folder_ / "trials");
  std::ifstream in(folder_ / "trials.jsonl");
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty()) continue;
    json j = json::parse(line, nullptr, false);
    // A line cut short by a crash is the last one; it is dropped and its test run again.
    if (j.is_discarded() || !j.is_object() || !j.contains("key")) {
      log_(fmt::format("calibrate: trials.jsonl line {} is unreadable; its test runs again",
                       lineno));
      continue;
    }
    book_[j["key"].get<std::string>()] = j;
    next_run_ = std::max(next_run_, j.value("run", 0) + 1);
  }
}

std::vector<std::string> Laboratory::set_overrides(const std::string& set) const {
  if (set == "calibration") return {};
  std::vector<std::string> o = c_.verify_set;
  o.push_back("engine.seed=" + set.substr(set.find('-') + 1));
  return o;
}

const json& Laboratory::sample_report(const std::string& set) const {
  return samples_.at(set).report;
}

void Laboratory::prepare_samples(const std::string& set, const std::vector<double>& values) {
  if (samples_.count(set)) return;
  SamplePaths paths;
  paths.prism = (folder_ / "samples" / (set + "-prism.geom")).string();
  paths.disc = (folder_ / "samples" / (set + "-disc.geom")).string();
  std::vector<std::string> o = parameter_overrides(c_, values);
  for (const auto& s : set_overrides(set)) o.push_back(s);
  auto pack = [&](const std::string& path, std::vector<std::string> extra, const char* what) {
    if (fs::exists(path) && fs::exists(path + ".json")) return read_json_object(path + ".json");
    log_(fmt::format("calibrate: packing the {} sample of set \"{}\"", what, set));
    extra.insert(extra.begin(), o.begin(), o.end());
    const ExperimentSpec s = parse_experiment_table(c_.text, c_.path, "experiment", extra);
    return generate_sample(s, path, [](const std::string&) {}).report;
  };
  paths.report = pack(paths.prism, {}, "compression");
  if (c_.needs_brazilian()) {
    std::vector<std::string> disc{fmt::format("sample.diameter={:.17g}", c_.disc_diameter)};
    if (c_.base.dimension == 2) {
      disc.push_back("sample.shape=\"disk\"");
    } else {
      disc.push_back("sample.shape=\"cylinder\"");
      disc.push_back(fmt::format("sample.height={:.17g}", c_.disc_thickness));
    }
    pack(paths.disc, disc, "Brazilian disc");
  }
  samples_[set] = paths;
}

namespace {

std::optional<double> number_or_none(const JsonView& v, const std::string& key) {
  return v.maybe_number(key);
}

// The properties one test gives (missing ones are absent, with the reason in `problems`).
json test_properties(const std::string& test, const JsonView& s, std::vector<std::string>& why) {
  json p = json::object();
  // Not targets, but what the honesty checks of a calibrated rock read (docs/materials.md): the
  // share of shear microcracks and whether the failure crushed an end of the sample.
  if (auto n = number_or_none(s, "bonds_broken"); n && *n > 0)
    if (auto sh = number_or_none(s, "cracks_shear")) p["shear_crack_fraction"] = *sh / *n;
  if (auto cp = s.find("crack_pattern"))
    if (auto q = cp->maybe_number("largest_end_quarter_share")) p["largest_end_quarter_share"] = *q;
  const bool peak = s.flag("peak_reached", false);
  if (!peak) why.push_back(test + ": no peak before the strain limit");
  if (test == "ucs") {
    if (auto e = number_or_none(s, "youngs_modulus_pa")) p["youngs_modulus"] = *e;
    if (auto nu = number_or_none(s, "poisson_ratio")) p["poisson_ratio"] = *nu;
    if (peak) {
      const double q = s.number("peak_deviatoric_stress_pa");
      p["uniaxial_strength"] = q;
      if (auto eps = number_or_none(s, "axial_strain_at_peak")) p["strain_at_peak"] = *eps;
      if (auto ci = number_or_none(s, "crack_initiation_stress_pa"); ci && q > 0)
        p["crack_initiation_ratio"] = *ci / q;
    }
  } else if (test == "brazilian") {
    if (peak) p["tensile_strength"] = s.number("tensile_strength_pa");
  } else if (peak) {
    p["sigma1_at_peak"] = s.number("sigma1_at_peak_pa");
  }
  return p;
}

void append_line(const fs::path& file, const json& j) {
  std::ofstream out(file, std::ios::app);
  out << j.dump() << '\n';
  out.flush();
  if (!out) throw InputError(file.string(), "", "", "cannot append to the trial record");
}

}  // namespace

json Laboratory::run_test(const std::string& set, const std::vector<double>& values,
                          const std::string& test, double sigma3, Measurement& m) {
  std::vector<std::string> o = parameter_overrides(c_, values);
  std::string key = set + "|" + test;
  for (const auto& s : o) key += "|" + s;
  if (auto it = book_.find(key); it != book_.end()) return it->second;
  throw_if_interrupted("calibrating");

  for (const auto& s : set_overrides(set)) o.push_back(s);
  const SamplePaths& sp = samples_.at(set);
  o.push_back("sample.source=\"file\"");
  o.push_back(fmt::format("sample.file=\"{}\"",
                          fs::absolute(test == "brazilian" ? sp.disc : sp.prism).string()));
  ExperimentSpec spec = parse_experiment_table(c_.text, c_.path, "experiment", o);
  if (test == "brazilian") {
    spec.test_kind = "brazilian";
    BrazilianTest::Params p;
    p.platen_speed = c_.disc_platen_speed;
    spec.test = p;
  } else {
    set_confining_stress(spec, sigma3, c_.path);
  }
  const int run = next_run_++;
  spec.name = fmt::format("{:03d}-{}-{}", run, set, test);
  spec.output_directory = (folder_ / "trials").string();
  spec.plot = false;
  spec.progress = false;
  spec.snapshot_strain_interval = 0.0;
  spec.checkpoint_interval = 0.0;
  spec.ae_moment_tensors = false;  // not needed for the properties; the mechanics is the same

  RunOptions opt;
  opt.interrupt = &interrupt_flag();
  opt.log = [](const std::string&) {};
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = run_experiment(spec, opt);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (r.status == "interrupted") throw Interrupted("running " + spec.name);

  json record{{"key", key},         {"run", run},          {"set", set},
              {"test", test},       {"sigma3_pa", sigma3}, {"values", values},
              {"folder", r.folder}, {"status", r.status},  {"wall_seconds", wall}};
  std::vector<std::string> why;
  if (r.status == "complete") {
    const json summary = read_json_object((fs::path(r.folder) / "summary.json").string());
    record["properties"] =
        test_properties(test, JsonView(summary, r.folder + "/summary.json"), why);
  } else {
    record["properties"] = json::object();
    why.push_back(test + ": run " + r.status + " (" + r.stop_reason + ")");
  }
  record["problems"] = why;
  append_line(folder_ / "trials.jsonl", record);
  book_[key] = record;
  m.new_runs += 1;
  m.wall_seconds += wall;
  return record;
}

Measurement Laboratory::measure(const std::string& set, const std::vector<double>& values,
                                const TestPlan& plan) {
  prepare_samples(set, values);
  Measurement m;
  auto take = [&](const json& rec) {
    m.tests[rec.value("test", "?")] = rec.at("properties");
    m.run_folders.push_back(rec.value("folder", ""));
    for (const auto& w : rec.value("problems", std::vector<std::string>{})) m.problems.push_back(w);
    return rec.at("properties");
  };
  const json ucs = take(run_test(set, values, "ucs", 0.0, m));
  for (const auto& i : property_table())
    if (ucs.contains(std::string(i.key)))
      m.properties[i.property] = ucs[std::string(i.key)].get<double>();
  if (plan.brazilian) {
    const json b = take(run_test(set, values, "brazilian", 0.0, m));
    if (b.contains("tensile_strength"))
      m.properties[Property::TensileStrength] = b["tensile_strength"].get<double>();
  }
  if (plan.envelope) {
    std::vector<double> s3{0.0}, s1;
    if (ucs.contains("uniaxial_strength")) s1.push_back(ucs["uniaxial_strength"].get<double>());
    for (double sigma3 : c_.confining_stresses) {
      const json t =
          take(run_test(set, values, fmt::format("triaxial-{:g}MPa", sigma3 / 1e6), sigma3, m));
      if (t.contains("sigma1_at_peak")) {
        s3.push_back(sigma3);
        s1.push_back(t["sigma1_at_peak"].get<double>());
      }
    }
    if (s1.size() == s3.size() && s1.size() >= 2) {
      const auto fit = analysis::fit_mohr_coulomb(s3, s1);
      if (fit.valid) {
        m.properties[Property::Cohesion] = fit.cohesion;
        m.properties[Property::FrictionAngle] = fit.friction_angle_deg;
      } else {
        m.problems.push_back("Mohr-Coulomb fit: " + fit.flag);
      }
    } else {
      m.problems.push_back("Mohr-Coulomb fit: a test gave no peak");
    }
  }
  return m;
}

}  // namespace breccia
