#include "breccia/protocol/abrasion.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <variant>

#include "breccia/analysis/fragments.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/interrupt.hpp"

namespace breccia {

namespace {

// Settling the plate's normal stress before it slides: every check is 20 steps; the mean of the
// last 10 checks within 2 % of the target for 20 checks in a row, or at most this many steps.
constexpr std::uint64_t kMaxSettleSteps = 200000;
constexpr double kSettleTolerance = 0.02;

// The grit layer's grains stand this far apart and this high above the top face, as fractions
// of their radius: clear of each other (no grit-grit contact) and of the slab at the start.
constexpr double kGritSpacing = 2.002, kGritClearance = 1.01;

// The mass no longer bonded to the slab: every fragment but the largest (which holds the base),
// among the rock's grains.
double worn_mass(const Simulation& sim, std::size_t rock, double density_scaling,
                 std::size_t& pieces) {
  const analysis::FragmentResult f = analysis::find_fragments(
      sim.particles(), [&](const analysis::BondVisit& visit) { sim.for_each_intact_bond(visit); },
      density_scaling, rock);
  pieces = f.fragments.empty() ? 0 : f.fragments.size() - 1;
  return f.total_mass - f.largest_mass;
}

}  // namespace

void AbrasionTest::check(const Params&, const SampleInfo& s, const std::string& where) {
  if (!s.shape.empty() && s.shape != "slab" && s.shape != "prism" && s.shape != "rectangle")
    throw InputError(where, "sample.shape", "\"" + s.shape + "\"",
                     "an abrasion test slides a plate on the top face of a \"slab\" (or a "
                     "\"prism\"; 2D: a \"rectangle\")");
}

TestBudget AbrasionTest::budget(const Params& p, double length, double bar_wave_speed) {
  TestBudget b;
  // The slab's length along x is not known here: ten times its thickness stands in for it.
  const double ramp = p.ramp_time > 0.0 ? p.ramp_time : 100.0 * length / bar_wave_speed;
  b.time = ramp + p.slide_distance / p.sliding_speed;
  b.speed = p.sliding_speed;
  b.max_strain = 1.0;
  b.what = fmt::format("ramp {} s + slide_distance {} m / sliding_speed {} m/s", num(ramp),
                       num(p.slide_distance), num(p.sliding_speed));
  b.keys = "test.sliding_speed / test.slide_distance / test.ramp_time";
  b.speed_key = "test.sliding_speed";
  b.remedy = "raise the sliding speed or shorten the distance";
  return b;
}

std::unique_ptr<Protocol> AbrasionTest::create(Simulation& sim, const Params& p,
                                               const SampleInfo& s) {
  return std::make_unique<AbrasionTest>(sim, p, s.density_scaling);
}

AbrasionTest::AbrasionTest(Simulation& sim, const Params& p, double density_scaling)
    : p_(p), density_scaling_(density_scaling) {
  ParticleStore& ps = sim.particles_mut();
  axis_ = ps.planar() ? 1 : 2;
  const auto [lo, hi, r_max] = sample_bounds(ps);
  length_ = hi.x - lo.x;
  width_ = ps.planar() ? ps.thickness() : hi.y - lo.y;
  area_ = length_ * width_;
  thickness_ = hi[axis_] - lo[axis_];
  bottom0_ = lo[axis_];
  const double depth = p.base_depth > 0.0 ? p.base_depth : 2.0 * r_max;
  for (std::uint32_t i = 0; i < ps.size(); ++i)
    if (ps.pos_rad[i].x[axis_] <= lo[axis_] + depth) {
      ps.set_motion(i, Motion::Fixed);
      base_.push_back(i);
    }
  if (base_.empty() || base_.size() == ps.size())
    throw InputError("abrasion test", "test.base_depth", num(depth),
                     "the held base must hold some grains and leave the rest free");
  if (p.flat_plate) {
    Vec3 down;
    down[axis_] = -1.0;
    plate_ = sim.add_wall(Wall::plane("abrading_plate", hi, down));
  } else {
    add_grit(sim, {lo, hi, r_max});
  }
}

void AbrasionTest::add_grit(Simulation& sim, const SampleBounds& b) {
  ParticleStore& ps = sim.particles_mut();
  const double r = p_.grit_radius > 0.0 ? p_.grit_radius : b.r_max;
  const double s = kGritSpacing * r;
  // From slide_distance behind the slab's x = min end to its x = max end (plus a grain either
  // side), so that the layer covers the top face all along the slide. 3D: a hexagonal layer
  // whose rows run across the sliding direction, each row shifted by half a spacing, so the
  // grains' tracks lie a radius apart.
  const double x_lo = b.lo.x - p_.slide_distance - s, x_hi = b.hi.x + s;
  const double row_pitch = ps.planar() ? s : s * std::sqrt(3.0) / 2.0;
  std::uint64_t tag = 0;
  for (std::uint64_t t : ps.tag) tag = std::max(tag, t);
  ParticleSpec grit;
  grit.radius = r;
  grit.density = ps.density.front();  // the rock's (scaled) density: the same time step
  grit.motion = Motion::Driven;
  grit.position[axis_] = b.hi[axis_] + kGritClearance * r;
  for (int row = 0; x_lo + row * row_pitch <= x_hi; ++row) {
    grit.position.x = x_lo + row * row_pitch;
    if (ps.planar()) {
      grit.tag = ++tag;
      grit_.push_back(static_cast<std::uint32_t>(ps.add(grit)));
      continue;
    }
    for (double y = b.lo.y + (row % 2 == 0 ? 0.0 : 0.5 * s); y <= b.hi.y + 0.5 * s; y += s) {
      grit.position.y = y;
      grit.tag = ++tag;
      grit_.push_back(static_cast<std::uint32_t>(ps.add(grit)));
    }
  }
  // The servo's stiffness bound: one grit-grain contact of a mean-size grain at an overlap of
  // 1 % of its radius (the law's tangent stiffness there; for Hertz it grows with the overlap).
  double rsum = 0.0;
  for (std::size_t i = 0; i < grit_.front(); ++i) rsum += ps.pos_rad[i].r;
  const double rm = rsum / static_cast<double>(grit_.front());
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        PairGeometry g = pair_geometry({}, r, {0, 0, r + rm}, rm, {}, {}, {}, {}, 1, 1, ps.planar(),
                                       ps.thickness());
        g.delta = 0.01 * rm;
        double ks = 0.0;
        CL::timestep_stiffness(c.params, g, grit_contact_stiffness_, ks);
      },
      sim.contact_model());
}

void AbrasionTest::drive(Simulation& sim, double sliding_factor) {
  const StressServo servo{p_.normal_stress, p_.servo_relaxation, 10.0 * p_.sliding_speed};
  if (grit_.empty()) {
    Wall& w = sim.walls()[plate_];
    // Along its normal the servo alone; the sliding adds its own component.
    servo.drive(w, area_, sim.time_step(), k_min_);
    w.velocity.x = p_.sliding_speed * sliding_factor;
    return;
  }
  // The grit layer moves as one body: the servo divides by an upper bound of its contacts'
  // summed stiffness (up to 3 contacts per touching grit grain, each at the bound above), so it
  // cannot overshoot into instability; its integral part takes out the lag that this low gain
  // leaves while the layer rides up and down over the grains (2.2 % of the normal force at
  // 0.2 m/s on the tiny slab of tests/test_protocols.cpp without it).
  ParticleStore& ps = sim.particles_mut();
  std::size_t touching = 0;
  for (std::uint32_t i : grit_) touching += ps.force[i][axis_] != 0.0 ? 1 : 0;
  const double k =
      3.0 * static_cast<double>(std::max<std::size_t>(touching, 1)) * grit_contact_stiffness_;
  Vec3 v;
  v[axis_] = -servo.speed_pi(normal_force(sim) / area_, area_, k, sim.time_step(), k_min_,
                             servo_integral_);
  v.x = p_.sliding_speed * sliding_factor;
  for (std::uint32_t i : grit_) {
    ps.drive_vel[i] = v;
    ps.drive_angvel[i] = {};
  }
}

std::uint64_t AbrasionTest::start(Simulation& sim, double bar_wave_speed) {
  k_min_ = smallest_wall_stiffness(sim);
  // The plate settles on the slab at the normal stress before it slides.
  const std::uint64_t step0 = sim.step_count();
  std::vector<double> recent;
  int held = 0;
  while (sim.step_count() - step0 < kMaxSettleSteps && held < 20) {
    throw_if_interrupted("pressing the plate on the slab");
    for (int k = 0; k < 20; ++k) {
      drive(sim, 0.0);
      sim.step();
    }
    recent.push_back(normal_force(sim) / area_);
    if (recent.size() > 10) recent.erase(recent.begin());
    const double avg =
        std::accumulate(recent.begin(), recent.end(), 0.0) / static_cast<double>(recent.size());
    const bool ok = recent.size() == 10 &&
                    std::abs(avg - p_.normal_stress) <= kSettleTolerance * p_.normal_stress;
    held = ok ? held + 1 : 0;
  }
  consolidated_ = held >= 20;
  // Grains a sample leaves without bonds are not wear.
  std::size_t pieces = 0;
  unbonded0_ = worn_mass(sim, rock_particles(sim), density_scaling_, pieces);
  pieces0_ = pieces;
  t0_ = sim.time();
  x0_ = position_x(sim);
  ramp_ = p_.ramp_time > 0.0 ? p_.ramp_time
                             : std::max(10.0 * length_ / bar_wave_speed, 1000.0 * sim.time_step());
  return sim.step_count() - step0;
}

void AbrasionTest::control(Simulation& sim) {
  const VelocityRamp ramp{t0_, ramp_};
  drive(sim, ramp.factor(sim.time() + 0.5 * sim.time_step()));
}

// A wall's force is the force it exerts on the grains; a grain's force is what the slab exerts
// on it, so the grit's push and drag on the slab are minus its grains' summed forces.
double AbrasionTest::normal_force(const Simulation& sim) const {
  if (grit_.empty()) {
    const Wall& w = sim.walls()[plate_];
    return dot(w.force, w.normal);
  }
  double f = 0.0;
  for (std::uint32_t i : grit_) f += sim.particles().force[i][axis_];
  return f;
}

double AbrasionTest::shear_force(const Simulation& sim) const {
  if (grit_.empty()) return sim.walls()[plate_].force.x;
  double f = 0.0;
  for (std::uint32_t i : grit_) f -= sim.particles().force[i].x;
  return f;
}

double AbrasionTest::position_x(const Simulation& sim) const {
  return grit_.empty() ? sim.walls()[plate_].point.x : sim.particles().pos_rad[grit_.front()].x.x;
}

double AbrasionTest::slid(const Simulation& sim) const {
  return position_x(sim) - x0_;
}

AxialState AbrasionTest::measure(const Simulation& sim) const {
  AxialState s;
  s.strain = slid(sim) / length_;
  s.force_top = normal_force(sim);
  s.force_bottom = shear_force(sim);
  s.stress = s.force_bottom / area_;
  s.stress_nominal = s.stress;
  s.deviatoric = s.stress;
  return s;
}

bool AbrasionTest::finished(const AxialState& s, std::size_t) {
  mu_.push_back(s.force_top > 0.0 ? s.force_bottom / s.force_top
                                  : std::numeric_limits<double>::quiet_NaN());
  slid_.push_back(s.strain * length_);
  if (s.strain * length_ < p_.slide_distance) return false;
  stop_reason_ = fmt::format("the abrader slid {:.4g} m", p_.slide_distance);
  return true;
}

std::vector<std::string> AbrasionTest::history_columns() const {
  return {"slid_m", "abrader_normal_force_n", "abrader_shear_force_n", "bulk_friction"};
}

void AbrasionTest::history_values(const Simulation& sim, std::vector<double>& out) const {
  const double n = normal_force(sim), t = shear_force(sim);
  out = {slid(sim), n, t, n > 0.0 ? t / n : std::numeric_limits<double>::quiet_NaN()};
}

void AbrasionTest::summarise(const Simulation& sim, nlohmann::json& out) const {
  // The steady part: the rows of the second half of the distance slid.
  const double total = slid_.empty() ? 0.0 : slid_.back();
  double sum = 0.0, sum2 = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < mu_.size(); ++k)
    if (slid_[k] >= 0.5 * total && std::isfinite(mu_[k])) {
      sum += mu_[k];
      sum2 += mu_[k] * mu_[k];
      ++n;
    }
  const double mean = n > 0 ? sum / static_cast<double>(n) : std::nan("");
  const double sd =
      n > 1 ? std::sqrt(std::max(0.0, sum2 / static_cast<double>(n) - mean * mean)) : std::nan("");
  std::size_t pieces = 0;
  const std::size_t rock = rock_particles(sim);
  const double worn = std::max(0.0, worn_mass(sim, rock, density_scaling_, pieces) - unbonded0_);
  pieces = pieces > pieces0_ ? pieces - pieces0_ : 0;
  double mass = 0.0;
  for (std::size_t i = 0; i < rock; ++i) mass += sim.particles().mass[i] / density_scaling_;
  const auto num_or_null = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  };
  out = {
      {"headline",
       {fmt::format("{} at {:.3g} MPa normal stress slid {:.3g} mm at {:.3g} m/s: bulk friction "
                    "coefficient {:.3f} +/- {:.3f} over the second half",
                    grit_.empty() ? "plate" : "grit layer", 1e-6 * p_.normal_stress, 1e3 * total,
                    p_.sliding_speed, mean, sd),
        fmt::format("{} cracks; worn off: {:.4g} g in {} pieces ({:.2f} % of the slab's mass)",
                    sim.cracks().size(), 1e3 * worn, pieces,
                    mass > 0.0 ? 100.0 * worn / mass : 0.0)}},
      {"sweep_metrics",
       {{"bulk_friction", num_or_null(mean)}, {"worn_mass_kg", worn}, {"slid_m", total}}},
      {"bulk_friction_mean", num_or_null(mean)},
      {"bulk_friction_sd", num_or_null(sd)},
      {"bulk_friction_method",
       "shear force on the abrader over its normal force (seed 001), mean and spread over the "
       "rows of the second half of the distance slid; every row is in history.csv"},
      {"abrader", grit_.empty() ? "flat plate" : "grit layer"},
      {"abrader_friction", grit_.empty() ? "contact.wall_friction" : "contact.friction"},
      {"grit_grains", grit_.size()},
      {"grit_radius_m", grit_.empty() ? nlohmann::json(nullptr)
                                      : nlohmann::json(sim.particles().pos_rad[grit_.front()].r)},
      {"normal_stress_pa", p_.normal_stress},
      {"normal_force_target_n", p_.normal_stress * area_},
      {"settled", consolidated_},
      {"sliding_speed_m_s", p_.sliding_speed},
      {"slid_m", total},
      {"worn_mass_kg", worn},
      {"worn_pieces", pieces},
      {"worn_fraction_of_mass", mass > 0.0 ? worn / mass : 0.0},
      {"worn_method",
       "mass (at the grains' density, without density scaling) no longer bonded to the slab's "
       "largest piece, which holds the base, less what was unbonded when the sliding began"},
      {"held_base_grains", base_.size()}};
}

template <class Archive>
void AbrasionTest::transfer(Archive& a) {
  a.label("abrasion test");
  a.value(p_);
  a.value(axis_);
  a.value(plate_);
  a.vector(base_);
  a.vector(grit_);
  a.value(grit_contact_stiffness_);
  a.value(servo_integral_);
  a.value(length_);
  a.value(width_);
  a.value(area_);
  a.value(thickness_);
  a.value(bottom0_);
  a.value(x0_);
  a.value(t0_);
  a.value(ramp_);
  a.value(k_min_);
  a.value(consolidated_);
  a.value(density_scaling_);
  a.value(unbonded0_);
  a.value(pieces0_);
  a.vector(mu_);
  a.vector(slid_);
  a.string(stop_reason_);
}

void AbrasionTest::save_state(ArchiveWriter& a) const {
  const_cast<AbrasionTest*>(this)->transfer(a);  // the writer only reads the fields
}

std::unique_ptr<AbrasionTest> AbrasionTest::restore(ArchiveReader& a) {
  std::unique_ptr<AbrasionTest> t(new AbrasionTest());
  t->transfer(a);
  return t;
}

void AbrasionTest::check_restored(const Simulation& sim, const std::string& where) const {
  const std::size_t n = sim.particles().size();
  bool ok = grit_.empty() ? plate_ < sim.walls().size() : !p_.flat_plate;
  for (std::uint32_t i : base_) ok = ok && i < n;
  for (std::uint32_t i : grit_) ok = ok && i < n;
  if (!ok)
    throw InputError(
        where, "abrasion test", "wall or particle index",
        "refers to a wall or particle the simulation lacks: the checkpoint is corrupt");
}

}  // namespace breccia
