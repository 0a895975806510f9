#pragma once
// Compression between two rigid platens (docs/physics.md §6.1): unconfined (UCS), or confined at a
// constant confining stress: triaxial in 3D by servo-controlled lateral walls (§6.2; four plane
// walls around a prism, or a cylindrical wall around a cylinder) and biaxial in 2D by flexible
// membranes on the outermost grain chains (§6.3, protocol/membrane.hpp) or two servo walls.
// Stages: consolidation (platens and lateral walls servo to sigma_3 until steady), then axial
// loading at a prescribed platen speed reached through a cosine ramp, stopping at a maximum strain
// or once the stress has fallen to a fraction of the peak. Axis: z in 3D, y in 2D.
// Stresses and strains follow docs/analysis.md §1.1, referred to the start of axial loading.
#include <array>
#include <cstddef>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "breccia/boundary/servo.hpp"
#include "breccia/core/error.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/law/param_table.hpp"
#include "breccia/protocol/adaptive_platens.hpp"
#include "breccia/protocol/membrane.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

// Prism: plane walls (2 in 2D, 4 in 3D); Cylinder: a cylindrical wall; Membrane (2D only): the
// follower load of Membrane2D on each side's outermost grain chain; CylinderMembrane (3D
// cylinders): MembraneCylinder's pressure on the outermost grains all round.
enum class LateralBoundary { Prism, Cylinder, Membrane, CylinderMembrane };

struct PlatenCompressionSettings {
  double platen_speed = 0.05;  // m/s, each platen
  double ramp_time = 0.0;      // s; 0 = automatic (10 bar-wave transits, at least 1000 steps)
  // > platen_speed: each platen's speed from the start of axial loading until the broken bonds
  // reach slow_down_broken_fraction of those intact then (0: the first crack); the platens then
  // slow to platen_speed through a cosine ramp of the same duration as the first.
  double elastic_speed = 0.0;              // m/s; 0 = platen_speed throughout
  double slow_down_broken_fraction = 0.0;  // of the intact bonds when axial loading starts
  // > 1: adaptive loading (boundary/adaptive_loading.hpp) between platen_speed and this many
  // times it, with the crack-rate budget and kinetic-energy target below.
  double adaptive_speed_ratio = 1.0;
  double adaptive_crack_rate = 2e-4;
  double adaptive_kinetic_ratio = 2.5e-4;
  double max_strain = 0.02;
  double stop_fraction = 0.5;  // stop after the peak once stress < stop_fraction x peak
  double platen_friction = 0.0;
  double confining_stress = 0.0;          // Pa; > 0: confined by lateral servo walls
  double servo_relaxation = 0.5;          // alpha_s of §6.2
  double consolidation_tolerance = 0.01;  // relative; lateral stress error for "consolidated"
  std::uint64_t max_consolidation_steps = 200000;
};

class PlatenCompression final : public Protocol, public StressStrainTest {
 public:
  // Adds the platens (and lateral walls when confined) around the sample's extremes. Call before
  // Simulation::initialise(). `kind` is the registry name it runs as.
  PlatenCompression(Simulation& sim, PlatenCompressionSettings settings,
                    LateralBoundary lateral = LateralBoundary::Prism, const char* kind = "ucs");
  // Consolidates to the confining stress (if any), then sets the platen ramp. Call after
  // Simulation::initialise(). Returns the consolidation steps taken.
  std::uint64_t start(Simulation& sim, double bar_wave_speed) override;
  // Servo update of the lateral walls; call before every step during loading.
  void control(Simulation& sim) override;
  // Every grain on the steps where adaptive loading reads the kinetic energy, else none.
  GrainReads grains_read_by_control(const Simulation& sim) const override;

  AxialState measure(const Simulation& sim) const override;
  // The gauges' layers and the lateral faces' grains, or a membrane's chains (a membrane finds
  // them in control, and brings its chains' grains from their owners there).
  GrainReads grains_read_by_measure() const override;
  // Updates the peak tracking; true when the test should stop. The post-peak rule applies only
  // once bonds have started to break during axial loading, so that ramp-up oscillations cannot
  // end a test.
  bool finished(const AxialState& s, std::size_t broken_bonds) override;
  const std::string& stop_reason() const noexcept override { return stop_reason_; }

  const char* kind() const noexcept override;
  std::string label() const override;
  double paced_steps(const Simulation& sim) const override {
    return adaptive_.on() ? paced_steps_ : static_cast<double>(sim.step_count());
  }
  double progress(const AxialState& s, const Simulation&) const override {
    return s.strain / st_.max_strain;
  }
  TestFrame frame() const noexcept override { return {axis_, z0_, h0_, area0_, w0_[0], w0_[1]}; }
  const StressStrainTest* stress_strain() const noexcept override { return this; }

  bool confined() const noexcept { return st_.confining_stress > 0.0; }
  double confining_stress() const noexcept override { return st_.confining_stress; }
  bool consolidated() const noexcept override { return consolidated_; }
  double max_strain() const noexcept override { return st_.max_strain; }
  double platen_speed() const noexcept override { return st_.platen_speed; }
  std::string lateral_boundary() const override;
  // Translational kinetic energy relative to the velocity field of a homogeneous compression
  // (the axial velocity interpolated linearly between the platens), plus all rotational energy.
  double fluctuating_kinetic_energy(const Simulation& sim) const override;
  // history.csv gains that energy beside the total (kinetic_j), for the quasi-static check, and
  // the platens' speed (each; it varies under two-speed and adaptive loading).
  std::vector<std::string> history_columns() const override {
    return {"kinetic_fluctuating_j", "platen_speed_m_per_s"};
  }
  void history_values(const Simulation& sim, std::vector<double>& out) const override;
  // The elastic-phase speed and where the platens began to slow down, when the test used one.
  void summarise_curve(const analysis::CompressionResult&, nlohmann::json& out) const override;
  bool slowed_down() const noexcept { return slowed_; }
  double slow_down_strain() const noexcept { return slow_down_strain_; }
  double height0() const noexcept { return h0_; }
  double area() const noexcept { return area0_; }
  double peak_stress() const noexcept { return peak_; }
  LateralBoundary lateral() const noexcept { return lateral_; }
  const PlatenCompressionSettings& settings() const noexcept { return st_; }

  // Checkpoints: the protocol's state (its walls live in the simulation's state).
  void save_state(ArchiveWriter& a) const override;
  static std::unique_ptr<PlatenCompression> restore(ArchiveReader& a);
  // Throws InputError naming `where` unless the restored walls and particles exist in `sim`.
  void check_restored(const Simulation& sim, const std::string& where) const override;

 private:
  PlatenCompression() = default;
  template <class Archive>
  void transfer(Archive& a);
  double height(const Simulation& sim) const;
  // Current lateral extents (x, y widths; cylinder: diameter twice) from walls or particles.
  void widths(const Simulation& sim, double w[2]) const;
  // The lateral extents spanned by the outer surfaces of the grains in `faces` (as face_).
  void particle_widths(const Simulation& sim, const std::vector<std::uint32_t> (&faces)[4],
                       double w[2]) const;
  // The grains within one largest radius of each lateral face (cylinder: of the shell) whose
  // centres lie in [z_from, z_to] along the axis.
  void find_face_grains(const Simulation& sim, double z_from, double z_to,
                        std::vector<std::uint32_t> (&faces)[4]) const;
  double current_area(const Simulation& sim) const;
  // The gauges of the loading stage (see AxialState): chosen from the grains as they stand when
  // axial loading starts.
  void place_gauges(const Simulation& sim);
  double gauge_length(const Simulation& sim) const;
  void drive_lateral(Simulation& sim);
  // Two-speed loading: ramps the platens from elastic_speed down to platen_speed.
  void slow_down(Simulation& sim);
  // Adaptive loading: at a check, the controller's new speed, reached through a cosine over the
  // check's interval.
  void adapt_speed(Simulation& sim);
  double lateral_stress(const Simulation& sim) const;

  PlatenCompressionSettings st_;
  std::string kind_ = "ucs";
  LateralBoundary lateral_ = LateralBoundary::Prism;
  int axis_ = 2;
  bool planar_ = false;
  double thickness_ = 1.0;
  std::size_t bottom_ = 0, top_ = 0;
  std::vector<std::size_t> side_;  // lateral walls: x0, x1, y0, y1 (prism) or the cylinder
  Vec3 centre_;                    // cylinder axis foot (x, y)
  // Unconfined: boundary particles that measure the lateral strain (docs/analysis.md §1.1).
  std::vector<std::uint32_t> face_[4];  // x-, x+, y-, y+ (prism) or face_[0] = outer shell
  double h0_ = 0.0, area0_ = 0.0, w0_[2] = {0.0, 0.0}, z0_ = 0.0;
  // Gauges: the grain layers centred at 1/4 and 3/4 of the height (one largest radius either
  // side), and the lateral-face grains of the middle half (as face_), with their initial spans.
  std::vector<std::uint32_t> gauge_layer_[2];
  std::vector<std::uint32_t> waist_[4];
  mutable std::vector<std::uint32_t> measured_;  // the grains above, ascending (made when asked)
  mutable std::vector<std::uint32_t> measured_now_;  // with the membrane's chains of the step
  double gauge_length0_ = 0.0, waist0_[2] = {0.0, 0.0};
  double peak_ = 0.0, k_min_ = 0.0;
  std::size_t broken_at_start_ = 0;  // cracks when axial loading began
  double arm_strain_ = 0.0;          // axial strain when the platens reach full speed
  // Two-speed loading: the ramp's duration, the cracks that slow the platens (counted from
  // broken_at_start_), whether they have, and the axial strain where they began to (NaN: not).
  double ramp_ = 0.0;
  std::size_t slow_down_cracks_ = 0;
  bool slowed_ = true;
  double slow_down_strain_ = std::numeric_limits<double>::quiet_NaN();
  AdaptiveLoading adaptive_;
  double paced_steps_ = 0.0;  // adaptive loading: Protocol::paced_steps
  bool consolidated_ = true;
  StressServo servo_;
  // The integral terms of the 2D side walls' servo (StressServo::drive_pi), a velocity each.
  std::array<double, 4> side_integral_{};
  std::string stop_reason_;
  // Recomputed from the particles every step (nothing of it is checkpointed), hence mutable:
  // the const measurements find the chains when a restored run has not stepped yet.
  mutable Membrane2D membrane_;
  mutable MembraneCylinder sleeve_;
  // The cylinder's shell (a wall or a membrane) and the flexible boundaries.
  bool round() const noexcept {
    return lateral_ == LateralBoundary::Cylinder || lateral_ == LateralBoundary::CylinderMembrane;
  }
  bool flexible() const noexcept {
    return lateral_ == LateralBoundary::Membrane || lateral_ == LateralBoundary::CylinderMembrane;
  }
  // The membrane's grains as of its last search.
  const std::vector<std::uint32_t>& membrane_grains() const noexcept {
    return planar_ ? membrane_.chain_grains() : sleeve_.grains();
  }
};

// --- the registered tests that run on PlatenCompression (protocol/registry.hpp) ---

// Fields every compression test shares (platen speed, ramp, stop rules), then `extra`.
template <class P, std::size_t N = 0>
constexpr std::array<ParamField<P>, 9 + N> compression_fields(
    const std::array<ParamField<P>, N>& extra = {}) {
  std::array<ParamField<P>, 9 + N> f{{
      {"platen_speed", "m/s", &P::platen_speed, 0, kInf, false, true,
       "speed of each platen toward the other"},
      {"ramp_time", "s", &P::ramp_time, 0, kInf, true, true,
       "cosine ramp of the platen speed; 0 = 10 bar-wave transit times"},
      {"max_strain", "-", &P::max_strain, 0, 1, false, true, "stop at this axial strain"},
      {"stop_fraction", "-", &P::stop_fraction, 0, 1, true, false,
       "after the peak, stop once the deviatoric stress is below this fraction of it (0: run "
       "to max_strain)"},
      {"elastic_speed", "m/s", &P::elastic_speed, 0, kInf, true, true,
       "speed of each platen until the sample cracks (at least platen_speed; then the platens "
       "slow to platen_speed through a cosine ramp as long as the first); 0 = platen_speed "
       "throughout"},
      {"slow_down_broken_fraction", "-", &P::slow_down_broken_fraction, 0, 1, true, false,
       "with elastic_speed: the platens slow down once this fraction of the bonds has broken "
       "during axial loading (0: at the first broken bond)"},
  }};
  const auto adaptive = adaptive_loading_fields<P>();
  for (std::size_t k = 0; k < 3; ++k) f[6 + k] = adaptive[k];
  for (std::size_t k = 0; k < N; ++k) f[9 + k] = extra[k];
  return f;
}

// sigma_3 and the servo gain of the confined tests. sigma_3 stops at 10 GPa: no triaxial cell
// reaches it (the highest-pressure rock tests run near 1-2 GPa), and the servo's wall speed grows
// with it until the consolidation cannot settle.
template <class P>
constexpr std::array<ParamField<P>, 2> confining_fields(std::string_view walls) {
  return {{{"confining_stress", "Pa", &P::confining_stress, 0, 1e10, false, true, walls},
           {"servo_relaxation", "-", &P::servo_relaxation, 0, 1, false, true,
            "alpha_s of the wall servo (docs/physics.md §6.2)"}}};
}

// What the sweeps vary in a test loaded by two platens: its loading and its confinement. A
// registered test takes part in strain-rate sweeps when its type reads and writes its loading
// (`loading`, `set_loading`), and in confining-stress sweeps when it also says at which sigma_3
// and dimension it is the test to run (`runs_at`); spec/experiment.cpp finds them in the registry.
struct PlatenLoading {
  double platen_speed = 0.0, ramp_time = 0.0, max_strain = 0.0, stop_fraction = 0.0;
  double elastic_speed = 0.0, slow_down_broken_fraction = 0.0;
  double adaptive_speed_ratio = 1.0, adaptive_crack_rate = 2e-4, adaptive_kinetic_ratio = 2.5e-4;
  double confining_stress = 0.0, servo_relaxation = 0.5;
};

// A two-speed loading must not be slower in its elastic phase than toward the peak.
template <class P>
void check_platen_speeds(const P& p, const std::string& where) {
  if (p.elastic_speed > 0.0 && p.elastic_speed < p.platen_speed)
    throw InputError(
        where, "test.elastic_speed", num(p.elastic_speed),
        "allowed: 0 (off) or at least test.platen_speed (" + num(p.platen_speed) + " m/s)");
}

template <class P>
PlatenLoading platen_loading(const P& p) {
  PlatenLoading l{p.platen_speed,         p.ramp_time,           p.max_strain,
                  p.stop_fraction,        p.elastic_speed,       p.slow_down_broken_fraction,
                  p.adaptive_speed_ratio, p.adaptive_crack_rate, p.adaptive_kinetic_ratio};
  if constexpr (requires { p.confining_stress; }) {
    l.confining_stress = p.confining_stress;
    l.servo_relaxation = p.servo_relaxation;
  }
  return l;
}

// The engine's settings for a test's loading (the other settings keep their defaults).
inline PlatenCompressionSettings platen_settings(const PlatenLoading& l) {
  PlatenCompressionSettings s;
  s.platen_speed = l.platen_speed;
  s.ramp_time = l.ramp_time;
  s.max_strain = l.max_strain;
  s.stop_fraction = l.stop_fraction;
  s.elastic_speed = l.elastic_speed;
  s.slow_down_broken_fraction = l.slow_down_broken_fraction;
  // Two-speed loading, when asked for, replaces adaptive loading.
  s.adaptive_speed_ratio = l.elastic_speed > 0.0 ? 1.0 : l.adaptive_speed_ratio;
  s.adaptive_crack_rate = l.adaptive_crack_rate;
  s.adaptive_kinetic_ratio = l.adaptive_kinetic_ratio;
  s.confining_stress = l.confining_stress;
  s.servo_relaxation = l.servo_relaxation;
  return s;
}

template <class P>
void set_platen_loading(P& p, const PlatenLoading& l) {
  p.platen_speed = l.platen_speed;
  p.ramp_time = l.ramp_time;
  p.max_strain = l.max_strain;
  p.stop_fraction = l.stop_fraction;
  p.elastic_speed = l.elastic_speed;
  p.slow_down_broken_fraction = l.slow_down_broken_fraction;
  p.adaptive_speed_ratio = l.adaptive_speed_ratio;
  p.adaptive_crack_rate = l.adaptive_crack_rate;
  p.adaptive_kinetic_ratio = l.adaptive_kinetic_ratio;
  if constexpr (requires { p.confining_stress; }) {
    p.confining_stress = l.confining_stress;
    p.servo_relaxation = l.servo_relaxation;
  }
}

struct UcsTest {
  static constexpr std::string_view name = "ucs";
  static constexpr std::string_view summary =
      "Uniaxial compression between two frictionless rigid platens (docs/physics.md §6.1, "
      "docs/analysis.md "
      "§1), 3D or 2D; the unconfined compressive strength and the ISRM moduli.";
  struct Params {
    double platen_speed = 0.02, ramp_time = 0.0, max_strain = 0.03, stop_fraction = 0.6;
    double elastic_speed = 0.0, slow_down_broken_fraction = 0.0;
    // Adaptive by default: on the default UCS it takes 2.3 times fewer steps for the peak, the
    // modulus and the cracks at the peak within 1.3 % (validation/adaptive-loading).
    double adaptive_speed_ratio = 8.0, adaptive_crack_rate = 2e-4, adaptive_kinetic_ratio = 2.5e-4;
  };
  static constexpr std::array<ParamField<Params>, 9> fields() {
    return compression_fields<Params>();
  }
  static void check(const Params& p, const SampleInfo&, const std::string& where) {
    check_platen_speeds(p, where);
  }
  static PlatenLoading loading(const Params& p) { return platen_loading(p); }
  static void set_loading(Params& p, const PlatenLoading& l) { set_platen_loading(p, l); }
  static bool runs_at(double sigma3, int) { return !(sigma3 > 0.0); }  // unconfined
  static std::unique_ptr<Protocol> create(Simulation& sim, const Params& p, const SampleInfo& s);
  static std::unique_ptr<Protocol> restore(ArchiveReader& a) {
    return PlatenCompression::restore(a);
  }
};

// Confined compression: triaxial in 3D, biaxial in 2D (Dim). The two are one test with the
// lateral boundary of the sample's dimension and shape; they are registered apart so that an
// experiment says which it means and a sample of the other dimension is refused.
template <int Dim>
struct ConfinedCompressionTest {
  static constexpr std::string_view name = Dim == 3 ? "triaxial" : "biaxial";
  static constexpr std::string_view summary =
      Dim == 3 ? "Triaxial compression (3D): the sample is consolidated to sigma_3 with the "
                 "platens and lateral walls servo-controlled (four plane walls around a prism, a "
                 "cylindrical wall around a cylinder; docs/physics.md §6.2), then loaded axially "
                 "while the lateral walls hold sigma_3 (a cylinder with membrane = true: a "
                 "flexible membrane on its outermost grains, §6.3)."
               : "Biaxial compression (2D, seed 002): consolidation to sigma_3 with "
                 "servo-controlled platens, then axial loading at constant platen speed to "
                 "max_strain (10.3 %) while flexible membranes on the outermost grain chains "
                 "hold sigma_3 on the sides (docs/physics.md §6.3; membrane = false: "
                 "servo-controlled side walls, §6.2).";
  // The biaxial test is seed 002's: loaded to 10.3 % axial strain whatever the peak, so that the
  // post-peak stages, the shear band and the energy partition are all recorded.
  struct Params {
    double platen_speed = 0.02, ramp_time = 0.0;
    double max_strain = Dim == 2 ? 0.103 : 0.03, stop_fraction = Dim == 2 ? 0.0 : 0.6;
    double elastic_speed = 0.0, slow_down_broken_fraction = 0.0;
    double adaptive_speed_ratio = 1.0, adaptive_crack_rate = 2e-4, adaptive_kinetic_ratio = 2.5e-4;
    double confining_stress = 5e6, servo_relaxation = 0.5;
    bool membrane = Dim == 2;  // flexible membranes (true) or servo walls
  };
  static constexpr auto fields() {
    const auto c = confining_fields<Params>(
        Dim == 3 ? "sigma_3 held by the lateral walls (or the membrane with membrane = true)"
                 : "sigma_3 held by the membranes (or the side walls with membrane = false)");
    return compression_fields<Params, 3>(std::array<ParamField<Params>, 3>{
        c[0], c[1],
        ParamField<Params>{
            "membrane", "-", &Params::membrane, 0, 0, true, true,
            Dim == 3 ? "a cylinder only: a flexible membrane (docs/physics.md §6.3), sigma_3 "
                       "acting as a pressure on a surface through the outermost grains all "
                       "round, found again every step, so the sample can bulge and a shear band "
                       "break through; false: the cylindrical servo wall (§6.2)"
                     : "flexible membranes (docs/physics.md §6.3): sigma_3 acts as a follower "
                       "load per unit length on the outermost grain chain of each side, found "
                       "again every step; false: rigid side walls servo-controlled to sigma_3 "
                       "(servo_relaxation)"}});
  }
  static void check(const Params& p, const SampleInfo& s, const std::string& where) {
    check_platen_speeds(p, where);
    if (s.dimension != Dim)
      throw InputError(where, "test.kind", "\"" + std::string(name) + "\"",
                       Dim == 3 ? "a triaxial test needs a 3D sample; 2D samples take \"biaxial\""
                                : "a biaxial test needs a 2D sample; 3D samples take \"triaxial\"");
    if (Dim == 3 && p.membrane && s.shape != "cylinder")
      throw InputError(where, "test.membrane", "true",
                       "a 3D membrane wraps a cylinder (sample.shape = \"cylinder\"); a " +
                           s.shape + " takes servo walls: membrane = false");
  }
  static PlatenLoading loading(const Params& p) { return platen_loading(p); }
  static void set_loading(Params& p, const PlatenLoading& l) { set_platen_loading(p, l); }
  static bool runs_at(double sigma3, int dimension) { return sigma3 > 0.0 && dimension == Dim; }
  static std::unique_ptr<Protocol> create(Simulation& sim, const Params& p, const SampleInfo& s) {
    return std::make_unique<PlatenCompression>(sim, platen_settings(platen_loading(p)),
                                               lateral_of(p, s), name.data());
  }
  static std::unique_ptr<Protocol> restore(ArchiveReader& a) {
    return PlatenCompression::restore(a);
  }

 private:
  static LateralBoundary lateral_of(const Params& p, const SampleInfo& s) {
    if (Dim == 2) return p.membrane ? LateralBoundary::Membrane : LateralBoundary::Prism;
    if (s.shape != "cylinder") return LateralBoundary::Prism;
    return p.membrane ? LateralBoundary::CylinderMembrane : LateralBoundary::Cylinder;
  }
};

using TriaxialTest = ConfinedCompressionTest<3>;
using BiaxialTest = ConfinedCompressionTest<2>;

}  // namespace breccia
