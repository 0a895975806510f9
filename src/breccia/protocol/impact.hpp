#pragma once
// The impact resistance test of seed 001: a rigid ball (default 3 mm across, 11,000 kg/m^3, near
// lead) starts a standoff above the slab's top face and flies at it along -z (2D: -y) at a given
// speed; the slab lies on a rigid floor (or is free). The ball is a free rigid wall
// (boundary/wall.hpp): the contact law's wall parameters act between it and the grains (Hertz on
// the two radii), it feels gravity and minus its contact force, and it does not spin. The test
// runs for a given time, by default the flight plus ten bar-wave transits across the slab.
//
// Rows: strain = indentation of the ball's lowest point below the slab's initial top face over the
// slab's thickness (negative while in flight); stress = the ball's contact force over its
// cross-section (3D: pi R^2; 2D: 2 R t); force_top = the ball's contact force, force_bottom =
// the floor's, both compression-positive. The summary gives the ball's momentum and energy in and
// out, the work it did on the slab (which closes its energy balance), the deepest indentation,
// the contact time, the cracks and how far from the impact axis they reach; fragments and their
// mass classes come with every run (summary "fragments", fragments.csv).
#include <array>
#include <memory>
#include <string>

#include "breccia/law/param_table.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

class ImpactTest final : public Protocol {
 public:
  static constexpr std::string_view name = "impact";
  static constexpr std::string_view summary =
      "impact resistance (seed 001): a rigid ball (default 3 mm, 11,000 kg/m^3, 100 m/s, from "
      "5 mm above) hits the top face of a slab lying on a rigid floor; cracks, fragments and "
      "their mass classes, indentation, and the ball's energy and momentum in and out.";
  struct Params {
    double projectile_diameter = 3e-3, projectile_density = 11000.0, impact_speed = 100.0;
    double standoff = 5e-3, duration = 0.0;
    bool floor = true;
    std::uint8_t unused[7]{};  // named, not padding (core/archive.hpp)
  };
  static constexpr std::array<ParamField<Params>, 6> fields() {
    return {{
        {"projectile_diameter", "m", &Params::projectile_diameter, 0, kInf, false, true,
         "diameter of the rigid ball"},
        {"projectile_density", "kg/m^3", &Params::projectile_density, 0, kInf, false, true,
         "density of the ball (seed 001: 11,000, close to lead); 2D: a disk of the run's "
         "thickness, or a sphere with planar spheres"},
        {"impact_speed", "m/s", &Params::impact_speed, 0, kInf, false, true,
         "the ball's speed toward the slab at the start"},
        {"standoff", "m", &Params::standoff, 0, kInf, true, true,
         "gap between the ball's lowest point and the slab's top face at the start"},
        {"duration", "s", &Params::duration, 0, kInf, true, true,
         "simulated time of the test; 0 = the flight over the standoff plus ten bar-wave "
         "transits across the slab's largest extent"},
        {"floor", "-", &Params::floor, 0, 0, true, true,
         "the slab lies on a rigid floor (false: a free slab)"},
    }};
  }
  // Refuses density scaling (an impact measures inertia) and shapes other than a slab or prism.
  static void check(const Params& p, const SampleInfo& s, const std::string& where);
  static std::unique_ptr<Protocol> create(Simulation& sim, const Params& p, const SampleInfo& s);
  static std::unique_ptr<ImpactTest> restore(ArchiveReader& a);
  // The duration (the automatic one from the sample's length), the ball's speed.
  static TestBudget budget(const Params& p, double length, double bar_wave_speed);

  ImpactTest(Simulation& sim, const Params& p);

  const char* kind() const noexcept override { return "impact"; }
  std::string label() const override { return "impact resistance (rigid ball)"; }
  std::uint64_t start(Simulation& sim, double bar_wave_speed) override;
  void control(Simulation& sim) override;
  AxialState measure(const Simulation& sim) const override;
  // The ball and the floor are walls.
  GrainReads grains_read_by_measure() const override { return {}; }
  bool finished(const AxialState& s, std::size_t broken_bonds) override;
  const std::string& stop_reason() const noexcept override { return stop_reason_; }

  TestFrame frame() const noexcept override {
    return {axis_, top0_ - thickness_, thickness_, width_[0] * width_[1], width_[0], width_[1]};
  }

  double progress(const AxialState&, const Simulation& sim) const override;
  // At least 1,000 rows over the test.
  double row_time() const noexcept override { return 1e-3 * duration_; }
  std::vector<std::string> history_columns() const override;
  void history_values(const Simulation& sim, std::vector<double>& out) const override;
  void summarise(const Simulation& sim, nlohmann::json& out) const override;

  void save_state(ArchiveWriter& a) const override;
  void check_restored(const Simulation& sim, const std::string& where) const override;

  std::size_t projectile() const noexcept { return ball_; }
  double projectile_mass() const noexcept { return mass_; }
  double duration() const noexcept { return duration_; }

 private:
  ImpactTest() = default;
  template <class Archive>
  void transfer(Archive& a);
  double contact_force(const Simulation& sim) const;  // on the ball, along +axis
  double ball_kinetic(const Simulation& sim) const;
  double indentation(const Simulation& sim) const;  // lowest point below the initial top face

  Params p_;
  int axis_ = 2;
  std::size_t ball_ = 0, floor_ = 0;
  bool has_floor_ = false;
  double mass_ = 0.0, radius_ = 0.0, thickness_ = 0.0, top0_ = 0.0, t0_ = 0.0, duration_ = 0.0;
  double width_[2] = {0.0, 0.0};
  Vec3 impact_point_;  // where the ball's path meets the initial top face
  // Tracked every step: the deepest indentation and the time in contact.
  double max_indentation_ = 0.0, contact_time_ = 0.0, first_contact_ = -1.0, elapsed_ = 0.0;
  std::string stop_reason_;
};

}  // namespace breccia
