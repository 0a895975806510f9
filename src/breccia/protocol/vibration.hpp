#pragma once
// The vibration resistance test of seed 001: part of a slab is held in a grip on a shaker and
// shaken sinusoidally for a number of cycles (default 8157 Hz, the seed's frequency). The grip is
// one end of the slab (the grains whose centres lie within grip_length of x = min: the rest of the
// slab hangs out of it as a cantilever, whose first bending mode lies near 8 kHz for seed 001's
// 30 mm slabs) or, with grip_length = 0, its bottom face (the grains within grip_depth of z = min;
// 2D: y = min). The gripped grains are driven so that their displacement is exactly
// A r(t) sin(2 pi f t), along the slab's normal (normal = true) or along its length x, where r
// is the cosine ramp from 0 to 1 over ramp_cycles; the rest of the slab follows through its
// bonds and contacts.
//
// Rows: strain = the grip's displacement over the slab's thickness; stress = the force the grip
// exerts on the slab along the shaking direction over the gripped face's area; force_top = that
// force.
// The summary gives the amplitude and frequency the face followed, the cracks per cycle, the
// energy the shaker put in and where it went; fragments and their mass classes come with every
// run.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "breccia/law/param_table.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

class VibrationTest final : public Protocol {
 public:
  static constexpr std::string_view name = "vibration";
  static constexpr std::string_view summary =
      "vibration resistance (seed 001): one end of a slab (or its bottom face) is held in a "
      "grip on a shaker and shaken, A sin(2 pi f t) (default 8157 Hz) along the slab's normal "
      "or its length, for a number of cycles; cracks over time, fragments and their mass "
      "classes.";
  struct Params {
    double frequency = 8157.0, amplitude = 50e-6, cycles = 10.0, grip_length = 10e-3;
    double grip_depth = 0.0, ramp_cycles = 1.0;
    bool normal = true;
    std::uint8_t unused[7]{};  // named, not padding (core/archive.hpp)
  };
  static constexpr std::array<ParamField<Params>, 7> fields() {
    return {{
        {"frequency", "Hz", &Params::frequency, 0, kInf, false, true,
         "shaking frequency f (seed 001: 8157 Hz)"},
        {"amplitude", "m", &Params::amplitude, 0, kInf, false, true,
         "displacement amplitude A of the shaken face"},
        {"cycles", "-", &Params::cycles, 0, 1e6, false, true, "cycles to shake for"},
        {"grip_length", "m", &Params::grip_length, 0, kInf, true, true,
         "the grip holds the slab's end over this length from x = min; 0: the grip holds the "
         "bottom face instead"},
        {"grip_depth", "m", &Params::grip_depth, 0, kInf, true, true,
         "grip_length = 0: grains whose centres lie this close to the bottom face are shaken; 0 "
         "= one largest grain diameter"},
        {"ramp_cycles", "-", &Params::ramp_cycles, 0, 1e6, true, true,
         "the amplitude grows from 0 through a cosine ramp over this many cycles, as a shaker "
         "starts (0: the full sine from the first step, a jump of the grip's speed to A 2 pi f)"},
        {"normal", "-", &Params::normal, 0, 0, true, true,
         "shake along the slab's normal (true) or along its length x (false)"},
    }};
  }
  // Refuses density scaling (a vibration measures inertia) and shapes other than a slab or prism.
  static void check(const Params& p, const SampleInfo& s, const std::string& where);
  static std::unique_ptr<Protocol> create(Simulation& sim, const Params& p, const SampleInfo& s);
  static std::unique_ptr<VibrationTest> restore(ArchiveReader& a);
  static TestBudget budget(const Params& p, double length, double bar_wave_speed);

  VibrationTest(Simulation& sim, const Params& p);

  const char* kind() const noexcept override { return "vibration"; }
  std::string label() const override { return "vibration resistance (shaken face)"; }
  std::uint64_t start(Simulation& sim, double bar_wave_speed) override;
  void control(Simulation& sim) override;
  AxialState measure(const Simulation& sim) const override;
  // The shaken grains.
  GrainReads grains_read_by_measure() const override { return {.all = false, .some = face_}; }
  bool finished(const AxialState& s, std::size_t broken_bonds) override;
  const std::string& stop_reason() const noexcept override { return stop_reason_; }

  TestFrame frame() const noexcept override {
    return {axis_, bottom0_, thickness_, face_area_, length_, width_};
  }

  double progress(const AxialState&, const Simulation& sim) const override;
  // At least 40 rows per cycle.
  double row_time() const noexcept override { return 1.0 / (40.0 * p_.frequency); }
  std::vector<std::string> history_columns() const override;
  void history_values(const Simulation& sim, std::vector<double>& out) const override;
  void summarise(const Simulation& sim, nlohmann::json& out) const override;

  void save_state(ArchiveWriter& a) const override;
  void check_restored(const Simulation& sim, const std::string& where) const override;

  const std::vector<std::uint32_t>& shaken() const noexcept { return face_; }
  bool end_grip() const noexcept { return p_.grip_length > 0.0; }

 private:
  VibrationTest() = default;
  template <class Archive>
  void transfer(Archive& a);
  int direction() const noexcept { return p_.normal ? axis_ : 0; }
  double grip_position(double t) const noexcept;          // A r(t) sin(2 pi f t), t from the start
  double face_displacement(const Simulation& sim) const;  // mean, along the shaking direction
  double face_force(const Simulation& sim) const;         // on the slab, along it

  Params p_;
  int axis_ = 2;
  std::vector<std::uint32_t> face_;
  double thickness_ = 0.0, length_ = 0.0, width_ = 0.0, face_area_ = 0.0, bottom0_ = 0.0;
  double t0_ = 0.0, duration_ = 0.0, elapsed_ = 0.0;
  double max_displacement_ = 0.0;  // largest |face displacement| seen at the rows
  std::string stop_reason_;
};

}  // namespace breccia
