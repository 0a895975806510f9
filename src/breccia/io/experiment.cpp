#include "breccia/io/experiment.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <sstream>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/io/toml_node.hpp"
#include "breccia/material/library.hpp"

namespace breccia {

namespace {

double get_real(const toml::node& n, const std::string& where, const std::string& key) {
  if (auto v = n.value<double>(); v && (n.is_floating_point() || n.is_integer())) return *v;
  throw InputError(where, key, show(n), "expected a number");
}
std::int64_t get_int(const toml::node& n, const std::string& where, const std::string& key) {
  if (n.is_integer()) return n.as_integer()->get();
  throw InputError(where, key, show(n), "expected an integer");
}
bool get_bool(const toml::node& n, const std::string& where, const std::string& key) {
  if (n.is_boolean()) return n.as_boolean()->get();
  throw InputError(where, key, show(n), "expected true or false");
}
std::string get_string(const toml::node& n, const std::string& where, const std::string& key) {
  if (n.is_string()) return n.as_string()->get();
  throw InputError(where, key, show(n), "expected a string");
}

struct Key {
  std::string section, name, unit, type, allowed, doc;
  std::function<void(ExperimentSpec&, const toml::node&, const std::string&, const std::string&)>
      set;
  std::function<std::string(const ExperimentSpec&)> get;
};

Key real_key(std::string section, std::string name, std::string unit, double lo, double hi,
             bool lo_open, std::string doc, double ExperimentSpec::*member) {
  const Range range{lo, hi, !lo_open, true, unit.empty() ? "-" : unit};
  Key k{section, name, unit, "number", range.allowed(), std::move(doc), {}, {}};
  k.get = [member](const ExperimentSpec& s) { return fmt::format("{}", s.*member); };
  k.set = [range, member](ExperimentSpec& s, const toml::node& n, const std::string& where,
                          const std::string& key) {
    const double v = get_real(n, where, key);
    if (!range.contains(v)) throw InputError(where, key, num(v), range.allowed());
    s.*member = v;
  };
  return k;
}

// Real-valued keys that live inside a nested struct of the spec.
template <class Getter>
Key nested_real(std::string section, std::string name, std::string unit, double lo, double hi,
                bool lo_open, bool hi_open, std::string doc, Getter ref) {
  const Range range{lo, hi, !lo_open, !hi_open, unit.empty() ? "-" : unit};
  Key k{section, name, unit, "number", range.allowed(), std::move(doc), {}, {}};
  k.set = [range, ref](ExperimentSpec& s, const toml::node& n, const std::string& where,
                       const std::string& key) {
    const double v = get_real(n, where, key);
    if (!range.contains(v)) throw InputError(where, key, num(v), range.allowed());
    ref(s) = v;
  };
  k.get = [ref](const ExperimentSpec& s) {
    return fmt::format("{}", ref(const_cast<ExperimentSpec&>(s)));
  };
  return k;
}

Key int_key(std::string section, std::string name, std::int64_t lo, std::int64_t hi,
            std::string doc, std::function<std::int64_t&(ExperimentSpec&)> ref) {
  const std::string allowed = fmt::format("allowed: integer {} <= value <= {}", lo, hi);
  Key k{section, name, "", "integer", allowed, std::move(doc), {}, {}};
  k.set = [lo, hi, allowed, ref](ExperimentSpec& s, const toml::node& n, const std::string& where,
                                 const std::string& key) {
    const std::int64_t v = get_int(n, where, key);
    if (v < lo || v > hi) throw InputError(where, key, std::to_string(v), allowed);
    ref(s) = v;
  };
  k.get = [ref](const ExperimentSpec& s) {
    return std::to_string(ref(const_cast<ExperimentSpec&>(s)));
  };
  return k;
}

Key choice_key(std::string section, std::string name, std::vector<std::string> choices,
               std::string doc, std::string ExperimentSpec::*member) {
  std::string allowed = "allowed: ";
  for (std::size_t i = 0; i < choices.size(); ++i)
    allowed += (i ? ", " : "") + std::string("\"") + choices[i] + "\"";
  Key k{section, name, "", "string", allowed, std::move(doc), {}, {}};
  k.set = [choices, allowed, member](ExperimentSpec& s, const toml::node& n,
                                     const std::string& where, const std::string& key) {
    const std::string v = get_string(n, where, key);
    if (std::find(choices.begin(), choices.end(), v) == choices.end())
      throw InputError(where, key, "\"" + v + "\"", allowed);
    s.*member = v;
  };
  k.get = [member](const ExperimentSpec& s) { return fmt::format("\"{}\"", s.*member); };
  return k;
}

// The law of [contact] or [bond], from the law registry. Naming another law starts from its
// defaults; naming the chosen one again keeps its parameters (a preset's, say).
template <class List, class Variant>
Key law_choice_key(std::string section, std::string doc, Variant ExperimentSpec::*member) {
  std::string allowed = "allowed: ";
  for_each_type<List>([&]<class Law>() {
    allowed += (allowed.size() > 9 ? ", " : "") + std::string("\"") + std::string(Law::name) + "\"";
  });
  Key k{section, "law", "", "string", allowed, std::move(doc), {}, {}};
  k.set = [allowed, member](ExperimentSpec& s, const toml::node& n, const std::string& where,
                            const std::string& key) {
    const std::string v = get_string(n, where, key);
    const bool known = with_named<List>(v, [&]<class Law>() {
      if (!std::holds_alternative<typename Law::Params>(s.*member))
        s.*member = typename Law::Params{};
    });
    if (!known) throw InputError(where, key, "\"" + v + "\"", allowed);
  };
  k.get = [member](const ExperimentSpec& s) {
    return fmt::format("\"{}\"", name_of_params<List>(s.*member));
  };
  return k;
}

// A TOML basic string: quotes, backslashes and control characters escaped.
std::string toml_quoted(const std::string& v) {
  std::string out = "\"";
  for (const char c : v) {
    if (c == '"' || c == '\\')
      out += std::string("\\") + c;
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      out += fmt::format("\\u{:04x}", static_cast<unsigned>(static_cast<unsigned char>(c)));
    else
      out += c;
  }
  return out + "\"";
}

Key string_key(std::string section, std::string name, std::string doc,
               std::string ExperimentSpec::*member, std::size_t max_length = 4096) {
  Key k{
      section,        name, "", "string", fmt::format("text of at most {} characters", max_length),
      std::move(doc), {},   {}};
  k.set = [member, max_length](ExperimentSpec& s, const toml::node& n, const std::string& where,
                               const std::string& key) {
    std::string v = get_string(n, where, key);
    if (v.size() > max_length)
      throw InputError(
          where, key,
          "\"" + v.substr(0, 40) + "...\" (" + std::to_string(v.size()) + " characters)",
          fmt::format("at most {} characters", max_length));
    s.*member = std::move(v);
  };
  k.get = [member](const ExperimentSpec& s) { return toml_quoted(s.*member); };
  return k;
}

Key bool_key(std::string section, std::string name, std::string doc, bool ExperimentSpec::*member) {
  Key k{section, name, "", "boolean", "true or false", std::move(doc), {}, {}};
  k.set = [member](ExperimentSpec& s, const toml::node& n, const std::string& where,
                   const std::string& key) { s.*member = get_bool(n, where, key); };
  k.get = [member](const ExperimentSpec& s) { return s.*member ? "true" : "false"; };
  return k;
}

Key real_list_key(std::string section, std::string name, std::string unit, std::string doc,
                  std::vector<double> ExperimentSpec::*member) {
  Key k{section, name, unit, "array of numbers", "each >= 0", std::move(doc), {}, {}};
  k.set = [member](ExperimentSpec& s, const toml::node& n, const std::string& where,
                   const std::string& key) {
    const auto* arr = n.as_array();
    if (!arr) throw InputError(where, key, show(n), "expected an array of numbers, e.g. [1, 2]");
    std::vector<double> v;
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const double x = get_real(*arr->get(i), where, key);
      if (!(x >= 0.0)) throw InputError(where, key, show(n), "every value must be >= 0");
      v.push_back(x);
    }
    s.*member = v;
  };
  k.get = [member](const ExperimentSpec& s) {
    std::string out = "[";
    for (std::size_t i = 0; i < (s.*member).size(); ++i)
      out += (i ? ", " : "") + fmt::format("{}", (s.*member)[i]);
    return out + "]";
  };
  return k;
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
      out[i] = get_real(*arr->get(i), where, key + "." + name);
      if (!std::isfinite(out[i])) throw InputError(where, key + "." + name, show(n), "finite");
    }
  };
  auto real = [&](const toml::node& n, const std::string& name, const Range& range) {
    const double v = get_real(n, where, key + "." + name);
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

Key joint_planes_key() {
  Key k{"joint",
        "planes",
        "",
        "array of tables",
        "each with centre, normal or dip_deg and dip_direction_deg, radius >= 0, spacing >= 0",
        "the joints: [[joint.planes]] tables (or an inline array) with centre = [x, y, z] "
        "(m, from the centre of the sample's bounding box; default the centre), normal = "
        "[nx, ny, nz] or dip_deg (plane from the horizontal; 2D: from the x axis) and "
        "dip_direction_deg (clockwise from +y; 90 = dipping towards +x, the default), radius "
        "(m: a disc joint, a segment of half-length radius in 2D; 0 = the whole plane) and "
        "spacing (m: a set of parallel planes; 0 = one plane). Every pair whose branch crosses "
        "a joint gets the joint law (docs/physics.md §5)",
        {},
        {}};
  k.set = [](ExperimentSpec& s, const toml::node& n, const std::string& where,
             const std::string& key) {
    const auto* arr = n.as_array();
    if (!arr)
      throw InputError(where, key, show(n),
                       "expected an array of tables, e.g. [[joint.planes]] with dip_deg = 63");
    s.joint_planes.clear();
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const auto* t = arr->get(i)->as_table();
      const std::string item = fmt::format("{}[{}]", key, i + 1);
      if (!t) throw InputError(where, item, show(*arr->get(i)), "expected a table");
      s.joint_planes.push_back(parse_joint_plane(*t, where, item));
    }
  };
  k.get = [](const ExperimentSpec& s) {
    std::string out = "[";
    for (std::size_t i = 0; i < s.joint_planes.size(); ++i)
      out += (i ? ", " : "") + joint_plane_toml(s.joint_planes[i]);
    return out + "]";
  };
  return k;
}

constexpr double kGrainRadiusMin = 1e-9, kGrainRadiusMax = 1e3;  // m

const std::vector<Key>& key_table() {
  static const std::vector<Key> keys = [] {
    std::vector<Key> k;
    k.push_back(string_key("", "name", "name of the experiment, used in the run folder's name",
                           &ExperimentSpec::name, 100));
    // [engine]
    k.push_back(int_key("engine", "dimension", 2, 3, "3: spheres; 2: disks in the x-y plane",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.dimension; }));
    k.back().allowed = "allowed: 2 or 3";
    k.push_back(int_key("engine", "threads", 0, 1024, "OpenMP threads; 0 = all cores",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.threads; }));
    k.push_back(int_key("engine", "seed", 0, std::numeric_limits<std::int64_t>::max(),
                        "seed of every random draw (bond strengths)",
                        [](ExperimentSpec& s) -> std::int64_t& {
                          return reinterpret_cast<std::int64_t&>(s.engine.seed);
                        }));
    k.push_back(
        nested_real("engine", "time_step", "s", 0, kInf, false, true,
                    "time step; 0 = critical estimate x safety_factor (docs/physics.md §1.5)",
                    [](ExperimentSpec& s) -> double& { return s.engine.time_step; }));
    k.push_back(nested_real("engine", "safety_factor", "", 0, 1, true, false,
                            "fraction of the critical time step used",
                            [](ExperimentSpec& s) -> double& { return s.engine.safety_factor; }));
    k.push_back(nested_real("engine", "local_damping", "", 0, 1, false, true,
                            "Cundall local damping coefficient alpha (§2.1); 0.7 is quasi-static",
                            [](ExperimentSpec& s) -> double& { return s.engine.local_damping; }));
    k.push_back(nested_real("engine", "skin", "m", 0, kInf, false, true,
                            "Verlet skin; 0 = 0.4 x mean radius",
                            [](ExperimentSpec& s) -> double& { return s.engine.skin; }));
    k.push_back(real_key("engine", "gravity", "m/s^2", 0, kInf, false,
                         "magnitude of gravity along -z (3D) or -y (2D); 0 = off",
                         &ExperimentSpec::gravity));
    k.push_back(real_key("engine", "density_scaling", "", 1, kInf, false,
                         "multiplies every particle's mass and inertia (quasi-static runs "
                         "only): the time step grows by its square root, wave speeds fall by "
                         "it; recorded in the manifest and used by every analysis of time",
                         &ExperimentSpec::density_scaling));
    k.back().allowed = "allowed: value >= 1";
    k.push_back(int_key("engine", "energy_interval", 1, 1000000000,
                        "steps between energy-ledger samples",
                        [](ExperimentSpec& s) -> std::int64_t& {
                          return reinterpret_cast<std::int64_t&>(s.engine.energy_interval);
                        }));
    // [material]
    {
      std::vector<std::string> names;
      std::string doc = "micro-parameter set applied before the other keys, which override it: ";
      for (const auto& [n, d] : material_presets()) {
        names.push_back(n);
        doc += "`" + n + "`: " + d + " ";
      }
      k.push_back(choice_key("material", "preset", names, doc, &ExperimentSpec::preset));
    }
    // [sample]
    k.push_back(choice_key("sample", "source", {"generate", "file", "table", "gengeo", "lattice"},
                           "generate: dense random packing (docs/physics.md §7.2); file: a "
                           "breccia-geometry file (what `breccia generate` writes); table: "
                           "whitespace- or comma-separated x y z radius rows (YADE/PFC exports); "
                           "gengeo: an ESyS-Particle GenGeo LSMGeometry 1.2 file; lattice: FCC "
                           "(3D) or hexagonal (2D) block of equal particles",
                           &ExperimentSpec::sample_source));
    k.push_back(choice_key("sample", "shape", {"prism", "cylinder", "rectangle", "disk", "slab"},
                           "generated sample shape: prism or cylinder (axis z) in 3D, rectangle "
                           "or disk (diameter) in 2D; also chooses the confining boundary of "
                           "triaxial tests; slab: a plate width x depth (x, y) of slab_thickness "
                           "along z for the slab tests (2D: its cross-section, width x "
                           "slab_thickness along y)",
                           &ExperimentSpec::shape));
    k.push_back(real_key("sample", "width", "m", 0, kInf, true, "prism/rectangle size along x",
                         &ExperimentSpec::width));
    k.push_back(real_key("sample", "depth", "m", 0, kInf, true, "prism size along y",
                         &ExperimentSpec::depth));
    k.push_back(real_key("sample", "height", "m", 0, kInf, true,
                         "size along the loading axis (z in 3D, y in 2D)",
                         &ExperimentSpec::height));
    k.push_back(real_key("sample", "diameter", "m", 0, kInf, true, "cylinder or disk diameter",
                         &ExperimentSpec::diameter));
    k.push_back(real_key("sample", "slab_thickness", "m", 0, kInf, true,
                         "slab: thickness along z (2D: along y); seed 001's slabs are 5-10 mm",
                         &ExperimentSpec::slab_thickness));
    k.push_back(choice_key("sample", "distribution", {"uniform", "lognormal", "classes"},
                           "radius distribution (docs/physics.md §7.1): uniform on [radius_min, "
                           "radius_max]; lognormal with radius_mean and radius_sd truncated to "
                           "[radius_min, radius_max]; classes: class_radii with "
                           "class_mass_fractions",
                           &ExperimentSpec::distribution));
    // Grains from a nanometre to a kilometre: beyond, volumes and masses leave the range of
    // doubles (a cube of 1e-308 is 0) and no rock is made of them.
    k.push_back(real_key("sample", "radius_min", "m", kGrainRadiusMin, kGrainRadiusMax, false,
                         "smallest radius", &ExperimentSpec::radius_min));
    k.push_back(real_key("sample", "radius_max", "m", kGrainRadiusMin, kGrainRadiusMax, false,
                         "largest radius (>= radius_min)", &ExperimentSpec::radius_max));
    k.push_back(real_key("sample", "radius_mean", "m", kGrainRadiusMin, kGrainRadiusMax, false,
                         "lognormal: mean radius", &ExperimentSpec::radius_mean));
    k.push_back(real_key("sample", "radius_sd", "m", 0, kInf, false,
                         "lognormal: standard deviation of the radius",
                         &ExperimentSpec::radius_sd));
    k.push_back(real_list_key("sample", "class_radii", "m", "classes: radius of each class",
                              &ExperimentSpec::class_radii));
    k.push_back(real_list_key("sample", "class_mass_fractions", "",
                              "classes: solid-mass fraction of each class (sum 1)",
                              &ExperimentSpec::class_mass_fractions));
    k.push_back(nested_real("sample", "porosity", "", 0, 1, true, true,
                            "target porosity: fixes the particle count; with packing_target = "
                            "\"porosity\" also the final state",
                            [](ExperimentSpec& s) -> double& { return s.porosity; }));
    k.push_back(choice_key(
        "sample", "packing", {"expansion", "insertion", "preconsolidation"},
        "how a generated sample is packed: expansion: radius expansion in a rigid vessel to "
        "isotropic_stress or porosity, floaters grown (PFC / Potyondy & Cundall 2004, "
        "docs/physics.md §7.2); insertion: GenGeo-style constructive packing, every grain fitted "
        "tangent to its neighbours, stress-free, radii emergent in [radius_min, radius_max] "
        "(§7.4); preconsolidation (2D): disks compacted between particle-row walls to "
        "preconsolidation_stress and bonded in that state (RICEBAL practice, seed 002, §7.3)",
        &ExperimentSpec::packing));
    k.push_back(choice_key("sample", "packing_target", {"stress", "porosity"},
                           "stress: radii servo to isotropic_stress after packing (low locked-in "
                           "stress, P&C 2004); porosity: packed at the target porosity, "
                           "whatever stress results",
                           &ExperimentSpec::packing_target));
    k.push_back(real_key("sample", "isotropic_stress", "Pa", 0, kInf, true,
                         "installation stress p0 of the packing (about 1 % of the UCS or less)",
                         &ExperimentSpec::isotropic_stress));
    k.push_back(real_key("sample", "preconsolidation_stress", "Pa", 0, kInf, true,
                         "packing = \"preconsolidation\": stress the particle-row walls compact "
                         "the disks to before bonding (seed 002: 10 MPa)",
                         &ExperimentSpec::preconsolidation_stress));
    k.push_back(int_key("sample", "floater_contacts", 1, 12,
                        "N_f: generated grains with fewer bonded neighbours are floaters and are "
                        "placed snug in their cages, touching N_f or more (P&C 2004: 3 contacts; "
                        "vessel walls do not count here)",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.floater_contacts; }));
    k.push_back(real_key("sample", "floater_max_growth", "", 0, 1, false,
                         "largest relative radius growth of a floater (P&C 2004: 0.2); 0 = "
                         "floaters are counted, not grown",
                         &ExperimentSpec::floater_max_growth));
    k.push_back(int_key("sample", "insertion_failures", 10, 100000000,
                        "packing = \"insertion\": consecutive failed fits that end the packing "
                        "(GenGeo's numFails; more gives a denser packing)",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.insertion_failures; }));
    k.push_back(int_key("sample", "max_particles", 1, 100000000,
                        "refuse to generate samples with more particles than this",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.max_particles; }));
    k.push_back(bool_key("sample", "cache",
                         "reuse a generated sample with identical settings from "
                         "<output.directory>/samples instead of packing again",
                         &ExperimentSpec::cache));
    {
      Key c{"sample",
            "cells",
            "",
            "array of 3 integers",
            "each >= 1; FCC: 4 spheres per cell, hexagonal: cells[0] x cells[1] disks",
            "lattice size in cells along x, y, z (z ignored in 2D)",
            {},
            {}};
      c.set = [](ExperimentSpec& s, const toml::node& n, const std::string& where,
                 const std::string& key) {
        const auto* arr = n.as_array();
        if (!arr || arr->size() != 3)
          throw InputError(where, key, show(n), "expected an array of 3 integers, e.g. [6, 6, 12]");
        for (std::size_t i = 0; i < 3; ++i) {
          const std::int64_t v = get_int(*arr->get(i), where, key);
          if (v < 1 || v > 100000)
            throw InputError(where, key, show(n), "each count must be 1 <= value <= 100000");
          s.cells[i] = v;
        }
      };
      c.get = [](const ExperimentSpec& s) {
        return fmt::format("[{}, {}, {}]", s.cells[0], s.cells[1], s.cells[2]);
      };
      k.push_back(c);
    }
    k.push_back(real_key("sample", "radius", "m", kGrainRadiusMin, kGrainRadiusMax, false,
                         "lattice: particle radius", &ExperimentSpec::radius));
    k.push_back(real_key("sample", "density", "kg/m^3", 0, kInf, true,
                         "grain density (not bulk density)", &ExperimentSpec::density));
    k.push_back(real_key("sample", "thickness", "m", 0, kInf, true,
                         "2D thickness t: disks' thickness (forces are for this thickness); "
                         "for planar spheres the effective thickness that turns forces into "
                         "stresses, 2 x the mean radius when not given (docs/physics.md §3.4)",
                         &ExperimentSpec::thickness));
    k.push_back(choice_key("sample", "planar_body", {"auto", "disk", "planar_sphere"},
                           "2D grains: disks of thickness t, or spheres confined to the plane "
                           "(sphere mass and inertia; needed by Hertz-Mindlin contacts, "
                           "docs/physics.md §3.4); auto: planar spheres with hertz_mindlin, disks "
                           "otherwise",
                           &ExperimentSpec::planar_body));
    k.push_back(string_key("sample", "file",
                           "geometry file when source = \"file\" (relative "
                           "paths are taken from the experiment file's folder)",
                           &ExperimentSpec::geometry_file));
    k.push_back(real_key("sample", "bond_gap_tolerance", "m", 0, kInf, false,
                         "pairs with a gap up to this get a bond (generated samples, and files "
                         "that list no bonds); a calibration parameter (docs/physics.md §7.6)",
                         &ExperimentSpec::bond_gap_tolerance));
    // [contact] and [bond]: the law keys come from the law tables (see make_law_keys).
    k.push_back(law_choice_key<ContactLaws>(
        "contact", "contact law between unbonded (or overlapping bonded) particles",
        &ExperimentSpec::contact));
    k.push_back(real_key("contact", "wall_friction", "", 0, kInf, false,
                         "friction coefficient between particles and walls (0: lubricated)",
                         &ExperimentSpec::wall_friction));
    k.push_back(law_choice_key<BondLaws>("bond", "bond law", &ExperimentSpec::bond));
    // [joint]: the law keys come from the law table, like [bond].
    k.push_back(law_choice_key<JointLaws>(
        "joint", "law of the pairs a joint plane cuts (used only when planes are given)",
        &ExperimentSpec::joint));
    k.push_back(joint_planes_key());
    // [test]: the kind here, its keys from the test's own table (see apply_table).
    {
      std::vector<std::string> kinds;
      std::string doc = "the lab test (protocol/registry.hpp): ";
      for_each_lab_test([&]<class T>() {
        kinds.emplace_back(T::name);
        doc += "`" + std::string(T::name) + "`: " + std::string(T::summary) + " ";
      });
      k.push_back(choice_key("test", "kind", kinds, doc, &ExperimentSpec::test_kind));
    }
    // [output]
    k.push_back(
        string_key("output", "directory",
                   "folder that receives the run folder (relative to the working directory)",
                   &ExperimentSpec::output_directory));
    k.push_back(int_key("output", "history_interval", 1, 1000000000,
                        "steps between rows of history.csv",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.history_interval; }));
    k.push_back(real_key("output", "history_strain_interval", "", 0, 1, false,
                         "axial strain between rows of history.csv (seed 002: 0.001), at the "
                         "platens' full speed: a row every strain x length / (2 v dt) steps; 0 = "
                         "every history_interval steps",
                         &ExperimentSpec::history_strain_interval));
    k.push_back(real_key("output", "snapshot_strain_interval", "", 0, 1, false,
                         "axial strain between ParaView snapshots (VTK, snapshots/); 0 = only "
                         "the first and last",
                         &ExperimentSpec::snapshot_strain_interval));
    k.push_back(bool_key("output", "plot",
                         "write stress_strain.png at the end (python3 with matplotlib)",
                         &ExperimentSpec::plot));
    k.push_back(
        bool_key("output", "progress", "progress bar on a terminal", &ExperimentSpec::progress));
    k.push_back(real_key("output", "checkpoint_interval_s", "s", 0, kInf, false,
                         "wall-clock seconds between checkpoints (checkpoint.bin, continued by "
                         "`breccia resume RUN_FOLDER`); 0 = only when interrupted. A checkpoint "
                         "is also written on Ctrl-C, SIGTERM and --stop-at-step",
                         &ExperimentSpec::checkpoint_interval));
    // [ae]
    k.push_back(choice_key(
        "ae", "clustering", {"source_radius", "grain"},
        "how cracks link into events (docs/analysis.md §4.1): \"source_radius\" (within r_s of any "
        "crack of the event, window T_d = 4 r_s / v_S after its latest crack) or \"grain\" "
        "(shares a grain with, or touches a contact of, the event's grains; window 2 D_c / v_S "
        "with D_c the larger grain's diameter)",
        &ExperimentSpec::ae_clustering));
    k.push_back(real_key("ae", "source_radius", "m", 0, kInf, false,
                         "r_s: a crack joins an event within this distance of any of its cracks "
                         "(docs/analysis.md §4.1); 0 = 3 x the largest particle diameter",
                         &ExperimentSpec::ae_source_radius));
    k.push_back(real_key("ae", "shear_wave_speed", "m/s", 0, kInf, false,
                         "v_S for the event duration T_d = 4 r_s / v_S; 0 = sqrt(G / rho) from "
                         "the test's own modulus and Poisson's ratio at the first crack and the "
                         "(scaled) bulk density",
                         &ExperimentSpec::ae_shear_wave_speed));
    k.push_back(bool_key("ae", "moment_tensors",
                         "watch the source particles of open events for moment tensors "
                         "(docs/analysis.md §4.2)",
                         &ExperimentSpec::ae_moment_tensors));
    k.push_back(int_key("ae", "moment_interval", 1, 1000000,
                        "steps between moment-tensor evaluations of an open event",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.ae_moment_interval; }));
    k.push_back(real_key("ae", "magnitude_constant", "", -kInf, kInf, false,
                         "c of M_w = 2/3 log10 M0 + c (M0 in N m; -6.0 after Hazzard & Young, "
                         "-6.07 IASPEI)",
                         &ExperimentSpec::ae_magnitude_constant));
    k.push_back(real_key("ae", "bin_width", "", 0, 1, true,
                         "strain bin of the indicator series (docs/analysis.md §3.2)",
                         &ExperimentSpec::ae_bin_width));
    k.push_back(int_key("ae", "window_bins", 1, 100000,
                        "trailing window of the indicator series, in bins (shear fraction, "
                        "MCvar, AEvar)",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.ae_window_bins; }));
    k.push_back(int_key("ae", "window_events", 10, 1000000,
                        "events (b-value) or cracks (D2) per moving window of the curves over "
                        "strain (docs/analysis.md §5.4, §6.3)",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.ae_window_events; }));
    k.push_back(int_key("ae", "window_step", 1, 1000000,
                        "events or cracks between successive moving windows",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.ae_window_step; }));
    k.push_back(int_key("ae", "min_events", 2, 1000000,
                        "fewest events (b-value) or points (D2) a statistic is computed from; "
                        "fewer give no value",
                        [](ExperimentSpec& s) -> std::int64_t& { return s.ae_min_events; }));
    return k;
  }();
  return keys;
}

template <class Law>
void set_law_key(typename Law::Params& p, const std::string& name, const toml::node& n,
                 const std::string& where, const std::string& key, bool& found) {
  for (const auto& f : Law::fields()) {
    if (f.key != name) continue;
    found = true;
    if (f.is_flag()) {
      f.set_flag(p, get_bool(n, where, key), where, "");
    } else {
      const double v = get_real(n, where, key);
      if (!f.in_range(v)) throw InputError(where, key, num(v), f.allowed());
      p.*std::get<double Law::Params::*>(f.member) = v;
    }
  }
}

template <class Law>
std::string law_key_list() {
  std::string s;
  for (const auto& f : Law::fields()) s += (s.empty() ? "" : ", ") + std::string(f.key);
  return s;
}

// The registered test a confining-stress sweep (or the old [loading] table) runs at sigma_3 in
// `dimension` ("" when none does).
std::string confinable_test_at(double sigma3, int dimension);

// The layout before the test registry: [loading] with platen_speed, ramp_time, max_strain,
// stop_fraction, confining_stress and servo_relaxation. Still read, as the test "ucs" when
// confining_stress is 0 (or absent), else "triaxial" (3D) or "biaxial" (2D); its keys keep their
// names in messages. Returns the kind ("" without [loading]).
std::string legacy_loading_kind(const toml::table& root, const std::string& source) {
  const toml::node* node = root.get("loading");
  if (!node) return {};
  const toml::table* loading = node->as_table();
  if (!loading)
    throw InputError(where_of(source, *node), "loading", show(*node), "must be a table");
  if (root.contains("test")) {
    const std::string where = where_of_table(source, *node);
    if (where.rfind("--set ", 0) == 0)
      throw InputError(where, "[loading]", "",
                       "this experiment has a [test] table, and the old [loading] table's keys "
                       "are its keys now: write test.<key> instead of loading.<key>");
    throw InputError(where, "[loading]", "",
                     "the old [loading] table and [test] cannot both be given: move its keys "
                     "into [test] (with kind = \"ucs\", \"triaxial\", \"biaxial\" or "
                     "\"brazilian\")");
  }
  double sigma3 = 0.0;
  if (const auto* c = loading->get("confining_stress"))
    sigma3 = get_real(*c, where_of(source, *c), "loading.confining_stress");
  std::int64_t dim = 3;
  if (const auto* e = root["engine"]["dimension"].node(); e && e->is_integer())
    dim = e->as_integer()->get();
  return confinable_test_at(sigma3, static_cast<int>(dim));
}

// The keys of an old [loading] table onto the test it maps to (see legacy_loading_kind).
void apply_legacy_loading(ExperimentSpec& spec, const toml::table& tbl, const std::string& source) {
  static const std::vector<std::string> known{"platen_speed",     "ramp_time",
                                              "max_strain",       "stop_fraction",
                                              "confining_stress", "servo_relaxation"};
  for (const auto& [kk, value] : tbl) {
    const toml::node& item_node = value;  // clang 14 cannot capture a structured binding
    const std::string item(kk.str()), full = "loading." + item;
    const std::string where = where_of(source, value);
    if (std::find(known.begin(), known.end(), item) == known.end())
      throw InputError(where, full, show(value),
                       "unknown key; allowed in the old [loading] table: platen_speed, ramp_time, "
                       "max_strain, stop_fraction, confining_stress, servo_relaxation (the [test] "
                       "table replaces it)");
    bool found = false;
    with_lab_test(spec.test_kind, [&]<class T>() {
      set_law_key<T>(std::get<typename T::Params>(spec.test), item, item_node, where, full, found);
    });
    // The test was chosen for this confining stress: one without confinement (sigma_3 = 0)
    // has no use for it or its servo gain.
    if (!found && (item == "confining_stress" || item == "servo_relaxation")) continue;
    if (!found)
      throw InputError(where, full, show(value),
                       "not a key of test kind \"" + spec.test_kind + "\"");
  }
}

void apply_table(ExperimentSpec& spec, const toml::table& root, const std::string& source) {
  const auto& keys = key_table();
  auto find_key = [&](const std::string& section, const std::string& name) -> const Key* {
    for (const Key& k : keys)
      if (k.section == section && k.name == name) return &k;
    return nullptr;
  };
  // The material preset first (explicit keys override it), then the laws: the other keys of
  // [contact] and [bond] depend on them.
  if (const auto* t = root["material"].as_table())
    if (const auto* pr = t->get("preset")) {
      if (pr->is_string() && (pr->as_string()->get() == "berea_analog" ||
                              pr->as_string()->get() == "lac_du_bonnet_analog"))
        apply_preset(spec, pr->as_string()->get(), where_of(source, *pr));  // says why
      find_key("material", "preset")->set(spec, *pr, where_of(source, *pr), "material.preset");
      apply_preset(spec, spec.preset, where_of(source, *pr));
    }
  for (const char* sec : {"contact", "bond", "joint"}) {
    if (const auto* t = root[sec].as_table())
      if (const auto* law = t->get("law"))
        find_key(sec, "law")->set(spec, *law, where_of(source, *law), std::string(sec) + ".law");
  }
  if (const auto* t = root["test"].as_table())
    if (const auto* kind = t->get("kind")) {
      find_key("test", "kind")->set(spec, *kind, where_of(source, *kind), "test.kind");
      with_lab_test(spec.test_kind, [&]<class T>() { spec.test = typename T::Params{}; });
    }
  const std::string legacy = legacy_loading_kind(root, source);
  if (!legacy.empty()) {
    spec.test_kind = legacy;
    with_lab_test(legacy, [&]<class T>() { spec.test = typename T::Params{}; });
  }
  for (const auto& [k, node] : root) {
    const std::string name(k.str());
    if (!node.is_table()) {
      const Key* key = find_key("", name);
      if (!key)
        throw InputError(where_of(source, node), name, show(node),
                         "unknown top-level key; allowed: name, and the tables [engine], "
                         "[material], [sample], [contact], [bond], [joint], [test], [output], "
                         "[ae]");
      key->set(spec, node, where_of(source, node), name);
      continue;
    }
    const toml::table& tbl = *node.as_table();
    if (name == "loading") {
      apply_legacy_loading(spec, tbl, source);
      continue;
    }
    bool section_known = false;
    for (const Key& key : keys) section_known |= key.section == name;
    if (!section_known)
      throw InputError(where_of_table(source, node), "[" + name + "]", "",
                       "unknown table; allowed: [engine], [material], [sample], [contact], "
                       "[bond], [joint], [test], [output], [ae]");
    for (const auto& [kk, value] : tbl) {
      const toml::node& item_node = value;  // clang 14 cannot capture a structured binding
      const std::string item(kk.str());
      const std::string full = name + "." + item;
      const std::string where = where_of(source, value);
      if (item == "law" && (name == "contact" || name == "bond" || name == "joint")) continue;
      if (item == "kind" && name == "test") continue;
      if (item == "preset" && name == "material") continue;
      if (const Key* key = find_key(name, item)) {
        key->set(spec, value, where, full);
        continue;
      }
      bool found = false;
      std::string allowed;
      if (name == "contact") {
        visit_params<ContactLaws>(spec.contact, [&]<class Law>(typename Law::Params& p) {
          set_law_key<Law>(p, item, item_node, where, full, found);
          allowed = "law, wall_friction, " + law_key_list<Law>();
        });
      } else if (name == "bond") {
        visit_params<BondLaws>(spec.bond, [&]<class Law>(typename Law::Params& p) {
          set_law_key<Law>(p, item, item_node, where, full, found);
          allowed = "law, " + law_key_list<Law>();
        });
      } else if (name == "joint") {
        visit_params<JointLaws>(spec.joint, [&]<class Law>(typename Law::Params& p) {
          set_law_key<Law>(p, item, item_node, where, full, found);
          allowed = "law, planes, " + law_key_list<Law>();
        });
      } else if (name == "test") {
        with_lab_test(spec.test_kind, [&]<class T>() {
          set_law_key<T>(std::get<typename T::Params>(spec.test), item, item_node, where, full,
                         found);
          allowed = "kind, " + law_key_list<T>();
        });
      } else {
        for (const Key& key : keys)
          if (key.section == name) allowed += (allowed.empty() ? "" : ", ") + key.name;
      }
      if (!found)
        throw InputError(where, full, show(value),
                         "unknown key" +
                             (name == "contact" || name == "bond" || name == "joint"
                                  ? " for law \"" +
                                        std::string(name == "contact" ? spec.contact_law()
                                                    : name == "bond"  ? spec.bond_law()
                                                                      : spec.joint_law()) +
                                        "\""
                              : name == "test" ? " for test kind \"" + spec.test_kind + "\""
                                               : std::string()) +
                             "; allowed: " + allowed);
    }
  }
}

void apply_overrides(toml::table& root, const std::vector<std::string>& overrides) {
  for (const std::string& o : overrides) {
    const auto eq = o.find('=');
    const std::string where = "--set " + o;
    if (eq == std::string::npos || eq == 0)
      throw InputError(where, o, "", "expected section.key=value, e.g. loading.max_strain=0.01");
    const std::string path = o.substr(0, eq), value = o.substr(eq + 1);
    // The option itself is the node's source, so errors name `--set ...`, not the file.
    toml::table parsed;
    try {
      parsed = toml::parse("v = " + value, where);
    } catch (const toml::parse_error&) {
      // A bare word is a string: law=hertz_mindlin.
      std::string quoted;
      for (char c : value) {
        if (c == '\\' || c == '"') quoted += '\\';
        if (static_cast<unsigned char>(c) < 0x20) continue;
        quoted += c;
      }
      try {
        parsed = toml::parse("v = \"" + quoted + "\"", where);
      } catch (const toml::parse_error& e) {
        throw InputError(where, path, value, "not a TOML value: " + std::string(e.description()));
      }
    }
    const auto dot = path.find('.');
    // Moved, not copied: a copied toml++ node loses its source (and errors would name the file).
    toml::node&& v = std::move(*parsed.get("v"));
    if (dot == std::string::npos) {
      root.insert_or_assign(path, std::move(v));
    } else {
      const std::string sec = path.substr(0, dot), key = path.substr(dot + 1);
      if (!root.contains(sec)) root.insert(sec, toml::table{});
      auto* t = root.get_as<toml::table>(sec);
      if (!t) throw InputError(where, sec, "", "is not a table");
      t->insert_or_assign(key, std::move(v));
    }
  }
}

void check_consistency(const ExperimentSpec& s, const std::string& source) {
  if ((s.sample_source == "file" || s.sample_source == "table" || s.sample_source == "gengeo") &&
      s.geometry_file.empty())
    throw InputError(source, "sample.file", "\"\"",
                     "a file is required when source = \"" + s.sample_source + "\"");
  visit_params<BondLaws>(s.bond, [&]<class Law>(const typename Law::Params&) {
    if (planar_only_law<Law> && s.dimension != 2)
      throw InputError(source, "bond.law", "\"" + std::string(Law::name) + "\"",
                       "a 2D law of disks and planar spheres: it needs engine.dimension = 2");
  });
  if (s.dimension == 2 && s.contact_law() == "hertz_mindlin" && s.planar_body == "disk")
    throw InputError(source, "contact.law", "\"hertz_mindlin\"",
                     "2D disks (sample.planar_body = \"disk\") use \"linear\" contacts: Hertz "
                     "has no disk form; set sample.planar_body = \"planar_sphere\" (or "
                     "\"auto\") for RICEBAL-style planar spheres (docs/physics.md §3.4)");
  if (s.sample_source == "generate") {
    if (s.dimension == 2 && s.shape != "rectangle" && s.shape != "disk" && s.shape != "slab")
      throw InputError(source, "sample.shape", "\"" + s.shape + "\"",
                       "2D samples are generated as \"rectangle\", \"disk\" or \"slab\"");
    if (s.dimension == 3 && (s.shape == "rectangle" || s.shape == "disk"))
      throw InputError(source, "sample.shape", "\"" + s.shape + "\"",
                       "3D samples are \"prism\", \"cylinder\" or \"slab\"");
    if (s.packing == "preconsolidation" && s.shape != "rectangle")
      throw InputError(source, "sample.packing", "\"preconsolidation\"",
                       "preconsolidation between particle rows is a 2D procedure (seed 002): it "
                       "needs engine.dimension = 2 and sample.shape = \"rectangle\"");
    if (s.distribution != "classes" && s.radius_min > s.radius_max)
      throw InputError(source, "sample.radius_max", num(s.radius_max),
                       "must be >= sample.radius_min = " + num(s.radius_min) + " m");
    if (s.distribution == "lognormal" &&
        (s.radius_mean < s.radius_min || s.radius_mean > s.radius_max))
      throw InputError(source, "sample.radius_mean", num(s.radius_mean),
                       "must lie within [radius_min, radius_max] = [" + num(s.radius_min) + ", " +
                           num(s.radius_max) + "] m");
    if (s.distribution == "classes" &&
        (s.class_radii.empty() || s.class_radii.size() != s.class_mass_fractions.size()))
      throw InputError(source, "sample.class_radii",
                       std::to_string(s.class_radii.size()) + " radii",
                       "classes need one sample.class_mass_fractions entry per radius");
  }
  if (s.sample_source == "lattice") {
    const double n = s.dimension == 2
                         ? static_cast<double>(s.cells[0]) * static_cast<double>(s.cells[1])
                         : 4.0 * static_cast<double>(s.cells[0]) * static_cast<double>(s.cells[1]) *
                               static_cast<double>(s.cells[2]);
    if (n > static_cast<double>(s.max_particles))
      throw InputError(
          source, "sample.cells",
          fmt::format("[{}, {}, {}] ({:.4g} particles)", s.cells[0], s.cells[1], s.cells[2], n),
          "more particles than sample.max_particles = " + std::to_string(s.max_particles));
  }
  if (!s.joint_planes.empty())
    visit_params<JointLaws>(s.joint, [&]<class Law>(const typename Law::Params& p) {
      if constexpr (requires { Law::check(p, source); }) Law::check(p, source);
    });
  for (std::size_t i = 0; i < s.joint_planes.size() && s.dimension == 2; ++i) {
    const JointPlaneSpec& p = s.joint_planes[i];
    const std::string key = fmt::format("joint.planes[{}]", i + 1);
    if (p.has_normal && p.normal[2] != 0.0)
      throw InputError(source, key + ".normal", num(p.normal[2]) + " along z",
                       "a 2D joint is a line in the x-y plane: its normal has no z part");
    if (p.centre[2] != 0.0)
      throw InputError(source, key + ".centre", num(p.centre[2]) + " along z",
                       "2D joints lie in the x-y plane");
    if (!p.has_normal && p.dip_direction_deg != 90.0 && p.dip_direction_deg != 270.0)
      throw InputError(source, key + ".dip_direction_deg", num(p.dip_direction_deg),
                       "in 2D a joint dips towards +x (90) or -x (270)");
  }
  visit_lab_test(
      s.test, [&]<class T>(const typename T::Params& p) { T::check(p, sample_info(s), source); });
  if (s.density_scaling > 1.0 && s.gravity > 0.0)
    throw InputError(source, "engine.density_scaling", num(s.density_scaling),
                     "must be 1 when gravity is on: scaled masses would scale the weight");
}

}  // namespace

bool is_integer_key(const std::string& key) {
  for (const Key& k : key_table())
    if (k.type == "integer" && (k.section.empty() ? k.name : k.section + "." + k.name) == key)
      return true;
  return false;
}

std::vector<std::pair<std::string, std::string>> material_presets() {
  std::vector<std::pair<std::string, std::string>> out{
      {"custom",
       "the plain law defaults (linear contacts, the parallel bond's defaults, 2650 kg/m^3), "
       "then the keys."}};
  for (const auto& m : embedded_materials())
    out.emplace_back(std::string(m.name), describe_material(m));
  return out;
}

void apply_preset(ExperimentSpec& s, const std::string& name, const std::string& where) {
  // Every preset starts from the plain law defaults, so that keys a preset leaves out do not
  // keep the values of the one before.
  const ExperimentSpec plain;
  s.density = plain.density;
  s.contact = plain.contact;
  s.bond = plain.bond;
  if (name == "custom") return;
  for (const auto& m : embedded_materials()) {
    if (m.name != name) continue;
    const std::string source = "material preset \"" + name + "\"";
    toml::table t = toml::parse(m.fragment, source);
    apply_table(s, t, source);
    return;
  }
  std::string allowed = "allowed: ";
  for (const auto& [n, d] : material_presets()) allowed += "\"" + n + "\" ";
  if (name == "berea_analog" || name == "lac_du_bonnet_analog")
    allowed =
        "this uncalibrated analog was withdrawn (presets that are not calibrated do not "
        "ship under a rock's name); use \"berea\", calibrated, or set the micro-parameters "
        "yourself (examples/calibrate-berea.toml lists the analog's values); " +
        allowed;
  throw InputError(where, "material.preset", "\"" + name + "\"", allowed);
}

// The built-in default: a UCS test on a small Berea-analog prism (8 x 8 x 16 mm, about 5,900
// grains of 0.22-0.36 mm: 27 mean grain diameters along the axis, the fewest for which the end
// eighths pass the homogeneity bars, see ARCHITECTURE.md "Samples").
ExperimentSpec default_experiment() {
  ExperimentSpec s;
  s.engine.local_damping = 0.7;
  s.engine.energy_interval = 100;
  s.preset = "berea";
  apply_preset(s, s.preset, "built-in default");
  s.density_scaling = 10.0;
  s.radius_min = 0.22e-3;
  s.radius_max = 0.36e-3;
  // Unlubricated steel platens (rock on steel, about 0.3): with frictionless platens the grains
  // against them, loaded at one point each and free to slide, break first and the test crushes
  // an end (ARCHITECTURE.md, "Samples").
  s.wall_friction = 0.3;
  s.test_kind = "ucs";
  // 0.03 m/s keeps kinetic/strain energy below 1e-3 before the peak on this sample (8.2e-4).
  s.test = UcsTest::Params{.platen_speed = 0.03};
  s.source = "built-in default";
  return s;
}

Vec3 joint_normal(const JointPlaneSpec& p, int dimension) {
  if (p.has_normal) {
    const Vec3 n{p.normal[0], p.normal[1], p.normal[2]};
    return n * (1.0 / norm(n));
  }
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double dip = p.dip_deg * kDeg, dir = p.dip_direction_deg * kDeg;
  const Vec3 n{std::sin(dip) * std::sin(dir), std::sin(dip) * std::cos(dir), std::cos(dip)};
  // 2D: the plane of the run is x-y with y up, so the 3D (x, z) of the formula becomes (x, y).
  return dimension == 2 ? Vec3{n.x, n.z, 0.0} * (1.0 / std::hypot(n.x, n.z)) : n;
}

RadiusDistribution radius_distribution(const ExperimentSpec& s) {
  RadiusDistribution d;
  d.kind = RadiusDistribution::kind_from(s.distribution, s.source);
  d.r_min = s.radius_min;
  d.r_max = s.radius_max;
  d.mean = s.radius_mean;
  d.sd = s.radius_sd;
  d.class_radius = s.class_radii;
  d.class_mass_fraction = s.class_mass_fractions;
  d.planar = s.dimension == 2;
  return d;
}

BondModuli bond_moduli(const ExperimentSpec& spec) {
  return visit_params<BondLaws>(
      spec.bond, []<class Law>(const typename Law::Params& p) { return Law::moduli(p); });
}

double confining_stress(const ExperimentSpec& spec) {
  return std::visit(
      [](const auto& p) {
        if constexpr (requires { p.confining_stress; })
          return p.confining_stress;
        else
          return 0.0;
      },
      spec.test);
}

namespace {

// A test whose loading a strain-rate sweep can vary, and one a confining-stress sweep can choose
// (protocol/compression.hpp).
template <class T>
concept PlatenLoaded = requires(typename T::Params& p, const PlatenLoading& l) {
  { T::loading(p) } -> std::same_as<PlatenLoading>;
  T::set_loading(p, l);
};
template <class T>
concept Confinable = PlatenLoaded<T> && requires(double sigma3, int dim) {
  { T::runs_at(sigma3, dim) } -> std::same_as<bool>;
};

// The registered tests a sweep can vary, for messages: "\"ucs\", \"triaxial\" or \"biaxial\"".
template <bool Confining>
std::string sweepable_tests() {
  std::vector<std::string> names;
  for_each_lab_test([&]<class T>() {
    if constexpr (Confining ? Confinable<T> : PlatenLoaded<T>)
      names.push_back("\"" + std::string(T::name) + "\"");
  });
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return s;
}

// The loading of the experiment's test; InputError naming the sweep unless it can be swept.
template <bool Confining>
PlatenLoading sweepable_loading(const ExperimentSpec& spec, const std::string& where,
                                const char* sweep) {
  std::optional<PlatenLoading> loading;
  visit_lab_test(spec.test, [&]<class T>(const typename T::Params& p) {
    if constexpr (Confining ? Confinable<T> : PlatenLoaded<T>) loading = T::loading(p);
  });
  if (!loading)
    throw InputError(where, "test.kind", "\"" + spec.test_kind + "\"",
                     std::string("a ") + sweep + " sweep needs a test loaded by platens (" +
                         sweepable_tests<Confining>() + ")");
  return *loading;
}

}  // namespace

namespace {
std::string confinable_test_at(double sigma3, int dimension) {
  std::string kind;
  for_each_lab_test([&]<class T>() {
    if constexpr (Confinable<T>)
      if (kind.empty() && T::runs_at(sigma3, dimension)) kind = T::name;
  });
  return kind;
}
}  // namespace

void set_confining_stress(ExperimentSpec& spec, double sigma3, const std::string& where) {
  PlatenLoading loading = sweepable_loading<true>(spec, where, "confining-stress");
  loading.confining_stress = sigma3 > 0.0 ? sigma3 : 0.0;
  bool found = false;
  for_each_lab_test([&]<class T>() {
    if constexpr (Confinable<T>) {
      if (found || !T::runs_at(sigma3, static_cast<int>(spec.dimension))) return;
      // The same test keeps its other keys (a biaxial test's membranes); another starts from
      // its defaults.
      auto* same = std::get_if<typename T::Params>(&spec.test);
      typename T::Params p = same ? *same : typename T::Params{};
      T::set_loading(p, loading);
      spec.test = p;
      spec.test_kind = std::string(T::name);
      found = true;
    }
  });
  if (!found)
    throw InputError(where, "confining_stress", fmt::format("{}", sigma3),
                     fmt::format("no registered test runs at this confining stress in {}D ({})",
                                 spec.dimension, sweepable_tests<true>()));
}

void set_platen_speed(ExperimentSpec& spec, double speed, const std::string& where) {
  PlatenLoading loading = sweepable_loading<false>(spec, where, "strain-rate");
  loading.platen_speed = speed;
  visit_lab_test(spec.test, [&]<class T>(const typename T::Params& p) {
    if constexpr (PlatenLoaded<T>) {
      typename T::Params q = p;
      T::set_loading(q, loading);
      spec.test = q;
    }
  });
}

SampleInfo sample_info(const ExperimentSpec& s) {
  SampleInfo info;
  info.dimension = static_cast<int>(s.dimension);
  info.thickness = s.thickness;
  info.density_scaling = s.density_scaling;
  if (s.sample_source == "generate") {
    info.shape = s.shape;
    info.diameter = s.diameter;
    info.height = s.shape == "slab" ? s.slab_thickness : s.height;
    info.r_max = s.distribution == "classes" && !s.class_radii.empty()
                     ? *std::max_element(s.class_radii.begin(), s.class_radii.end())
                     : s.radius_max;
  }
  return info;
}

namespace {

toml::table parse_toml(const std::string& text, const std::string& source) {
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw InputError(source + ":" + std::to_string(e.source().begin.line), "", "",
                     std::string("TOML syntax error: ") + std::string(e.description()));
  }
}

// The thickness a breccia-geometry file records in its header (0 when it has none), for planar
// spheres read back from a sample `breccia generate` wrote (the calibration's trials do so).
double geometry_file_thickness(const ExperimentSpec& s) {
  std::filesystem::path p = s.geometry_file;
  if (p.is_relative() && s.source != "built-in default")
    p = std::filesystem::path(s.source).parent_path() / p;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(p, ec)) return 0.0;  // the reader names it later
  std::ifstream in(p);
  std::string key;
  double value = 0.0;
  for (std::string line; std::getline(in, line);) {
    std::istringstream ls(line);
    if (!(ls >> key) || key == "particles") break;
    if (key == "thickness" && (ls >> value)) return value;
  }
  return 0.0;
}

// The 2D body and thickness that "auto" and an absent thickness stand for (docs/physics.md §3.4):
// planar spheres with Hertz-Mindlin contacts, and for them t_eff = 2 R_bar of the grains the
// sample will have.
void resolve_planar_body(ExperimentSpec& s, bool thickness_given, const std::string& source) {
  if (s.dimension != 2) return;
  if (s.planar_body == "auto")
    s.planar_body = s.contact_law() == "hertz_mindlin" ? "planar_sphere" : "disk";
  if (s.planar_body != "planar_sphere" || thickness_given) return;
  if (s.sample_source == "lattice") {
    s.thickness = 2.0 * s.radius;
  } else if (s.sample_source == "generate") {
    const RadiusDistribution d = radius_distribution(s);  // 2D: counts disk areas
    d.validate(source);
    s.thickness = 2.0 * d.number_mean(s.engine.seed);
  } else if (const double t = s.sample_source == "file" ? geometry_file_thickness(s) : 0.0;
             t > 0.0) {
    s.thickness = t;  // the one the sample was generated with
  } else {
    throw InputError(source, "sample.thickness", "(not set)",
                     "planar spheres read from a file that records no thickness need the "
                     "effective thickness that turns their forces into stresses (docs/physics.md "
                     "§3.4: 2 x the mean radius)");
  }
}

ExperimentSpec spec_from_table(toml::table root, const std::string& source,
                               const std::vector<std::string>& overrides) {
  apply_overrides(root, overrides);
  ExperimentSpec spec = default_experiment();
  spec.source = source;
  apply_table(spec, root, source);
  check_consistency(spec, source);
  resolve_planar_body(spec, root.at_path("sample.thickness").node() != nullptr, source);
  return spec;
}

}  // namespace

ExperimentSpec parse_experiment(const std::string& text, const std::string& source,
                                const std::vector<std::string>& overrides) {
  return spec_from_table(parse_toml(text, source), source, overrides);
}

ExperimentSpec parse_experiment_table(const std::string& text, const std::string& source,
                                      const std::string& table,
                                      const std::vector<std::string>& overrides) {
  toml::table file = parse_toml(text, source);
  toml::table root;
  if (auto* t = file.get_as<toml::table>(table)) {
    root = std::move(*t);  // moved, so that the nodes keep their lines in the file
  } else if (file.contains(table)) {
    throw InputError(where_of(source, *file.get(table)), table, "", "expected a table");
  }
  return spec_from_table(std::move(root), source, overrides);
}

ExperimentSpec load_experiment(const std::string& path, const std::vector<std::string>& overrides) {
  const std::string text = read_text_file(path, "an experiment file (TOML)");
  // A file without a key (empty, or comments only) is a mistake more often than a wish for the
  // defaults, which need no file. (A syntax error is left to the parser to name.)
  bool no_key = false;
  try {
    no_key = toml::parse(text, path).empty();
  } catch (const toml::parse_error&) {
  }
  if (no_key)
    throw InputError(path, "", "",
                     "the experiment file is empty; write its tables (docs/experiment.md), or give "
                     "no file for the built-in default experiment");
  return parse_experiment(text, path, overrides);
}

std::string to_toml(const ExperimentSpec& spec) {
  std::string out = "# Resolved experiment (every key, defaults included)\n";
  std::string section = "\x01";
  for (const Key& k : key_table()) {
    if (k.section != section) {
      section = k.section;
      if (!section.empty()) out += "\n[" + section + "]\n";
    }
    out += k.name + " = " + k.get(spec) + "\n";
    auto dump = [&]<class Law>(const typename Law::Params& p) {
      for (const auto& f : Law::fields())
        out += std::string(f.key) + " = " + f.default_text(p) + "\n";
    };
    if (k.section == "contact" && k.name == "wall_friction")
      visit_params<ContactLaws>(spec.contact, dump);
    if (k.section == "bond" && k.name == "law") visit_params<BondLaws>(spec.bond, dump);
    if (k.section == "joint" && k.name == "law") visit_params<JointLaws>(spec.joint, dump);
    if (k.section == "test" && k.name == "kind")
      visit_lab_test(spec.test, [&]<class T>(const typename T::Params& p) {
        for (const auto& f : T::fields())
          out += std::string(f.key) + " = " + f.default_text(p) + "\n";
      });
  }
  return out;
}

namespace {
template <class Law>
std::string law_docs(const std::string& section, const char* what = "law") {
  std::string s =
      fmt::format("\n#### `{}` {} `\"{}\"`\n\n{}\n\n", section, what, Law::name, Law::summary);
  s += "| key | unit | default | allowed | meaning |\n|---|---|---|---|---|\n";
  static const typename Law::Params d{};
  for (const auto& f : Law::fields())
    s += fmt::format("| `{}` | {} | {} | {} | {} |\n", f.key, f.unit, f.default_text(d),
                     f.allowed(), f.doc);
  return s;
}
}  // namespace

std::string experiment_docs() {
  const ExperimentSpec d = default_experiment();
  std::string s =
      "# Experiment file reference\n\n"
      "Generated by `breccia docs` from the same tables that validate input: every key, its unit,\n"
      "default and allowed range. Experiment files are TOML; units are SI unless the unit column\n"
      "says otherwise. Any key can be overridden on the command line with\n"
      "`--set section.key=value` (for example `--set loading.max_strain=0.01`).\n";
  std::string section = "\x01";
  for (const Key& k : key_table()) {
    if (k.section != section) {
      section = k.section;
      s += "\n## " + (section.empty() ? std::string("top level") : "[" + section + "]") + "\n\n";
      s += "| key | type | unit | default | allowed | meaning |\n|---|---|---|---|---|---|\n";
    }
    s += fmt::format("| `{}` | {} | {} | `{}` | {} | {} |\n", k.name, k.type,
                     k.unit.empty() ? "-" : k.unit, k.get(d), k.allowed, k.doc);
    if (k.section == "contact" && k.name == "wall_friction")
      for_each_type<ContactLaws>([&]<class Law>() { s += law_docs<Law>("contact"); });
    if (k.section == "bond" && k.name == "law")
      for_each_type<BondLaws>([&]<class Law>() { s += law_docs<Law>("bond"); });
    if (k.section == "joint" && k.name == "planes")
      for_each_type<JointLaws>([&]<class Law>() { s += law_docs<Law>("joint"); });
    if (k.section == "test" && k.name == "kind") {
      for_each_lab_test([&]<class T>() { s += law_docs<T>("test", "kind"); });
      s += "\nThe old `[loading]` table (platen_speed, ramp_time, max_strain, stop_fraction, "
           "confining_stress, servo_relaxation) is still read: it becomes `[test]` with kind "
           "`\"ucs\"` when confining_stress is 0 or absent, else `\"triaxial\"` (3D) or "
           "`\"biaxial\"` (2D). `--set loading.confining_stress=...` works the same way.\n";
    }
  }
  return s;
}

}  // namespace breccia
