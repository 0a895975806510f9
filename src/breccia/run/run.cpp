#include "breccia/run/run.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>
#include <thread>

#include "breccia/analysis/compression.hpp"
#include "breccia/analysis/crack_pattern.hpp"
#include "breccia/analysis/stress_strain.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/core/byte_text.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/io/json_view.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/material/library.hpp"
#include "breccia/run/failure_analysis.hpp"
#include "breccia/run/manifest_file.hpp"
#include "breccia/run/quality.hpp"
#include "breccia/run/sample_build.hpp"
#include "breccia/run/session.hpp"
#include "breccia/version.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

json ledger_json(const EnergyLedger& L) {
  return json{{"kinetic_j", L.kinetic()},
              {"bond_strain_j",
               {{"tension", L.bond.tension},
                {"compression", L.bond.compression},
                {"shear", L.bond.shear},
                {"bending", L.bond.bending},
                {"twisting", L.bond.twisting}}},
              {"contact_strain_j", L.contact},
              {"boundary_work_j", L.boundary_work},
              {"external_load_work_j", L.external_work},
              {"body_force_work_j", L.body_force_work},
              {"friction_j", L.friction},
              {"joint_slip_j", L.joint_slip},
              {"joint_dilation_work_j", L.joint_dilation},
              {"local_damping_j", L.local_damping},
              {"viscous_damping_j", L.viscous_damping},
              {"deleted_springs_j", L.deleted},
              {"released_by_breaks_j", L.released.total()},
              {"residual_j", L.residual},
              {"residual_relative", L.residual_relative}};
}

json nan_null(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}

// v_S for the event duration (docs/analysis.md §4.1), fixed at the first crack: sqrt(G / rho) with
// E and nu fitted over the rows recorded so far above 20 % of the current peak (the sample is still
// intact), and rho the (scaled) grain density times (1 - n0).
double estimate_shear_wave_speed(const ExperimentSpec& spec, LoopState& L) {
  const auto& s = L.series;
  double qmax = 0.0;
  for (double q : s.deviatoric) qmax = std::max(qmax, q);
  // The sample gauges where the test has them (they leave out the platen contacts).
  const bool gauges = analysis::has_gauges(s);
  std::vector<double> x, y, lat;
  for (std::size_t k = 0; k < s.deviatoric.size(); ++k)
    if (s.deviatoric[k] >= 0.2 * qmax && qmax > 0.0) {
      x.push_back(gauges ? s.gauge_axial_strain[k] : s.axial_strain[k]);
      y.push_back(s.deviatoric[k]);
      lat.push_back(gauges ? s.gauge_lateral_strain[k] : s.lateral_strain[k]);
    }
  const analysis::LinearFit fe = analysis::fit_line(x, y, 3);
  const analysis::LinearFit fn = analysis::fit_line(x, lat, 3);
  const bool e_ok = fe.valid && fe.slope > 0.0;
  const double E = e_ok ? fe.slope : bond_moduli(spec).young;
  double nu = fn.valid ? -fn.slope : -1.0;
  const bool nu_ok = nu > 0.0 && nu < 0.5;
  if (!nu_ok) nu = 0.25;
  const double rho = spec.density * spec.density_scaling * (1.0 - L.porosity0);
  const double vs = analysis::shear_wave_speed(E, nu, rho);
  L.wave_speed_method = fmt::format(
      "sqrt(G / rho) fixed at the first crack: E = {:.4g} Pa ({}), nu = {:.3g} ({}), rho = {:.5g} "
      "kg/m^3 (simulated grain density x (1 - n0))",
      E, e_ok ? "slope of q over the rows so far" : "bond modulus: too few rows", nu,
      nu_ok ? "lateral/axial strain slope" : "default 0.25", rho);
  return vs;
}

// Where the cracks are: shares per quarter along the loading axis (between the platens as they
// stood when loading began), the failure plane, and what the test adds for its geometry (a
// Brazilian disc: how close they lie to the loaded diameter).
json crack_pattern_json(const Protocol& test, const Simulation& sim) {
  const TestFrame f = test.frame();
  std::vector<double> axial;
  std::vector<Vec3> midpoints;
  for (const CrackRecord& c : sim.cracks()) {
    axial.push_back(c.position[f.axis]);
    midpoints.push_back(c.position);
  }
  const auto q = analysis::quarter_shares(axial, f.origin, f.origin + f.length);
  json j{{"quarter_shares_along_axis", {q[0], q[1], q[2], q[3]}},
         {"largest_end_quarter_share", std::max(q[0], q[3])},
         {"quarters",
          "cracks per quarter of the initial length along the loading axis, from the "
          "bottom platen; a test that fails through its body has no end quarter "
          "above 0.40"}};
  const analysis::FailurePlane fp =
      analysis::failure_plane(midpoints, f.axis, sim.particles().planar());
  j["failure_plane"] = {
      {"valid", fp.valid},
      {"cracks", fp.cracks},
      {"angle_from_normal_plane_deg", fp.valid ? json(fp.angle_from_normal_plane_deg) : json()},
      {"planarity", fp.valid ? json(fp.planarity) : json()},
      {"method",
       "principal components of all crack midpoints: the plane (2D: line) of largest spread, "
       "its angle to the plane normal to the load (90 = axial splitting; Coulomb: 45 + phi/2); "
       "planarity 1 - least/next spread (0 isotropic, 1 one plane); a conjugate or cone-shaped "
       "failure gives a low planarity and an angle between its branches"}};
  test.describe_crack_pattern(sim, j);
  return j;
}

// NaN or inf in the state: the run cannot recover and everything after would be garbage, so it
// stops at once, failed, naming the step and the first particle affected. Checked at every history
// row (one pass over the particles every history_interval steps).
void check_finite_state(const Simulation& sim, const AxialState& a) {
  const ParticleStore& p = sim.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3& x = p.pos_rad[i].x;
    const Vec3& v = p.vel[i];
    const Vec3& f = p.force[i];
    if (std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z + f.x + f.y + f.z)) continue;
    throw std::runtime_error(fmt::format(
        "non-finite state at step {}: particle {} (tag {}) has position ({}, {}, {}), velocity "
        "({}, {}, {}), force ({}, {}, {}); the run stops here. Usual causes: a time step above "
        "the critical one (engine.time_step, engine.safety_factor), grains that overlap deeply "
        "in the sample, or stiffnesses or loads far outside the physical range",
        sim.step_count(), i, p.tag[i], x.x, x.y, x.z, v.x, v.y, v.z, f.x, f.y, f.z));
  }
  for (const double q : {a.strain, a.stress, a.deviatoric, a.force_bottom, a.force_top,
                         a.lateral_strain, a.volumetric_strain, a.confining_stress})
    if (!std::isfinite(q))
      throw std::runtime_error(fmt::format(
          "non-finite test state at step {} (strain {}, stress {} Pa, forces {} / {} N): the run "
          "stops here; check the platen speed, the confining stress and the time step",
          sim.step_count(), a.strain, a.stress, a.force_bottom, a.force_top));
}

// Steps between history rows: output.history_interval, or the steps in which the platens, at
// full speed, strain the sample by output.history_strain_interval; at most the steps of the
// test's own row time. Under adaptive loading these are paced steps (Protocol::paced_steps).
std::uint64_t history_step_interval(const ExperimentSpec& spec, const Protocol& test,
                                    const Simulation& sim) {
  const double rate = strain_rate(test);
  double steps = static_cast<double>(spec.history_interval);
  if (spec.history_strain_interval > 0.0 && rate > 0.0)
    steps = spec.history_strain_interval / (rate * sim.time_step());
  if (test.row_time() > 0.0) steps = std::min(steps, test.row_time() / sim.time_step());
  return static_cast<std::uint64_t>(std::clamp(std::round(steps), 1.0, 1e9));
}

// How the loading loop ended.
struct LoopEnd {
  std::string status = "complete";  // complete | interrupted
  std::string reason;
  // This sitting's loading loop: the steps it made and their wall time with the recorders and
  // rows, without the build before it, its checkpoints and the analysis after it (the time a
  // peer such as LAMMPS reports as its loop time).
  std::uint64_t loop_steps = 0;
  double loop_seconds = 0.0;
};

// One history row: the recorders (tables flushed, so an interrupted run keeps them; a snapshot
// when its strain is due), the analysed series and the quality monitors (docs/physics.md §6.1).
void record_row(Session& ss, const AxialState& a) {
  Simulation& sim = ss.sim;
  LoopState& L = ss.loop;
  std::vector<double> extra;
  ss.test->history_values(sim, extra);
  const RecordedRow row{a, extra};
  // A recorder that reads every pair (a snapshot) sees a split sample gathered whole, which then
  // splits again and goes on to the bit as before.
  const bool whole =
      sim.split() && std::any_of(ss.recorders.begin(), ss.recorders.end(),
                                 [&](const auto& r) { return r->reads_whole_sample(row); });
  if (whole) sim.unsplit();
  for (const auto& r : ss.recorders) r->at_row(sim, *ss.test, row);
  if (whole) sim.split_over_ranks();
  analysis::CompressionSeries& series = L.series;
  series.axial_strain.push_back(a.strain);
  series.deviatoric.push_back(a.deviatoric);
  series.lateral_strain.push_back(a.lateral_strain);
  series.volumetric_strain.push_back(a.volumetric_strain);
  series.gauge_axial_strain.push_back(a.gauge_strain);
  series.gauge_lateral_strain.push_back(a.gauge_lateral_strain);
  series.broken_bonds.push_back(static_cast<double>(sim.cracks().size()));
  const double fbar = 0.5 * (a.force_bottom + a.force_top);
  const double stored = sim.ledger().bond.total() + sim.ledger().contact;
  L.imbalance.push_back(fbar > 0.0 ? std::abs(a.force_top - a.force_bottom) / fbar : 0.0);
  const StressStrainTest* curve = ss.test->stress_strain();
  const double kinetic = curve ? curve->fluctuating_kinetic_energy(sim) : sim.ledger().kinetic();
  L.ke_ratio.push_back(stored > 0.0 ? kinetic / stored : 0.0);
  const double sigma3 = confining_stress(*ss.test);
  if (sigma3 > 0.0) L.confine_err.push_back(std::abs(a.confining_stress - sigma3) / sigma3);
}

void print_progress_bar(const Session& ss, const AxialState& a, double elapsed) {
  const double frac = std::clamp(ss.test->progress(a, ss.sim), 1e-9, 1.0);
  const int width = 30, fill = static_cast<int>(frac * width);
  std::fprintf(stderr,
               "\r[%s%s] strain %.4f  q %.2f MPa  cracks %zu  %.0fs elapsed, <= %.0fs left ",
               std::string(static_cast<std::size_t>(fill), '#').c_str(),
               std::string(static_cast<std::size_t>(width - fill), '.').c_str(), a.strain,
               a.deviatoric * 1e-6, ss.sim.cracks().size(), elapsed, elapsed * (1 - frac) / frac);
  std::fflush(stderr);
}

RunProgress progress_of(const Session& ss, const AxialState& a, double elapsed) {
  return {.fraction = std::clamp(ss.test->progress(a, ss.sim), 0.0, 1.0),
          .axial_strain = a.strain,
          .deviatoric_stress = a.deviatoric,
          .cracks = ss.sim.cracks().size(),
          .steps = ss.sim.step_count(),
          .elapsed_seconds = elapsed};
}

// Steps the test until it stops, the run is interrupted (a signal or --stop-at-step: then it
// saves a checkpoint first) or it fails. `wall` gives the run's wall time so far.
LoopEnd run_loading_loop(const ExperimentSpec& spec, Session& ss, const RunOptions& opt,
                         const std::function<void(const std::string&)>& checkpoint,
                         const std::function<double()>& wall,
                         const std::function<void(const std::string&)>& log,
                         const fs::path& folder) {
  Simulation& sim = ss.sim;
  Protocol& test = *ss.test;
  const std::uint64_t interval = history_step_interval(spec, test, sim);
  auto last_bar = std::chrono::steady_clock::now(), last_checkpoint = last_bar;
  const auto loop_start = last_bar;
  const std::uint64_t loop_step0 = sim.step_count();
  double checkpoint_seconds = 0.0;
  auto ended = [&](std::string status, std::string reason) {
    LoopEnd e{std::move(status), std::move(reason)};
    e.loop_steps = sim.step_count() - loop_step0;
    e.loop_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count() -
        checkpoint_seconds;
    return e;
  };
  for (;;) {
    const bool stop_step = opt.stop_at_step > 0 && sim.step_count() >= opt.stop_at_step;
    const bool signalled = opt.interrupt && opt.interrupt->load();
    // The ranks of a split sample stop at one step: after the step that told every rank that a
    // signal had reached one of them (the request travels with the step's loads).
    const bool interrupted = sim.split() ? sim.stop_requested_anywhere() : signalled;
    if (interrupted || stop_step) {
      LoopEnd e =
          ended("interrupted",
                stop_step ? fmt::format("stopped at step {} (--stop-at-step)", sim.step_count())
                          : "interrupted by a signal");
      // Between two steps: the checkpoint continues exactly from here. The manifest says
      // "interrupted" with it, before the analysis of what was recorded (a launcher may end the
      // process before that is done).
      checkpoint(e.reason);
      log(fmt::format("checkpoint at step {}: continue with `breccia resume {}`", sim.step_count(),
                      folder.string()));
      return e;
    }
    // A split sample's ranks share the grains each reader declares (gather_grains is nothing
    // otherwise), and every grain at a row.
    const double paced_before = test.paced_steps(sim);
    sim.gather_grains(test.grains_read_by_control(sim));
    test.control(sim);
    // A row every `interval` paced steps (with the first step's): every interval steps at a
    // constant speed. An adaptive test has counted the coming step in its control (at least
    // one); the others count it when it is taken. The row's step samples the energies.
    const auto rows_by = [&](double paced) {
      return std::floor((paced - 1.0) / static_cast<double>(interval));
    };
    const bool row_due =
        rows_by(std::max(test.paced_steps(sim), paced_before + 1.0)) != rows_by(paced_before);
    if (row_due) sim.request_energy_sample();
    sim.request_stop(signalled);
    sim.step();
    for (const auto& r : ss.recorders) {
      sim.gather_grains(r->grains_read_after_step(sim, test));
      r->after_step(sim, test);
    }
    if (!row_due) continue;
    sim.gather_particles();
    const AxialState a = test.measure(sim);
    check_finite_state(sim, a);
    record_row(ss, a);
    if (test.finished(a, sim.cracks().size())) {
      if (opt.progress) opt.progress(progress_of(ss, a, wall()));  // the last word: where it ended
      return ended("complete", test.stop_reason());
    }
    const auto now = std::chrono::steady_clock::now();
    bool checkpoint_due =
        spec.checkpoint_interval > 0.0 &&
        std::chrono::duration<double>(now - last_checkpoint).count() >= spec.checkpoint_interval;
    // Root's clock decides for every rank of a split sample.
    if (sim.split()) checkpoint_due = ranks::broadcast(checkpoint_due ? "1" : "0") == "1";
    if (checkpoint_due) {
      checkpoint({});
      last_checkpoint = std::chrono::steady_clock::now();
      checkpoint_seconds += std::chrono::duration<double>(last_checkpoint - now).count();
    }
    if ((opt.show_progress || opt.progress) && now - last_bar > std::chrono::milliseconds(250)) {
      last_bar = now;
      if (opt.show_progress) print_progress_bar(ss, a, wall());
      if (opt.progress) opt.progress(progress_of(ss, a, wall()));
    }
  }
}

// The headline numbers of a finished (or interrupted) run, for the caller.
RunResult run_result(const fs::path& folder, const Session& ss, const LoopEnd& end,
                     const analysis::CompressionResult& an, double wall_seconds) {
  const Simulation& sim = ss.sim;
  RunResult r;
  r.folder = folder.string();
  r.status = end.status;
  r.stop_reason = end.reason;
  r.particles = sim.particles().size();
  r.bonds = ss.loop.bonds_initial;
  r.confining_stress = confining_stress(*ss.test);
  r.wall_seconds = wall_seconds;
  r.steps = sim.step_count();
  r.loop_steps = end.loop_steps;
  r.loop_seconds = end.loop_seconds;
  r.peak_stress = an.peak_deviatoric;
  r.sigma1_at_peak = an.sigma1_at_peak;
  r.strain_at_peak = an.strain_at_peak;
  r.youngs_modulus = an.e_t50.valid ? an.e_t50.slope : std::nan("");
  r.poisson = an.poisson;
  r.cracks = sim.cracks().size();
  for (const auto& c : sim.cracks()) (c.mode == CrackMode::Tensile ? r.tensile : r.shear)++;
  r.energy_residual_relative = sim.ledger().residual_relative;
  return r;
}

// The compression analysis's moduli, strengths and thresholds, with how each was read.
json compression_fields(const analysis::CompressionResult& an) {
  const char* strain_read = an.moduli_from_gauges
                                ? "the axial strain of the sample gauge (grain layers at 1/4 and "
                                  "3/4 of the height, clear of the platen contacts)"
                                : "the platen approach strain";
  return {
      {"peak_reached", an.peak_reached},
      {"peak_deviatoric_stress_pa", an.peak_deviatoric},
      {"peak_deviatoric_stress_mpa", an.peak_deviatoric * 1e-6},
      {"sigma1_at_peak_pa", an.sigma1_at_peak},
      {"axial_strain_at_peak", an.strain_at_peak},
      {"youngs_modulus_pa", an.e_t50.valid ? json(an.e_t50.slope) : json(nullptr)},
      {"youngs_modulus_method",
       fmt::format("ISRM tangent E_t50: least-squares slope of q = sigma_1 - sigma_3 against {} "
                   "over pre-peak samples at {:.0f}-{:.0f} % of the peak",
                   strain_read, 100 * an.e_t50_lo, 100 * an.e_t50_hi)},
      {"youngs_modulus_fit",
       {{"points", an.e_t50.points},
        {"r2", an.e_t50.r2},
        {"strain_column", an.moduli_from_gauges ? "gauge_axial_strain" : "axial_strain"},
        {"window_fraction_of_peak", {an.e_t50_lo, an.e_t50_hi}}}},
      {"youngs_modulus_platen_pa",
       an.e_t50_platen.valid ? json(an.e_t50_platen.slope) : json(nullptr)},
      {"youngs_modulus_average_pa", an.e_av.valid ? json(an.e_av.slope) : json(nullptr)},
      {"youngs_modulus_secant50_pa", nan_null(an.e_s50)},
      {"poisson_ratio", nan_null(an.poisson)},
      {"poisson_ratio_method",
       an.moduli_from_gauges ? "-slope of the gauge lateral strain (lateral-face grains of the "
                               "middle half) against the gauge axial strain, E_t50 window"
                             : "-slope of the lateral strain against the platen approach "
                               "strain, E_t50 window"},
      {"crack_initiation_stress_pa", nan_null(an.crack_initiation)},
      {"crack_initiation_method", "q when the broken bonds reach 5 % of those at the peak"},
      {"crack_damage_stress_pa", nan_null(an.crack_damage)},
      {"residual_strength_pa", nan_null(an.residual)},
      {"brittleness_index", nan_null(an.brittleness)},
      {"analysis_flags", an.flags}};
}

json quality_fields(const QualityVerdict& q) {
  return {{"quasi_static",
           {{"ok", q.quasi_static()},
            {"max_platen_force_imbalance_before_peak", q.imbalance_pre},
            {"max_kinetic_to_strain_energy_before_peak", q.ke_ratio_pre},
            {"rows_before_first_crack", q.intact_rows},
            {"max_kinetic_to_strain_energy_before_first_crack",
             q.intact_rows > 0 ? json(q.ke_ratio_intact) : json(nullptr)},
            {"max_platen_force_imbalance_before_first_crack",
             q.intact_rows > 0 ? json(q.imbalance_intact) : json(nullptr)}}},
          {"confining_stress_error",
           {{"max_relative_before_peak", q.confine_err_pre},
            {"max_relative_overall", q.confine_err_all}}}};
}

// summary.json: the run, the test, the analysis, the quality verdict and the warnings.
json run_summary(const ExperimentSpec& spec, const Session& ss, const RunResult& r,
                 const analysis::CompressionResult& an, const QualityVerdict& q,
                 const std::vector<std::string>& warnings, const json& manifest) {
  const Simulation& sim = ss.sim;
  const Protocol& test = *ss.test;
  json summary{{"status", r.status},
               {"stop_reason", r.stop_reason},
               {"experiment", spec.name},
               {"test", test.label()},
               {"test_kind", test.kind()},
               {"dimension", spec.dimension},
               {"particles", r.particles},
               {"bonds_initial", r.bonds},
               {"bond_sites_initial", ss.loop.bond_sites_initial},
               {"bonds_broken", r.cracks},
               {"cracks_tensile", r.tensile},
               {"cracks_shear", r.shear},
               {"steps", r.steps},
               {"consolidation_steps", ss.loop.consolidation_steps},
               {"simulated_time_s", sim.time()},
               {"time_step_s", sim.time_step()},
               {"density_scaling", spec.density_scaling},
               {"wall_seconds", r.wall_seconds},
               {"particle_steps_per_second",
                static_cast<double>(r.particles) * static_cast<double>(r.steps) / r.wall_seconds},
               {"loading_loop",
                {{"what",
                  "this sitting's loading loop: its steps with the recorders and rows, without the "
                  "build, checkpoints and analysis"},
                 {"steps", r.loop_steps},
                 {"seconds", r.loop_seconds},
                 {"particle_steps_per_second",
                  r.loop_seconds > 0.0 ? static_cast<double>(r.particles) *
                                             static_cast<double>(r.loop_steps) / r.loop_seconds
                                       : 0.0}}}};
  if (const StressStrainTest* curve = test.stress_strain()) {
    summary.update(json{{"confining_stress_pa", curve->confining_stress()},
                        {"lateral_boundary", curve->lateral_boundary()},
                        {"platen_speed_m_per_s", curve->platen_speed()},
                        {"strain_rate_per_s", strain_rate(test)}});
    summary.update(compression_fields(an));
    summary.update(quality_fields(q));
    curve->summarise_curve(an, summary);
  } else {
    json own = json::object();
    test.summarise(sim, own);
    summary[test.kind()] = std::move(own);
  }
  summary.update(json{{"sample_height_m", test.frame().length},
                      {"sample_area_m2", test.frame().area},
                      {"sample", manifest.value("sample", json::object())},
                      {"energy", ledger_json(sim.ledger())},
                      {"snapshots", find_recorder<SnapshotWriter>(ss.recorders).count()},
                      {"warnings", warnings}});
  if (manifest.contains("resumed")) summary["resumed"] = manifest["resumed"];
  if (!spec.joint_planes.empty())
    summary["joints"] = {{"law", spec.joint_law()},
                         {"planes", spec.joint_planes.size()},
                         {"elements", sim.joint_count()},
                         {"bonded_at_end", sim.bonded_joints()}};
  summary["crack_pattern"] = crack_pattern_json(test, sim);
  return summary;
}

// The run folder's files in the manifest; a finished run drops its checkpoint, an interrupted
// one keeps it for `breccia resume`. Plots and the report are made here when asked for.
void list_run_files(const ExperimentSpec& spec, const fs::path& folder, const Session& ss,
                    const LoopEnd& end, json& manifest,
                    const std::function<void(const std::string&)>& log) {
  manifest["files"] = {"experiment.toml"};
  for (const auto& r : ss.recorders)
    for (const std::string& f : r->files()) manifest["files"].push_back(f);
  for (const char* f : {"events.csv", "indicators.csv", "b_value_windows.csv", "d2_windows.csv",
                        "fragments.csv", "summary.json"})
    manifest["files"].push_back(f);
  // The records that outgrew memory stay beside the checkpoint they belong to.
  const char* const record_files[] = {kCrackCatalogueFile, kAeEventFile, kAeContextFile};
  if (end.status == "complete") {
    fs::remove(folder / kCheckpointFile);
    for (const char* f : record_files) fs::remove(folder / f);
    manifest.erase("checkpoint");
  } else {
    manifest["files"].push_back(kCheckpointFile);
    for (const char* f : record_files)
      if (fs::exists(folder / f)) manifest["files"].push_back(f);
  }
  if (!spec.plot) return;
  make_plot(folder, log);
  if (fs::exists(folder / "stress_strain.png")) manifest["files"].push_back("stress_strain.png");
  if (fs::exists(folder / "report.html")) {
    manifest["files"].push_back("report.html");
    manifest["files"].push_back("report/");
  }
}

// What each rank of a split sample has received from the others, and its wall time inside the
// exchanges (waiting included), in this process's life: the split, the ghosts and shares of each
// step, the grains the test and recorders read, the rows' and checkpoints' gathers. Collective.
json split_traffic(const LoopEnd& end) {
  std::string mine;
  bytes::put(mine, ranks::received_bytes());
  bytes::put(mine, ranks::exchange_seconds());
  // The same on every rank of the sample (they call the same collectives): root's is reported.
  const std::uint64_t collectives = ranks::collectives();
  json received = json::array(), seconds = json::array();
  for (const std::string& part : ranks::all_gather(mine)) {
    std::size_t at = 0;
    received.push_back(bytes::take<std::uint64_t>(part, at));
    seconds.push_back(bytes::take<double>(part, at));
  }
  return {{"loop_steps", end.loop_steps},
          {"loop_seconds", end.loop_seconds},
          {"received_bytes", received},
          {"exchange_seconds", seconds},
          {"collectives", collectives}};
}

// After the loop: the recorders' last rows, the analysis, summary.json and the manifest.
RunResult conclude_run(const ExperimentSpec& spec, const fs::path& folder, json& manifest,
                       Session& ss, const LoopEnd& end, const std::function<double()>& wall,
                       const std::function<void(const std::string&)>& log) {
  Simulation& sim = ss.sim;
  // The last records and the analysis read the whole sample: a split one is gathered; its
  // lead rank alone goes on to the analysis, and the others' part of the run ends there.
  const bool lead = sim.lead_rank();
  if (sim.split()) {
    json& launch = manifest.contains("resumed") ? manifest["resumed"].back() : manifest;
    launch["mpi"]["traffic"] = split_traffic(end);
  }
  sim.unsplit();
  for (const auto& r : ss.recorders) r->finish(sim);
  const analysis::CompressionResult an = analysis::analyse_compression(ss.loop.series);
  RunResult result = run_result(folder, ss, end, an, wall());
  if (!lead) return result;
  const QualityVerdict q =
      judge_quality(ss.loop.series, ss.loop.imbalance, ss.loop.ke_ratio, ss.loop.confine_err, an);
  std::vector<std::string> warnings = ss.loop.warnings;      // those of the set-up, logged already
  const StressStrainTest* curve = ss.test->stress_strain();  // none: dynamic by design
  for (const std::string& w :
       curve ? quality_warnings(q, curve->confining_stress()) : std::vector<std::string>{}) {
    log("warning: " + w);
    warnings.push_back(w);
  }
  json summary = run_summary(spec, ss, result, an, q, warnings, manifest);
  // The loading is over and its checkpoint (if any) written: the contacts and pair forces make
  // room for the analysis, which reads only grains, bonds and cracks.
  sim.retire_interactions();
  // Failure analysis: events, indicators, stages, fragments, energy budget (docs/analysis.md
  // §2-§9). A signal stops it between its stages: the loading's tables are whole, the summary is
  // not written, and the run is marked interrupted.
  json failure;
  try {
    failure = write_failure_analysis(
        folder, FailureInputs{spec, sim, ss.ae(), ss.loop.series, an, ss.loop.volume0,
                              ss.loop.porosity0, ss.loop.length_min, ss.loop.wave_speed_method,
                              ss.test->stress_strain() != nullptr, ss.test->rock_particles(sim),
                              end.status != "interrupted"});
  } catch (const Interrupted& e) {
    log(std::string(e.what()) + ": the loading had ended (" + result.stop_reason +
        "); its tables are whole, summary.json is not written");
    result.status = "interrupted";
    result.stop_reason = std::string(e.what()) + " (the loading had ended: " + result.stop_reason +
                         "; no summary.json)";
    return result;
  }
  for (const auto& [key, value] : failure.items()) summary[key] = value;
  write_json(folder / "summary.json", summary);
  list_run_files(spec, folder, ss, end, manifest, log);
  return result;
}

// Loads the loop, runs it to its end (or the next interruption), and writes the summary and the
// final manifest. `t_start` is when this session began.
RunResult execute(const ExperimentSpec& spec, const fs::path& folder, json& manifest,
                  ManifestFile& manifest_file, Session& ss, const RunOptions& opt,
                  std::chrono::steady_clock::time_point t_start) {
  auto log = [&](const std::string& m) {
    if (opt.log) opt.log(m);
  };
  ss.ae().set_wave_speed_source([&] { return estimate_shear_wave_speed(spec, ss.loop); });
  auto wall = [&] {
    return ss.loop.wall_seconds +
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  };
  auto finish = [&](const std::string& status, const std::string& reason, double seconds) {
    manifest["status"] = status;
    manifest["stop_reason"] = reason;
    manifest["wall_seconds"] = seconds;
    if (status == "failed")
      manifest_file.write_final(manifest);
    else
      manifest_file.write(manifest);
  };
  // `stop_reason`: why the loop stops here (empty: a periodic checkpoint, the run goes on).
  auto checkpoint = [&](const std::string& stop_reason) {
    const double before = ss.loop.wall_seconds;
    ss.loop.wall_seconds = wall();
    write_checkpoint(folder, spec, ss);
    ss.loop.wall_seconds = before;
    manifest["checkpoint"] = {{"file", kCheckpointFile},
                              {"step", ss.sim.step_count()},
                              {"time_s", ss.sim.time()},
                              {"resume_command", "breccia resume " + folder.string()}};
    if (!stop_reason.empty()) {
      manifest["status"] = "interrupted";
      manifest["stop_reason"] = stop_reason + " (checkpoint written)";
    }
    manifest_file.write(manifest);
  };
  try {
    const LoopEnd end = run_loading_loop(spec, ss, opt, checkpoint, wall, log, folder);
    if (opt.show_progress) std::fprintf(stderr, "\n");
    const RunResult result = conclude_run(spec, folder, manifest, ss, end, wall, log);
    finish(result.status, result.stop_reason, result.wall_seconds);
    return result;
  } catch (const std::exception& e) {
    finish("failed", e.what(), wall());
    throw;
  }
}

}  // namespace

namespace {

// The calibration record of the run's preset; null for "custom" or a preset without one.
json preset_record(const ExperimentSpec& spec) {
  for (const EmbeddedMaterial& e : embedded_materials())
    if (e.name == spec.preset && !e.record.empty()) {
      json r = json::parse(e.record, nullptr, false);
      return r.is_discarded() ? json(nullptr) : r;
    }
  return nullptr;
}

// The warning when a run of a calibrated preset loads its platens less quasi-statically than the
// preset's verification tests did (their loading is in its record).
std::optional<std::string> preset_loading_check(const ExperimentSpec& spec, const Protocol& test) {
  const StressStrainTest* curve = test.stress_strain();
  const json r = preset_record(spec);
  if (!curve || !r.is_object() || !r.contains("loading")) return std::nullopt;
  const json& l = r["loading"];
  return preset_loading_warning(spec.preset, l.value("platen_speed_m_per_s", 0.0),
                                l.value("density_scaling", 0.0), curve->platen_speed(),
                                spec.density_scaling);
}

// Where the run's micro-parameters come from: the material preset and, for a library rock, its
// calibration record, with whether the run kept the calibrated values (applying the preset
// again to the resolved experiment changes nothing) or overrode some of them.
json material_provenance(const ExperimentSpec& spec) {
  json m = {{"preset", spec.preset}, {"record", preset_record(spec)}};
  if (m["record"].is_null()) return m;
  ExperimentSpec as_calibrated = spec;
  apply_preset(as_calibrated, spec.preset, "material provenance");
  m["parameters_as_calibrated"] = to_toml(as_calibrated) == to_toml(spec);
  return m;
}

// Where a run ran in an MPI launch (a sweep's or a calibration's run, on one rank with the whole
// sample); nothing in a single process.
void add_launch(json& j) {
  if (ranks::launch_size() > 1)
    j["mpi"] = {{"ranks", ranks::launch_size()},
                {"rank", ranks::launch_rank()},
                {"sample_split_over_ranks", false}};
}

// One sample split over the ranks: each rank's particles (an index range of the store).
json decomposition(const Simulation& sim) {
  json first = json::array(), count = json::array();
  for (const IndexRange& r : sim.rank_ranges()) {
    first.push_back(r.begin);
    count.push_back(r.size());
  }
  json j = {{"ranks", ranks::size()},
            {"sample_split_over_ranks", true},
            {"first_particle", first},
            {"particles", count}};
  // A sweep's run split over a group of the launch's ranks: which.
  if (ranks::launch_size() != ranks::size()) {
    j["launch_ranks"] = ranks::launch_size();
    j["first_launch_rank"] = ranks::launch_rank() - ranks::rank();
  }
  return j;
}

// A folder of this rank's own under the system's temporary folder, removed with its contents
// when the run ends: where a split sample's other ranks write what root writes in the run folder.
class ScratchFolder {
 public:
  ScratchFolder() = default;
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  ~ScratchFolder() {
    std::error_code ec;
    if (!path_.empty()) fs::remove_all(path_, ec);
  }
  const fs::path& make() {
    path_ = fs::temp_directory_path() /
            fmt::format("breccia-rank{}-{}", ranks::rank(), static_cast<long>(::getpid()));
    std::error_code ec;
    fs::remove_all(path_, ec);
    fs::create_directories(path_);
    return path_;
  }

 private:
  fs::path path_;
};

// Dynamic damping as the engine applies it (null when off).
json dynamic_damping_json(const EngineConfig& c) {
  if (!(c.dynamic_damping_radius > 0.0 && c.dynamic_damping_time > 0.0)) return nullptr;
  return {{"alpha", c.dynamic_damping_alpha},
          {"radius_m", c.dynamic_damping_radius},
          {"time_s", c.dynamic_damping_time}};
}

// manifest.json as a run starts: what made it, on what, from which experiment, "running".
json initial_manifest(const ExperimentSpec& spec, const Built& b, const RunOptions& opt) {
  json m = {{"program", "breccia"},
            {"version", kVersion},
            {"commit", kCommit},
            {"created", fmt::format("{:%Y-%m-%dT%H:%M:%S}", fmt::localtime(std::time(nullptr)))},
            {"command", opt.command_line},
            {"experiment_source", spec.source},
            {"seed", spec.engine.seed},
            {"threads", max_threads()},
            {"machine", machine_description()},
            {"instruction_set", instruction_set_name(b.sim.instruction_set())},
            {"status", "running"},
            {"density_scaling", spec.density_scaling},
            {"grain_density_kg_m3", spec.density},
            {"simulated_density_kg_m3", spec.density * spec.density_scaling},
            {"bar_wave_speed_m_s", b.bar_wave_speed},
            {"dynamic_damping", dynamic_damping_json(b.sim.config())},
            {"sample", b.sample_report},
            {"material", material_provenance(spec)},
            {"resolved_experiment", to_toml(spec)}};
  add_launch(m);
  return m;
}

// The experiment's threads, or with engine.threads = 0 the machine's cores, shared among the
// ranks a launch started on it.
void use_threads(const ExperimentSpec& spec) {
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  if (spec.threads > 0)
    set_threads(static_cast<int>(spec.threads));
  else if (ranks::local_size() > 1)
    set_threads(std::max(1, cores / ranks::local_size()));
}

// The sample and the test, built whole by every process. A split sample's root builds first (its
// failure is every rank's), so that a generated sample is packed and cached once and the other
// ranks read it from the cache.
Built build_on_every_rank(const ExperimentSpec& spec, const RunOptions& opt,
                          const std::function<void(const std::string&)>& log) {
  if (!opt.split_over_ranks) return build(spec, log);
  std::optional<Built> b;
  ranks::on_root([&] {
    b.emplace(build(spec, log));
    return std::string();
  });
  // A signal may reach the ranks at different moments of their builds (the others build from
  // root's packing, consolidating each on its own): they stop together, or not at all.
  bool stopped = false;
  if (!b) {
    try {
      b.emplace(build(spec, log));
    } catch (const Interrupted&) {
      stopped = true;
    }
  }
  stopped = stopped || (opt.interrupt && opt.interrupt->load());
  if (ranks::any_flags(stopped ? 1u : 0u) != 0) {
    ranks::failure_released_the_others();
    throw Interrupted("building the sample (on every rank)");
  }
  return std::move(*b);
}

// Where a rank writes (`own`) and the run folder (`run`). A split sample's root makes the run
// folder (its failure is every rank's); the other ranks write into scratch folders.
struct RankFolders {
  fs::path own, run;
};

RankFolders run_folder_of_rank(const ExperimentSpec& spec, const RunOptions& opt,
                               ScratchFolder& scratch) {
  if (!opt.split_over_ranks) {
    const fs::path made = make_folder(spec);
    return {made, made};
  }
  const fs::path made = ranks::on_root([&] { return make_folder(spec).string(); });
  return {ranks::root() ? made : scratch.make(), made};
}

// The run folder's manifest: written by the process that owns the run folder, marked by any
// rank when a signal comes.
bool writes_manifest(const RunOptions& opt) {
  return !opt.split_over_ranks || ranks::root();
}

}  // namespace

RunResult run_experiment(const ExperimentSpec& spec, const RunOptions& opt) {
  auto log = [&](const std::string& m) {
    if (opt.log) opt.log(m);
  };
  use_threads(spec);
  const auto t_start = std::chrono::steady_clock::now();
  // Build first: a bad sample (geometry file, bond list) fails before any file is written.
  Built b = build_on_every_rank(spec, opt, log);
  ScratchFolder scratch;
  const RankFolders folders = run_folder_of_rank(spec, opt, scratch);
  const fs::path& folder = folders.own;
  ManifestFile manifest_file(folders.run, writes_manifest(opt));
  const SignalWatch watch(opt.interrupt, manifest_file);
  json manifest = initial_manifest(spec, b, opt);
  write_file_atomically(folder / "experiment.toml", to_toml(spec));
  manifest_file.write(manifest);

  Simulation& sim = b.sim;
  sim.record_cracks_in(folder / kCrackCatalogueFile,
                       static_cast<std::size_t>(spec.resident_cracks));
  Protocol& test = *b.protocol;
  LoopState loop;
  loop.warnings = sim.warnings();
  loop.consolidation_steps = b.consolidation_steps;
  loop.bonds_initial = sim.intact_bonds();
  loop.bond_sites_initial = sim.intact_bond_sites();
  const double sigma3 = confining_stress(test);
  loop.series.confining_stress = sigma3;
  if (auto w = preset_loading_check(spec, test)) loop.warnings.push_back(*w);
  if (sigma3 > 0.0 && !test.stress_strain()->consolidated())
    loop.warnings.push_back(fmt::format(
        "consolidation to {} MPa did not settle within {} steps; loading started anyway",
        sigma3 * 1e-6, b.consolidation_steps));
  for (const std::string& w : loop.warnings) log("warning: " + w);
  manifest["time_step_s"] = sim.time_step();
  manifest["critical_time_step_s"] = sim.critical_time_step();
  manifest["particles"] = sim.particles().size();
  manifest["bonds"] = sim.intact_bonds();
  manifest["consolidation_steps"] = b.consolidation_steps;
  manifest["strain_rate_per_s"] = strain_rate(test);
  manifest_file.write(manifest);
  log(fmt::format("sample: {} particles, {} bonds; time step {:.3g} s (critical {:.3g} s){}",
                  sim.particles().size(), sim.intact_bonds(), sim.time_step(),
                  sim.critical_time_step(),
                  sigma3 > 0.0 ? fmt::format("; consolidated to {:.3g} MPa in {} steps",
                                             sigma3 * 1e-6, b.consolidation_steps)
                               : ""));
  // Reference state for porosity and D2.
  {
    const ParticleStore& p = sim.particles();
    double solid = 0.0;
    for (std::size_t i = 0; i < test.rock_particles(sim); ++i) solid += p.mass[i] / p.density[i];
    const TestFrame f = test.frame();
    loop.volume0 = f.length * f.area;
    loop.porosity0 = 1.0 - solid / loop.volume0;
    loop.length_min =
        spec.dimension == 2 ? std::min(f.length, f.width) : std::min({f.length, f.width, f.depth});
  }
  if (spec.ae_shear_wave_speed > 0.0)
    loop.wave_speed_method = "given in the experiment file (ae.shear_wave_speed)";
  std::unique_ptr<Session> ss;
  try {
    RecorderList recorders =
        make_recorders({folder, spec, sim, test, !opt.split_over_ranks || ranks::root()});
    if (opt.split_over_ranks) {
      sim.split_over_ranks();
      manifest["mpi"] = decomposition(sim);
      manifest_file.write(manifest);
    }
    ss.reset(new Session{std::move(b.sim), std::move(b.protocol), std::move(loop),
                         std::move(recorders)});
  } catch (const std::exception& e) {
    manifest["status"] = "failed";
    manifest["stop_reason"] = e.what();
    manifest_file.write_final(manifest);
    throw;
  }
  return execute(spec, folder, manifest, manifest_file, *ss, opt, t_start);
}

namespace {

// A split sample's other ranks resume in scratch folders holding copies of the run folder's
// tables and logs (what the recorders cut back and continue), not of its checkpoint or
// snapshots, which they read in place or never.
fs::path resume_folder_of_rank(const fs::path& folder, ScratchFolder& scratch) {
  const fs::path& mine = scratch.make();
  for (const auto& e : fs::directory_iterator(folder))
    if (e.is_regular_file() && e.path().filename() != kCheckpointFile &&
        e.path().extension() != ".tmp")
      fs::copy_file(e.path(), mine / e.path().filename());
  return mine;
}

// The temporaries of writes a killed run never finished (a launcher's SIGKILL during a table's
// or the checkpoint's atomic write leaves `name.tmp` beside `name`): litter, never data.
void remove_unfinished_writes(const fs::path& folder) {
  for (const auto& e : fs::recursive_directory_iterator(folder))
    if (e.is_regular_file() && e.path().extension() == ".tmp") fs::remove(e.path());
}

}  // namespace

RunResult resume_run(const std::string& folder_name, const ResumeOptions& ro,
                     const RunOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  const fs::path source(folder_name);
  ScratchFolder scratch;
  const bool other_rank = opt.split_over_ranks && !ranks::root();
  const fs::path mpath = source / "manifest.json", cpath = source / kCheckpointFile;
  if (!fs::exists(mpath))
    throw InputError(folder_name, "manifest.json", "(missing)",
                     "a run folder (with manifest.json) or a sweep folder (with sweep-plan.json)");
  json manifest = read_json_object(mpath.string());
  const std::string status = JsonView(manifest, mpath.string()).text("status", "unknown");
  if (status == "complete")
    throw InputError(mpath.string(), "status", status, "the run is complete: nothing to resume");
  if (!fs::exists(cpath))
    throw InputError(cpath.string(), "", "(missing)",
                     "the run (status '" + status +
                         "') has no checkpoint: it stopped before writing one "
                         "(see output.checkpoint_interval_s)");
  std::ifstream in = open_checkpoint(cpath);
  ArchiveReader a(in, cpath.string());
  const fs::path folder = other_rank ? resume_folder_of_rank(source, scratch) : source;
  // Root cuts its tables back to the checkpoint's length below: not while another rank copies.
  if (opt.split_over_ranks) ranks::barrier();
  if (!other_rank) remove_unfinished_writes(source);
  a.string();  // magic, format and version: checked with the hash
  a.get<std::uint32_t>();
  a.string();
  const std::string commit = a.string();
  // The resolved experiment travels in the checkpoint; only run-time options may change.
  std::vector<std::string> overrides;
  if (ro.threads >= 0) overrides.push_back("engine.threads=" + std::to_string(ro.threads));
  const ExperimentSpec spec = parse_experiment(a.string(), cpath.string(), overrides);
  use_threads(spec);

  LoopState loop;
  loop.load(a);
  Simulation sim = Simulation::restore(a);
  sim.reattach_cracks(folder / kCrackCatalogueFile, static_cast<std::size_t>(spec.resident_cracks));
  std::unique_ptr<Protocol> test;
  visit_lab_test(spec.test, [&]<class T>(const typename T::Params&) { test = T::restore(a); });
  test->check_restored(sim, cpath.string());
  RecorderList recorders = restore_recorders({folder, spec, sim, *test, !other_rank}, a);
  a.label("end of checkpoint");
  if (loop.imbalance.size() != loop.series.axial_strain.size())
    throw InputError(cpath.string(), "loop", "", "inconsistent series: the checkpoint is corrupt");

  if (opt.log)
    opt.log(fmt::format("resuming {} at step {} (simulated time {:.6g} s)", folder_name,
                        sim.step_count(), sim.time()));
  json entry{{"at_step", sim.step_count()},
             {"at_time_s", sim.time()},
             {"previous_status", status},
             {"checkpoint_written_by", std::string(kVersion) + " (" + commit + ")"},
             {"when", fmt::format("{:%Y-%m-%dT%H:%M:%S}", fmt::localtime(std::time(nullptr)))},
             {"command", opt.command_line},
             {"threads", max_threads()},
             {"machine", machine_description()},
             {"instruction_set", instruction_set_name(sim.instruction_set())}};
  if (opt.split_over_ranks) {
    sim.split_over_ranks();
    entry["mpi"] = decomposition(sim);
  } else {
    add_launch(entry);
  }
  if (!manifest.contains("resumed")) manifest["resumed"] = json::array();
  manifest["resumed"].push_back(entry);
  manifest["status"] = "running";
  manifest.erase("stop_reason");
  ManifestFile manifest_file(source, writes_manifest(opt));
  const SignalWatch watch(opt.interrupt, manifest_file);
  manifest_file.write(manifest);
  Session ss{std::move(sim), std::move(test), std::move(loop), std::move(recorders)};
  return execute(spec, folder, manifest, manifest_file, ss, opt, t_start);
}

}  // namespace breccia
