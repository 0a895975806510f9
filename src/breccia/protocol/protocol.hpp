#pragma once
// A lab test, as the run loop sees it: it adds its boundaries to the simulation before
// Simulation::initialise(), prepares the sample after (consolidation), steers its walls before
// every step, measures one row of the test's state, and says when to stop. Each registered test
// (protocol/registry.hpp) is a type with a `Params` table that drives parsing, validation and the
// generated docs, and `create` / `restore` functions that make one of these.
//
// Every test has the small core below. Compression-type tests (UCS, triaxial, biaxial,
// Brazilian) add the StressStrainTest part: their rows are read as stress-strain curves (moduli,
// strengths, quasi-static checks). Slab and dynamic tests (impact, cantilever, ...) do not: they
// add their own history columns and their own block of summary.json, and report their progress
// in their own measure (time, displacement).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <variant>
#include <vector>

#include "breccia/analysis/compression.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

class ArchiveWriter;
class ArchiveReader;

// One row of a test's state. "Axial" is the loading direction: the sample axis of a compression
// test, the loaded diameter of a Brazilian test, the path of a projectile. Compression-positive.
// Each test's header says what its strain and stress are.
struct AxialState {
  double strain = 0.0;                         // platen approach / initial length along the load
  double stress = 0.0;                         // Pa, the test's stress measure (current area)
  double stress_nominal = 0.0;                 // Pa, over the area at the start of loading
  double force_bottom = 0.0, force_top = 0.0;  // N, compression-positive
  double lateral_strain = 0.0;                 // compression-positive (negative = expansion)
  double volumetric_strain = 0.0;
  double confining_stress = 0.0;  // Pa, measured on the lateral walls (0 when unconfined)
  double deviatoric = 0.0;        // q = stress - sigma_3 (target sigma_3)
  // Strain gauges on the sample itself, away from the platens (NaN when the test has none): the
  // axial strain between two grain layers at 1/4 and 3/4 of the length, and the lateral strain
  // of the middle half. They leave out the compliance of the platen contacts, which the platen
  // approach `strain` includes.
  double gauge_strain = std::numeric_limits<double>::quiet_NaN();
  double gauge_lateral_strain = std::numeric_limits<double>::quiet_NaN();
};

// What a test needs to know about the sample it is given.
struct SampleInfo {
  int dimension = 3;
  // "prism", "cylinder", "rectangle", "disk", "slab", or "" (imported, unknown)
  std::string shape;
  double thickness = 1.0;  // 2D disk thickness
  // Generated samples: the requested size (a slab's thickness is its height) and the largest
  // grain radius (0 when not known before the sample is built).
  double diameter = 0.0, height = 0.0, r_max = 0.0;
  // The run's mass scaling (docs/physics.md §1.5): dynamic tests measure inertia and refuse it.
  double density_scaling = 1.0;
};

// The box the grains' surfaces span, and the largest radius: where a test puts its walls.
struct SampleBounds {
  Vec3 lo, hi;
  double r_max = 0.0;
};
inline SampleBounds sample_bounds(const ParticleStore& p) {
  const double inf = std::numeric_limits<double>::infinity();
  SampleBounds b{{inf, inf, inf}, {-inf, -inf, -inf}, 0.0};
  for (const PosRad& q : p.pos_rad) {
    for (int k = 0; k < 3; ++k) {
      b.lo[k] = std::min(b.lo[k], q.x[k] - q.r);
      b.hi[k] = std::max(b.hi[k], q.x[k] + q.r);
    }
    b.r_max = std::max(b.r_max, q.r);
  }
  return b;
}

// The sample's width along `axis` read on two sets of grains at its opposite faces: the mean
// outer surface of `high` (centre plus radius) less the mean outer surface of `low` (centre less
// radius); an empty set counts as 0.
inline double width_between(const ParticleStore& p, const std::vector<std::uint32_t>& low,
                            const std::vector<std::uint32_t>& high, int axis) {
  auto mean = [&](const std::vector<std::uint32_t>& ids, double sign) {
    double v = 0.0;
    for (std::uint32_t i : ids) v += p.pos_rad[i].x[axis] + sign * p.pos_rad[i].r;
    return ids.empty() ? 0.0 : v / static_cast<double>(ids.size());
  };
  return mean(high, 1.0) - mean(low, -1.0);
}

// The smallest stiffness a wall servo divides by (docs/physics.md §6.2): one wall contact of a
// mean-size grain at a small overlap, so that a wall without contacts still moves at a bounded
// speed.
inline double smallest_wall_stiffness(const Simulation& sim) {
  const ParticleStore& p = sim.particles();
  double rsum = 0.0;
  for (const PosRad& q : p.pos_rad) rsum += q.r;
  const double r = rsum / static_cast<double>(p.size());
  double k = 0.0;
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        PairGeometry g =
            pair_geometry({}, r, {0, 0, 2 * r}, r, {}, {}, {}, {}, 1, 1, p.planar(), p.thickness());
        g.wall = true;
        g.delta = 1e-4 * r;
        double ks = 0.0;
        CL::timestep_stiffness(c.wall_params, g, k, ks);
      },
      sim.contact_model());
  return k;
}

// What a test will need, checked before it runs (run/sample_build.cpp): the simulated time, the
// fastest boundary speed, the largest strain its bins and snapshots span, and the keys and
// remedies an error names. Compression tests get theirs from their platen fields; other tests
// provide `static TestBudget budget(const Params&, double length, double bar_wave_speed)`.
struct TestBudget {
  double time = 0.0;        // s
  double speed = 0.0;       // m/s
  double max_strain = 0.0;  // of the rows' strain measure
  std::string what;         // how the time was found
  std::string keys = "test.platen_speed / test.max_strain / test.ramp_time";
  std::string speed_key = "test.platen_speed";
  std::string remedy = "raise the platen speed, lower the strain or the ramp";
};

// Where the sample stood when loading began, in the test's own frame: every test has one. The
// loading axis (2: z in 3D, 1: y; a slab's normal), where the sample's bottom face stood along it,
// the length along the load, the loaded area (length x area is the sample's volume) and the
// extents across the load (2D: depth is the thickness). Porosity, the fractal dimension's box,
// the crack pattern's quarters and the summary read it.
struct TestFrame {
  int axis = 2;
  double origin = 0.0;              // m
  double length = 0.0;              // m
  double area = 0.0;                // m^2
  double width = 0.0, depth = 0.0;  // m
};

// The optional part of a test whose rows are a stress-strain curve (compression and the
// Brazilian test): the run reads moduli, strengths and the quasi-static checks from its rows, and
// reports its loading. Tests without it (slab and dynamic tests) report their own results through
// Protocol::summarise.
class StressStrainTest {
 public:
  virtual ~StressStrainTest() = default;
  virtual double confining_stress() const noexcept = 0;  // target sigma_3; 0 when unconfined
  virtual bool consolidated() const noexcept = 0;        // the consolidation settled
  virtual double max_strain() const noexcept = 0;        // where the test stops at the latest
  virtual double platen_speed() const noexcept = 0;      // m/s, each platen
  virtual std::string lateral_boundary() const = 0;      // "none", "walls", "membranes", ...
  // The grains' kinetic energy beyond the motion the loading prescribes, which the quasi-static
  // check weighs against the stored strain energy (docs/physics.md §6.1); by default all of it.
  virtual double fluctuating_kinetic_energy(const Simulation& sim) const {
    return sim.ledger().kinetic();
  }
  // What the test adds to summary.json from its curve's analysis (the Brazilian test reads its
  // peak as the tensile strength); most add nothing.
  virtual void summarise_curve(const analysis::CompressionResult&, nlohmann::json&) const {}
};

class Protocol {
 public:
  virtual ~Protocol() = default;

  virtual const char* kind() const noexcept = 0;  // its registry name
  virtual std::string label() const = 0;          // "uniaxial compression (UCS)", ...
  // After Simulation::initialise(): consolidation and the loading ramp. Returns the steps taken.
  virtual std::uint64_t start(Simulation& sim, double bar_wave_speed) = 0;
  // Before every loading step (servo walls, driven grips).
  virtual void control(Simulation& sim) = 0;
  // The grains control() reads besides the walls (a grit layer's): on a sample split over ranks
  // the run brings them current first. A control that must search first (a membrane's chains)
  // gathers what it finds itself. At each row the run gathers the whole sample.
  virtual GrainReads grains_read_by_control(const Simulation&) const { return {}; }
  virtual AxialState measure(const Simulation& sim) const = 0;
  // The grains measure() reads besides the walls (a reader between rows, such as the AE
  // monitor, brings them current on a split sample); by default every grain.
  virtual GrainReads grains_read_by_measure() const { return GrainReads::every(); }
  // Updates the peak tracking; true when the test should stop.
  virtual bool finished(const AxialState& s, std::size_t broken_bonds) = 0;
  virtual const std::string& stop_reason() const noexcept = 0;
  // The steps a loading at the test's own constant speed would have taken to bring the sample
  // where it stands: the step count, or under adaptive loading the steps weighted by the speed
  // over the floor, so that history rows keep the spacing in strain of a constant-speed run.
  virtual double paced_steps(const Simulation& sim) const {
    return static_cast<double>(sim.step_count());
  }
  // How far the test has gone (0-1), for progress bars.
  virtual double progress(const AxialState& s, const Simulation& sim) const = 0;
  virtual TestFrame frame() const noexcept = 0;

  // The stress-strain part, or null for a test that reports its own results.
  virtual const StressStrainTest* stress_strain() const noexcept { return nullptr; }
  // Simulated time between history rows that the test needs to be resolved (an impact lasts
  // microseconds), or 0: the experiment's output settings alone decide.
  virtual double row_time() const noexcept { return 0.0; }
  // Columns the test adds to history.csv after the common ones, and their values in a row.
  virtual std::vector<std::string> history_columns() const { return {}; }
  virtual void history_values(const Simulation&, std::vector<double>&) const {}
  // The test's own results, written under its kind in summary.json when it ends.
  virtual void summarise(const Simulation&, nlohmann::json&) const {}
  // What the test adds to the crack pattern from the cracks (where they lie for its geometry).
  virtual void describe_crack_pattern(const Simulation&, nlohmann::json&) const {}
  // The grains that are rock: the first rock_particles() of the store. A test may append
  // grains of its own apparatus after them (the abrasion test's grit), which fragments, wear and
  // porosity leave out.
  virtual std::size_t rock_particles(const Simulation& sim) const noexcept {
    return sim.particles().size();
  }

  // Checkpoints: the test's own state (its walls live in the simulation's state).
  virtual void save_state(ArchiveWriter& a) const = 0;
  // Throws InputError naming `where` unless the restored walls and particles exist in `sim`.
  virtual void check_restored(const Simulation& sim, const std::string& where) const = 0;
};

// The target sigma_3 of a confined stress-strain test; 0 for every other test.
inline double confining_stress(const Protocol& test) noexcept {
  const StressStrainTest* s = test.stress_strain();
  return s ? s->confining_stress() : 0.0;
}

// The axial strain rate a stress-strain test loads at, 2 v / L0; 0 for other tests.
inline double strain_rate(const Protocol& test) noexcept {
  const StressStrainTest* s = test.stress_strain();
  return s ? 2.0 * s->platen_speed() / test.frame().length : 0.0;
}

}  // namespace breccia
