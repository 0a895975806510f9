#include "breccia/protocol/direct_tension.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia {

namespace {

// A default grip holds two layers of the largest grains; the grips must leave at least half of
// the sample free between them, so that it can break away from them (ISRM: the fracture should
// lie away from the end caps).
constexpr double kDefaultGripDiameters = 2.0;
constexpr double kMinFreeFraction = 0.5;

double grip_length_of(const DirectTensionTest::Params& p, double r_max) {
  return p.grip_length > 0.0 ? p.grip_length : kDefaultGripDiameters * 2.0 * r_max;
}

void check_grips(double grip, double length, const std::string& where) {
  if (!(length - 2.0 * grip >= kMinFreeFraction * length))
    throw InputError(where, "test.grip_length", num(grip) + " m",
                     "the two grips must leave at least half of the sample's length (" +
                         num(length) + " m) free between them: at most " +
                         num(0.5 * (1.0 - kMinFreeFraction) * length) + " m");
}

}  // namespace

void DirectTensionTest::check(const Params& p, const SampleInfo& s, const std::string& where) {
  if (s.dimension == 3 && !s.shape.empty() && s.shape != "prism" && s.shape != "cylinder")
    throw InputError(where, "sample.shape", "\"" + s.shape + "\"",
                     "a 3D direct tension test pulls a \"prism\" or a \"cylinder\" along z");
  if (s.dimension == 2 && !s.shape.empty() && s.shape != "rectangle")
    throw InputError(where, "sample.shape", "\"" + s.shape + "\"",
                     "a 2D direct tension test pulls a \"rectangle\" along y");
  if (s.height > 0.0 && s.r_max > 0.0) check_grips(grip_length_of(p, s.r_max), s.height, where);
}

DirectTensionTest::DirectTensionTest(Simulation& sim, const Params& p, const SampleInfo& s)
    : p_(p) {
  ParticleStore& ps = sim.particles_mut();
  axis_ = ps.planar() ? 1 : 2;
  across_ = 0;
  const auto [lo, hi, r_max] = sample_bounds(ps);
  origin_ = lo[axis_];
  length_ = hi[axis_] - lo[axis_];
  width_ = hi.x - lo.x;
  depth_ = ps.planar() ? ps.thickness() : hi.y - lo.y;
  area_ = s.shape == "cylinder" ? 0.25 * std::numbers::pi * width_ * depth_ : width_ * depth_;
  grip_ = grip_length_of(p, r_max);
  check_grips(grip_, length_, "direct tension test");
  free_length_ = length_ - 2.0 * grip_;
  const double mid = origin_ + 0.5 * length_;
  for (std::uint32_t i = 0; i < ps.size(); ++i) {
    const PosRad& q = ps.pos_rad[i];
    const double z = q.x[axis_];
    if (z <= lo[axis_] + grip_ || z >= hi[axis_] - grip_) {
      ps.set_motion(i, Motion::Driven);
      ps.drive_vel[i] = {};
      ps.drive_angvel[i] = {};
      (z <= mid ? bottom_ : top_).push_back(i);
      continue;
    }
    // The width is read on the middle quarter of the length, one largest radius deep.
    if (std::abs(z - mid) > 0.125 * length_) continue;
    if (q.x.x - q.r < lo.x + r_max) left_.push_back(i);
    if (q.x.x + q.r > hi.x - r_max) right_.push_back(i);
  }
  if (bottom_.empty() || top_.empty())
    throw InputError("direct tension test", "test.grip_length", num(grip_) + " m",
                     "a grip holds no grain: lengthen it");
}

std::unique_ptr<Protocol> DirectTensionTest::create(Simulation& sim, const Params& p,
                                                    const SampleInfo& s) {
  return std::make_unique<DirectTensionTest>(sim, p, s);
}

double DirectTensionTest::mean_position(const Simulation& sim,
                                        const std::vector<std::uint32_t>& grip) const {
  double z = 0.0;
  for (std::uint32_t i : grip) z += sim.particles().pos_rad[i].x[axis_];
  return z / static_cast<double>(grip.size());
}

std::uint64_t DirectTensionTest::start(Simulation& sim, double bar_wave_speed) {
  t0_ = sim.time();
  ramp_ = p_.ramp_time > 0.0 ? p_.ramp_time
                             : std::max(10.0 * length_ / bar_wave_speed, 1000.0 * sim.time_step());
  separation0_ = mean_position(sim, top_) - mean_position(sim, bottom_);
  w0_ = width_between(sim.particles(), left_, right_, across_);
  peak_ = 0.0;
  cracks_at_start_ = static_cast<double>(sim.cracks().size());
  adaptive_ = adaptive_loading_of(p_, bar_wave_speed, length_, sim, t0_ + ramp_);
  paced_steps_ = static_cast<double>(sim.step_count());
  return 0;
}

double DirectTensionTest::speed_factor(double time, double time_step) const {
  // At the middle of the coming step, so that the grips travel the ramps' integral.
  const double t = time + 0.5 * time_step;
  if (adaptive_.on() && t >= t0_ + ramp_) return adaptive_.factor() * change_.factor(t);
  return VelocityRamp{t0_, ramp_}.factor(t);
}

GrainReads DirectTensionTest::grains_read_by_control(const Simulation& sim) const {
  if (adaptive_.due(sim.step_count(), sim.time())) return GrainReads::every();
  return {};
}

// At a check: the state adaptive loading reads, and the cosine to its new speed over the check's
// interval.
void DirectTensionTest::adapt_speed(Simulation& sim) {
  if (!adaptive_check_now(adaptive_, sim)) return;
  const LoadingReading r = loading_reading(
      sim, (mean_position(sim, top_) - mean_position(sim, bottom_) - separation0_) / free_length_,
      static_cast<double>(sim.cracks().size()) - cracks_at_start_, fluctuating_kinetic_energy(sim),
      grip_tension(sim, bottom_, -1.0), grip_tension(sim, top_, 1.0));
  const double before = adaptive_.factor();
  const double after = adaptive_.update(r);
  if (after != before)
    change_ = {sim.time(), static_cast<double>(adaptive_.check_steps()) * sim.time_step(),
               before / after};
}

void DirectTensionTest::history_values(const Simulation& sim, std::vector<double>& out) const {
  out.push_back(std::abs(sim.particles().drive_vel[top_.front()][axis_]));
}

void DirectTensionTest::control(Simulation& sim) {
  if (adaptive_.on()) adapt_speed(sim);
  const double factor = speed_factor(sim.time(), sim.time_step());
  if (adaptive_.on()) paced_steps_ += std::max(1.0, factor);
  const double v = p_.platen_speed * factor;
  ParticleStore& ps = sim.particles_mut();
  for (std::uint32_t i : bottom_) ps.drive_vel[i][axis_] = -v;
  for (std::uint32_t i : top_) ps.drive_vel[i][axis_] = v;
}

// The force the rest of the sample pulls a grip with, away from it: the sum of the forces on the
// grip's grains (the grip's own pairs cancel), along -sign (top grip: sign +1, pulled down).
double DirectTensionTest::grip_tension(const Simulation& sim,
                                       const std::vector<std::uint32_t>& grip, double sign) const {
  double f = 0.0;
  for (std::uint32_t i : grip) f += sim.particles().force[i][axis_];
  return -sign * f;
}

AxialState DirectTensionTest::measure(const Simulation& sim) const {
  AxialState s;
  const double separation = mean_position(sim, top_) - mean_position(sim, bottom_);
  s.strain = (separation - separation0_) / free_length_;
  s.force_bottom = grip_tension(sim, bottom_, -1.0);
  s.force_top = grip_tension(sim, top_, 1.0);
  s.stress = 0.5 * (s.force_bottom + s.force_top) / area_;
  s.stress_nominal = s.stress;
  s.deviatoric = s.stress;
  const double w = width_between(sim.particles(), left_, right_, across_);
  s.lateral_strain = w0_ > 0.0 ? (w - w0_) / w0_ : 0.0;
  s.volumetric_strain = s.strain + (sim.particles().planar() ? 1.0 : 2.0) * s.lateral_strain;
  return s;
}

GrainReads DirectTensionTest::grains_read_by_measure() const {
  if (read_.empty()) {
    for (const auto* ids : {&bottom_, &top_, &left_, &right_})
      read_.insert(read_.end(), ids->begin(), ids->end());
    std::sort(read_.begin(), read_.end());
    read_.erase(std::unique(read_.begin(), read_.end()), read_.end());
  }
  return {.all = false, .some = read_};
}

// The grains' motion beyond the stretch between the grips, v(z) = v_b + (v_t - v_b)(z - z_b) /
// (z_t - z_b) through the grips' mean positions, which the loading itself prescribes; the grips
// move exactly with it.
double DirectTensionTest::fluctuating_kinetic_energy(const Simulation& sim) const {
  const ParticleStore& ps = sim.particles();
  const double zb = mean_position(sim, bottom_), zt = mean_position(sim, top_);
  const double vb = ps.drive_vel[bottom_.front()][axis_], vt = ps.drive_vel[top_.front()][axis_];
  const double rate = (vt - vb) / (zt - zb);
  double e = 0.0;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    if (ps.motion[i] == Motion::Driven) continue;
    Vec3 d = ps.vel[i];
    d[axis_] -= vb + rate * (ps.pos_rad[i].x[axis_] - zb);
    e += 0.5 * ps.mass[i] * dot(d, d);
  }
  return e + sim.ledger().kinetic_rotational;
}

bool DirectTensionTest::finished(const AxialState& s, std::size_t broken_bonds) {
  peak_ = std::max(peak_, s.stress);
  if (s.strain >= p_.max_strain) {
    stop_reason_ = "reached the maximum strain " + num(p_.max_strain);
    return true;
  }
  if (broken_bonds > 0 && peak_ > 0.0 && s.stress < p_.stop_fraction * peak_) {
    stop_reason_ = "tension fell below " + num(p_.stop_fraction) + " of the peak";
    return true;
  }
  return false;
}

template <class Archive>
void DirectTensionTest::transfer(Archive& a) {
  a.label("direct tension test");
  a.value(p_);
  a.value(axis_);
  a.value(across_);
  a.vector(bottom_);
  a.vector(top_);
  a.vector(left_);
  a.vector(right_);
  for (double* v : {&origin_, &length_, &area_, &width_, &depth_, &grip_, &free_length_,
                    &separation0_, &w0_, &t0_, &ramp_, &peak_, &paced_steps_, &cracks_at_start_})
    a.value(*v);
  a.value(adaptive_);
  a.value(change_);
  a.string(stop_reason_);
}

void DirectTensionTest::save_state(ArchiveWriter& a) const {
  const_cast<DirectTensionTest*>(this)->transfer(a);  // the writer only reads the fields
}

std::unique_ptr<DirectTensionTest> DirectTensionTest::restore(ArchiveReader& a) {
  std::unique_ptr<DirectTensionTest> t(new DirectTensionTest());
  t->transfer(a);
  return t;
}

void DirectTensionTest::check_restored(const Simulation& sim, const std::string& where) const {
  const std::size_t n = sim.particles().size();
  bool ok = !bottom_.empty() && !top_.empty();
  for (const auto* ids : {&bottom_, &top_, &left_, &right_})
    for (std::uint32_t i : *ids) ok = ok && i < n;
  if (!ok)
    throw InputError(where, "direct tension test", "particle index",
                     "refers to a particle the simulation lacks: the checkpoint is corrupt");
}

void DirectTensionTest::summarise_curve(const analysis::CompressionResult& an,
                                        nlohmann::json& out) const {
  out["tensile_strength_pa"] = an.peak_deviatoric;
  out["tensile_strength_mpa"] = an.peak_deviatoric * 1e-6;
  out["tensile_strength_method"] =
      "sigma_t = F / A at the largest mean grip force F over the cross-section A (direct "
      "tension)";
  out["peak_force_n"] = an.peak_deviatoric * area_;
  if (adaptive_.on()) out["adaptive_loading"] = adaptive_loading_summary(adaptive_);
  out["tensile_strength_reading"] = {
      {"name", "direct tensile strength"},
      {"formula", "F/A"},
      {"sample_moduli", true},  // the rows are the sample's stress and strain
      {"specimen", fmt::format("A = {:.4g} mm^2, grips {:.3g} mm, free length {:.4g} mm",
                               area_ * 1e6, grip_ * 1e3, free_length_ * 1e3)}};
  out["cross_section_m2"] = area_;
  out["grip_length_m"] = grip_;
  out["free_length_m"] = free_length_;
  out["gripped_grains"] = gripped();
}

void DirectTensionTest::describe_crack_pattern(const Simulation& sim,
                                               nlohmann::json& pattern) const {
  // Cracks by where they lie along the free length, in tenths from the bottom grip; those in the
  // end tenths next to a grip say how much the grips, not the rock, set the failure.
  std::array<std::size_t, 10> tenths{};
  std::size_t n = 0;
  for (const CrackRecord& c : sim.cracks()) {
    const double u = (c.position[axis_] - (origin_ + grip_)) / free_length_;
    const auto k = static_cast<std::size_t>(std::clamp(std::floor(10.0 * u), 0.0, 9.0));
    ++tenths[k];
    ++n;
  }
  const double next_to_grips =
      n > 0 ? static_cast<double>(tenths[0] + tenths[9]) / static_cast<double>(n) : 0.0;
  pattern["direct_tension"] = {
      {"cracks_by_tenth_of_free_length", tenths},
      {"next_to_grips_share", next_to_grips},
      {"note",
       "cracks by tenth of the free length between the grips, from the bottom grip (cracks "
       "inside a grip counted in the nearest end tenth); a uniform scatter puts 20 % in the two "
       "end tenths, a break at a grip far more"}};
}

}  // namespace breccia
