#pragma once
// The failure resistance test of seed 001: a slab clamped in a vice over part of its length, its
// protruding part pushed down near the free end until it breaks. The vice holds the grains of the
// clamped length fixed (a perfect clamp); the pusher is a rigid rod across the slab's width (a
// loading nose; 2D: a circle) that moves down (-z; 2D: -y) at a constant speed reached through a
// cosine ramp, so the slab's end is loaded along a line and free to turn, as a cantilever's tip
// is. The length runs along x.
//
// Rows: strain = the rod's travel over the lever L (from the vice's edge to the rod's axis);
// stress = the bending stress at the root of an elastic cantilever, 6 F L / (b h^2) for the rod's
// force F, width b (2D: the run's thickness) and slab thickness h; force_top = F; force_bottom =
// the load the beam puts on the vice, both positive when the end is pushed down (in a
// quasi-static test they balance). The summary gives the largest force, the travel and initial
// stiffness (an elastic cantilever has 3 E I / L^3), the flexural strength 6 F_max L / (b h^2),
// and where the cracks lie along the protruding part.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "breccia/analysis/stress_strain.hpp"
#include "breccia/law/param_table.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

class CantileverTest final : public Protocol {
 public:
  static constexpr std::string_view name = "cantilever";
  static constexpr std::string_view summary =
      "failure resistance (seed 001): a slab clamped in a vice over clamp_length (grains held "
      "fixed), its protruding part pushed down near the free end by a rigid rod across its "
      "width until it breaks; force-deflection curve, largest force, flexural strength, crack "
      "pattern.";
  struct Params {
    double clamp_length = 10e-3, load_distance = 1.5e-3, nose_radius = 1e-3;
    double pusher_speed = 0.02, ramp_time = 0.0, max_deflection = 1e-3, stop_fraction = 0.3;
  };
  static constexpr std::array<ParamField<Params>, 7> fields() {
    return {{
        {"clamp_length", "m", &Params::clamp_length, 0, kInf, false, true,
         "length of the slab held in the vice, from its x = min end"},
        {"load_distance", "m", &Params::load_distance, 0, kInf, true, true,
         "distance of the pushing rod's axis from the slab's free end"},
        {"nose_radius", "m", &Params::nose_radius, 0, kInf, false, true,
         "radius of the pushing rod (the loading nose)"},
        {"pusher_speed", "m/s", &Params::pusher_speed, 0, kInf, false, true,
         "speed of the rod, down the slab's thickness"},
        {"ramp_time", "s", &Params::ramp_time, 0, kInf, true, true,
         "cosine ramp of the pusher's speed; 0 = 10 bar-wave transits along the slab"},
        {"max_deflection", "m", &Params::max_deflection, 0, kInf, false, true,
         "stop when the rod has moved this far"},
        {"stop_fraction", "-", &Params::stop_fraction, 0, 1, true, false,
         "after the peak, stop once the force is below this fraction of it (0: run to "
         "max_deflection)"},
    }};
  }
  static void check(const Params& p, const SampleInfo& s, const std::string& where);
  static std::unique_ptr<Protocol> create(Simulation& sim, const Params& p, const SampleInfo& s);
  static std::unique_ptr<CantileverTest> restore(ArchiveReader& a);
  static TestBudget budget(const Params& p, double length, double bar_wave_speed);

  CantileverTest(Simulation& sim, const Params& p);

  const char* kind() const noexcept override { return "cantilever"; }
  std::string label() const override { return "cantilever (failure resistance)"; }
  std::uint64_t start(Simulation& sim, double bar_wave_speed) override;
  void control(Simulation& sim) override;
  AxialState measure(const Simulation& sim) const override;
  // The vice's grains (the rod is a wall).
  GrainReads grains_read_by_measure() const override { return {.all = false, .some = vice_}; }
  bool finished(const AxialState& s, std::size_t broken_bonds) override;
  const std::string& stop_reason() const noexcept override { return stop_reason_; }

  double progress(const AxialState& s, const Simulation&) const override {
    return s.strain * free_length_ / p_.max_deflection;
  }
  TestFrame frame() const noexcept override {
    return {axis_, bottom0_, thickness_, length_ * width_, length_, width_};
  }

  std::vector<std::string> history_columns() const override;
  void history_values(const Simulation& sim, std::vector<double>& out) const override;
  void summarise(const Simulation& sim, nlohmann::json& out) const override;

  void save_state(ArchiveWriter& a) const override;
  void check_restored(const Simulation& sim, const std::string& where) const override;

  double lever() const noexcept { return free_length_; }
  const std::vector<std::uint32_t>& vice() const noexcept { return vice_; }
  std::size_t rod() const noexcept { return rod_; }

 private:
  CantileverTest() = default;
  template <class Archive>
  void transfer(Archive& a);
  // The rod's push on the slab and the beam's load on the vice, along -axis.
  double rod_force(const Simulation& sim) const;
  double vice_force(const Simulation& sim) const;
  double deflection(const Simulation& sim) const;  // the rod's travel, down
  // The force-travel curve of the rows: its peak, initial stiffness and quasi-static check.
  struct Curve {
    std::size_t peak = 0;
    double f_max = 0.0, travel_at_max = 0.0, imbalance = 0.0;
    analysis::LinearFit stiffness;
  };
  Curve read_curve() const;

  Params p_;
  int axis_ = 2;
  std::vector<std::uint32_t> vice_;
  std::size_t rod_ = 0;
  double rod0_ = 0.0;  // the rod's axis along the load axis when loading starts
  // free_length_ is the lever: from the vice's edge (root_) to the rod's axis.
  double x_lo_ = 0.0, root_ = 0.0, length_ = 0.0, free_length_ = 0.0, width_ = 0.0;
  double thickness_ = 0.0, bottom0_ = 0.0, t0_ = 0.0, ramp_ = 0.0;
  // The rows' force and deflection (for the stiffness and the peak).
  std::vector<double> force_, deflection_, vice_load_;
  double peak_ = 0.0;
  std::string stop_reason_;
};

}  // namespace breccia
