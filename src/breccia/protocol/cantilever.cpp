#include "breccia/protocol/cantilever.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "breccia/analysis/stress_strain.hpp"
#include "breccia/boundary/wall.hpp"
#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia {

void CantileverTest::check(const Params& p, const SampleInfo& s, const std::string& where) {
  if (!s.shape.empty() && s.shape != "slab" && s.shape != "prism" && s.shape != "rectangle")
    throw InputError(where, "sample.shape", "\"" + s.shape + "\"",
                     "a cantilever test clamps and bends a \"slab\" (or a \"prism\"; 2D: a "
                     "\"rectangle\") along x");
  if (!(p.max_deflection > 0.0))
    throw InputError(where, "test.max_deflection", num(p.max_deflection), "must be > 0 m");
}

TestBudget CantileverTest::budget(const Params& p, double length, double bar_wave_speed) {
  TestBudget b;
  // The slab's length along x is not known here: ten times its thickness stands in for it.
  const double ramp = p.ramp_time > 0.0 ? p.ramp_time : 10.0 * 10.0 * length / bar_wave_speed;
  b.time = ramp + p.max_deflection / p.pusher_speed;
  b.speed = p.pusher_speed;
  b.max_strain = 1.0;
  b.what = fmt::format("ramp {} s + max_deflection {} m / pusher_speed {} m/s", num(ramp),
                       num(p.max_deflection), num(p.pusher_speed));
  b.keys = "test.pusher_speed / test.max_deflection / test.ramp_time";
  b.speed_key = "test.pusher_speed";
  b.remedy = "raise the pusher speed or lower the deflection";
  return b;
}

std::unique_ptr<Protocol> CantileverTest::create(Simulation& sim, const Params& p,
                                                 const SampleInfo&) {
  return std::make_unique<CantileverTest>(sim, p);
}

CantileverTest::CantileverTest(Simulation& sim, const Params& p) : p_(p) {
  ParticleStore& ps = sim.particles_mut();
  axis_ = ps.planar() ? 1 : 2;
  const auto [lo, hi, r_max] = sample_bounds(ps);
  x_lo_ = lo.x;
  length_ = hi.x - lo.x;
  root_ = lo.x + p.clamp_length;
  const double load_x = hi.x - p.load_distance;
  free_length_ = load_x - root_;
  thickness_ = hi[axis_] - lo[axis_];
  bottom0_ = lo[axis_];
  width_ = ps.planar() ? ps.thickness() : hi.y - lo.y;
  if (!(free_length_ > 0.0))
    throw InputError(
        "cantilever test", "test.clamp_length / test.load_distance",
        num(p.clamp_length) + " m / " + num(p.load_distance) + " m",
        "the slab is " + num(length_) + " m long: the rod must push beyond the vice's edge");
  // The vice holds the grains whose centres lie in the clamped length.
  for (std::uint32_t i = 0; i < ps.size(); ++i)
    if (ps.pos_rad[i].x.x <= root_) {
      ps.set_motion(i, Motion::Fixed);
      vice_.push_back(i);
    }
  if (vice_.empty())
    throw InputError("cantilever test", "test.clamp_length", num(p.clamp_length),
                     "the vice holds no grain: lengthen it");
  // The rod lies across the width (along y; 2D: a circle), touching the top face.
  Vec3 axis_point = (lo + hi) * 0.5, along{0, 1, 0};
  axis_point.x = load_x;
  axis_point[axis_] = hi[axis_] + p.nose_radius;
  if (ps.planar()) {
    axis_point.z = 0.0;
    along = {0, 0, 1};
  }
  rod_ = sim.add_wall(Wall::rod("loading_rod", axis_point, along, p.nose_radius));
}

std::uint64_t CantileverTest::start(Simulation& sim, double bar_wave_speed) {
  t0_ = sim.time();
  ramp_ = p_.ramp_time > 0.0 ? p_.ramp_time
                             : std::max(10.0 * length_ / bar_wave_speed, 1000.0 * sim.time_step());
  Wall& w = sim.walls()[rod_];
  rod0_ = w.point[axis_];
  w.target_velocity = {};
  w.target_velocity[axis_] = -p_.pusher_speed;
  w.ramp = {t0_, ramp_};
  w.update_motion(sim.time());
  return 0;
}

void CantileverTest::control(Simulation&) {}

double CantileverTest::rod_force(const Simulation& sim) const {
  return -sim.walls()[rod_].force[axis_];  // pushes the grains down: positive
}

double CantileverTest::vice_force(const Simulation& sim) const {
  double f = 0.0;
  for (std::uint32_t i : vice_) f -= sim.particles().force[i][axis_];
  return f;  // the beam's net load on the vice, down: positive
}

double CantileverTest::deflection(const Simulation& sim) const {
  return rod0_ - sim.walls()[rod_].point[axis_];
}

AxialState CantileverTest::measure(const Simulation& sim) const {
  AxialState s;
  s.strain = deflection(sim) / free_length_;
  s.force_top = rod_force(sim);
  s.force_bottom = vice_force(sim);
  s.stress = 6.0 * s.force_top * free_length_ / (width_ * thickness_ * thickness_);
  s.stress_nominal = s.stress;
  s.deviatoric = s.stress;
  return s;
}

bool CantileverTest::finished(const AxialState& s, std::size_t broken_bonds) {
  force_.push_back(s.force_top);
  vice_load_.push_back(s.force_bottom);
  deflection_.push_back(s.strain * free_length_);
  peak_ = std::max(peak_, s.force_top);
  if (s.strain * free_length_ >= p_.max_deflection) {
    stop_reason_ =
        fmt::format("the rod travelled the maximum deflection, {:.4g} m", p_.max_deflection);
    return true;
  }
  if (broken_bonds > 0 && peak_ > 0.0 && s.force_top < p_.stop_fraction * peak_) {
    stop_reason_ = "the force fell below " + num(p_.stop_fraction) + " of its peak";
    return true;
  }
  return false;
}

std::vector<std::string> CantileverTest::history_columns() const {
  return {"rod_travel_m", "rod_force_n", "vice_force_n"};
}

void CantileverTest::history_values(const Simulation& sim, std::vector<double>& out) const {
  out = {deflection(sim), rod_force(sim), vice_force(sim)};
}

namespace {

// Crack midpoints' distances from the root (the vice's edge), along x over the free span.
std::vector<double> crack_distances(const CrackCatalogue& cracks, double root) {
  std::vector<double> d;
  for (const CrackRecord& c : cracks) d.push_back(c.position.x - root);
  return d;
}

}  // namespace

CantileverTest::Curve CantileverTest::read_curve() const {
  Curve c;
  for (std::size_t k = 0; k < force_.size(); ++k)
    if (force_[k] > force_[c.peak]) c.peak = k;
  c.f_max = force_.empty() ? 0.0 : force_[c.peak];
  c.travel_at_max = force_.empty() ? 0.0 : deflection_[c.peak];
  // Initial stiffness: the slope of force on travel over 10-50 % of the peak, before it.
  // Quasi-static: the vice carries what the rod puts on the beam (rows above 10 %, up to it).
  std::vector<double> x, y;
  for (std::size_t k = 0; k <= c.peak && k < force_.size(); ++k) {
    if (force_[k] < 0.1 * c.f_max) continue;
    c.imbalance = std::max(c.imbalance, std::abs(force_[k] - vice_load_[k]) / force_[k]);
    if (force_[k] > 0.5 * c.f_max) continue;
    x.push_back(deflection_[k]);
    y.push_back(force_[k]);
  }
  c.stiffness = analysis::fit_line(x, y, 3);
  return c;
}

void CantileverTest::summarise(const Simulation& sim, nlohmann::json& out) const {
  const Curve curve = read_curve();
  const double f_max = curve.f_max, imbalance = curve.imbalance;
  const analysis::LinearFit& fit = curve.stiffness;
  const std::vector<double> d = crack_distances(sim.cracks(), root_);
  std::size_t near_root = 0, in_vice = 0;
  for (double v : d) {
    near_root += v >= 0.0 && v <= free_length_ / 3.0 ? 1 : 0;
    in_vice += v < 0.0 ? 1 : 0;
  }
  const double n = static_cast<double>(std::max<std::size_t>(d.size(), 1));
  const double strength = 6.0 * f_max * free_length_ / (width_ * thickness_ * thickness_);
  std::vector<std::string> headline{
      fmt::format("largest force {:.4g} N at a rod travel of {:.3g} mm; flexural strength "
                  "6 F L / (b h^2) = {:.3g} MPa",
                  f_max, 1e3 * curve.travel_at_max, 1e-6 * strength),
      fmt::format("slab {:.3g} mm thick, {:.3g} mm wide; {:.3g} mm in the vice, lever {:.3g} "
                  "mm; initial stiffness {}",
                  1e3 * thickness_, 1e3 * width_, 1e3 * p_.clamp_length, 1e3 * free_length_,
                  fit.valid ? fmt::format("{:.4g} N/mm", 1e-3 * fit.slope) : "n/a"),
      fmt::format("{} cracks: {:.0f} % in the third of the lever next to the vice, {:.0f} % "
                  "inside the vice",
                  d.size(), 100.0 * static_cast<double>(near_root) / n,
                  100.0 * static_cast<double>(in_vice) / n)};
  if (imbalance > 0.05)
    headline.push_back(fmt::format(
        "not quasi-static before the peak: the rod's and the vice's forces differ by up to "
        "{:.0f} % (limit 5 %): the slab vibrates; lower test.pusher_speed",
        100.0 * imbalance));
  out = {{"headline", headline},
         {"sweep_metrics",
          {{"max_force_n", f_max},
           {"flexural_strength_pa", strength},
           {"deflection_at_max_m", curve.travel_at_max},
           {"initial_stiffness_n_per_m", fit.valid ? nlohmann::json(fit.slope) : nullptr}}},
         {"max_force_n", f_max},
         {"deflection_at_max_force_m", curve.travel_at_max},
         {"flexural_strength_pa", strength},
         {"flexural_strength_method",
          "bending stress at the root of an elastic cantilever under an end load: 6 F_max L / (b "
          "h^2) with L the lever, b the width, h the thickness"},
         {"initial_stiffness_n_per_m", fit.valid ? nlohmann::json(fit.slope) : nullptr},
         {"initial_stiffness_method",
          "least-squares slope of the rod's force on its travel over 10-50 % of the largest force, "
          "before it; an elastic cantilever has 3 E I / L^3 (I = b h^3 / 12), less the compliance "
          "of the rod's contacts and of shear in a short lever"},
         {"quasi_static",
          {{"ok", imbalance <= 0.05},
           {"max_force_imbalance_before_peak", imbalance},
           {"note",
            "|F_pusher - F_vice| / F_pusher over the rows above 10 % of the largest force, "
            "up to it (limit 0.05, as the platens' of docs/physics.md §6.1)"}}},
         {"lever_m", free_length_},
         {"lever_note", "from the vice's edge to the rod's axis"},
         {"clamp_length_m", p_.clamp_length},
         {"slab_thickness_m", thickness_},
         {"slab_width_m", width_},
         {"cracks_near_root_share", static_cast<double>(near_root) / n},
         {"cracks_in_vice_share", static_cast<double>(in_vice) / n},
         {"crack_location_note",
          "near the root: within a third of the lever from the vice's edge, where the bending "
          "moment is largest"}};
}

template <class Archive>
void CantileverTest::transfer(Archive& a) {
  a.label("cantilever test");
  a.value(p_);
  a.value(axis_);
  a.vector(vice_);
  a.value(rod_);
  a.value(rod0_);
  a.value(x_lo_);
  a.value(root_);
  a.value(length_);
  a.value(free_length_);
  a.value(width_);
  a.value(thickness_);
  a.value(bottom0_);
  a.value(t0_);
  a.value(ramp_);
  a.vector(force_);
  a.vector(deflection_);
  a.vector(vice_load_);
  a.value(peak_);
  a.string(stop_reason_);
}

void CantileverTest::save_state(ArchiveWriter& a) const {
  const_cast<CantileverTest*>(this)->transfer(a);  // the writer only reads the fields
}

std::unique_ptr<CantileverTest> CantileverTest::restore(ArchiveReader& a) {
  std::unique_ptr<CantileverTest> t(new CantileverTest());
  t->transfer(a);
  return t;
}

void CantileverTest::check_restored(const Simulation& sim, const std::string& where) const {
  const std::size_t n = sim.particles().size();
  bool ok = true;
  for (std::uint32_t i : vice_) ok = ok && i < n;
  ok = ok && rod_ < sim.walls().size() && sim.walls()[rod_].shape == WallShape::Rod;
  if (!ok)
    throw InputError(where, "cantilever test", "particle index",
                     "refers to a particle the simulation lacks: the checkpoint is corrupt");
}

}  // namespace breccia
