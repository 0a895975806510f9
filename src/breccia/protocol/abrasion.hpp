#pragma once
// The abrasion resistance test of seed 001: a slab whose base is held (the grains within
// base_depth of z = min fixed) is pressed on its top face by an abrader with a constant normal
// stress while the abrader slides along x at a constant speed; the bulk friction coefficient is
// the shear force needed to keep it sliding over the normal force (seed 001), and the mass worn
// off is the mass no longer bonded to the slab.
//
// The abrader is a rough particle surface by default: one hexagonal layer of rigid grit grains
// (grit_radius, default the sample's largest grain radius; 2D: a row of disks) carried as one
// body, long enough to cover the top face over the whole slide. The grit touches the slab's
// grains through the grain contact law, with the grains' friction. Riding over the grains makes
// the shear force swing, but on an unworn elastic slab that part does no net work, so the mean
// coefficient is the grains' friction (tests/test_protocols.cpp); broken bonds and worn grains
// rolling under the grit change it. With flat_plate = true it is a smooth plane wall whose
// only roughness is its Coulomb friction, contact.wall_friction: on an unbreakable slab whose
// contacts all slide, the bulk coefficient is then that friction exactly
// (tests/test_protocols.cpp). Either way a servo holds the normal stress (docs/physics.md §6.2):
// first until it settles, then through the sliding, reached through a cosine ramp. The grit
// grains are apparatus, not rock: fragments and wear leave them out (rock_particles()). 2D: the
// slab's top is y = max and the abrader slides along x.
//
// Rows: strain = the distance slid over the slab's length; stress = the shear stress on the top
// face; force_top = the normal force, force_bottom = the shear force. The summary gives the bulk
// friction coefficient over time and its mean over the second half of the sliding, the cracks,
// and the mass worn off.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "breccia/boundary/servo.hpp"
#include "breccia/law/param_table.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

class AbrasionTest final : public Protocol {
 public:
  static constexpr std::string_view name = "abrasion";
  static constexpr std::string_view summary =
      "abrasion resistance (seed 001): a rough abrader (a layer of rigid grit grains, or a flat "
      "plate) pressed on a slab's top face with a constant normal stress slides along it at a "
      "constant speed; the bulk friction coefficient (shear over normal force) over time and "
      "the mass worn off.";
  struct Params {
    double normal_stress = 1e6, sliding_speed = 0.1, slide_distance = 2e-3, ramp_time = 0.0;
    double base_depth = 0.0, servo_relaxation = 0.2, grit_radius = 0.0;
    bool flat_plate = false;
    std::uint8_t unused[7]{};  // named, not padding (core/archive.hpp)
  };
  static constexpr std::array<ParamField<Params>, 8> fields() {
    return {{
        {"normal_stress", "Pa", &Params::normal_stress, 0, 1e10, false, true,
         "normal stress the abrader holds on the top face (normal force over the face's area)"},
        {"sliding_speed", "m/s", &Params::sliding_speed, 0, kInf, false, true,
         "speed of the abrader along x"},
        {"slide_distance", "m", &Params::slide_distance, 0, kInf, false, true,
         "stop once the abrader has slid this far"},
        {"ramp_time", "s", &Params::ramp_time, 0, kInf, true, true,
         "cosine ramp of the sliding speed; 0 = 10 bar-wave transits along the slab"},
        {"base_depth", "m", &Params::base_depth, 0, kInf, true, true,
         "grains whose centres lie this close to the bottom face are held fixed; 0 = one "
         "largest grain diameter"},
        {"servo_relaxation", "-", &Params::servo_relaxation, 0, 1, false, true,
         "alpha_s of the abrader's normal-stress servo (docs/physics.md §6.2)"},
        {"grit_radius", "m", &Params::grit_radius, 0, kInf, true, true,
         "radius of the abrader's grit grains (one hexagonal layer); 0 = the sample's largest "
         "grain radius"},
        {"flat_plate", "-", &Params::flat_plate, 0, 0, true, true,
         "abrade with a smooth plane wall whose roughness is contact.wall_friction instead of "
         "the grit layer"},
    }};
  }
  static void check(const Params& p, const SampleInfo& s, const std::string& where);
  static std::unique_ptr<Protocol> create(Simulation& sim, const Params& p, const SampleInfo& s);
  static std::unique_ptr<AbrasionTest> restore(ArchiveReader& a);
  static TestBudget budget(const Params& p, double length, double bar_wave_speed);

  AbrasionTest(Simulation& sim, const Params& p, double density_scaling);

  const char* kind() const noexcept override { return "abrasion"; }
  std::string label() const override {
    return p_.flat_plate ? "abrasion resistance (sliding plate)"
                         : "abrasion resistance (sliding grit layer)";
  }
  std::uint64_t start(Simulation& sim, double bar_wave_speed) override;
  void control(Simulation& sim) override;
  // The grit layer's servo reads the grit's forces (its grains come last: ascending).
  GrainReads grains_read_by_control(const Simulation&) const override {
    return {.all = false, .some = grit_};
  }
  AxialState measure(const Simulation& sim) const override;
  // The grit layer's grains (a plate is a wall).
  GrainReads grains_read_by_measure() const override { return {.all = false, .some = grit_}; }
  bool finished(const AxialState& s, std::size_t broken_bonds) override;
  const std::string& stop_reason() const noexcept override { return stop_reason_; }

  double progress(const AxialState& s, const Simulation&) const override {
    return s.strain * length_ / p_.slide_distance;
  }
  TestFrame frame() const noexcept override {
    return {axis_, bottom0_, thickness_, area_, length_, width_};
  }

  std::vector<std::string> history_columns() const override;
  void history_values(const Simulation& sim, std::vector<double>& out) const override;
  void summarise(const Simulation& sim, nlohmann::json& out) const override;

  void save_state(ArchiveWriter& a) const override;
  void check_restored(const Simulation& sim, const std::string& where) const override;

  std::size_t rock_particles(const Simulation& sim) const noexcept override {
    return grit_.empty() ? sim.particles().size() : grit_.front();
  }

  // The plane wall of a flat-plate abrader (flat_plate = true), and the grit grains (indices,
  // after the rock's) of a rough one.
  std::size_t plate() const noexcept { return plate_; }
  const std::vector<std::uint32_t>& grit() const noexcept { return grit_; }

 private:
  AbrasionTest() = default;
  template <class Archive>
  void transfer(Archive& a);
  void add_grit(Simulation& sim, const SampleBounds& b);
  double normal_force(const Simulation& sim) const;  // the abrader's push on the slab, down
  double shear_force(const Simulation& sim) const;   // the abrader's drag on the slab, along +x
  double slid(const Simulation& sim) const;
  double position_x(const Simulation& sim) const;  // where the abrader stands along x
  void drive(Simulation& sim, double sliding_factor);

  Params p_;
  int axis_ = 2;
  std::size_t plate_ = 0;
  std::vector<std::uint32_t> base_, grit_;
  // A grit contact's normal stiffness at a deep overlap (1 % of the grain radius), an upper
  // bound the grit's servo divides by: a grit layer has no summed contact stiffness of its own.
  double grit_contact_stiffness_ = 0.0, servo_integral_ = 0.0;
  double length_ = 0.0, width_ = 0.0, area_ = 0.0, thickness_ = 0.0, bottom0_ = 0.0;
  double x0_ = 0.0, t0_ = 0.0, ramp_ = 0.0, k_min_ = 0.0;
  bool consolidated_ = false;
  double density_scaling_ = 1.0;
  double unbonded0_ = 0.0;  // mass without a bond to the slab when the sliding began
  std::size_t pieces0_ = 0;
  // The rows' friction coefficient and distance slid (its mean over the second half).
  std::vector<double> mu_, slid_;
  std::string stop_reason_;
};

}  // namespace breccia
