#include "breccia/protocol/abrasion_test.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>

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

// The mass no longer bonded to the slab: every fragment but the largest (which holds the base).
double worn_mass(const Simulation& sim, double density_scaling, std::size_t& pieces) {
  const analysis::FragmentResult f =
      analysis::find_fragments(sim.particles(), sim.intact_bond_pairs(), density_scaling);
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
      ps.motion[i] = Motion::Fixed;
      base_.push_back(i);
    }
  if (base_.empty() || base_.size() == ps.size())
    throw InputError("abrasion test", "test.base_depth", num(depth),
                     "the held base must hold some grains and leave the rest free");
  Vec3 down;
  down[axis_] = -1.0;
  plate_ = sim.add_wall(Wall::plane("abrading_plate", hi, down));
}

void AbrasionTest::drive(Simulation& sim, double sliding_factor) {
  Wall& w = sim.walls()[plate_];
  StressServo servo{p_.normal_stress, p_.servo_relaxation, 10.0 * p_.sliding_speed};
  // Along its normal the servo alone; the sliding adds its own component.
  servo.drive(w, area_, sim.time_step(), k_min_);
  w.velocity.x = p_.sliding_speed * sliding_factor;
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
  unbonded0_ = worn_mass(sim, density_scaling_, pieces);
  pieces0_ = pieces;
  t0_ = sim.time();
  x0_ = sim.walls()[plate_].point.x;
  ramp_ = p_.ramp_time > 0.0 ? p_.ramp_time
                             : std::max(10.0 * length_ / bar_wave_speed, 1000.0 * sim.time_step());
  return sim.step_count() - step0;
}

void AbrasionTest::control(Simulation& sim) {
  const VelocityRamp ramp{t0_, ramp_};
  drive(sim, ramp.factor(sim.time() + 0.5 * sim.time_step()));
}

double AbrasionTest::normal_force(const Simulation& sim) const {
  const Wall& w = sim.walls()[plate_];
  return dot(w.force, w.normal);
}

double AbrasionTest::shear_force(const Simulation& sim) const {
  return sim.walls()[plate_].force.x;
}

double AbrasionTest::slid(const Simulation& sim) const {
  return sim.walls()[plate_].point.x - x0_;
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
  stop_reason_ = fmt::format("the plate slid {:.4g} m", p_.slide_distance);
  return true;
}

std::vector<std::string> AbrasionTest::history_columns() const {
  return {"slid_m", "plate_normal_force_n", "plate_shear_force_n", "bulk_friction"};
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
  const double worn = std::max(0.0, worn_mass(sim, density_scaling_, pieces) - unbonded0_);
  pieces = pieces > pieces0_ ? pieces - pieces0_ : 0;
  double mass = 0.0;
  for (double m : sim.particles().mass) mass += m / density_scaling_;
  const auto num_or_null = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  };
  out = {
      {"headline",
       {fmt::format("plate at {:.3g} MPa normal stress slid {:.3g} mm at {:.3g} m/s: bulk friction "
                    "coefficient {:.3f} +/- {:.3f} over the second half",
                    1e-6 * p_.normal_stress, 1e3 * total, p_.sliding_speed, mean, sd),
        fmt::format("{} cracks; worn off: {:.4g} g in {} pieces ({:.2f} % of the slab's mass)",
                    sim.cracks().size(), 1e3 * worn, pieces,
                    mass > 0.0 ? 100.0 * worn / mass : 0.0)}},
      {"sweep_metrics",
       {{"bulk_friction", num_or_null(mean)}, {"worn_mass_kg", worn}, {"slid_m", total}}},
      {"bulk_friction_mean", num_or_null(mean)},
      {"bulk_friction_sd", num_or_null(sd)},
      {"bulk_friction_method",
       "shear force on the plate over its normal force (seed 001), mean and spread over the rows "
       "of the second half of the distance slid; every row is in history.csv"},
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
  bool ok = plate_ < sim.walls().size();
  for (std::uint32_t i : base_) ok = ok && i < n;
  if (!ok)
    throw InputError(
        where, "abrasion test", "wall or particle index",
        "refers to a wall or particle the simulation lacks: the checkpoint is corrupt");
}

}  // namespace breccia
