#include "breccia/protocol/vibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia {

void VibrationTest::check(const Params&, const SampleInfo& s, const std::string& where) {
  if (s.density_scaling != 1.0)
    throw InputError(where, "engine.density_scaling", num(s.density_scaling),
                     "a vibration test measures inertia, which density scaling changes: set "
                     "engine.density_scaling = 1");
  if (!s.shape.empty() && s.shape != "slab" && s.shape != "prism" && s.shape != "rectangle")
    throw InputError(where, "sample.shape", "\"" + s.shape + "\"",
                     "a vibration test shakes the bottom face of a \"slab\" (or a \"prism\"; 2D: "
                     "a \"rectangle\")");
}

TestBudget VibrationTest::budget(const Params& p, double, double) {
  TestBudget b;
  b.time = p.cycles / p.frequency;
  b.speed = 2.0 * std::numbers::pi * p.frequency * p.amplitude;
  b.max_strain = 1.0;
  b.what = fmt::format("{} cycles at {} Hz", num(p.cycles), num(p.frequency));
  b.keys = "test.cycles / test.frequency";
  b.speed_key = "test.amplitude / test.frequency";
  b.remedy = "shake for fewer cycles";
  return b;
}

std::unique_ptr<Protocol> VibrationTest::create(Simulation& sim, const Params& p,
                                                const SampleInfo&) {
  return std::make_unique<VibrationTest>(sim, p);
}

VibrationTest::VibrationTest(Simulation& sim, const Params& p) : p_(p) {
  ParticleStore& ps = sim.particles_mut();
  axis_ = ps.planar() ? 1 : 2;
  const auto [lo, hi, r_max] = sample_bounds(ps);
  thickness_ = hi[axis_] - lo[axis_];
  bottom0_ = lo[axis_];
  length_ = hi.x - lo.x;
  width_ = ps.planar() ? ps.thickness() : hi.y - lo.y;
  const bool end = p.grip_length > 0.0;
  face_area_ = end ? p.grip_length * width_ : length_ * width_;
  if (end && !(p.grip_length < length_))
    throw InputError("vibration test", "test.grip_length", num(p.grip_length),
                     "the slab is " + num(length_) + " m long: the grip must leave part of it out");
  const double depth = p.grip_depth > 0.0 ? p.grip_depth : 2.0 * r_max;
  for (std::uint32_t i = 0; i < ps.size(); ++i) {
    const Vec3& x = ps.pos_rad[i].x;
    if (end ? x.x > lo.x + p.grip_length : x[axis_] > lo[axis_] + depth) continue;
    ps.set_motion(i, Motion::Driven);
    ps.drive_vel[i] = {};
    ps.drive_angvel[i] = {};
    face_.push_back(i);
  }
  if (face_.empty())
    throw InputError("vibration test", end ? "test.grip_length" : "test.grip_depth",
                     num(end ? p.grip_length : depth), "the grip holds no grain: lengthen it");
}

std::uint64_t VibrationTest::start(Simulation& sim, double) {
  t0_ = sim.time();
  duration_ = p_.cycles / p_.frequency;
  return 0;
}

double VibrationTest::grip_position(double t) const noexcept {
  const VelocityRamp ramp{0.0, p_.ramp_cycles / p_.frequency};
  return p_.amplitude * ramp.factor(t) * std::sin(2.0 * std::numbers::pi * p_.frequency * t);
}

void VibrationTest::control(Simulation& sim) {
  // The step's velocity moves the grip from u(t) to u(t + dt) exactly.
  const double dt = sim.time_step(), t = sim.time() - t0_;
  elapsed_ = t + dt;
  Vec3 v;
  v[direction()] = (grip_position(t + dt) - grip_position(t)) / dt;
  ParticleStore& ps = sim.particles_mut();
  for (std::uint32_t i : face_) ps.drive_vel[i] = v;
}

double VibrationTest::face_displacement(const Simulation& sim) const {
  double d = 0.0;
  for (std::uint32_t i : face_) d += sim.particles().displacement[i][direction()];
  return d / static_cast<double>(face_.size());
}

double VibrationTest::face_force(const Simulation& sim) const {
  double f = 0.0;
  for (std::uint32_t i : face_) f -= sim.particles().force[i][direction()];
  return f;  // the slab's force on the face is the opposite of the face's on the slab
}

AxialState VibrationTest::measure(const Simulation& sim) const {
  AxialState s;
  s.strain = face_displacement(sim) / thickness_;
  s.force_top = face_force(sim);
  s.stress = s.force_top / face_area_;
  s.stress_nominal = s.stress;
  s.deviatoric = s.stress;
  return s;
}

double VibrationTest::progress(const AxialState&, const Simulation& sim) const {
  return duration_ > 0.0 ? (sim.time() - t0_) / duration_ : 0.0;
}

bool VibrationTest::finished(const AxialState& s, std::size_t) {
  max_displacement_ = std::max(max_displacement_, std::abs(s.strain * thickness_));
  if (!(elapsed_ >= duration_)) return false;
  stop_reason_ = fmt::format("shook for {} cycles at {} Hz", num(p_.cycles), num(p_.frequency));
  return true;
}

std::vector<std::string> VibrationTest::history_columns() const {
  return {"face_displacement_m", "face_force_n", "cycles_done"};
}

void VibrationTest::history_values(const Simulation& sim, std::vector<double>& out) const {
  out = {face_displacement(sim), face_force(sim), (sim.time() - t0_) * p_.frequency};
}

void VibrationTest::summarise(const Simulation& sim, nlohmann::json& out) const {
  const EnergyLedger& L = sim.ledger();
  const double work = L.boundary_work;
  const auto share = [&](double e) { return work > 0.0 ? e / work : 0.0; };
  const double cycles = (sim.time() - t0_) * p_.frequency;
  const double per_cycle = cycles > 0.0 ? static_cast<double>(sim.cracks().size()) / cycles : 0.0;
  const double w = 2.0 * std::numbers::pi * p_.frequency;
  out = {{"headline",
          {fmt::format(
               "{} ({} grains) shaken {} at {:.5g} Hz, amplitude {:.3g} um (it "
               "followed {:.3g} um), {:.3g} cycles; peak acceleration {:.3g} m/s^2",
               end_grip() ? fmt::format("the slab's end, {:.3g} mm of it,", 1e3 * p_.grip_length)
                          : std::string("the bottom face"),
               face_.size(), p_.normal ? "along the normal" : "along the length", p_.frequency,
               1e6 * p_.amplitude, 1e6 * max_displacement_, cycles, p_.amplitude * w * w),
           fmt::format("{} cracks, {:.3g} per cycle; the shaker put in {:.4g} J: {:.1f} % released "
                       "by breaking bonds, {:.1f} % friction, {:.1f} % damping",
                       sim.cracks().size(), per_cycle, work, 100.0 * share(L.released.total()),
                       100.0 * share(L.friction),
                       100.0 * share(L.local_damping + L.viscous_damping))}},
         {"sweep_metrics",
          {{"cracks_per_cycle", per_cycle},
           {"shaker_work_j", work},
           {"released_by_breaks_fraction", share(L.released.total())}}},
         {"frequency_hz", p_.frequency},
         {"amplitude_m", p_.amplitude},
         {"amplitude_followed_m", max_displacement_},
         {"amplitude_note", "largest |mean displacement| of the shaken grains over the rows"},
         {"direction", p_.normal ? "normal" : "length"},
         {"cycles", cycles},
         {"shaken_grains", face_.size()},
         {"grip", end_grip() ? "end" : "bottom face"},
         {"grip_length_m", p_.grip_length},
         {"peak_velocity_m_s", p_.amplitude * w},
         {"peak_acceleration_m_s2", p_.amplitude * w * w},
         {"slab_thickness_m", thickness_},
         {"cracks_per_cycle", per_cycle},
         {"shaker_work_j", work},
         {"energy_shares_of_shaker_work",
          {{"released_by_breaks", share(L.released.total())},
           {"friction", share(L.friction)},
           {"damping", share(L.local_damping + L.viscous_damping)},
           {"kinetic_at_end", share(L.kinetic())},
           {"strain_at_end", share(L.bond.total() + L.contact)}}}};
}

template <class Archive>
void VibrationTest::transfer(Archive& a) {
  a.label("vibration test");
  a.value(p_);
  a.value(axis_);
  a.vector(face_);
  a.value(thickness_);
  a.value(length_);
  a.value(width_);
  a.value(face_area_);
  a.value(bottom0_);
  a.value(t0_);
  a.value(duration_);
  a.value(elapsed_);
  a.value(max_displacement_);
  a.string(stop_reason_);
}

void VibrationTest::save_state(ArchiveWriter& a) const {
  const_cast<VibrationTest*>(this)->transfer(a);  // the writer only reads the fields
}

std::unique_ptr<VibrationTest> VibrationTest::restore(ArchiveReader& a) {
  std::unique_ptr<VibrationTest> t(new VibrationTest());
  t->transfer(a);
  return t;
}

void VibrationTest::check_restored(const Simulation& sim, const std::string& where) const {
  const std::size_t n = sim.particles().size();
  for (std::uint32_t i : face_)
    if (i >= n)
      throw InputError(where, "vibration test", "particle index",
                       "refers to a particle the simulation lacks: the checkpoint is corrupt");
}

}  // namespace breccia
