#pragma once
// The direct tension test (uniaxial tensile strength; ISRM suggested method, 1978, and PFC's
// tension test of its material-modelling package): the grains whose centres lie within
// grip_length of either end of a prism or cylinder (2D: a rectangle) are held in rigid grips, as
// end caps glued to a core hold it, and the grips pull apart along the axis (3D: z; 2D: y), each
// at a constant speed reached through the cosine ramp of docs/physics.md §6.1. Gripped grains
// neither turn nor move except with their grip; the rest of the sample follows through its bonds.
// With the largest mean grip force F and the sample's cross-section A, the direct tensile
// strength is sigma_t = F / A.
//
// Rows are extension-positive (the sign of the compression tests reversed): strain = the grips'
// separation beyond its start over the free length between them, stress = the mean grip force
// over A (tension), force_bottom and force_top = the force each grip carries (tension),
// lateral_strain = the change of the width at mid-height over the width (negative as the sample
// narrows), volumetric_strain = the dilation. Poisson's ratio is then -lateral / axial, as in
// compression.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "breccia/law/param_table.hpp"
#include "breccia/protocol/adaptive_platens.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

class DirectTensionTest final : public Protocol, public StressStrainTest {
 public:
  static constexpr std::string_view name = "direct_tension";
  static constexpr std::string_view summary =
      "Direct tension test (uniaxial tensile strength, ISRM; PFC's tension test): the grains "
      "within grip_length of each end of a prism or cylinder (2D: a rectangle) are held in "
      "rigid grips that pull apart along the axis; sigma_t = F / A at the peak grip force F.";
  struct Params {
    double platen_speed = 0.02, ramp_time = 0.0, max_strain = 0.01, stop_fraction = 0.5;
    double grip_length = 0.0;
    double adaptive_speed_ratio = 1.0, adaptive_crack_rate = 2e-4, adaptive_kinetic_ratio = 2.5e-4;
  };
  static constexpr std::array<ParamField<Params>, 8> fields() {
    std::array<ParamField<Params>, 8> f{{
        {"platen_speed", "m/s", &Params::platen_speed, 0, kInf, false, true,
         "speed of each grip away from the other"},
        {"ramp_time", "s", &Params::ramp_time, 0, kInf, true, true,
         "cosine ramp of the grip speed; 0 = 10 bar-wave transit times along the sample"},
        {"max_strain", "-", &Params::max_strain, 0, 1, false, true,
         "stop when the grips have separated by this fraction of the free length between them"},
        {"stop_fraction", "-", &Params::stop_fraction, 0, 1, true, false,
         "after the peak, stop once the tension is below this fraction of it"},
        {"grip_length", "m", &Params::grip_length, 0, kInf, true, true,
         "each grip holds the grains whose centres lie this close to its end face; 0 = two "
         "largest grain diameters"},
    }};
    const auto adaptive = adaptive_loading_fields<Params>();
    for (std::size_t k = 0; k < 3; ++k) f[5 + k] = adaptive[k];
    return f;
  }
  // Shapes the test accepts, and grips that leave the middle of the sample free.
  static void check(const Params& p, const SampleInfo& s, const std::string& where);
  static std::unique_ptr<Protocol> create(Simulation& sim, const Params& p, const SampleInfo& s);
  static std::unique_ptr<DirectTensionTest> restore(ArchiveReader& a);

  DirectTensionTest(Simulation& sim, const Params& p, const SampleInfo& s);

  const char* kind() const noexcept override { return "direct_tension"; }
  std::string label() const override { return "direct tension"; }
  std::uint64_t start(Simulation& sim, double bar_wave_speed) override;
  void control(Simulation& sim) override;
  // Every grain on the steps where adaptive loading reads the kinetic energy, else none.
  GrainReads grains_read_by_control(const Simulation& sim) const override;
  double paced_steps(const Simulation& sim) const override {
    return adaptive_.on() ? paced_steps_ : static_cast<double>(sim.step_count());
  }
  // history.csv gains the grips' speed (each).
  std::vector<std::string> history_columns() const override { return {"grip_speed_m_per_s"}; }
  void history_values(const Simulation& sim, std::vector<double>& out) const override;
  AxialState measure(const Simulation& sim) const override;
  // The gripped grains and those at the width's extremes at mid-height.
  GrainReads grains_read_by_measure() const override;
  bool finished(const AxialState& s, std::size_t broken_bonds) override;
  const std::string& stop_reason() const noexcept override { return stop_reason_; }

  double progress(const AxialState& s, const Simulation&) const override {
    return s.strain / p_.max_strain;
  }
  // The whole sample (length x area is its volume); the strain is read on the free length.
  TestFrame frame() const noexcept override {
    return {axis_, origin_, length_, area_, width_, depth_};
  }
  const StressStrainTest* stress_strain() const noexcept override { return this; }

  double confining_stress() const noexcept override { return 0.0; }
  bool consolidated() const noexcept override { return true; }
  double max_strain() const noexcept override { return p_.max_strain; }
  double platen_speed() const noexcept override { return p_.platen_speed; }
  std::string lateral_boundary() const override { return "none"; }
  // The grips' kinetic energy is the loading's; the rest is what the quasi-static check weighs.
  double fluctuating_kinetic_energy(const Simulation& sim) const override;

  double free_length() const noexcept { return free_length_; }
  double area() const noexcept { return area_; }
  std::size_t gripped() const noexcept { return bottom_.size() + top_.size(); }

  // sigma_t = F / A at the peak (docs/analysis.md §1.11), and the grips' geometry.
  void summarise_curve(const analysis::CompressionResult& an, nlohmann::json& out) const override;
  // Where the cracks lie along the free length: a valid test breaks away from the grips.
  void describe_crack_pattern(const Simulation& sim, nlohmann::json& pattern) const override;

  void save_state(ArchiveWriter& a) const override;
  void check_restored(const Simulation& sim, const std::string& where) const override;

 private:
  DirectTensionTest() = default;
  template <class Archive>
  void transfer(Archive& a);
  double grip_tension(const Simulation& sim, const std::vector<std::uint32_t>& grip,
                      double sign) const;
  double mean_position(const Simulation& sim, const std::vector<std::uint32_t>& grip) const;

  Params p_;
  int axis_ = 2, across_ = 0;  // the loading axis, and the one the width is read along
  std::vector<std::uint32_t> bottom_, top_;  // gripped grains, ascending
  std::vector<std::uint32_t> left_, right_;  // grains at the width's extremes, mid-height
  mutable std::vector<std::uint32_t> read_;  // all four, ascending (made when asked)
  double origin_ = 0.0, length_ = 0.0, area_ = 0.0, width_ = 0.0, depth_ = 0.0;
  double grip_ = 0.0, free_length_ = 0.0, separation0_ = 0.0, w0_ = 0.0;
  double t0_ = 0.0, ramp_ = 0.0, peak_ = 0.0;
  // Adaptive loading: the controller, the cosine between its last two speeds, the paced steps
  // and the cracks when loading began.
  AdaptiveLoading adaptive_;
  VelocityRamp change_;
  double paced_steps_ = 0.0, cracks_at_start_ = 0.0;
  // The grips' speed over the floor for the step that starts at `time`.
  double speed_factor(double time, double time_step) const;
  void adapt_speed(Simulation& sim);
  std::string stop_reason_;
};

}  // namespace breccia
