#pragma once
// The Brazilian test (indirect tensile strength; ISRM suggested method, 1978): a disc loaded
// across a diameter between two rigid platens until it splits. With the peak platen force F, the
// disc diameter D and thickness t, the tensile strength is sigma_t = 2 F / (pi D t), the tensile
// stress at the centre of an elastic disc under two opposite line loads (Hertz 1883; Hondros
// 1959). 3D: a cylinder with its axis along z (the disc's thickness), loaded along y; 2D: a disk
// in the x-y plane of thickness t, loaded along y. The platens approach at a constant speed
// reached through the cosine ramp of docs/physics.md §6.1, or adaptively (§6.1).
//
// Rows: strain = platen approach / D, stress = 2 F / (pi D t) with F the mean platen force,
// lateral strain from the grains at the x extremes (the disc's horizontal diameter).
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "breccia/law/param_table.hpp"
#include "breccia/protocol/adaptive_platens.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

class BrazilianTest final : public Protocol, public StressStrainTest {
 public:
  static constexpr std::string_view name = "brazilian";
  static constexpr std::string_view summary =
      "Brazilian test (indirect tensile strength, ISRM): a disc (3D: a cylinder of thickness "
      "about half its diameter, axis along z; 2D: a disk) loaded across its diameter along y "
      "between two rigid platens; sigma_t = 2 F / (pi D t) at the peak force F.";
  struct Params {
    double platen_speed = 0.02, ramp_time = 0.0, max_strain = 0.05, stop_fraction = 0.6;
    double adaptive_speed_ratio = 1.0, adaptive_crack_rate = 2e-4, adaptive_kinetic_ratio = 2.5e-4;
  };
  static constexpr std::array<ParamField<Params>, 7> fields() {
    std::array<ParamField<Params>, 7> f{{
        {"platen_speed", "m/s", &Params::platen_speed, 0, kInf, false, true,
         "speed of each platen toward the other"},
        {"ramp_time", "s", &Params::ramp_time, 0, kInf, true, true,
         "cosine ramp of the platen speed; 0 = 10 bar-wave transit times across the disc"},
        {"max_strain", "-", &Params::max_strain, 0, 1, false, true,
         "stop when the platens have approached by this fraction of the diameter"},
        {"stop_fraction", "-", &Params::stop_fraction, 0, 1, true, false,
         "after the peak, stop once the stress is below this fraction of it"},
    }};
    const auto adaptive = adaptive_loading_fields<Params>();
    for (std::size_t k = 0; k < 3; ++k) f[4 + k] = adaptive[k];
    return f;
  }
  // Shapes and proportions a Brazilian disc must have (from the experiment, before packing).
  static void check(const Params& p, const SampleInfo& s, const std::string& where);
  // Also checks the disc actually built (imported samples are only known here).
  static std::unique_ptr<Protocol> create(Simulation& sim, const Params& p, const SampleInfo& s);
  static std::unique_ptr<BrazilianTest> restore(ArchiveReader& a);

  BrazilianTest(Simulation& sim, const Params& p, const SampleInfo& s);

  const char* kind() const noexcept override { return "brazilian"; }
  std::string label() const override { return "Brazilian (indirect tensile)"; }
  std::uint64_t start(Simulation& sim, double bar_wave_speed) override;
  // Adaptive loading's checks (nothing at a constant speed).
  void control(Simulation& sim) override;
  double paced_steps(const Simulation& sim) const override {
    return adaptive_.on() ? paced_steps_ : static_cast<double>(sim.step_count());
  }
  // history.csv gains the platens' speed (each).
  std::vector<std::string> history_columns() const override { return {"platen_speed_m_per_s"}; }
  void history_values(const Simulation& sim, std::vector<double>& out) const override;
  AxialState measure(const Simulation& sim) const override;
  // The grains at the ends of the horizontal diameter.
  GrainReads grains_read_by_measure() const override;
  bool finished(const AxialState& s, std::size_t broken_bonds) override;
  const std::string& stop_reason() const noexcept override { return stop_reason_; }

  double progress(const AxialState& s, const Simulation&) const override {
    return s.strain / p_.max_strain;
  }
  // The area is such that length x area is the disc's volume (pi D^2 t / 4).
  TestFrame frame() const noexcept override {
    return {1, y0_, d0_, 0.25 * 3.141592653589793 * d0_ * t_, d0_, t_};
  }
  const StressStrainTest* stress_strain() const noexcept override { return this; }

  double confining_stress() const noexcept override { return 0.0; }
  bool consolidated() const noexcept override { return true; }
  double max_strain() const noexcept override { return p_.max_strain; }
  double platen_speed() const noexcept override { return p_.platen_speed; }
  std::string lateral_boundary() const override { return "none"; }
  double thickness() const noexcept { return t_; }
  double diameter() const noexcept { return d0_; }
  // The loaded diameter: the line x = centre.x (3D: the plane), along y.
  Vec3 centre() const noexcept { return centre_; }

  // sigma_t = 2 F / (pi D t) at the peak (docs/analysis.md §1.10), and how close the cracks lie
  // to the loaded diameter.
  void summarise_curve(const analysis::CompressionResult& an, nlohmann::json& out) const override;
  void describe_crack_pattern(const Simulation& sim, nlohmann::json& pattern) const override;

  void save_state(ArchiveWriter& a) const override;
  void check_restored(const Simulation& sim, const std::string& where) const override;

 private:
  BrazilianTest() = default;
  template <class Archive>
  void transfer(Archive& a);

  Params p_;
  std::size_t bottom_ = 0, top_ = 0;
  std::vector<std::uint32_t> left_, right_;      // grains at the x extremes (horizontal diameter)
  mutable std::vector<std::uint32_t> measured_;  // both, ascending (made when asked)
  Vec3 centre_;
  double d0_ = 0.0, t_ = 0.0, w0_ = 0.0, y0_ = 0.0, peak_ = 0.0;
  AdaptiveLoading adaptive_;
  double paced_steps_ = 0.0;  // adaptive loading: Protocol::paced_steps
  double cracks_at_start_ = 0.0;
  std::string stop_reason_;
};

}  // namespace breccia
