// The experiment file's keys, section by section: one row each (spec/spec_field.hpp).
#include <fmt/format.h>

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/spec/experiment.hpp"
#include "breccia/spec/spec_field.hpp"
#include "breccia/spec/toml_node.hpp"

namespace breccia {

namespace {

using S = ExperimentSpec;
template <auto Member>
constexpr auto at = &spec_member<Member>;
template <auto Member>
constexpr auto engine_at = &spec_nested<&S::engine, Member>;

// Grains from a nanometre to a kilometre: beyond, volumes and masses leave the range of doubles
// (a cube of 1e-308 is 0) and no rock is made of them.
constexpr double kGrainRadiusMin = 1e-9, kGrainRadiusMax = 1e3;  // m
constexpr double kText = 4096;                                   // characters of a free text

// --- keys whose values are none of the plain kinds ---

// The law of [contact], [bond] or [joint], by its registry name. Naming another law starts from
// its defaults; naming the chosen one again keeps its parameters (a preset's, say).
template <class List>
std::string registry_names() {
  std::string allowed = "allowed: ";
  for_each_type<List>([&]<class T>() {
    allowed += (allowed.size() > 9 ? ", " : "") + std::string("\"") + std::string(T::name) + "\"";
  });
  return allowed;
}

template <class List, auto Member>
CustomValue law_choice() {
  return {[](S& s, const toml::node& n, const std::string& where, const std::string& key) {
            const std::string v = toml_string(n, where, key);
            const bool known = with_named<List>(v, [&]<class Law>() {
              if (!std::holds_alternative<typename Law::Params>(s.*Member))
                s.*Member = typename Law::Params{};
            });
            if (!known) throw InputError(where, key, "\"" + v + "\"", registry_names<List>());
          },
          [](const S& s) { return fmt::format("\"{}\"", name_of_params<List>(s.*Member)); },
          &registry_names<List>, "string"};
}

// The lab test: naming one starts from its defaults.
CustomValue test_choice() {
  return {[](S& s, const toml::node& n, const std::string& where, const std::string& key) {
            const std::string v = toml_string(n, where, key);
            if (!with_lab_test(v, [&]<class T>() { s.test = typename T::Params{}; }))
              throw InputError(where, key, "\"" + v + "\"", registry_names<LabTests>());
          },
          [](const S& s) { return fmt::format("\"{}\"", s.test_kind()); },
          &registry_names<LabTests>, "string"};
}

// The material preset: applied when it is read, so that the keys after it override it.
CustomValue preset_choice() {
  return {[](S& s, const toml::node& n, const std::string& where, const std::string& key) {
            const std::string v = toml_string(n, where, key);
            apply_preset(s, v, where);  // names the allowed presets when `v` is none of them
            s.preset = v;
          },
          [](const S& s) { return fmt::format("\"{}\"", s.preset); },
          [] {
            std::string allowed = "allowed: ";
            for (const auto& [n, d] : material_presets())
              allowed += (allowed.size() > 9 ? ", " : "") + ("\"" + n + "\"");
            return allowed;
          },
          "string"};
}

CustomValue lattice_cells() {
  return {
      [](S& s, const toml::node& n, const std::string& where, const std::string& key) {
        const auto* arr = n.as_array();
        if (!arr || arr->size() != 3)
          throw InputError(where, key, show(n), "expected an array of 3 integers, e.g. [6, 6, 12]");
        for (std::size_t i = 0; i < 3; ++i) {
          const std::int64_t v = toml_integer(*arr->get(i), where, key);
          if (v < 1 || v > 100000)
            throw InputError(where, key, show(n), "each count must be 1 <= value <= 100000");
          s.cells[i] = v;
        }
      },
      [](const S& s) { return fmt::format("[{}, {}, {}]", s.cells[0], s.cells[1], s.cells[2]); },
      [] {
        return std::string(
            "each >= 1; FCC: 4 spheres per cell, hexagonal: cells[0] x cells[1] disks");
      },
      "array of 3 integers"};
}

// One joint plane from its TOML table; `key` names it in errors (joint.planes[2]).
JointPlaneSpec parse_joint_plane(const toml::table& t, const std::string& where,
                                 const std::string& key) {
  JointPlaneSpec p;
  auto vec3 = [&](const toml::node& n, const std::string& name, std::array<double, 3>& out) {
    const auto* arr = n.as_array();
    if (!arr || arr->size() < 2 || arr->size() > 3)
      throw InputError(where, key + "." + name, show(n),
                       "expected 3 numbers [x, y, z] (2 in 2D: [x, y])");
    out = {0, 0, 0};
    for (std::size_t i = 0; i < arr->size(); ++i) {
      out[i] = toml_real(*arr->get(i), where, key + "." + name);
      if (!std::isfinite(out[i])) throw InputError(where, key + "." + name, show(n), "finite");
    }
  };
  auto real = [&](const toml::node& n, const std::string& name, const Range& range) {
    const double v = toml_real(n, where, key + "." + name);
    if (!range.contains(v)) throw InputError(where, key + "." + name, num(v), range.allowed());
    return v;
  };
  bool has_dip = false;
  for (const auto& [kk, value] : t) {
    const std::string name(kk.str());
    if (name == "centre") {
      vec3(value, name, p.centre);
    } else if (name == "normal") {
      vec3(value, name, p.normal);
      p.has_normal = true;
      if (p.normal[0] == 0.0 && p.normal[1] == 0.0 && p.normal[2] == 0.0)
        throw InputError(where, key + ".normal", show(value), "must not be the zero vector");
    } else if (name == "dip_deg") {
      p.dip_deg = real(value, name, Range{0, 90, true, true, "deg"});
      has_dip = true;
    } else if (name == "dip_direction_deg") {
      p.dip_direction_deg = real(value, name, Range{0, 360, true, false, "deg"});
      has_dip = true;
    } else if (name == "radius") {
      p.radius = real(value, name, Range{0, kInf, true, true, "m"});
    } else if (name == "spacing") {
      p.spacing = real(value, name, Range{0, kInf, true, true, "m"});
    } else {
      throw InputError(where, key + "." + name, show(value),
                       "unknown key of a joint plane; allowed: centre, normal, dip_deg, "
                       "dip_direction_deg, radius, spacing");
    }
  }
  if (p.has_normal && has_dip)
    throw InputError(where, key, "normal and dip",
                     "give the orientation either as normal or as dip_deg and "
                     "dip_direction_deg, not both");
  if (p.spacing > 0.0 && p.radius > 0.0)
    throw InputError(where, key + ".radius", num(p.radius),
                     "a set of parallel planes (spacing > 0) is unlimited: radius must be 0");
  return p;
}

std::string joint_plane_toml(const JointPlaneSpec& p) {
  std::string s = fmt::format("{{centre = [{}, {}, {}]", p.centre[0], p.centre[1], p.centre[2]);
  if (p.has_normal)
    s += fmt::format(", normal = [{}, {}, {}]", p.normal[0], p.normal[1], p.normal[2]);
  else
    s += fmt::format(", dip_deg = {}, dip_direction_deg = {}", p.dip_deg, p.dip_direction_deg);
  return s + fmt::format(", radius = {}, spacing = {}}}", p.radius, p.spacing);
}

CustomValue joint_planes() {
  return {[](S& s, const toml::node& n, const std::string& where, const std::string& key) {
            const auto* arr = n.as_array();
            if (!arr)
              throw InputError(where, key, show(n),
                               "expected an array of tables, e.g. [[joint.planes]] with dip_deg "
                               "= 63");
            s.joint_planes.clear();
            for (std::size_t i = 0; i < arr->size(); ++i) {
              const auto* t = arr->get(i)->as_table();
              const std::string item = fmt::format("{}[{}]", key, i + 1);
              if (!t) throw InputError(where, item, show(*arr->get(i)), "expected a table");
              s.joint_planes.push_back(parse_joint_plane(*t, where, item));
            }
          },
          [](const S& s) {
            std::string out = "[";
            for (std::size_t i = 0; i < s.joint_planes.size(); ++i)
              out += (i ? ", " : "") + joint_plane_toml(s.joint_planes[i]);
            return out + "]";
          },
          [] {
            return std::string(
                "each with centre, normal or dip_deg and dip_direction_deg, radius >= 0, "
                "spacing >= 0");
          },
          "array of tables"};
}

// --- the sections ---

std::vector<SpecField> top_level_fields() {
  return {{"", "name", "", at<&S::name>, "name of the experiment, used in the run folder's name", 0,
           100}};
}

std::vector<SpecField> engine_fields() {
  const double int64_max = static_cast<double>(std::numeric_limits<std::int64_t>::max());
  return {
      {"engine", "dimension", "", at<&S::dimension>, "3: spheres; 2: disks in the x-y plane", 2, 3},
      {"engine", "threads", "", at<&S::threads>, "OpenMP threads; 0 = all cores", 0, 1024},
      {"engine",
       "seed",
       "",
       engine_at<&EngineConfig::seed>,
       "seed of every random draw (bond strengths)",
       0,
       int64_max,
       true,
       true,
       {},
       "allowed: integer 0 <= value <= 9223372036854775807"},
      {"engine", "time_step", "s", engine_at<&EngineConfig::time_step>,
       "time step; 0 = critical estimate x safety_factor (docs/physics.md §1.5)", 0, kInf},
      {"engine", "safety_factor", "", engine_at<&EngineConfig::safety_factor>,
       "fraction of the critical time step used", 0, 1, false, true},
      {"engine", "local_damping", "", engine_at<&EngineConfig::local_damping>,
       "Cundall local damping coefficient alpha (§2.1); 0.7 is quasi-static", 0, 1, true, false},
      {"engine", "dynamic_damping", "", at<&S::dynamic_damping>,
       "lower the local damping of the grains around each fresh crack while its waves leave the "
       "source (Hazzard et al. 2000's dynamic damping; docs/physics.md §2.1)"},
      {"engine", "dynamic_damping_alpha", "", engine_at<&EngineConfig::dynamic_damping_alpha>,
       "local damping coefficient of the grains near a fresh crack (with dynamic_damping)", 0, 1,
       true, false},
      {"engine", "dynamic_damping_radius", "m", engine_at<&EngineConfig::dynamic_damping_radius>,
       "the grains whose centres lie within this distance of a crack's contact point are damped "
       "less (with dynamic_damping); 0 = the largest grain diameter (the crack's grains and "
       "those touching them)",
       0, kInf},
      {"engine", "dynamic_damping_time", "s", engine_at<&EngineConfig::dynamic_damping_time>,
       "how long after its crack a grain is damped less (with dynamic_damping); 0 = 2 r / v_S, "
       "a rupture at half the shear-wave speed reaching the radius above, with v_S = sqrt(G / "
       "rho) from the bond modulus, Poisson's ratio 0.25 and the (scaled) bulk density (or "
       "ae.shear_wave_speed)",
       0, kInf},
      {"engine", "bond_normal_damping_ratio", "",
       engine_at<&EngineConfig::bond_normal_damping_ratio>,
       "critical-damping ratio of a dashpot along every intact bond's normal, on its normal "
       "stiffness (§2.2); 0 = none",
       0, 1},
      {"engine", "bond_shear_damping_ratio", "", engine_at<&EngineConfig::bond_shear_damping_ratio>,
       "critical-damping ratio of a dashpot across every intact bond, on its shear stiffness "
       "(§2.2); 0 = none",
       0, 1},
      {"engine", "skin", "m", engine_at<&EngineConfig::skin>, "Verlet skin; 0 = 0.4 x mean radius",
       0, kInf},
      {"engine", "gravity", "m/s^2", at<&S::gravity>,
       "magnitude of gravity along -z (3D) or -y (2D); 0 = off", 0, kInf},
      {"engine", "density_scaling", "", at<&S::density_scaling>,
       "multiplies every particle's mass and inertia (quasi-static runs only): the time step "
       "grows by its square root, wave speeds fall by it; recorded in the manifest and used by "
       "every analysis of time",
       1, kInf},
      {"engine", "energy_interval", "", engine_at<&EngineConfig::energy_interval>,
       "steps between energy-ledger samples", 1, 1e9},
      {"engine",
       "instruction_set",
       "",
       at<&S::instruction_set>,
       "the instruction set of the pair pass and the integrator (the packing's too): auto = "
       "x86-64-v3 where the CPU has it (AVX2 with fused multiply-adds), else baseline (the "
       "build's own flags: the portable x86-64 of the README's build); the run's manifest names "
       "the set. Results are the same to the bit within one set at any thread and rank count and "
       "differ between sets by the rounding of fused multiply-adds (docs/physics.md §1.7): name "
       "one to reproduce a run of another machine to the bit",
       0,
       kText,
       true,
       true,
       {"auto", "baseline", "x86-64-v3"}},
  };
}

std::vector<SpecField> material_fields() {
  static const std::string doc = [] {
    std::string d =
        "micro-parameter set applied before the other keys, which override it. A preset is "
        "calibrated in 2D or in 3D and is refused on a sample of the other dimension; a 2D "
        "experiment that names none keeps the 3D default's values for the keys it leaves out "
        "and is recorded as `custom`: ";
    for (const auto& [n, text] : material_presets()) d += "`" + n + "`: " + text + " ";
    return d;
  }();
  return {{"material", "preset", "", preset_choice(), doc}};
}

std::vector<SpecField> sample_shape_fields() {
  return {
      {"sample",
       "source",
       "",
       at<&S::sample_source>,
       "generate: dense random packing (docs/physics.md §7.2); file: a breccia-geometry file "
       "(what `breccia generate` writes); table: whitespace- or comma-separated x y z radius rows "
       "(YADE/PFC exports); gengeo: an ESyS-Particle GenGeo LSMGeometry 1.2 file; lattice: FCC "
       "(3D) or hexagonal (2D) block of equal particles",
       0,
       kText,
       true,
       true,
       {"generate", "file", "table", "gengeo", "lattice"}},
      {"sample",
       "shape",
       "",
       at<&S::shape>,
       "generated sample shape: prism or cylinder (axis z) in 3D, rectangle or disk (diameter) "
       "in 2D; also chooses the confining boundary of triaxial tests; slab: a plate width x depth "
       "(x, y) of slab_thickness along z for the slab tests (2D: its cross-section, width x "
       "slab_thickness along y)",
       0,
       kText,
       true,
       true,
       {"prism", "cylinder", "rectangle", "disk", "slab"}},
      {"sample", "width", "m", at<&S::width>, "prism/rectangle size along x", 0, kInf, false},
      {"sample", "depth", "m", at<&S::depth>, "prism size along y", 0, kInf, false},
      {"sample", "height", "m", at<&S::height>, "size along the loading axis (z in 3D, y in 2D)", 0,
       kInf, false},
      {"sample", "diameter", "m", at<&S::diameter>, "cylinder or disk diameter", 0, kInf, false},
      {"sample", "slab_thickness", "m", at<&S::slab_thickness>,
       "slab: thickness along z (2D: along y); seed 001's slabs are 5-10 mm", 0, kInf, false},
  };
}

std::vector<SpecField> sample_grain_fields() {
  return {
      {"sample",
       "distribution",
       "",
       at<&S::distribution>,
       "radius distribution (docs/physics.md §7.1): uniform on [radius_min, radius_max]; "
       "lognormal with radius_mean and radius_sd truncated to [radius_min, radius_max]; classes: "
       "class_radii with class_mass_fractions",
       0,
       kText,
       true,
       true,
       {"uniform", "lognormal", "classes"}},
      {"sample", "radius_min", "m", at<&S::radius_min>, "smallest radius", kGrainRadiusMin,
       kGrainRadiusMax},
      {"sample", "radius_max", "m", at<&S::radius_max>, "largest radius (>= radius_min)",
       kGrainRadiusMin, kGrainRadiusMax},
      {"sample", "radius_mean", "m", at<&S::radius_mean>, "lognormal: mean radius", kGrainRadiusMin,
       kGrainRadiusMax},
      {"sample", "radius_sd", "m", at<&S::radius_sd>, "lognormal: standard deviation of the radius",
       0, kInf},
      {"sample", "class_radii", "m", at<&S::class_radii>, "classes: radius of each class", 0},
      {"sample", "class_mass_fractions", "", at<&S::class_mass_fractions>,
       "classes: solid-mass fraction of each class (sum 1)", 0},
  };
}

std::vector<SpecField> sample_packing_fields() {
  return {
      {"sample", "porosity", "", at<&S::porosity>,
       "target porosity: fixes the particle count; with packing_target = \"porosity\" also the "
       "final state",
       0, 1, false, false},
      {"sample",
       "packing",
       "",
       at<&S::packing>,
       "how a generated sample is packed: expansion: radius expansion in a rigid vessel to "
       "isotropic_stress or porosity, floaters grown (PFC / Potyondy & Cundall 2004, "
       "docs/physics.md §7.2); insertion: GenGeo-style constructive packing, every grain fitted "
       "tangent to its neighbours, stress-free, radii emergent in [radius_min, radius_max] "
       "(§7.4); preconsolidation (2D): disks compacted between particle-row walls to "
       "preconsolidation_stress and bonded in that state (RICEBAL practice, seed 002, §7.3)",
       0,
       kText,
       true,
       true,
       {"expansion", "insertion", "preconsolidation"}},
      {"sample",
       "packing_target",
       "",
       at<&S::packing_target>,
       "stress: radii servo to isotropic_stress after packing (low locked-in stress, P&C 2004); "
       "porosity: packed at the target porosity, whatever stress results",
       0,
       kText,
       true,
       true,
       {"stress", "porosity"}},
      {"sample", "isotropic_stress", "Pa", at<&S::isotropic_stress>,
       "installation stress p0 of the packing (about 1 % of the UCS or less)", 0, kInf, false},
      {"sample", "preconsolidation_stress", "Pa", at<&S::preconsolidation_stress>,
       "packing = \"preconsolidation\": stress the particle-row walls compact the disks to "
       "before bonding (seed 002: 10 MPa)",
       0, kInf, false},
      {"sample",
       "compaction",
       "",
       at<&S::compaction>,
       "packing = \"preconsolidation\": rows: the side rows pushed in by a servo, the sample "
       "following as a stress wave crosses it (its steps grow with the width; the 2D presets "
       "were calibrated on such samples); homogeneous: the sample and its side rows strained "
       "together, steps about independent of the width (docs/physics.md §7.3)",
       0,
       kText,
       true,
       true,
       {"rows", "homogeneous"}},
      {"sample", "floater_contacts", "", at<&S::floater_contacts>,
       "N_f: generated grains with fewer bonded neighbours are floaters and are placed snug in "
       "their cages, touching N_f or more (P&C 2004: 3 contacts; vessel walls do not count here)",
       1, 12},
      {"sample", "floater_max_growth", "", at<&S::floater_max_growth>,
       "largest relative radius growth of a floater (P&C 2004: 0.2); 0 = floaters are counted, "
       "not grown",
       0, 1},
      {"sample", "insertion_failures", "", at<&S::insertion_failures>,
       "packing = \"insertion\": consecutive failed fits that end the packing (GenGeo's "
       "numFails; more gives a denser packing)",
       10, 1e8},
      {"sample", "max_particles", "", at<&S::max_particles>,
       "refuse to generate samples with more particles than this", 1, 1e8},
      {"sample", "cache", "", at<&S::cache>,
       "reuse a generated sample with identical settings from <output.directory>/samples "
       "instead of packing again"},
  };
}

std::vector<SpecField> sample_source_fields() {
  return {
      {"sample", "cells", "", lattice_cells(),
       "lattice size in cells along x, y, z (z ignored in 2D)"},
      {"sample", "radius", "m", at<&S::radius>, "lattice: particle radius", kGrainRadiusMin,
       kGrainRadiusMax},
      {"sample", "density", "kg/m^3", at<&S::density>, "grain density (not bulk density)", 0, kInf,
       false},
      {"sample", "thickness", "m", at<&S::thickness>,
       "2D thickness t: disks' thickness (forces are for this thickness); for planar spheres "
       "the effective thickness that turns forces into stresses, 2 x the mean radius when not "
       "given (docs/physics.md §3.4)",
       0, kInf, false},
      {"sample",
       "planar_body",
       "",
       at<&S::planar_body>,
       "2D grains: disks of thickness t, or spheres confined to the plane (sphere mass and "
       "inertia; needed by Hertz-Mindlin contacts, docs/physics.md §3.4); auto: planar spheres "
       "with hertz_mindlin, disks otherwise",
       0,
       kText,
       true,
       true,
       {"auto", "disk", "planar_sphere"}},
      {"sample", "file", "", at<&S::geometry_file>,
       "geometry file when source = \"file\" (relative paths are taken from the experiment "
       "file's folder)",
       0, kText},
      {"sample", "bond_gap_tolerance", "m", at<&S::bond_gap_tolerance>,
       "pairs with a gap up to this get a bond (generated samples, and files that list no "
       "bonds); a calibration parameter (docs/physics.md §7.6); at most the smallest grain "
       "radius (sample.radius_min, the lattice's radius, or the file's smallest grain): a wider "
       "gap bonds grains that another could sit between",
       0, kInf},
  };
}

// [contact], [bond], [joint] and [test]: the chosen type here, its keys from its own table.
std::vector<SpecField> registry_fields() {
  static const std::string test_doc = [] {
    std::string d = "the lab test (protocol/registry.hpp): ";
    for_each_lab_test([&]<class T>() {
      d += "`" + std::string(T::name) + "`: " + std::string(T::summary) + " ";
    });
    return d;
  }();
  return {
      {"contact", "law", "", law_choice<ContactLaws, &S::contact>(),
       "contact law between unbonded (or overlapping bonded) particles"},
      {"contact", "wall_friction", "", at<&S::wall_friction>,
       "friction coefficient between particles and walls (0: lubricated)", 0, kInf},
      {"bond", "law", "", law_choice<BondLaws, &S::bond>(), "bond law"},
      {"joint", "law", "", law_choice<JointLaws, &S::joint>(),
       "law of the pairs a joint plane cuts (used only when planes are given)"},
      {"joint", "planes", "", joint_planes(),
       "the joints: [[joint.planes]] tables (or an inline array) with centre = [x, y, z] (m, "
       "from the centre of the sample's bounding box; default the centre), normal = [nx, ny, nz] "
       "or dip_deg (plane from the horizontal; 2D: from the x axis) and dip_direction_deg "
       "(clockwise from +y; 90 = dipping towards +x, the default), radius (m: a disc joint, a "
       "segment of half-length radius in 2D; 0 = the whole plane) and spacing (m: a set of "
       "parallel planes; 0 = one plane). Every pair whose branch crosses a joint gets the joint "
       "law (docs/physics.md §5)"},
      {"test", "kind", "", test_choice(), test_doc},
  };
}

std::vector<SpecField> output_fields() {
  return {
      {"output", "directory", "", at<&S::output_directory>,
       "folder that receives the run folder (relative to the working directory)", 0, kText},
      {"output", "history_interval", "", at<&S::history_interval>,
       "steps between rows of history.csv", 1, 1e9},
      {"output", "history_strain_interval", "", at<&S::history_strain_interval>,
       "axial strain between rows of history.csv (seed 002: 0.001), at the platens' full speed: "
       "a row every strain x length / (2 v dt) steps; 0 = every history_interval steps",
       0, 1},
      {"output", "snapshot_strain_interval", "", at<&S::snapshot_strain_interval>,
       "axial strain between ParaView snapshots (VTK, snapshots/); 0 = only the first and last", 0,
       1},
      {"output", "plot", "", at<&S::plot>,
       "write stress_strain.png at the end (python3 with matplotlib)"},
      {"output", "progress", "", at<&S::progress>, "progress bar on a terminal"},
      {"output", "checkpoint_interval_s", "s", at<&S::checkpoint_interval>,
       "wall-clock seconds between checkpoints (checkpoint.bin, continued by `breccia resume "
       "RUN_FOLDER`); 0 = only when interrupted. A checkpoint is also written on Ctrl-C, SIGTERM "
       "and --stop-at-step",
       0, kInf},
      {"output", "resident_cracks", "", at<&S::resident_cracks>,
       "crack records a run holds in memory (240 B each); older ones go to the run folder's "
       "checkpoint-cracks.bin, read back in order by the analysis, snapshots and checkpoints, "
       "and removed when the run completes. The AE monitor's event catalogue and crack "
       "contexts keep as many, at most 4096, before theirs go to checkpoint-ae-events.bin and "
       "checkpoint-ae-context.bin. Results do not depend on it",
       1, 1e12},
  };
}

std::vector<SpecField> ae_fields() {
  return {
      {"ae",
       "clustering",
       "",
       at<&S::ae_clustering>,
       "how cracks link into events (docs/analysis.md §4.1): \"source_radius\" (within r_s of "
       "any crack of the event, window T_d = 4 r_s / v_S after its latest crack), \"grain\" "
       "(shares a grain with, or touches a contact of, the event's grains; window 2 D_c / v_S "
       "with D_c the larger grain's diameter) or \"source_region\" (within r_s of the event's "
       "first crack and within T_d of it: events bounded in size and duration, never merged)",
       0,
       kText,
       true,
       true,
       {"source_radius", "grain", "source_region"}},
      {"ae", "source_radius", "m", at<&S::ae_source_radius>,
       "r_s: a crack joins an event within this distance of any of its cracks (docs/analysis.md "
       "§4.1); 0 = 3 x the largest particle diameter",
       0, kInf},
      {"ae", "shear_wave_speed", "m/s", at<&S::ae_shear_wave_speed>,
       "v_S for the event duration T_d = 4 r_s / v_S; 0 = sqrt(G / rho) from the test's own "
       "modulus and Poisson's ratio at the first crack and the (scaled) bulk density",
       0, kInf},
      {"ae", "moment_tensors", "", at<&S::ae_moment_tensors>,
       "watch the source particles of open events for moment tensors (docs/analysis.md §4.2)"},
      {"ae", "moment_interval", "", at<&S::ae_moment_interval>,
       "steps between moment-tensor evaluations of an open event", 1, 1e6},
      {"ae", "magnitude_constant", "", at<&S::ae_magnitude_constant>,
       "c of M_w = 2/3 log10 M0 + c (M0 in N m; -6.0 after Hazzard & Young, -6.07 IASPEI)"},
      {"ae", "bin_width", "", at<&S::ae_bin_width>,
       "strain bin of the indicator series (docs/analysis.md §3.2)", 0, 1, false},
      {"ae", "window_bins", "", at<&S::ae_window_bins>,
       "trailing window of the indicator series, in bins (shear fraction, MCvar, AEvar)", 1, 1e5},
      {"ae", "window_events", "", at<&S::ae_window_events>,
       "events (b-value) or cracks (D2) per moving window of the curves over strain "
       "(docs/analysis.md §5.4, §6.3)",
       10, 1e6},
      {"ae", "window_step", "", at<&S::ae_window_step>,
       "events or cracks between successive moving windows", 1, 1e6},
      {"ae", "min_events", "", at<&S::ae_min_events>,
       "fewest events (b-value) or points (D2) a statistic is computed from; fewer give no value",
       2, 1e6},
  };
}

// --- the sections whose keys come from a registered type ---

// The docs of one registered type: its summary and a table of its keys.
template <class T>
std::string type_docs(std::string_view section, std::string_view selector) {
  std::string s =
      fmt::format("\n#### `{}` {} `\"{}\"`\n\n{}\n\n", section, selector, T::name, T::summary);
  s += "| key | unit | default | allowed | meaning |\n|---|---|---|---|---|\n";
  static const typename T::Params d{};
  for (const auto& f : T::fields())
    s += fmt::format("| `{}` | {} | {} | {} | {} |\n", f.key, f.unit, f.default_text(d),
                     f.allowed(), f.doc);
  return s;
}

template <class List, auto Member>
RegistrySection registry_section(std::string_view section, std::string_view selector,
                                 std::string_view what) {
  return {section,
          selector,
          what,
          [](S& s, const std::string& key, const toml::node& n, const std::string& where,
             const std::string& full) {
            return visit_params<List>(s.*Member, [&]<class T>(typename T::Params& p) {
              return set_table_key<T>(p, key, n, where, full);
            });
          },
          [](const S& s) { return std::string(name_of_params<List>(s.*Member)); },
          [](const S& s) {
            return visit_params<List>(s.*Member, []<class T>(const typename T::Params&) {
              std::string list;
              for (const auto& f : T::fields())
                list += (list.empty() ? "" : ", ") + std::string(f.key);
              return list;
            });
          },
          [](const S& s) {
            return visit_params<List>(s.*Member, []<class T>(const typename T::Params& p) {
              std::string out;
              for (const auto& f : T::fields())
                out += std::string(f.key) + " = " + f.default_text(p) + "\n";
              return out;
            });
          },
          [](std::string_view sec, std::string_view sel) {
            std::string out;
            for_each_type<List>([&]<class T>() { out += type_docs<T>(sec, sel); });
            return out;
          }};
}

}  // namespace

const std::vector<SpecField>& spec_fields() {
  static const std::vector<SpecField> fields = [] {
    std::vector<SpecField> all;
    for (auto part : {top_level_fields, engine_fields, material_fields, sample_shape_fields,
                      sample_grain_fields, sample_packing_fields, sample_source_fields,
                      registry_fields, output_fields, ae_fields}) {
      std::vector<SpecField> f = part();
      all.insert(all.end(), f.begin(), f.end());
    }
    return all;
  }();
  return fields;
}

const std::vector<RegistrySection>& registry_sections() {
  static const std::vector<RegistrySection> sections{
      registry_section<ContactLaws, &S::contact>("contact", "law", "law"),
      registry_section<BondLaws, &S::bond>("bond", "law", "law"),
      registry_section<JointLaws, &S::joint>("joint", "law", "law"),
      registry_section<LabTests, &S::test>("test", "kind", "test kind"),
  };
  return sections;
}

const std::vector<std::string_view>& spec_sections() {
  static const std::vector<std::string_view> sections{
      "", "engine", "material", "sample", "contact", "bond", "joint", "test", "output", "ae"};
  return sections;
}

}  // namespace breccia
