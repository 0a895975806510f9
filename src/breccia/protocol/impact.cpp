#include "breccia/protocol/impact.hpp"

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

namespace {

// The cross-section the ball's contact force is spread over in the stress column.
double ball_section(double radius, bool planar, double thickness) {
  return planar ? 2.0 * radius * thickness : std::numbers::pi * radius * radius;
}

// The smallest radius around `centre` (in the plane normal to `axis`) that holds `fraction` of
// the crack midpoints; 0 without cracks.
double crack_reach(const CrackCatalogue& cracks, const Vec3& centre, int axis, double fraction) {
  std::vector<double> d;
  d.reserve(cracks.size());
  for (const CrackRecord& c : cracks) {
    Vec3 r = c.position - centre;
    r[axis] = 0.0;
    d.push_back(norm(r));
  }
  if (d.empty()) return 0.0;
  std::sort(d.begin(), d.end());
  const auto k = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(d.size())));
  return d[std::clamp<std::size_t>(k, 1, d.size()) - 1];
}

}  // namespace

void ImpactTest::check(const Params&, const SampleInfo& s, const std::string& where) {
  if (s.density_scaling != 1.0)
    throw InputError(where, "engine.density_scaling", num(s.density_scaling),
                     "an impact test measures inertia, which density scaling changes: set "
                     "engine.density_scaling = 1");
  if (!s.shape.empty() && s.shape != "slab" && s.shape != "prism" && s.shape != "rectangle")
    throw InputError(where, "sample.shape", "\"" + s.shape + "\"",
                     "an impact test hits the top face of a \"slab\" (or a \"prism\"; 2D: a "
                     "\"rectangle\")");
}

TestBudget ImpactTest::budget(const Params& p, double length, double bar_wave_speed) {
  TestBudget b;
  // The slab's largest extent is not known before it is built: its thickness stands in, and the
  // check allows for a slab 10 times wider than thick.
  b.time =
      p.duration > 0.0 ? p.duration : p.standoff / p.impact_speed + 100.0 * length / bar_wave_speed;
  b.speed = p.impact_speed;
  b.max_strain = 1.0;
  b.what = p.duration > 0.0 ? "duration " + num(p.duration) + " s"
                            : "the flight over the standoff and ten bar-wave transits";
  b.keys = "test.duration / test.standoff";
  b.speed_key = "test.impact_speed";
  b.remedy = "shorten the duration or the standoff";
  return b;
}

std::unique_ptr<Protocol> ImpactTest::create(Simulation& sim, const Params& p, const SampleInfo&) {
  return std::make_unique<ImpactTest>(sim, p);
}

ImpactTest::ImpactTest(Simulation& sim, const Params& p) : p_(p) {
  const ParticleStore& ps = sim.particles();
  if (ps.size() == 0)
    throw InputError("impact test", "sample", "(empty)", "the slab has no grains");
  axis_ = ps.planar() ? 1 : 2;
  const auto [lo, hi, r_max] = sample_bounds(ps);
  top0_ = hi[axis_];
  thickness_ = hi[axis_] - lo[axis_];
  width_[0] = hi.x - lo.x;
  width_[1] = ps.planar() ? ps.thickness() : hi.y - lo.y;
  radius_ = 0.5 * p.projectile_diameter;
  mass_ = ps.mass_of(radius_, p.projectile_density);
  Vec3 centre = (lo + hi) * 0.5, down;
  down[axis_] = -1.0;
  if (ps.planar()) centre.z = 0.0;
  impact_point_ = centre;
  impact_point_[axis_] = top0_;
  Vec3 start = impact_point_;
  start[axis_] = top0_ + p.standoff + radius_;
  ball_ = sim.add_wall(Wall::sphere("projectile", start, radius_, mass_, down * p.impact_speed));
  if (p.floor) {
    Vec3 up;
    up[axis_] = 1.0;
    floor_ = sim.add_wall(Wall::plane("floor", lo, up));
    has_floor_ = true;
  }
}

std::uint64_t ImpactTest::start(Simulation& sim, double bar_wave_speed) {
  t0_ = sim.time();
  const double extent = std::max({width_[0], width_[1], thickness_});
  duration_ = p_.duration > 0.0 ? p_.duration
                                : p_.standoff / p_.impact_speed + 10.0 * extent / bar_wave_speed;
  return 0;
}

void ImpactTest::control(Simulation& sim) {
  elapsed_ = sim.time() + sim.time_step() - t0_;  // after the step about to be taken
  const Wall& b = sim.walls()[ball_];
  if (b.contacts > 0) {
    if (first_contact_ < 0.0) first_contact_ = sim.time();
    contact_time_ += sim.time_step();
  }
  max_indentation_ = std::max(max_indentation_, indentation(sim));
}

double ImpactTest::indentation(const Simulation& sim) const {
  return top0_ - (sim.walls()[ball_].point[axis_] - radius_);
}

double ImpactTest::ball_kinetic(const Simulation& sim) const {
  // At the step's time t_n, between the half-step velocities the leapfrog holds: m v- . v+ / 2,
  // the form whose change equals the trapezoidal work of the ball's contacts exactly.
  const Wall& b = sim.walls()[ball_];
  const Vec3 v_before =
      b.velocity - (sim.config().gravity - b.force * (1.0 / mass_)) * sim.time_step();
  return 0.5 * mass_ * dot(v_before, b.velocity);
}

double ImpactTest::contact_force(const Simulation& sim) const {
  return -sim.walls()[ball_].force[axis_];  // the grains push the ball back along +axis
}

AxialState ImpactTest::measure(const Simulation& sim) const {
  AxialState s;
  s.strain = indentation(sim) / thickness_;
  s.force_top = contact_force(sim);
  s.force_bottom = has_floor_ ? sim.walls()[floor_].force[axis_] : 0.0;
  const ParticleStore& ps = sim.particles();
  s.stress = s.force_top / ball_section(radius_, ps.planar(), ps.thickness());
  s.stress_nominal = s.stress;
  s.deviatoric = s.stress;
  return s;
}

double ImpactTest::progress(const AxialState&, const Simulation& sim) const {
  return duration_ > 0.0 ? (sim.time() - t0_) / duration_ : 0.0;
}

bool ImpactTest::finished(const AxialState&, std::size_t) {
  if (!(elapsed_ >= duration_)) return false;
  stop_reason_ = fmt::format("reached the test's duration, {:.4g} s", duration_);
  return true;
}

std::vector<std::string> ImpactTest::history_columns() const {
  return {"projectile_position_m",      "projectile_velocity_m_s", "projectile_kinetic_j",
          "projectile_contact_force_n", "floor_force_n",           "indentation_m"};
}

void ImpactTest::history_values(const Simulation& sim, std::vector<double>& out) const {
  const Wall& b = sim.walls()[ball_];
  const double v = b.velocity[axis_];
  out = {b.point[axis_],
         v,
         ball_kinetic(sim),
         contact_force(sim),
         has_floor_ ? sim.walls()[floor_].force[axis_] : 0.0,
         indentation(sim)};
}

void ImpactTest::summarise(const Simulation& sim, nlohmann::json& out) const {
  const Wall& b = sim.walls()[ball_];
  const double v_in = p_.impact_speed, v_out = b.velocity[axis_];
  const double ke_in = 0.5 * mass_ * v_in * v_in;
  const double ke_out = ball_kinetic(sim);
  const EnergyLedger& L = sim.ledger();
  const auto share = [&](double e) { return ke_in > 0.0 ? e / ke_in : 0.0; };
  const double fracture = share(L.released.total()), friction = share(L.friction);
  const std::vector<std::string> headline{
      fmt::format(
          "ball {:.3g} mm, {:.4g} kg/m^3 at {:.4g} m/s ({:.4g} J), at {:+.4g} m/s in the end "
          "(+ away from the slab); {:.1f} % of its energy went into the slab (balance "
          "residual {:.1e})",
          1e3 * p_.projectile_diameter, p_.projectile_density, v_in, ke_in, v_out,
          100.0 * share(b.work), ke_in > 0.0 ? (ke_in - ke_out - b.work) / ke_in : 0.0),
      fmt::format("contact {:.3g} us; deepest indentation {:.3g} mm into a {:.3g} mm slab; 90 % of "
                  "the cracks within {:.3g} mm of the impact axis",
                  1e6 * contact_time_, 1e3 * max_indentation_, 1e3 * thickness_,
                  1e3 * crack_reach(sim.cracks(), impact_point_, axis_, 0.9)),
      fmt::format("of the impact energy: {:.1f} % released by breaking bonds, {:.1f} % friction, "
                  "{:.1f} % damping, {:.1f} % still kinetic in the slab",
                  100.0 * fracture, 100.0 * friction,
                  100.0 * share(L.local_damping + L.viscous_damping), 100.0 * share(L.kinetic()))};
  out = {
      {"headline", headline},
      {"sweep_metrics",
       {{"max_indentation_m", max_indentation_},
        {"crack_reach_90_m", crack_reach(sim.cracks(), impact_point_, axis_, 0.9)},
        {"projectile_velocity_out_m_s", v_out},
        {"energy_into_slab_fraction", share(b.work)},
        {"released_by_breaks_fraction", fracture}}},
      {"projectile",
       {{"diameter_m", p_.projectile_diameter},
        {"density_kg_m3", p_.projectile_density},
        {"mass_kg", mass_},
        {"speed_in_m_s", v_in},
        {"velocity_out_m_s", v_out},
        {"restitution", v_in > 0.0 ? v_out / v_in : 0.0},
        {"restitution_note",
         "velocity along +axis (away from the slab) at the end over the impact speed; negative: "
         "still moving into the slab"},
        {"momentum_in_kg_m_s", mass_ * v_in},
        {"momentum_out_kg_m_s", mass_ * v_out},
        {"kinetic_energy_in_j", ke_in},
        {"kinetic_energy_out_j", ke_out},
        {"work_on_slab_j", b.work},
        {"energy_balance_residual_relative", ke_in > 0.0 ? (ke_in - ke_out - b.work) / ke_in : 0.0},
        {"note",
         "the ball's lost kinetic energy equals the work its contacts did on the slab; the "
         "residual is the leapfrog's O(dt) at the contact's start and end"}}},
      {"standoff_m", p_.standoff},
      {"slab_thickness_m", thickness_},
      {"floor", has_floor_},
      {"duration_s", duration_},
      {"first_contact_s", first_contact_ >= 0.0 ? nlohmann::json(first_contact_ - t0_) : nullptr},
      {"contact_time_s", contact_time_},
      {"max_indentation_m", max_indentation_},
      {"cracks", sim.cracks().size()},
      {"crack_reach_50_m", crack_reach(sim.cracks(), impact_point_, axis_, 0.5)},
      {"crack_reach_90_m", crack_reach(sim.cracks(), impact_point_, axis_, 0.9)},
      {"crack_reach_method",
       "radius about the impact axis (measured across it) holding 50 % and 90 % of the crack "
       "midpoints"},
      {"energy_shares_of_impact",
       {{"released_by_breaks", fracture},
        {"friction", friction},
        {"local_damping", share(L.local_damping)},
        {"viscous_damping", share(L.viscous_damping)},
        {"slab_kinetic_at_end", share(L.kinetic())},
        {"slab_strain_at_end", share(L.bond.total() + L.contact)},
        {"floor_work", has_floor_ ? share(sim.walls()[floor_].work) : 0.0},
        {"note", "fractions of the ball's kinetic energy at the start"}}}};
}

template <class Archive>
void ImpactTest::transfer(Archive& a) {
  a.label("impact test");
  a.value(p_);
  a.value(axis_);
  a.value(ball_);
  a.value(floor_);
  a.value(has_floor_);
  a.value(mass_);
  a.value(radius_);
  a.value(thickness_);
  a.value(top0_);
  a.value(t0_);
  a.value(duration_);
  a.value(width_[0]);
  a.value(width_[1]);
  a.value(impact_point_);
  a.value(max_indentation_);
  a.value(contact_time_);
  a.value(first_contact_);
  a.value(elapsed_);
  a.string(stop_reason_);
}

void ImpactTest::save_state(ArchiveWriter& a) const {
  const_cast<ImpactTest*>(this)->transfer(a);  // the writer only reads the fields
}

std::unique_ptr<ImpactTest> ImpactTest::restore(ArchiveReader& a) {
  std::unique_ptr<ImpactTest> t(new ImpactTest());
  t->transfer(a);
  return t;
}

void ImpactTest::check_restored(const Simulation& sim, const std::string& where) const {
  const auto& W = sim.walls();
  const bool ok = ball_ < W.size() && W[ball_].shape == WallShape::Sphere && W[ball_].free_body() &&
                  (!has_floor_ || floor_ < W.size());
  if (!ok)
    throw InputError(where, "impact test", "wall index",
                     "refers to a wall the simulation lacks: the checkpoint is corrupt");
}

}  // namespace breccia
