#include "breccia/calibrate/laboratory.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>

#include "breccia/analysis/compression.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/ranks.hpp"
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
  p.tensile = c.needs_tensile() && (all || *stage == CalibrationStage::Strength);
  p.envelope = c.needs_envelope() && (all || *stage == CalibrationStage::Friction);
  return p;
}

Laboratory::Laboratory(const CalibrationSpec& c, fs::path folder,
                       std::function<void(const std::string&)> log, RankPool* pool)
    : c_(c), folder_(std::move(folder)), log_(std::move(log)), pool_(pool) {
  if (!log_) log_ = [](const std::string&) {};
  fs::create_directories(folder_ / "samples");
  fs::create_directories(folder_ / "trials");
  read_trial_record();
}

namespace {

// A trial record's fields, checked: a record that does not check out names trials.jsonl, its
// line and the key, so that no library message reaches the user.
void check_trial_line(const json& j, const std::string& where) {
  if (!j.is_object()) throw InputError(where, "", "", "a trial record must be a JSON object");
  auto need = [&](const char* key, bool ok, const char* what) {
    if (!j.contains(key))
      throw InputError(where, key, "(missing)", std::string("expected ") + what);
    if (!ok) throw InputError(where, key, j[key].dump(), std::string("expected ") + what);
  };
  need("key", j.contains("key") && j["key"].is_string(), "a string");
  need("run",
       j.contains("run") && j["run"].is_number_integer() && j["run"].get<std::int64_t>() >= 0,
       "a run number >= 0");
  need("test", j.contains("test") && j["test"].is_string(), "a string");
  need("folder", j.contains("folder") && j["folder"].is_string(), "a string");
  need("properties", j.contains("properties") && j["properties"].is_object(),
       "an object of numbers");
  for (const auto& [k, v] : j["properties"].items())
    if (!v.is_number()) throw InputError(where, "properties." + k, v.dump(), "expected a number");
  need("problems",
       j.contains("problems") && j["problems"].is_array() &&
           std::all_of(j["problems"].begin(), j["problems"].end(),
                       [](const json& x) { return x.is_string(); }),
       "an array of strings");
}

}  // namespace

// Reads the finished tests back. The last line may have been cut by a crash mid-write (it has
// no newline): it is dropped, and its test runs again. Any other line must check out.
void Laboratory::read_trial_record() {
  const fs::path file = folder_ / "trials.jsonl";
  if (!fs::exists(file)) return;
  if (!fs::is_regular_file(file))
    throw InputError(file.string(), "", "",
                     "is not a file; expected the calibration's trial "
                     "record (JSON lines)");
  std::ifstream in(file, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  if (!text.empty() && text.back() != '\n') {
    const std::size_t keep = text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1;
    log_("calibrate: the last line of trials.jsonl was cut short; its test runs again");
    text.resize(keep);
    fs::resize_file(file, keep);
  }
  std::istringstream lines(text);
  std::string line;
  int lineno = 0;
  while (std::getline(lines, line)) {
    ++lineno;
    if (line.empty()) continue;
    const std::string where = fmt::format("{}:{}", file.string(), lineno);
    const json j = json::parse(line, nullptr, false);
    if (j.is_discarded())
      throw InputError(where, "", "", "not valid JSON; delete the line to run its test again");
    check_trial_line(j, where);
    book_[j["key"].get<std::string>()] = j;
    next_run_ = std::max(next_run_, j["run"].get<int>() + 1);
  }
}

// "calibration": the [experiment] as it is; "fit-<seed>": with that packing seed;
// "verify-<seed>": the verification's overrides and that seed.
std::vector<std::string> Laboratory::set_overrides(const std::string& set) const {
  if (set == "calibration") return {};
  std::vector<std::string> o;
  if (set.starts_with("verify-")) o = c_.verify_set;
  o.push_back("engine.seed=" + set.substr(set.find('-') + 1));
  return o;
}

Measurement Laboratory::measure_fit(const std::vector<double>& values, const TestPlan& plan) {
  const std::vector<std::string> sets = c_.fit_sets();
  if (sets.size() == 1) return measure(sets.front(), values, plan);
  Measurement all = prefetch(sets, values, plan);
  std::map<Property, std::vector<double>> seen;
  for (const std::string& set : sets) {
    Measurement m = measure(set, values, plan);
    for (const auto& [p, v] : m.properties) seen[p].push_back(v);
    all.tests[set] = std::move(m.tests);
    all.run_folders.insert(all.run_folders.end(), m.run_folders.begin(), m.run_folders.end());
    for (const std::string& problem : m.problems) all.problems.push_back(set + ": " + problem);
    all.new_runs += m.new_runs;
    all.wall_seconds += m.wall_seconds;
  }
  // A property every packing measured; one that a packing missed is missing (and said so).
  for (const auto& [p, xs] : seen) {
    if (xs.size() != sets.size()) continue;
    double sum = 0.0;
    for (double x : xs) sum += x;
    all.properties[p] = sum / static_cast<double>(xs.size());
  }
  return all;
}

const json& Laboratory::sample_report(const std::string& set,
                                      const std::vector<double>& values) const {
  return samples_.at(packing_name(set, values)).report;
}

// The [sample] keys among the overrides shape the packing itself; each is named by the shortest
// text that reads back as its value (distinct values, distinct packings).
std::string Laboratory::packing_name(const std::string& set,
                                     const std::vector<double>& values) const {
  constexpr std::string_view prefix = "sample.";
  std::string name = set;
  for (const std::string& s : parameter_overrides(c_, values)) {
    if (!s.starts_with(prefix)) continue;
    const auto eq = s.find('=');
    name += fmt::format("-{}={}", s.substr(prefix.size(), eq - prefix.size()),
                        std::stod(s.substr(eq + 1)));
  }
  return name;
}

void Laboratory::prepare_samples(const std::string& set, const std::vector<double>& values) {
  const std::string name = packing_name(set, values);
  if (samples_.count(name)) return;
  SamplePaths paths;
  paths.prism = (folder_ / "samples" / (name + "-prism.geom")).string();
  paths.disc = (folder_ / "samples" / (name + "-disc.geom")).string();
  std::vector<std::string> o = parameter_overrides(c_, values);
  for (const auto& s : set_overrides(set)) o.push_back(s);
  auto pack = [&](const std::string& path, std::vector<std::string> extra, const char* what) {
    if (fs::exists(path) && fs::exists(path + ".json")) return read_json_object(path + ".json");
    log_(fmt::format("calibrate: packing the {} sample of set \"{}\"{}", what, set,
                     name == set ? "" : " (" + name.substr(set.size() + 1) + ")"));
    extra.insert(extra.begin(), o.begin(), o.end());
    const ExperimentSpec s = parse_experiment_table(c_.text, c_.path, "experiment", extra);
    return generate_sample(s, path, [](const std::string&) {}).report;
  };
  paths.report = pack(paths.prism, {}, "compression");
  if (c_.needs_disc()) {
    std::vector<std::string> disc{fmt::format("sample.diameter={:.17g}", c_.disc_diameter)};
    if (c_.base.dimension == 2) {
      disc.push_back("sample.shape=\"disk\"");
    } else {
      disc.push_back("sample.shape=\"cylinder\"");
      disc.push_back(fmt::format("sample.height={:.17g}", c_.disc_thickness));
    }
    pack(paths.disc, disc, "Brazilian disc");
  }
  samples_[name] = paths;
}

ExperimentSpec Laboratory::trial_spec(const std::string& set, const std::vector<double>& values,
                                      const std::string& test, double sigma3,
                                      const SamplePaths& sp) const {
  std::vector<std::string> o = parameter_overrides(c_, values);
  for (const auto& s : set_overrides(set)) o.push_back(s);
  o.push_back("sample.source=\"file\"");
  o.push_back(fmt::format("sample.file=\"{}\"",
                          fs::absolute(test == "brazilian" ? sp.disc : sp.prism).string()));
  ExperimentSpec spec = parse_experiment_table(c_.text, c_.path, "experiment", o);
  if (test == "brazilian") {
    BrazilianTest::Params p;
    p.platen_speed = c_.disc_platen_speed;
    spec.test = p;
  } else if (test == "direct_tension") {
    DirectTensionTest::Params p;
    p.platen_speed = c_.grip_speed;
    spec.test = p;
  } else {
    set_confining_stress(spec, sigma3, c_.path);
    // A search compares trials whose small differences matter, and adaptive loading changes
    // speed at moments the cracks choose: it scatters the tangent modulus by about 2 %, and a
    // tiny calibration then missed its modulus target by 9 %. Calibrations load at a constant
    // speed.
    load_at_constant_speed(spec);
  }
  spec.name = fmt::format("{}-{}", set, test);
  spec.output_directory = (folder_ / "trials").string();
  spec.plot = false;
  spec.progress = false;
  spec.snapshot_strain_interval = 0.0;
  spec.checkpoint_interval = 0.0;
  spec.ae_moment_tensors = false;  // not needed for the properties; the mechanics is the same
  return spec;
}

void Laboratory::preflight(const std::vector<std::vector<double>>& points) {
  std::vector<std::string> sets = c_.fit_sets();
  for (auto seed : c_.verify_seeds) sets.push_back(fmt::format("verify-{}", seed));
  std::vector<std::pair<std::string, double>> tests{{"ucs", 0.0}};
  if (c_.needs_tensile()) tests.emplace_back(c_.tensile_test, 0.0);
  if (c_.needs_envelope())
    for (double s3 : c_.confining_stresses)
      tests.emplace_back(fmt::format("triaxial-{:g}MPa", s3 / 1e6), s3);
  for (const std::string& set : sets) {
    throw_if_interrupted("checking the calibration");
    prepare_samples(set, points.front());
    // A verification sample is packed with the calibrated values when the time comes (the
    // contact law packs it): the one packed here for the check is not kept. Every point is
    // checked on the start's packing: a [sample] key changes where bonds are, not whether a
    // test can be built.
    const std::string name = packing_name(set, points.front());
    struct Forget {
      Laboratory* lab;
      const std::string& set;
      const std::string& name;
      ~Forget() {
        if (!set.starts_with("verify-") || !lab->samples_.count(name)) return;
        std::error_code ec;
        for (const std::string& f : {lab->samples_.at(name).prism, lab->samples_.at(name).disc})
          for (const std::string& g : {f, f + ".json"}) fs::remove(g, ec);
        lab->samples_.erase(name);
      }
    } forget{this, set, name};
    for (const auto& [test, sigma3] : tests)
      for (const std::vector<double>& values : points) {
        try {
          check_buildable(trial_spec(set, values, test, sigma3, samples_.at(name)));
        } catch (const InputError& e) {
          std::string at;
          for (const std::string& o : parameter_overrides(c_, values)) at += " " + o;
          throw InputError(
              c_.path, "", "",
              fmt::format("the {} test of sample set \"{}\" cannot run with{}: {}{}", test, set, at,
                          e.what(),
                          test == "brazilian" ? " (the disc: calibration.brazilian_diameter and "
                                                "brazilian_thickness)"
                                              : ""));
        }
      }
  }
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
  } else if (test == "brazilian" || test == "direct_tension") {
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

std::string Laboratory::test_key(const std::string& set, const std::vector<double>& values,
                                 const std::string& test) const {
  std::string key = set + "|" + test;
  for (const auto& s : parameter_overrides(c_, values)) key += "|" + s;
  return key;
}

Laboratory::PendingTest Laboratory::pending_test(const std::string& set,
                                                 const std::vector<double>& values,
                                                 const std::string& test, double sigma3) {
  PendingTest t{test_key(set, values, test),
                set,
                test,
                sigma3,
                next_run_++,
                trial_spec(set, values, test, sigma3, samples_.at(packing_name(set, values)))};
  t.spec.name = fmt::format("{:03d}-{}-{}", t.run, set, test);
  return t;
}

json Laboratory::book_test(const PendingTest& t, const std::vector<double>& values,
                           const std::string& folder, const std::string& status,
                           const std::string& stop_reason, double wall, Measurement& m) {
  json record{{"key", t.key},     {"run", t.run},          {"set", t.set},
              {"test", t.test},   {"sigma3_pa", t.sigma3}, {"values", values},
              {"folder", folder}, {"status", status},      {"wall_seconds", wall}};
  std::vector<std::string> why;
  if (status == "complete") {
    const json summary = read_json_object((fs::path(folder) / "summary.json").string());
    record["properties"] =
        test_properties(t.test, JsonView(summary, folder + "/summary.json"), why);
  } else {
    record["properties"] = json::object();
    why.push_back(t.test + ": run " + status + " (" + stop_reason + ")");
  }
  record["problems"] = why;
  append_line(folder_ / "trials.jsonl", record);
  book_[t.key] = record;
  m.new_runs += 1;
  m.wall_seconds += wall;
  return record;
}

namespace {

RunOptions quiet_run() {
  RunOptions opt;
  opt.interrupt = &interrupt_flag();
  opt.log = [](const std::string&) {};
  return opt;
}

std::string triaxial_name(double sigma3) {
  return fmt::format("triaxial-{:g}MPa", sigma3 / 1e6);
}

}  // namespace

json Laboratory::run_test(const std::string& set, const std::vector<double>& values,
                          const std::string& test, double sigma3, Measurement& m) {
  if (auto it = book_.find(test_key(set, values, test)); it != book_.end()) return it->second;
  throw_if_interrupted("calibrating");
  const PendingTest t = pending_test(set, values, test, sigma3);
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = run_experiment(t.spec, quiet_run());
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (r.status == "interrupted") throw Interrupted("running " + t.spec.name);
  return book_test(t, values, r.folder, r.status, r.stop_reason, wall, m);
}

Measurement Laboratory::prefetch(const std::vector<std::string>& sets,
                                 const std::vector<double>& values, const TestPlan& plan) {
  Measurement m;
  if (pool_ == nullptr || ranks::size() == 1) return m;
  std::vector<std::pair<std::string, double>> tests{{"ucs", 0.0}};
  if (plan.tensile) tests.emplace_back(c_.tensile_test, 0.0);
  if (plan.envelope)
    for (double sigma3 : c_.confining_stresses) tests.emplace_back(triaxial_name(sigma3), sigma3);
  std::vector<PendingTest> todo;
  for (const std::string& set : sets) {
    prepare_samples(set, values);
    for (const auto& [test, sigma3] : tests)
      if (!book_.count(test_key(set, values, test)))
        todo.push_back(pending_test(set, values, test, sigma3));
  }
  if (todo.empty()) return m;
  throw_if_interrupted("calibrating");
  std::vector<ExperimentSpec> specs;
  for (const PendingTest& t : todo) specs.push_back(t.spec);
  const std::vector<PooledRun> runs = pool_->run(specs, quiet_run());
  // Every test that ended is recorded before a failure or a stop is raised, so that a resumed
  // calibration reads them back.
  std::string failure, stopped;
  for (std::size_t i = 0; i < todo.size(); ++i) {
    if (!runs[i].error.empty()) {
      if (failure.empty()) failure = todo[i].spec.name + ": " + runs[i].error;
    } else if (runs[i].status == "interrupted") {
      if (stopped.empty()) stopped = todo[i].spec.name;
    } else {
      book_test(todo[i], values, runs[i].folder, runs[i].status, runs[i].stop_reason,
                runs[i].wall_seconds, m);
    }
  }
  if (!failure.empty()) throw std::runtime_error(failure);
  if (!stopped.empty()) throw Interrupted("running " + stopped);
  return m;
}

Measurement Laboratory::measure(const std::string& set, const std::vector<double>& values,
                                const TestPlan& plan) {
  prepare_samples(set, values);
  Measurement m = prefetch({set}, values, plan);
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
  if (plan.tensile) {
    const json b = take(run_test(set, values, c_.tensile_test, 0.0, m));
    if (b.contains("tensile_strength"))
      m.properties[Property::TensileStrength] = b["tensile_strength"].get<double>();
  }
  if (plan.envelope) {
    std::vector<double> s3{0.0}, s1;
    if (ucs.contains("uniaxial_strength")) s1.push_back(ucs["uniaxial_strength"].get<double>());
    for (double sigma3 : c_.confining_stresses) {
      const json t = take(run_test(set, values, triaxial_name(sigma3), sigma3, m));
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
