#pragma once
// The experiment file (TOML, SI units) and its validation. The key tables of spec/sections.cpp
// (and the laws' and tests' own) drive parsing, validation, defaults, `--set` and the generated
// docs (docs/experiment.md). The spec is plain data; the runner builds a Simulation from it.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "breccia/engine/simulation.hpp"
#include "breccia/protocol/registry.hpp"
#include "breccia/sample/radius_distribution.hpp"

namespace breccia {

// One joint of the [joint] table (docs/physics.md §5): a plane through the sample centre plus
// `centre`, oriented by `normal` or by dip and dip direction, limited to a disc of `radius` (0:
// unlimited), or a set of parallel planes `spacing` apart.
struct JointPlaneSpec {
  std::array<double, 3> centre{};  // m, from the centre of the sample's bounding box
  bool has_normal = false;
  std::array<double, 3> normal{0, 0, 1};
  double dip_deg = 0.0;             // angle of the plane from the horizontal (x-y plane; 2D: x)
  double dip_direction_deg = 90.0;  // azimuth of the dip, clockwise from +y (North); 90 = +x
  double radius = 0.0;              // m; 0 = the whole plane
  double spacing = 0.0;             // m; 0 = one plane
};

struct ExperimentSpec {
  std::string name = "ucs-berea";
  // [engine]
  std::int64_t dimension = 3;
  std::int64_t threads = 0;      // 0 = all cores
  double gravity = 0.0;          // m/s^2 along -z (3D) or -y (2D)
  EngineConfig engine;           // gravity is filled from `gravity` when the simulation is built
  double density_scaling = 1.0;  // mass and inertia factor for quasi-static runs (>= 1)
  // The hot kernels' instruction set: "auto" (the fastest this CPU runs), "baseline" or
  // "x86-64-v3" (core/instruction_set.hpp); resolved into engine.instruction_set when built.
  std::string instruction_set = "auto";
  // Dynamic damping (engine.dynamic_damping_*; radius and time 0 = resolved when the sample is
  // built: the AE source radius and its event duration).
  bool dynamic_damping = false;
  // [material]
  std::string preset = "custom";
  // [sample]
  // "generate" (random packing), "file" (breccia-geometry), "table" (x y z r), "gengeo"
  // (LSMGeometry 1.2), "lattice" (FCC in 3D, hexagonal in 2D)
  std::string sample_source = "generate";
  std::string shape = "prism";  // generate: prism or cylinder (3D), rectangle (2D)
  double width = 8e-3, depth = 8e-3, height = 16e-3, diameter = 8e-3;
  double slab_thickness = 5e-3;  // shape "slab": along z (2D: y)
  std::string distribution = "uniform";
  double radius_min = 0.3e-3, radius_max = 0.5e-3, radius_mean = 0.4e-3, radius_sd = 0.05e-3;
  std::vector<double> class_radii, class_mass_fractions;
  double porosity = 0.37;
  std::string packing = "expansion";      // expansion | insertion | preconsolidation (2D)
  std::string packing_target = "stress";  // "stress" (servo to isotropic_stress) or "porosity"
  double isotropic_stress = 0.1e6;
  double preconsolidation_stress = 10e6;
  std::string compaction = "rows";  // preconsolidation: "rows" | "homogeneous"
  std::int64_t floater_contacts = 3;
  double floater_max_growth = 0.2;
  std::int64_t insertion_failures = 5000;
  std::int64_t max_particles = 2'000'000;
  bool cache = true;                            // reuse a generated sample with the same settings
  std::array<std::int64_t, 3> cells{6, 6, 12};  // lattice
  double radius = 0.5e-3;                       // lattice
  double density = 2650.0;
  double thickness = 1e-3;  // 2D only; planar spheres: 2 R_bar unless the file sets it
  // 2D grain bodies (docs/physics.md §3.4): "disk", "planar_sphere", or "auto" (planar spheres with
  // Hertz-Mindlin contacts, disks otherwise; resolved when the file is read)
  std::string planar_body = "auto";
  std::string geometry_file;  // file, table, gengeo
  // Bonds between pairs with gap <= this when the sample lists none (generated samples: at
  // generation).
  double bond_gap_tolerance = 5e-6;
  // [contact] and [bond]: the chosen laws with their parameters (law/registry.hpp)
  ContactParams contact = LinearContact::Params{};
  double wall_friction = 0.0;
  BondParams bond = ParallelBond::Params{};
  // [joint]: the joint law and its planes (none: no joints)
  JointParams joint = SmoothJoint::Params{};
  std::vector<JointPlaneSpec> joint_planes;
  // [test] (the old [loading] table is still read and mapped onto it)
  TestParams test = UcsTest::Params{};
  // [output]
  std::string output_directory = "runs";
  std::int64_t history_interval = 200;      // steps
  double history_strain_interval = 0.0;     // axial strain between rows; 0: every interval steps
  double snapshot_strain_interval = 0.002;  // axial strain between ParaView snapshots; 0 = none
  bool plot = true;                         // stress-strain PNG at the end (needs matplotlib)
  bool progress = true;
  double checkpoint_interval = 600.0;    // wall-clock s between checkpoints; 0 = on interrupt only
  std::int64_t resident_cracks = 16384;  // crack records held in memory; older ones on disk
  // [ae] acoustic emission and indicator series (docs/analysis.md §3-§6)
  std::string ae_clustering = "source_region";  // source_region | grain | source_radius (§4.1)
  double ae_source_radius = 0.0;                // m; 0 = 3 x the largest particle diameter
  double ae_shear_wave_speed = 0.0;             // m/s; 0 = estimated at the first crack
  bool ae_moment_tensors = true;
  std::int64_t ae_moment_interval = 1;
  double ae_magnitude_constant = -6.0;
  double ae_bin_width = 5e-5;
  std::int64_t ae_window_bins = 10;
  std::int64_t ae_window_events = 100;
  std::int64_t ae_window_step = 10;
  std::int64_t ae_min_events = 50;

  std::string source;  // file the spec came from ("built-in default" otherwise)

  // The resolved 2D body (Disk in 3D, where it does not apply).
  PlanarBody grain_body() const {
    return planar_body == "planar_sphere" ? PlanarBody::PlanarSphere : PlanarBody::Disk;
  }

  std::string_view contact_law() const { return name_of_params<ContactLaws>(contact); }
  std::string_view bond_law() const { return name_of_params<BondLaws>(bond); }
  std::string_view joint_law() const { return name_of_params<JointLaws>(joint); }
  std::string_view test_kind() const { return name_of_params<LabTests>(test); }
};

// The unit normal of a joint plane (from `normal`, or from dip and dip direction: docs/physics.md
// §5 with x = East, y = North, z = Up; in 2D the loading axis y is "up").
Vec3 joint_normal(const JointPlaneSpec& plane, int dimension);

ExperimentSpec default_experiment();

// sigma_3 of the experiment's test (0 for tests without confinement).
double confining_stress(const ExperimentSpec& spec);
// The compression test of the same loading at confining stress `sigma3`: "ucs" at 0, "triaxial"
// (3D) or "biaxial" (2D) above (sweeps). Throws InputError for tests that are not compression.
void set_confining_stress(ExperimentSpec& spec, double sigma3, const std::string& where);
// Sets the platens' speed of the experiment's compression test (strain-rate sweeps), constant
// throughout (no adaptive loading). Throws InputError for tests that are not compression.
void set_platen_speed(ExperimentSpec& spec, double speed, const std::string& where);
// Turns adaptive loading off in the experiment's compression test (nothing for other tests).
void load_at_constant_speed(ExperimentSpec& spec);
// The platens' speed of the experiment's compression test, m/s; 0 for tests without platens.
double platen_speed(const ExperimentSpec& spec);
// The [sample] radius distribution of a generated sample.
RadiusDistribution radius_distribution(const ExperimentSpec& spec);
// The chosen bond law's moduli (bar-wave speed, crack energies).
BondModuli bond_moduli(const ExperimentSpec& spec);
// What the test knows about the sample before it is built.
SampleInfo sample_info(const ExperimentSpec& spec);

// Material presets: names, and a one-line description of each (with its provenance).
std::vector<std::pair<std::string, std::string>> material_presets();
// Sets the micro-parameters of a preset (density, contact and bond laws); throws InputError.
void apply_preset(ExperimentSpec& spec, const std::string& name, const std::string& where);

// Reads a TOML experiment file and applies `overrides` ("section.key=value", value in TOML
// syntax). Throws InputError naming the file, the key, the value and what is allowed.
ExperimentSpec load_experiment(const std::string& path, const std::vector<std::string>& overrides);
// Same, from TOML text (`source` names it in errors); empty text gives the default experiment.
ExperimentSpec parse_experiment(const std::string& text, const std::string& source,
                                const std::vector<std::string>& overrides);

// Same, from the table `table` of a larger TOML file (a calibration file's [experiment]); errors
// name the lines of that file. A missing table is the default experiment.
ExperimentSpec parse_experiment_table(const std::string& text, const std::string& source,
                                      const std::string& table,
                                      const std::vector<std::string>& overrides);

// The fully resolved spec as TOML text (every key, defaults included), for the run manifest.
std::string to_toml(const ExperimentSpec& spec);
// Whether an experiment key ("section.name") takes integers only (the seed, thread and cell
// counts): such a key cannot take the scaled real values a calibration gives a parameter.
bool is_integer_key(const std::string& key);

// Reference documentation of every key, generated from the validation tables (Markdown).
std::string experiment_docs();

}  // namespace breccia
