#include "breccia/protocol/compression.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/interrupt.hpp"

namespace breccia {

PlatenCompression::PlatenCompression(Simulation& sim, PlatenCompressionSettings s,
                                     LateralBoundary lateral, const char* kind)
    : st_(s), kind_(kind), lateral_(lateral) {
  const ParticleStore& p = sim.particles();
  planar_ = p.planar();
  thickness_ = p.thickness();
  axis_ = planar_ ? 1 : 2;
  // Chain membranes are 2D only, a cylinder (walled or wrapped) 3D only.
  if (planar_ && lateral_ == LateralBoundary::Cylinder) lateral_ = LateralBoundary::Prism;
  if (planar_ && lateral_ == LateralBoundary::CylinderMembrane)
    lateral_ = LateralBoundary::Membrane;
  if (!planar_ && lateral_ == LateralBoundary::Membrane) lateral_ = LateralBoundary::Prism;
  const auto [lo, hi, r_max] = sample_bounds(p);
  Vec3 up{};
  up[axis_] = 1.0;
  Wall b = Wall::plane("platen_bottom", lo, up);
  Wall t = Wall::plane("platen_top", hi, -up);
  bottom_ = sim.add_wall(b);
  top_ = sim.add_wall(t);
  centre_ = (lo + hi) * 0.5;
  double shell = 0.0;  // cylinder radius: outermost particle surface
  for (const PosRad& q : p.pos_rad)
    shell = std::max(shell, std::hypot(q.x.x - centre_.x, q.x.y - centre_.y) + q.r);
  if (confined() && !flexible()) {
    if (lateral_ == LateralBoundary::Cylinder) {
      side_.push_back(sim.add_wall(
          Wall::cylinder("confining_cylinder", {centre_.x, centre_.y, 0}, {0, 0, 1}, shell)));
    } else {
      side_.push_back(sim.add_wall(Wall::plane("confining_x0", lo, {1, 0, 0})));
      side_.push_back(sim.add_wall(Wall::plane("confining_x1", hi, {-1, 0, 0})));
      if (!planar_) {
        side_.push_back(sim.add_wall(Wall::plane("confining_y0", lo, {0, 1, 0})));
        side_.push_back(sim.add_wall(Wall::plane("confining_y1", hi, {0, -1, 0})));
      }
    }
  } else if (!confined()) {
    find_face_grains(sim, -kInf, kInf, face_);  // they measure the lateral strain (§1.1)
  }
  servo_ = StressServo{st_.confining_stress, st_.servo_relaxation, 10.0 * st_.platen_speed};
}

void PlatenCompression::find_face_grains(const Simulation& sim, double z_from, double z_to,
                                         std::vector<std::uint32_t> (&faces)[4]) const {
  const ParticleStore& p = sim.particles();
  const double inf = std::numeric_limits<double>::infinity();
  Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
  double r_max = 0.0, shell = 0.0;
  for (const PosRad& q : p.pos_rad) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], q.x[k] - q.r);
      hi[k] = std::max(hi[k], q.x[k] + q.r);
    }
    r_max = std::max(r_max, q.r);
    shell = std::max(shell, std::hypot(q.x.x - centre_.x, q.x.y - centre_.y) + q.r);
  }
  for (auto& f : faces) f.clear();
  for (std::uint32_t i = 0; i < p.size(); ++i) {
    const PosRad& q = p.pos_rad[i];
    if (q.x[axis_] < z_from || q.x[axis_] > z_to) continue;
    if (round()) {
      if (std::hypot(q.x.x - centre_.x, q.x.y - centre_.y) + q.r > shell - r_max)
        faces[0].push_back(i);
      continue;
    }
    if (q.x.x - q.r < lo.x + r_max) faces[0].push_back(i);
    if (q.x.x + q.r > hi.x - r_max) faces[1].push_back(i);
    if (!planar_ && q.x.y - q.r < lo.y + r_max) faces[2].push_back(i);
    if (!planar_ && q.x.y + q.r > hi.y - r_max) faces[3].push_back(i);
  }
}

void PlatenCompression::place_gauges(const Simulation& sim) {
  const ParticleStore& p = sim.particles();
  double r_max = 0.0;
  for (const PosRad& q : p.pos_rad) r_max = std::max(r_max, q.r);
  for (int k = 0; k < 2; ++k) {
    const double at = z0_ + (k == 0 ? 0.25 : 0.75) * h0_;
    gauge_layer_[k].clear();
    for (std::uint32_t i = 0; i < p.size(); ++i)
      if (std::abs(p.pos_rad[i].x[axis_] - at) <= r_max) gauge_layer_[k].push_back(i);
  }
  gauge_length0_ = gauge_length(sim);
  find_face_grains(sim, z0_ + 0.25 * h0_, z0_ + 0.75 * h0_, waist_);
  particle_widths(sim, waist_, waist0_);
  measured_.clear();  // made again from these sets when asked
}

double PlatenCompression::gauge_length(const Simulation& sim) const {
  const ParticleStore& p = sim.particles();
  double mean[2] = {0.0, 0.0};
  for (int k = 0; k < 2; ++k) {
    if (gauge_layer_[k].empty()) return std::numeric_limits<double>::quiet_NaN();
    for (std::uint32_t i : gauge_layer_[k]) mean[k] += p.pos_rad[i].x[axis_];
    mean[k] /= static_cast<double>(gauge_layer_[k].size());
  }
  return mean[1] - mean[0];
}

double PlatenCompression::height(const Simulation& sim) const {
  return sim.walls()[top_].point[axis_] - sim.walls()[bottom_].point[axis_];
}

void PlatenCompression::widths(const Simulation& sim, double w[2]) const {
  const auto& W = sim.walls();
  if (confined() && lateral_ == LateralBoundary::Membrane) {
    if (membrane_.chains()[0].empty())
      membrane_.find(sim.particles(), W[bottom_].point[axis_], W[top_].point[axis_]);
    w[0] = membrane_.width(sim.particles());
    w[1] = thickness_;
    return;
  }
  if (confined() && lateral_ == LateralBoundary::CylinderMembrane) {
    if (sleeve_.grains().empty())
      sleeve_.find(sim.particles(), centre_, W[bottom_].point[axis_], W[top_].point[axis_]);
    w[0] = w[1] = sleeve_.diameter(sim.particles());
    return;
  }
  if (confined()) {
    if (lateral_ == LateralBoundary::Cylinder) {
      w[0] = w[1] = 2.0 * W[side_[0]].radius;
    } else {
      w[0] = W[side_[1]].point.x - W[side_[0]].point.x;
      w[1] = planar_ ? thickness_ : W[side_[3]].point.y - W[side_[2]].point.y;
    }
    return;
  }
  particle_widths(sim, face_, w);
}

void PlatenCompression::particle_widths(const Simulation& sim,
                                        const std::vector<std::uint32_t> (&faces)[4],
                                        double w[2]) const {
  const ParticleStore& p = sim.particles();
  auto mean = [&](const std::vector<std::uint32_t>& ids, auto&& f) {
    double s = 0.0;
    for (std::uint32_t i : ids) s += f(p.pos_rad[i]);
    return ids.empty() ? 0.0 : s / static_cast<double>(ids.size());
  };
  if (round()) {
    const double r = mean(faces[0], [&](const PosRad& q) {
      return std::hypot(q.x.x - centre_.x, q.x.y - centre_.y) + q.r;
    });
    w[0] = w[1] = 2.0 * r;
    return;
  }
  w[0] = mean(faces[1], [](const PosRad& q) { return q.x.x + q.r; }) -
         mean(faces[0], [](const PosRad& q) { return q.x.x - q.r; });
  w[1] = planar_ ? thickness_ : mean(faces[3], [](const PosRad& q) {
                                  return q.x.y + q.r;
                                }) - mean(faces[2], [](const PosRad& q) { return q.x.y - q.r; });
}

double PlatenCompression::current_area(const Simulation& sim) const {
  double w[2];
  widths(sim, w);
  if (round()) return std::numbers::pi * 0.25 * w[0] * w[0];
  return w[0] * w[1];
}

double PlatenCompression::lateral_stress(const Simulation& sim) const {
  if (!confined()) return 0.0;
  if (lateral_ == LateralBoundary::Membrane) return membrane_.stress();
  if (lateral_ == LateralBoundary::CylinderMembrane) return sleeve_.stress();
  const auto& W = sim.walls();
  const double h = height(sim);
  if (lateral_ == LateralBoundary::Cylinder) {
    const Wall& c = W[side_[0]];
    return c.radial_force / (2.0 * std::numbers::pi * c.radius * h);
  }
  double w[2];
  widths(sim, w);
  double sum = 0.0;
  for (std::size_t k = 0; k < side_.size(); ++k) {
    const Wall& s = W[side_[k]];
    const double area = h * (k < 2 ? w[1] : w[0]);
    sum += dot(s.force, s.normal) / area;
  }
  return sum / static_cast<double>(side_.size());
}

void PlatenCompression::drive_lateral(Simulation& sim) {
  auto& W = sim.walls();
  if (lateral_ == LateralBoundary::Membrane) {
    membrane_.apply(sim, st_.confining_stress, W[bottom_].point[axis_], W[top_].point[axis_]);
    return;
  }
  if (lateral_ == LateralBoundary::CylinderMembrane) {
    sleeve_.apply(sim, st_.confining_stress, centre_, W[bottom_].point[axis_],
                  W[top_].point[axis_]);
    return;
  }
  const double h = height(sim), dt = sim.time_step();
  if (lateral_ == LateralBoundary::Cylinder) {
    servo_.drive_cylinder(W[side_[0]], h, dt, k_min_);
    return;
  }
  double w[2];
  widths(sim, w);
  for (std::size_t k = 0; k < side_.size(); ++k) {
    const double area = h * (k < 2 ? w[1] : w[0]);
    if (planar_)
      servo_.drive_pi(W[side_[k]], area, dt, k_min_, side_integral_[k]);
    else
      servo_.drive(W[side_[k]], area, dt, k_min_);
  }
}

void PlatenCompression::control(Simulation& sim) {
  if (confined()) drive_lateral(sim);
  if (!slowed_ && sim.cracks().size() - broken_at_start_ >= slow_down_cracks_) slow_down(sim);
  if (adaptive_.on()) adapt_speed(sim);
}

GrainReads PlatenCompression::grains_read_by_control(const Simulation& sim) const {
  if (adaptive_.due(sim.step_count(), sim.time())) return GrainReads::every();
  return {};
}

void PlatenCompression::adapt_speed(Simulation& sim) {
  auto& W = sim.walls();
  // The start-up ramp counts as the floor, as a constant-speed run's rows would stand there.
  paced_steps_ += paced_step(W[top_], axis_, st_.platen_speed, sim.time(), sim.time_step());
  if (!adaptive_check_now(adaptive_, sim)) return;
  const LoadingReading r = loading_reading(
      sim, (h0_ - height(sim)) / h0_, static_cast<double>(sim.cracks().size() - broken_at_start_),
      fluctuating_kinetic_energy(sim), dot(W[bottom_].force, W[bottom_].normal),
      dot(W[top_].force, W[top_].normal));
  const auto [before, after] =
      steer_platens(adaptive_, r, W[bottom_], W[top_], axis_, sim.time(), sim.time_step());
  // The lateral servo keeps its cap at ten times the platens' speed, as at the floor.
  if (after != before) servo_.max_speed = 10.0 * st_.platen_speed * std::max(before, after);
}

void PlatenCompression::history_values(const Simulation& sim, std::vector<double>& out) const {
  out.push_back(fluctuating_kinetic_energy(sim));
  out.push_back(std::abs(sim.walls()[top_].velocity[axis_]));
}

void PlatenCompression::slow_down(Simulation& sim) {
  slowed_ = true;
  slow_down_strain_ = (h0_ - height(sim)) / h0_;
  auto& W = sim.walls();
  Vec3 up{};
  up[axis_] = 1.0;
  for (auto [w, sign] : {std::pair{bottom_, 1.0}, std::pair{top_, -1.0}}) {
    W[w].target_velocity = up * (sign * st_.platen_speed);
    W[w].ramp = {sim.time(), ramp_, st_.elastic_speed / st_.platen_speed};
    W[w].update_motion(sim.time());
  }
}

double PlatenCompression::fluctuating_kinetic_energy(const Simulation& sim) const {
  const Wall& b = sim.walls()[bottom_];
  const Wall& t = sim.walls()[top_];
  const double z0 = b.point[axis_], vb = b.velocity[axis_];
  const double rate = (t.velocity[axis_] - vb) / (t.point[axis_] - z0);
  const ParticleStore& p = sim.particles();
  double e = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    Vec3 d = p.vel[i];
    d[axis_] -= vb + rate * (p.pos_rad[i].x[axis_] - z0);
    e += 0.5 * p.mass[i] * dot(d, d);
  }
  return e + sim.ledger().kinetic_rotational;
}

void PlatenCompression::summarise_curve(const analysis::CompressionResult&,
                                        nlohmann::json& out) const {
  if (adaptive_.on()) out["adaptive_loading"] = adaptive_loading_summary(adaptive_);
  if (!(st_.elastic_speed > st_.platen_speed)) return;
  out["elastic_speed_m_per_s"] = st_.elastic_speed;
  out["slow_down_axial_strain"] =
      slowed_ ? nlohmann::json(slow_down_strain_) : nlohmann::json(nullptr);
}

std::uint64_t PlatenCompression::start(Simulation& sim, double bar_wave_speed) {
  k_min_ = smallest_wall_stiffness(sim);
  auto& W = sim.walls();
  const std::uint64_t step0 = sim.step_count();
  if (confined()) {
    // Consolidation: platens and lateral walls servo to sigma_3 until every wall's stress (mean
    // of 10 checks, 20 steps apart) has held within the tolerance for 20 checks.
    consolidated_ = false;
    std::vector<std::vector<double>> recent(2);
    int held = 0;
    while (sim.step_count() - step0 < st_.max_consolidation_steps) {
      throw_if_interrupted("consolidating the sample");
      for (int k = 0; k < 20; ++k) {
        const double a = current_area(sim);
        servo_.drive(W[bottom_], a, sim.time_step(), k_min_);
        servo_.drive(W[top_], a, sim.time_step(), k_min_);
        drive_lateral(sim);
        sim.step();
      }
      const double a = current_area(sim);
      const double axial =
          0.5 * (dot(W[bottom_].force, W[bottom_].normal) + dot(W[top_].force, W[top_].normal)) / a;
      const double values[2] = {axial, lateral_stress(sim)};
      bool ok = true;
      for (int k = 0; k < 2; ++k) {
        recent[k].push_back(values[k]);
        if (recent[k].size() > 10) recent[k].erase(recent[k].begin());
        const double avg = std::accumulate(recent[k].begin(), recent[k].end(), 0.0) /
                           static_cast<double>(recent[k].size());
        ok = ok && recent[k].size() == 10 &&
             std::abs(avg - st_.confining_stress) <=
                 st_.consolidation_tolerance * st_.confining_stress;
      }
      held = ok ? held + 1 : 0;
      if (held >= 20) {
        consolidated_ = true;
        break;
      }
    }
  }
  // Axial loading from here: the reference state of docs/analysis.md §1.1.
  h0_ = height(sim);
  z0_ = sim.walls()[bottom_].point[axis_];
  widths(sim, w0_);
  area0_ = current_area(sim);
  place_gauges(sim);
  Vec3 up{};
  up[axis_] = 1.0;
  double ramp = st_.ramp_time;
  if (ramp <= 0.0) ramp = std::max(10.0 * h0_ / bar_wave_speed, 1000.0 * sim.time_step());
  ramp_ = ramp;
  slowed_ = !(st_.elastic_speed > st_.platen_speed);
  const double speed = slowed_ ? st_.platen_speed : st_.elastic_speed;
  for (auto [w, sign] : {std::pair{bottom_, 1.0}, std::pair{top_, -1.0}}) {
    W[w].controlled = false;
    W[w].target_velocity = up * (sign * speed);
    W[w].ramp = {sim.time(), ramp};
    W[w].update_motion(sim.time());
  }
  peak_ = 0.0;
  // Bonds broken before axial loading (a preconsolidated sample unloading to sigma_3) do not
  // arm the post-peak stop rule, nor does a dip while the platens ramp up: the sample settles
  // from consolidation then, and a membrane-confined granite broke 3 bonds and stopped at a
  // "peak" of 0.01 MPa. The cosine ramp closes the platens by platen_speed x ramp in all.
  broken_at_start_ = sim.cracks().size();
  arm_strain_ = speed * ramp / h0_;
  slow_down_cracks_ = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::ceil(st_.slow_down_broken_fraction *
                                            static_cast<double>(sim.intact_bond_sites()))));
  adaptive_ = adaptive_loading_of(st_, bar_wave_speed, h0_, sim, sim.time() + ramp);
  paced_steps_ = static_cast<double>(sim.step_count());
  return sim.step_count() - step0;
}

AxialState PlatenCompression::measure(const Simulation& sim) const {
  const Wall& b = sim.walls()[bottom_];
  const Wall& t = sim.walls()[top_];
  AxialState s;
  s.strain = (h0_ - height(sim)) / h0_;
  // Platen loads: the force the platen exerts on the sample, along its inward normal.
  s.force_bottom = dot(b.force, b.normal);
  s.force_top = dot(t.force, t.normal);
  const double f = 0.5 * (s.force_bottom + s.force_top);
  s.stress = f / current_area(sim);
  s.stress_nominal = f / area0_;
  double w[2];
  widths(sim, w);
  if (round()) {
    s.lateral_strain = (w0_[0] - w[0]) / w0_[0];
    s.volumetric_strain = s.strain + 2.0 * s.lateral_strain;
  } else if (planar_) {
    s.lateral_strain = (w0_[0] - w[0]) / w0_[0];
    s.volumetric_strain = s.strain + s.lateral_strain;
  } else {
    const double ex = (w0_[0] - w[0]) / w0_[0], ey = (w0_[1] - w[1]) / w0_[1];
    s.lateral_strain = 0.5 * (ex + ey);
    s.volumetric_strain = s.strain + ex + ey;
  }
  s.confining_stress = lateral_stress(sim);
  s.deviatoric = s.stress - st_.confining_stress;
  s.gauge_strain = (gauge_length0_ - gauge_length(sim)) / gauge_length0_;
  particle_widths(sim, waist_, w);
  const double gx = (waist0_[0] - w[0]) / waist0_[0], gy = (waist0_[1] - w[1]) / waist0_[1];
  s.gauge_lateral_strain = round() || planar_ ? gx : 0.5 * (gx + gy);
  return s;
}

GrainReads PlatenCompression::grains_read_by_measure() const {
  if (measured_.empty()) {
    for (const auto* sets : {&face_, &waist_})
      for (const auto& s : *sets) measured_.insert(measured_.end(), s.begin(), s.end());
    for (const auto& s : gauge_layer_) measured_.insert(measured_.end(), s.begin(), s.end());
    std::sort(measured_.begin(), measured_.end());
    measured_.erase(std::unique(measured_.begin(), measured_.end()), measured_.end());
  }
  if (!(confined() && flexible())) return {.all = false, .some = measured_};
  const std::vector<std::uint32_t>& chains = membrane_grains();
  measured_now_.clear();
  std::set_union(measured_.begin(), measured_.end(), chains.begin(), chains.end(),
                 std::back_inserter(measured_now_));
  return {.all = false, .some = measured_now_};
}

bool PlatenCompression::finished(const AxialState& s, std::size_t broken_bonds) {
  peak_ = std::max(peak_, s.deviatoric);
  if (s.strain >= st_.max_strain) {
    stop_reason_ = "reached the maximum strain " + num(st_.max_strain);
    return true;
  }
  if (st_.stop_fraction > 0.0 && broken_bonds > broken_at_start_ && s.strain >= arm_strain_ &&
      peak_ > 0.0 && s.deviatoric < st_.stop_fraction * peak_) {
    stop_reason_ = "deviatoric stress fell below " + num(st_.stop_fraction) + " of the peak";
    return true;
  }
  return false;
}

const char* PlatenCompression::kind() const noexcept {
  for (const char* k : {"ucs", "triaxial", "biaxial"})
    if (kind_ == k) return k;
  return "ucs";
}

std::string PlatenCompression::label() const {
  if (!confined()) return "uniaxial compression (UCS)";
  return planar_ ? "biaxial compression" : "triaxial compression";
}

std::string PlatenCompression::lateral_boundary() const {
  if (!confined()) return "none";
  if (lateral_ == LateralBoundary::Membrane) return "flexible membranes on the outer grain chains";
  if (lateral_ == LateralBoundary::CylinderMembrane)
    return "flexible membrane on the outermost grains all round";
  return lateral_ == LateralBoundary::Cylinder ? "cylindrical servo wall"
                                               : "servo-controlled plane walls";
}

template <class Archive>
void PlatenCompression::transfer(Archive& a) {
  a.label("platen compression");
  a.value(st_);
  a.string(kind_);
  a.value(lateral_);
  a.value(axis_);
  a.value(planar_);
  a.value(thickness_);
  a.value(bottom_);
  a.value(top_);
  a.vector(side_);
  a.value(centre_);
  for (auto& f : face_) a.vector(f);
  a.value(h0_);
  a.value(z0_);
  a.value(area0_);
  a.value(w0_);
  for (auto& g : gauge_layer_) a.vector(g);
  for (auto& f : waist_) a.vector(f);
  a.value(gauge_length0_);
  a.value(waist0_);
  a.value(peak_);
  a.value(broken_at_start_);
  a.value(arm_strain_);
  a.value(ramp_);
  a.value(slow_down_cracks_);
  a.value(slowed_);
  a.value(slow_down_strain_);
  a.value(adaptive_);
  a.value(paced_steps_);
  a.value(k_min_);
  a.value(consolidated_);
  a.value(servo_);
  a.value(side_integral_);
  a.string(stop_reason_);
}

void PlatenCompression::save_state(ArchiveWriter& a) const {
  const_cast<PlatenCompression*>(this)->transfer(a);  // the writer only reads the fields
}

std::unique_ptr<PlatenCompression> PlatenCompression::restore(ArchiveReader& a) {
  std::unique_ptr<PlatenCompression> t(new PlatenCompression());
  t->transfer(a);
  return t;
}

void PlatenCompression::check_restored(const Simulation& sim, const std::string& where) const {
  const std::size_t walls = sim.walls().size(), n = sim.particles().size();
  bool ok = bottom_ < walls && top_ < walls;
  for (std::size_t w : side_) ok = ok && w < walls;
  for (const auto* set : {&face_, &waist_})
    for (const auto& f : *set)
      for (std::uint32_t i : f) ok = ok && i < n;
  for (const auto& g : gauge_layer_)
    for (std::uint32_t i : g) ok = ok && i < n;
  if (!ok)
    throw InputError(
        where, "platen compression", "wall or particle index",
        "refers to a wall or particle the simulation lacks: the checkpoint is corrupt");
}

// --- registered tests ---

std::unique_ptr<Protocol> UcsTest::create(Simulation& sim, const Params& p, const SampleInfo& s) {
  return std::make_unique<PlatenCompression>(
      sim, platen_settings(platen_loading(p)),
      s.shape == "cylinder" ? LateralBoundary::Cylinder : LateralBoundary::Prism, "ucs");
}

}  // namespace breccia
