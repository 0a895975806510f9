#include "breccia/calibrate/calibrate.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <nlopt.hpp>
#include <optional>
#include <sstream>
#include <tuple>

#include "breccia/calibrate/affine_elasticity.hpp"
#include "breccia/calibrate/laboratory.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/io/json_view.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/version.hpp"

namespace breccia {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Residual given to a target the trial could not measure (no peak, a failed run): far outside
// any tolerance, so the optimiser moves away, yet finite.
constexpr double kUnmeasured = 30.0;
// Scaling steps a stage may take before the optimiser (each one trial).
constexpr int kScalingSteps = 3;

// The error of a measurement in units of the target's tolerance: |r| <= 1 is met. Relative
// targets are compared in log space (a factor 2 too strong weighs as a factor 2 too weak).
double residual(const Target& t, const Properties& p) {
  const auto it = p.find(t.property);
  if (it == p.end() || !std::isfinite(it->second)) return kUnmeasured;
  if (!t.relative) return (it->second - t.value) / t.tolerance;
  if (!(it->second > 0.0)) return kUnmeasured;
  return std::log(it->second / t.value) / std::log1p(t.tolerance);
}

// The signed error a user reads: relative (fraction) or in the target's unit.
double signed_error(const Target& t, double achieved) {
  return t.relative ? achieved / t.value - 1.0 : achieved - t.value;
}

std::string show_value(Property p, double v) {
  if (!std::isfinite(v)) return "n/a";
  switch (p) {
    case Property::YoungsModulus:
      return fmt::format("{:.2f} GPa", v / 1e9);
    case Property::UniaxialStrength:
    case Property::TensileStrength:
    case Property::Cohesion:
      return fmt::format("{:.2f} MPa", v / 1e6);
    case Property::FrictionAngle:
      return fmt::format("{:.1f} deg", v);
    case Property::StrainAtPeak:
      return fmt::format("{:.3f} %", 100 * v);
    default:
      return fmt::format("{:.3f}", v);
  }
}

std::string show_error(const Target& t, double err) {
  if (!std::isfinite(err)) return "n/a";
  if (t.relative) return fmt::format("{:+.1f} %", 100 * err);
  return info(t.property).unit == std::string_view("-")
             ? fmt::format("{:+.3f}", err)
             : fmt::format("{:+.2f} {}", err, info(t.property).unit);
}

struct Evaluation {
  int index = 0;
  std::string stage;  // elastic | strength | friction | final
  int pass = 0;
  int correction = 0;        // the size-correction round it belongs to (0: the first search)
  std::vector<double> aims;  // the value each target had in the search (shifted by corrections)
  std::vector<double> values;
  Properties properties;
  double objective = 0.0;
  bool met = false;
  std::vector<std::string> problems;
  std::vector<std::string> run_folders;
  int new_runs = 0;
  double wall_seconds = 0.0;
};

void write_text(const fs::path& p, const std::string& text) {
  write_file_atomically(p, text);
}

std::string now_text() {
  const auto t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  return fmt::format("{:%Y-%m-%dT%H:%M:%S}", fmt::localtime(t));
}

// The parameter sets the preflight builds every test at: the start, and the free parameters all
// at their lower and all at their upper bounds (the stiffest and softest, strongest and weakest
// trials the optimiser may ask for).
std::vector<std::vector<double>> check_points(const CalibrationSpec& c) {
  std::vector<double> start, lower, upper;
  for (const auto& f : c.free) {
    start.push_back(f.start);
    lower.push_back(f.lower);
    upper.push_back(f.upper);
  }
  return {start, lower, upper};
}

class Calibrator {
 public:
  Calibrator(const CalibrationSpec& c, const CalibrationOptions& o, fs::path folder)
      : c_(c),
        o_(o),
        folder_(std::move(folder)),
        lab_(c, folder_, o.log, o.pool),
        aims_(c.targets) {
    for (const auto& f : c_.free) values_.push_back(f.start);
  }

  CalibrationResult run();

 private:
  Evaluation evaluate(const std::vector<double>& v, std::optional<CalibrationStage> stage,
                      int pass);
  void fit_stage(CalibrationStage stage, int pass);
  Evaluation search();
  bool correct_for_size(const Evaluation& small);
  std::map<Property, std::vector<double>> measure_verification(const std::vector<double>& values,
                                                               json& runs);
  std::vector<double> scaled_start(CalibrationStage stage, const Evaluation& e) const;
  std::vector<TargetVerdict> verify(const Evaluation& final_eval);
  void report_progress(const Evaluation& e) const;
  void write_outputs(const CalibrationResult& r) const;
  void write_convergence() const;
  void write_manifest(const std::string& status, const std::string& error = "") const;

  std::vector<std::size_t> stage_parameters(CalibrationStage s) const {
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < c_.free.size(); ++i)
      if (c_.free[i].stage == s) idx.push_back(i);
    return idx;
  }
  // The targets the search aims at: the lab's, shifted by the size corrections so far.
  std::vector<const Target*> stage_targets(std::optional<CalibrationStage> s) const {
    std::vector<const Target*> t;
    for (const auto& tg : aims_)
      if (!s || info(tg.property).stage == *s) t.push_back(&tg);
    return t;
  }
  const Target* aim(Property p) const {
    for (const auto& t : aims_)
      if (t.property == p) return &t;
    return nullptr;
  }
  int free_index(std::string_view key) const {
    for (std::size_t i = 0; i < c_.free.size(); ++i)
      if (c_.free[i].key == key) return static_cast<int>(i);
    return -1;
  }
  double to_unit(std::size_t i, double v) const {
    const auto& f = c_.free[i];
    return f.log_scale ? std::log(v / f.lower) / std::log(f.upper / f.lower)
                       : (v - f.lower) / (f.upper - f.lower);
  }
  double from_unit(std::size_t i, double u) const {
    const auto& f = c_.free[i];
    return f.log_scale ? f.lower * std::exp(u * std::log(f.upper / f.lower))
                       : f.lower + u * (f.upper - f.lower);
  }
  int evaluations_left_at_most() const;

  const CalibrationSpec& c_;
  const CalibrationOptions& o_;
  fs::path folder_;
  Laboratory lab_;
  std::vector<double> values_;
  std::vector<Evaluation> evals_;
  std::vector<TargetVerdict> verdicts_;
  json verification_ = json::array();  // per seed: the sample and what each test measured
  std::vector<Target> aims_;           // the search's targets (see stage_targets)
  int correction_ = 0;                 // the size-correction round under way
  json corrections_ = json::array();   // per round: both sizes' properties and the shifts
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
  int stages_done_ = 0;
  double new_run_seconds_ = 0.0;
  int new_evaluations_ = 0;
};

Evaluation Calibrator::evaluate(const std::vector<double>& v, std::optional<CalibrationStage> stage,
                                int pass) {
  const Measurement m = lab_.measure_fit(v, tests_for(c_, stage));
  Evaluation e;
  e.index = static_cast<int>(evals_.size()) + 1;
  e.stage = stage ? std::string(stage_name(*stage)) : "final";
  e.pass = pass;
  e.correction = correction_;
  for (const auto& t : aims_) e.aims.push_back(t.value);
  e.values = v;
  e.properties = m.properties;
  e.problems = m.problems;
  e.run_folders = m.run_folders;
  e.new_runs = m.new_runs;
  e.wall_seconds = m.wall_seconds;
  e.met = true;
  for (const Target* t : stage_targets(stage)) {
    const double r = residual(*t, e.properties);
    e.objective += r * r;
    e.met = e.met && std::abs(r) <= c_.aim;
  }
  if (m.new_runs > 0) {
    new_run_seconds_ += m.wall_seconds;
    ++new_evaluations_;
  }
  // COBYLA may ask for a point it has seen (its start): it is not a new trial.
  for (const auto& old : evals_)
    if (old.values == e.values && old.stage == e.stage && old.pass == e.pass &&
        old.correction == e.correction)
      return e;
  evals_.push_back(e);
  report_progress(e);
  write_convergence();
  return e;
}

int Calibrator::evaluations_left_at_most() const {
  const int stages_total = 3 * static_cast<int>(c_.passes);
  const int search = stages_total * static_cast<int>(c_.trials_per_stage) +
                     static_cast<int>(c_.passes) + static_cast<int>(c_.verify_seeds.size());
  const int rounds_left = static_cast<int>(c_.size_corrections) - correction_;
  return std::max(0, stages_total - stages_done_) * static_cast<int>(c_.trials_per_stage) +
         static_cast<int>(c_.passes) + static_cast<int>(c_.verify_seeds.size()) +
         std::max(0, rounds_left) * search;
}

void Calibrator::report_progress(const Evaluation& e) const {
  std::string line =
      e.correction > 0
          ? fmt::format("[calibrate] trial {} ({}, pass {}, size correction {}):", e.index, e.stage,
                        e.pass, e.correction)
          : fmt::format("[calibrate] trial {} ({}, pass {}):", e.index, e.stage, e.pass);
  for (const auto& t : c_.targets) {
    const auto it = e.properties.find(t.property);
    const double v = it == e.properties.end() ? kNaN : it->second;
    line += fmt::format(" {} {} ({})", info(t.property).key, show_value(t.property, v),
                        show_error(t, signed_error(t, v)));
  }
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  const double per_eval = new_evaluations_ > 0 ? new_run_seconds_ / new_evaluations_ : 0.0;
  line +=
      fmt::format(" | {:.1f} min elapsed; at most {} trials left (ETA <= {:.0f} min)", elapsed / 60,
                  evaluations_left_at_most(), per_eval * evaluations_left_at_most() / 60);
  if (o_.log) o_.log(line);
  for (const auto& p : e.problems)
    if (o_.log) o_.log("[calibrate]   " + p);
}

// A first move from the field's scaling laws before the optimiser starts (Potyondy & Cundall
// 2004): the assembly's modulus is proportional to the micro-moduli, its strengths to the bond
// strengths. One measurement then gives a start close to the target; COBYLA does the rest.
std::vector<double> Calibrator::scaled_start(CalibrationStage stage, const Evaluation& e) const {
  std::vector<double> v = e.values;
  auto ratio = [&](Property p) -> double {
    const Target* t = aim(p);
    const auto it = e.properties.find(p);
    if (!t || it == e.properties.end() || !(it->second > 0.0)) return 1.0;
    return t->value / it->second;
  };
  // Moves a free parameter of this stage; bond strengths move together whatever their stage,
  // since the assembly's strengths scale with all of them (their ratios are the friction
  // stage's business).
  auto scale = [&](std::string_view key, double r) {
    const int i = free_index(key);
    const bool strength = key.find("strength") != std::string_view::npos ||
                          key.find("cohesion") != std::string_view::npos;
    if (i >= 0 && (c_.free[i].stage == stage || strength)) v[i] *= r;
  };
  if (stage == CalibrationStage::Elastic) {
    double r = ratio(Property::YoungsModulus);
    const int kappa = free_index("bond.stiffness_ratio");
    const Target* nu = aim(Property::PoissonRatio);
    const auto nu_seen = e.properties.find(Property::PoissonRatio);
    if (kappa >= 0 && c_.free[kappa].stage == stage && nu && nu_seen != e.properties.end()) {
      const AffineElasticity affine{static_cast<int>(c_.base.dimension)};
      const double from = v[kappa];
      // The packing's departure from the affine estimate (non-affine relaxation, the gauges'
      // end effects) is kept as an offset: kappa goes where the affine estimate plus that
      // offset meets the target. The offset can put the measured nu above the affine limit
      // (gauges read 0.28 at kappa 10), so it is not a ratio of stiffness ratios.
      const double offset = nu_seen->second - affine.poisson(from);
      const double aim = nu->value - offset;
      double to = from;
      if (aim >= affine.poisson_limit())
        to = c_.free[kappa].upper;
      else if (aim <= affine.poisson(c_.free[kappa].lower))
        to = c_.free[kappa].lower;
      else
        to = affine.stiffness_ratio(aim);
      to = std::clamp(to, c_.free[kappa].lower, c_.free[kappa].upper);
      v[kappa] = to;
      // The shear stiffness falls with the ratio and takes E with it.
      r *= affine.modulus_factor(from) / affine.modulus_factor(to);
    }
    for (auto key : {"bond.modulus", "contact.modulus", "contact.shear_modulus"}) scale(key, r);
  } else if (stage == CalibrationStage::Strength) {
    const bool ts =
        c_.has_target(Property::TensileStrength) && free_index("bond.tensile_strength") >= 0;
    if (ts) scale("bond.tensile_strength", ratio(Property::TensileStrength));
    const double r = ratio(Property::UniaxialStrength);
    scale("bond.cohesion", r);
    scale("bond.cohesion_sd", r);
    if (!ts) {
      scale("bond.tensile_strength", r);
      scale("bond.tensile_strength_sd", r);
    }
    // The strain at the peak goes as the UCS over the modulus: a modulus calibrated in this
    // stage (the file puts it here when E is not a target) moves so that the strain the scaled
    // strengths would give meets its target.
    const Target* peak_strain = aim(Property::StrainAtPeak);
    const auto strain_seen = e.properties.find(Property::StrainAtPeak);
    if (peak_strain && strain_seen != e.properties.end() && strain_seen->second > 0.0) {
      const double r_modulus = r * strain_seen->second / peak_strain->value;
      for (auto key : {"bond.modulus", "contact.modulus", "contact.shear_modulus"})
        scale(key, r_modulus);
    }
  }
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] = std::clamp(v[i], c_.free[i].lower, c_.free[i].upper);
  return v;
}

void Calibrator::fit_stage(CalibrationStage stage, int pass) {
  const auto idx = stage_parameters(stage);
  if (idx.empty() || stage_targets(stage).empty()) return;
  Evaluation best = evaluate(values_, stage, pass);
  int used = 1;
  // Scaling steps while they help: each is a Newton step on the proportional laws, so two or
  // three usually land inside the tolerance. COBYLA's linear model of the summed squares is poor
  // near a minimum, so it only takes over where the scaling stops improving.
  for (int k = 0; k < kScalingSteps && !best.met && used < c_.trials_per_stage; ++k) {
    const std::vector<double> next = scaled_start(stage, best);
    if (next == best.values) break;
    const Evaluation e = evaluate(next, stage, pass);
    ++used;
    if (!(e.objective < best.objective)) break;
    best = e;
  }
  if (!best.met && used < c_.trials_per_stage) {
    const std::vector<double> start = best.values;
    std::vector<double> x0(idx.size());
    for (std::size_t k = 0; k < idx.size(); ++k) x0[k] = to_unit(idx[k], start[idx[k]]);
    struct Context {
      Calibrator* self;
      const std::vector<std::size_t>* idx;
      const std::vector<double>* x0;
      const std::vector<double>* start;
      Evaluation* best;
      CalibrationStage stage;
      int pass;
      std::exception_ptr failure;
    } ctx{this, &idx, &x0, &start, &best, stage, pass, nullptr};
    auto objective = [](const std::vector<double>& x, std::vector<double>&, void* data) -> double {
      auto& cx = *static_cast<Context*>(data);
      try {
        // The start is asked for exactly (the unit-cube round trip would change its last bit
        // and so the trial record's key).
        std::vector<double> v = *cx.start;
        if (x != *cx.x0)
          for (std::size_t k = 0; k < cx.idx->size(); ++k)
            v[(*cx.idx)[k]] = cx.self->from_unit((*cx.idx)[k], x[k]);
        const Evaluation e = cx.self->evaluate(v, cx.stage, cx.pass);
        if (e.objective < cx.best->objective) *cx.best = e;
        if (e.met) throw nlopt::forced_stop();
        return e.objective;
      } catch (const nlopt::forced_stop&) {
        throw;
      } catch (...) {
        cx.failure = std::current_exception();
        throw nlopt::forced_stop();
      }
    };
    nlopt::opt opt(nlopt::LN_COBYLA, static_cast<unsigned>(idx.size()));
    opt.set_lower_bounds(std::vector<double>(idx.size(), 0.0));
    opt.set_upper_bounds(std::vector<double>(idx.size(), 1.0));
    opt.set_min_objective(objective, &ctx);
    // Its first point is the best so far, read back from the cache, not a new trial.
    opt.set_maxeval(static_cast<int>(c_.trials_per_stage) - used + 1);
    opt.set_xtol_abs(1e-3);
    // A first step of 5 % of the unit range (about 20 % of the value for a factor-50 range in
    // log scale) after the scaling start; the friction stage has no scaling law to start from
    // and takes steps twice as large.
    opt.set_initial_step(stage == CalibrationStage::Friction ? 0.1 : 0.05);
    std::vector<double> x = x0;
    double fmin = 0.0;
    try {
      opt.optimize(x, fmin);
    } catch (const nlopt::forced_stop&) {
    } catch (const nlopt::roundoff_limited&) {
    }
    if (ctx.failure) std::rethrow_exception(ctx.failure);
  }
  values_ = best.values;
}

// Each target's measurements over the verification's packings (the sample of verify_set, one
// packing per seed), run at once over the ranks; `runs` gets each seed's sample and tests.
std::map<Property, std::vector<double>> Calibrator::measure_verification(
    const std::vector<double>& values, json& runs) {
  std::map<Property, std::vector<double>> seen;
  std::vector<std::string> sets;
  for (auto seed : c_.verify_seeds) sets.push_back(fmt::format("verify-{}", seed));
  lab_.prefetch(sets, values, tests_for(c_, std::nullopt));
  for (auto seed : c_.verify_seeds) {
    const std::string set = fmt::format("verify-{}", seed);
    if (o_.log) o_.log(fmt::format("[calibrate] verifying with packing seed {}", seed));
    const Measurement m = lab_.measure(set, values, tests_for(c_, std::nullopt));
    runs.push_back({{"seed", seed},
                    {"particles", lab_.sample_report(set, values).value("particles", 0)},
                    {"tests", m.tests},
                    {"run_folders", m.run_folders}});
    for (const auto& p : m.problems)
      if (o_.log) o_.log("[calibrate]   " + p);
    for (const auto& [p, v] : m.properties) seen[p].push_back(v);
  }
  return seen;
}

// Mean and sample standard deviation (NaN when empty; sd 0 for one value).
std::pair<double, double> mean_sd(const std::vector<double>& xs) {
  if (xs.empty()) return {kNaN, kNaN};
  double s = 0;
  for (double x : xs) s += x;
  const auto n = static_cast<double>(xs.size());
  const double mean = s / n;
  double ss = 0;
  for (double x : xs) ss += (x - mean) * (x - mean);
  return {mean, xs.size() > 1 ? std::sqrt(ss / (n - 1.0)) : 0.0};
}

// The verdict on a target from its measurements: their mean within the full tolerance, and
// every packing measured it (`wanted` values; a property missing on one packing is a miss).
bool verdict_met(const Target& t, const std::vector<double>& xs, std::size_t wanted) {
  if (xs.empty() || xs.size() != wanted) return false;
  const double mean = mean_sd(xs).first;
  return std::abs(t.relative ? std::log(mean / t.value) / std::log1p(t.tolerance)
                             : signed_error(t, mean) / t.tolerance) <= 1.0;
}

std::vector<TargetVerdict> Calibrator::verify(const Evaluation& final_eval) {
  const auto seen = c_.verify_seeds.empty() ? std::map<Property, std::vector<double>>{}
                                            : measure_verification(values_, verification_);
  std::vector<TargetVerdict> out;
  for (const auto& t : c_.targets) {
    TargetVerdict v;
    v.target = t;
    const auto it = final_eval.properties.find(t.property);
    v.calibrated = it == final_eval.properties.end() ? kNaN : it->second;
    std::vector<double> xs;
    if (const auto s = seen.find(t.property); s != seen.end()) xs = s->second;
    if (c_.verify_seeds.empty() && std::isfinite(v.calibrated)) xs.push_back(v.calibrated);
    v.samples = static_cast<int>(xs.size());
    std::tie(v.mean, v.sd) = mean_sd(xs);
    v.error = std::isfinite(v.mean) ? signed_error(t, v.mean) : kNaN;
    v.met = verdict_met(t, xs, c_.verify_seeds.empty() ? 1 : c_.verify_seeds.size());
    out.push_back(v);
  }
  return out;
}

// One round of size correction (output space mapping): the parameters the search found are
// measured at the verification's size and packings. If every target is met there, the
// calibration is done (false). Otherwise each target the search aims at becomes the lab's
// value carried over by the gap between the sizes at these parameters, relative targets by
// the ratio of the small sample's value to the large one's, the others by their difference,
// and the search runs again (true). Both sizes respond alike to a small change of the
// parameters, so the search on the small sample moves the large one by nearly what it moves
// the small one: each round's full-size tests correct what the small sample cannot see.
bool Calibrator::correct_for_size(const Evaluation& small) {
  json runs = json::array();
  const auto large = measure_verification(values_, runs);
  json round{{"round", correction_ + 1},
             {"values", values_},
             {"verification", runs},
             {"targets", json::array()}};
  bool all_met = true;
  for (std::size_t k = 0; k < c_.targets.size(); ++k) {
    const Target& t = c_.targets[k];
    const auto s = small.properties.find(t.property);
    const auto l = large.find(t.property);
    const double at_small = s == small.properties.end() ? kNaN : s->second;
    const std::vector<double> xs = l == large.end() ? std::vector<double>{} : l->second;
    const double at_large = mean_sd(xs).first;
    const bool met = verdict_met(t, xs, c_.verify_seeds.size());
    all_met = all_met && met;
    double shifted = aims_[k].value;
    const bool usable = std::isfinite(at_small) && std::isfinite(at_large) &&
                        (!t.relative || (at_small > 0.0 && at_large > 0.0));
    if (!met && usable)
      shifted = t.relative ? t.value * at_small / at_large : t.value + (at_small - at_large);
    auto num = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
    round["targets"].push_back({{"target", info(t.property).key},
                                {"lab", t.value},
                                {"aimed_at", aims_[k].value},
                                {"calibration_sample", num(at_small)},
                                {"verification_mean", num(at_large)},
                                {"met_at_verification", met},
                                {"next_aim", shifted}});
    if (o_.log)
      o_.log(fmt::format(
          "[calibrate] size correction {}: {} {} on the calibration sample, {} at "
          "the verification's size ({}){}",
          correction_ + 1, info(t.property).key, show_value(t.property, at_small),
          show_value(t.property, at_large), met ? "met" : "missed",
          met || !usable
              ? ""
              : fmt::format("; the search now aims at {}", show_value(t.property, shifted))));
    aims_[k].value = shifted;
  }
  round["met"] = all_met;
  corrections_.push_back(round);
  return !all_met;
}

// One row a trial; a trial's target columns hold what its search aimed at (the lab's value,
// shifted after a size correction) and its error is against that aim.
void Calibrator::write_convergence() const {
  std::string csv = "trial,stage,pass,size_correction,new_test_runs";
  for (const auto& f : c_.free) csv += "," + f.key;
  for (const auto& t : c_.targets)
    csv += fmt::format(",{0}_target,{0}_achieved,{0}_error", info(t.property).key);
  csv += ",objective,met\n";
  for (const auto& e : evals_) {
    csv += fmt::format("{},{},{},{},{}", e.index, e.stage, e.pass, e.correction, e.new_runs);
    for (double v : e.values) csv += fmt::format(",{:.9g}", v);
    for (std::size_t k = 0; k < c_.targets.size(); ++k) {
      Target t = c_.targets[k];
      t.value = e.aims[k];
      const auto it = e.properties.find(t.property);
      if (it == e.properties.end())
        csv += fmt::format(",{:.9g},,", t.value);
      else
        csv +=
            fmt::format(",{:.9g},{:.9g},{:.6g}", t.value, it->second, signed_error(t, it->second));
    }
    csv += fmt::format(",{:.6g},{}\n", e.objective, e.met ? "yes" : "no");
  }
  write_text(folder_ / "convergence.csv", csv);
}

void Calibrator::write_manifest(const std::string& status, const std::string& error) const {
  json m{{"kind", "calibration"},
         {"name", c_.name},
         {"status", status},
         {"version", kVersion},
         {"commit", kCommit},
         {"command", o_.command_line},
         {"calibration_file", c_.path},
         {"machine", machine_description()},
         {"updated", now_text()}};
  if (!error.empty()) m["error"] = error;
  write_text(folder_ / "manifest.json", m.dump(2) + "\n");
}

// The staged search over the passes, on the calibration sample: the last pass's final trial.
Evaluation Calibrator::search() {
  Evaluation final_eval;
  for (int pass = 1; pass <= c_.passes; ++pass) {
    for (auto s :
         {CalibrationStage::Elastic, CalibrationStage::Strength, CalibrationStage::Friction}) {
      fit_stage(s, pass);
      ++stages_done_;
    }
    final_eval = evaluate(values_, std::nullopt, pass);
    if (final_eval.met) break;
    stages_done_ = 3 * pass;
  }
  stages_done_ = 3 * static_cast<int>(c_.passes);
  return final_eval;
}

CalibrationResult Calibrator::run() {
  write_manifest("running");
  CalibrationResult r;
  r.folder = folder_.string();
  try {
    lab_.preflight(check_points(c_));
    Evaluation final_eval = search();
    while (correction_ < c_.size_corrections && correct_for_size(final_eval)) {
      ++correction_;
      stages_done_ = 0;
      final_eval = search();
    }
    verdicts_ = verify(final_eval);
    r.status = "complete";
  } catch (const Interrupted&) {
    r.status = "interrupted";
  } catch (const std::exception& e) {
    // The trials finished so far stay in trials.jsonl; the manifest says why it stopped (if
    // even that cannot be written, the error that stopped it is still the one reported).
    try {
      write_convergence();
      write_manifest("failed", e.what());
    } catch (const std::exception&) {
    }
    throw;
  }
  r.values = values_;
  r.verdicts = verdicts_;
  r.evaluations = static_cast<int>(evals_.size());
  r.test_runs = static_cast<int>(lab_.recorded_tests());
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  write_convergence();
  if (r.status == "complete") write_outputs(r);
  write_manifest(r.status);
  return r;
}

}  // namespace

std::string verdict_table(const CalibrationResult& r) {
  std::string s = fmt::format("{:<24} {:>14} {:>26} {:>10}  verdict\n", "target", "lab",
                              "achieved (mean +/- sd, n)", "error");
  for (const auto& v : r.verdicts) {
    const Property p = v.target.property;
    const std::string achieved =
        fmt::format("{} +/- {} ({})", show_value(p, v.mean),
                    std::isfinite(v.sd) ? show_value(p, v.sd) : "n/a", v.samples);
    const std::string tol = v.target.relative ? fmt::format("{:g} %", 100 * v.target.tolerance)
                                              : fmt::format("{:g}", v.target.tolerance);
    s += fmt::format("{:<24} {:>14} {:>26} {:>10}  {}\n", info(p).key,
                     show_value(p, v.target.value), achieved, show_error(v.target, v.error),
                     v.met ? "met (within " + tol + ")" : "MISSED (tolerance " + tol + ")");
  }
  return s;
}

std::string material_fragment(const CalibrationSpec& c, const std::vector<double>& values) {
  const ExperimentSpec s =
      parse_experiment_table(c.text, c.path, "experiment", parameter_overrides(c, values));
  bool gap_calibrated = false;
  for (const auto& o : parameter_overrides(c, values))
    gap_calibrated = gap_calibrated || o.starts_with("sample.bond_gap_tolerance=");
  const std::string all = to_toml(s);
  std::string out, sample;
  std::istringstream in(all);
  std::string section;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] == '[') {
      section = line;
      if (section == "[contact]" || section == "[bond]") out += "\n" + line + "\n";
      continue;
    }
    if (section == "[contact]" || section == "[bond]") {
      // Platen friction is the test's, not the rock's.
      if (!line.empty() && line.rfind("wall_friction", 0) != 0) out += line + "\n";
    } else if (section == "[sample]" &&
               (line.rfind("density =", 0) == 0 ||
                (gap_calibrated && line.rfind("bond_gap_tolerance =", 0) == 0))) {
      sample += line + "\n";
    }
  }
  return "[sample]\n" + sample + out;
}

void Calibrator::write_outputs(const CalibrationResult& r) const {
  const std::string fragment = material_fragment(c_, r.values);
  std::string header = fmt::format(
      "# Micro-parameters of \"{}\", calibrated by breccia {} ({}).\n"
      "# Reproduce: breccia calibrate {}\n# Verdicts (verification over {} packing seeds):\n",
      c_.name, kVersion, kCommit, c_.path, c_.verify_seeds.size());
  std::istringstream table(verdict_table(r));
  for (std::string line; std::getline(table, line);) header += "#   " + line + "\n";
  write_text(folder_ / "material.toml", header + fragment);

  json verdicts = json::array();
  for (const auto& v : r.verdicts) {
    auto num = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
    verdicts.push_back({{"target", info(v.target.property).key},
                        {"unit", info(v.target.property).unit},
                        {"value", v.target.value},
                        {"tolerance", v.target.tolerance},
                        {"relative", v.target.relative},
                        {"source", v.target.source},
                        {"calibration_sample", num(v.calibrated)},
                        {"mean", num(v.mean)},
                        {"sd", num(v.sd)},
                        {"samples", v.samples},
                        {"error", num(v.error)},
                        {"met", v.met}});
  }
  json params = json::object();
  for (std::size_t i = 0; i < c_.free.size(); ++i) params[c_.free[i].key] = r.values[i];
  for (const auto& t : c_.tied)
    params[t.key] = t.factor * r.values[static_cast<std::size_t>(free_index(t.follows))];
  const json& sample = lab_.sample_report(c_.fit_sets().front(), r.values);
  // The loading behind the verdicts (a run of the preset that loads faster warns).
  const ExperimentSpec verified =
      parse_experiment_table(c_.text, c_.path, "experiment", c_.verify_set);
  const json loading{{"platen_speed_m_per_s", platen_speed(verified)},
                     {"density_scaling", verified.density_scaling}};
  json record{{"name", c_.name},
              {"rock", c_.rock.empty() ? c_.name : c_.rock},
              {"version", kVersion},
              {"commit", kCommit},
              {"command", o_.command_line},
              {"calibration_file", c_.path},
              {"contact_law", std::string(c_.base.contact_law())},
              {"bond_law", std::string(c_.base.bond_law())},
              {"dimension", c_.base.dimension},
              {"parameters", params},
              {"verdicts", verdicts},
              {"fit_seeds", c_.fit_seeds},
              {"verify_seeds", c_.verify_seeds},
              {"verify_set", c_.verify_set},
              {"loading", loading},
              {"calibration_sample", sample},
              {"verification", verification_},
              {"size_corrections", corrections_},
              {"evaluations", r.evaluations},
              {"test_runs", r.test_runs},
              {"wall_seconds", r.wall_seconds},
              {"machine", machine_description()}};
  write_text(folder_ / "record.json", record.dump(2) + "\n");
  if (!run_python_module("calibration_plots", folder_.string(), "plot.log") && o_.log)
    o_.log("[calibrate] convergence.png not drawn (see plot.log)");
}

CalibrationResult run_calibration(const CalibrationSpec& c, const CalibrationOptions& o) {
  const fs::path folder = fs::path(o.output_directory) / c.name;
  const fs::path copy = folder / "calibration.toml";
  if (fs::exists(folder) && !fs::is_directory(folder))
    throw InputError(folder.string(), "--output", o.output_directory,
                     "is a file; the calibration needs a folder there: choose another --output");
  if (fs::exists(copy) && !fs::is_regular_file(copy))
    throw InputError(copy.string(), "", "",
                     "is not a file: a calibration folder keeps its calibration file there; move "
                     "the folder away or choose another --output");
  if (fs::exists(copy)) {
    // The recorded tests stay valid while the samples and the laws are the same: targets,
    // tolerances, bounds, trial budgets and passes may change (to add a pass, say), and the
    // tests already run are read back.
    std::ifstream in(copy);
    std::stringstream ss;
    ss << in.rdbuf();
    const CalibrationSpec before = parse_calibration(ss.str(), copy.string());
    if (to_toml(before.base) != to_toml(c.base) || before.verify_set != c.verify_set ||
        before.disc_diameter != c.disc_diameter || before.disc_thickness != c.disc_thickness ||
        before.disc_platen_speed != c.disc_platen_speed || before.tensile_test != c.tensile_test ||
        before.grip_speed != c.grip_speed)
      throw InputError(folder.string(), "", "",
                       "holds a calibration of another sample or other laws ([experiment], "
                       "verify_set or the tensile test differ); move it away or choose another "
                       "--output");
    if (ss.str() != c.text) write_text(copy, c.text);
    if (o.log)
      o.log("[calibrate] resuming in " + folder.string() +
            " (finished tests are read back from trials.jsonl)");
  } else {
    fs::create_directories(folder);
    write_text(copy, c.text);
  }
  Calibrator cal(c, o, folder);
  return cal.run();
}

void check_calibration(const CalibrationSpec& c,
                       const std::function<void(const std::string&)>& log) {
  // The samples are packed into a folder of their own, removed afterwards.
  const fs::path scratch =
      fs::temp_directory_path() / fmt::format("breccia-check-{}-{}", c.name, ::getpid());
  fs::remove_all(scratch);
  struct Remove {
    fs::path p;
    ~Remove() {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  } remove{scratch};
  Laboratory lab(c, scratch, log);
  lab.preflight(check_points(c));
}

}  // namespace breccia
