#include "breccia/spec/experiment.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/material/library.hpp"
#include "breccia/spec/spec_field.hpp"
#include "breccia/spec/toml_node.hpp"

namespace breccia {

namespace {

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
    sigma3 = toml_real(*c, where_of(source, *c), "loading.confining_stress");
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
    const bool found = visit_params<LabTests>(spec.test, [&]<class T>(typename T::Params& p) {
      return set_table_key<T>(p, item, item_node, where, full);
    });
    // The test was chosen for this confining stress: one without confinement (sigma_3 = 0)
    // has no use for it or its servo gain.
    if (!found && (item == "confining_stress" || item == "servo_relaxation")) continue;
    if (!found)
      throw InputError(where, full, show(value),
                       "not a key of test kind \"" + std::string(spec.test_kind()) + "\"");
  }
}

const SpecField* find_field(std::string_view section, std::string_view key) {
  for (const SpecField& f : spec_fields())
    if (f.section == section && f.key == key) return &f;
  return nullptr;
}

const RegistrySection* find_registry_section(std::string_view section) {
  for (const RegistrySection& r : registry_sections())
    if (r.section == section) return &r;
  return nullptr;
}

// The keys set before all others, because the rest depend on them: the material preset (which
// the file's keys override), then the laws and the test (whose tables hold their sections'
// other keys), then the old [loading] table's test.
void apply_leading_keys(ExperimentSpec& spec, const toml::table& root, const std::string& source) {
  auto apply = [&](std::string_view section, std::string_view key) {
    const toml::node* node = root.at_path(std::string(section) + "." + std::string(key)).node();
    if (!node || !root[section].is_table()) return;
    find_field(section, key)
        ->set(spec, *node, where_of(source, *node), std::string(section) + "." + std::string(key));
  };
  apply("material", "preset");
  for (const RegistrySection& r : registry_sections()) apply(r.section, r.selector);
  const std::string legacy = legacy_loading_kind(root, source);
  if (!legacy.empty()) with_lab_test(legacy, [&]<class T>() { spec.test = typename T::Params{}; });
}

std::string section_list() {
  std::string s;
  for (std::string_view sec : spec_sections())
    if (!sec.empty()) s += (s.empty() ? "[" : ", [") + std::string(sec) + "]";
  return s;
}

// One key of a section: a field of the spec's tables, or of the registered type the section
// names; InputError listing the section's keys when it is neither.
void apply_section_key(ExperimentSpec& spec, const std::string& section, const std::string& item,
                       const toml::node& value, const std::string& source) {
  const std::string full = section + "." + item, where = where_of(source, value);
  const RegistrySection* reg = find_registry_section(section);
  if (reg && item == reg->selector) return;  // applied first
  if (section == "material" && item == "preset") return;
  if (const SpecField* f = find_field(section, item)) return f->set(spec, value, where, full);
  if (reg && reg->set_key(spec, item, value, where, full)) return;
  std::string allowed;
  for (const SpecField& f : spec_fields())
    if (f.section == section) allowed += (allowed.empty() ? "" : ", ") + std::string(f.key);
  std::string chosen;
  if (reg) {
    const std::string keys = reg->key_list(spec);
    allowed += keys.empty() ? "" : ", " + keys;
    chosen = " for " + std::string(reg->what) + " \"" + reg->chosen(spec) + "\"";
  }
  throw InputError(where, full, show(value), "unknown key" + chosen + "; allowed: " + allowed);
}

void apply_table(ExperimentSpec& spec, const toml::table& root, const std::string& source) {
  apply_leading_keys(spec, root, source);
  for (const auto& [k, node] : root) {
    const std::string name(k.str());
    if (!node.is_table()) {
      const SpecField* f = find_field("", name);
      if (!f)
        throw InputError(where_of(source, node), name, show(node),
                         "unknown top-level key; allowed: name, and the tables " + section_list());
      f->set(spec, node, where_of(source, node), name);
      continue;
    }
    const toml::table& tbl = *node.as_table();
    if (name == "loading") {
      apply_legacy_loading(spec, tbl, source);
      continue;
    }
    const auto& sections = spec_sections();
    if (name.empty() || std::find(sections.begin(), sections.end(), name) == sections.end())
      throw InputError(where_of_table(source, node), "[" + name + "]", "",
                       "unknown table; allowed: " + section_list());
    for (const auto& [kk, value] : tbl)
      apply_section_key(spec, name, std::string(kk.str()), value, source);
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

// Pairs up to sample.bond_gap_tolerance apart are bonded: beyond the smallest grain's radius a
// bond would join grains that another grain could sit between, which is no longer a bonded
// contact. A sample read from a file is checked against its grains when it is read.
void check_bond_gap(const ExperimentSpec& s, const std::string& source) {
  double smallest = 0.0;
  std::string which;
  if (s.sample_source == "generate") {
    smallest = s.radius_min;
    which = "sample.radius_min";
    if (s.distribution == "classes" && !s.class_radii.empty()) {
      smallest = *std::min_element(s.class_radii.begin(), s.class_radii.end());
      which = "the smallest of sample.class_radii";
    }
  } else if (s.sample_source == "lattice") {
    smallest = s.radius;
    which = "sample.radius";
  }
  if (smallest > 0.0 && s.bond_gap_tolerance > smallest)
    throw InputError(source, "sample.bond_gap_tolerance", num(s.bond_gap_tolerance),
                     fmt::format("at most the smallest grain radius ({} = {} m): a wider gap "
                                 "bonds grains that another grain could sit between",
                                 which, num(smallest)));
}

// The [engine] keys that depend on others.
void check_engine(const ExperimentSpec& s, const std::string& source) {
  if (!s.dynamic_damping)
    for (const auto& [key, value] :
         {std::pair{"engine.dynamic_damping_alpha", s.engine.dynamic_damping_alpha},
          std::pair{"engine.dynamic_damping_radius", s.engine.dynamic_damping_radius},
          std::pair{"engine.dynamic_damping_time", s.engine.dynamic_damping_time}})
      if (value != 0.0)
        throw InputError(source, key, num(value),
                         "applies with engine.dynamic_damping = true only (it is false)");
  if (s.density_scaling > 1.0 && s.gravity > 0.0)
    throw InputError(source, "engine.density_scaling", num(s.density_scaling),
                     "must be 1 when gravity is on: scaled masses would scale the weight");
}

void check_consistency(const ExperimentSpec& s, const std::string& source) {
  if ((s.sample_source == "file" || s.sample_source == "table" || s.sample_source == "gengeo") &&
      s.geometry_file.empty())
    throw InputError(source, "sample.file", "\"\"",
                     "a file is required when source = \"" + s.sample_source + "\"");
  visit_params<BondLaws>(s.bond, [&]<class Law>(const typename Law::Params& p) {
    if (planar_only_law<Law> && s.dimension != 2)
      throw InputError(source, "bond.law", "\"" + std::string(Law::name) + "\"",
                       "a 2D law of disks and planar spheres: it needs engine.dimension = 2");
    if constexpr (requires { Law::check(p, source, s.dimension); })
      Law::check(p, source, s.dimension);
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
  check_bond_gap(s, source);
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
  check_engine(s, source);
}

}  // namespace

bool is_integer_key(const std::string& key) {
  for (const SpecField& f : spec_fields())
    if (f.is_integer() &&
        (f.section.empty() ? std::string(f.key)
                           : std::string(f.section) + "." + std::string(f.key)) == key)
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
  s.bond_gap_tolerance = plain.bond_gap_tolerance;  // a preset may carry its calibrated gap
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
    throw InputError(where, "test.kind", "\"" + std::string(spec.test_kind()) + "\"",
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
  loading.adaptive_speed_ratio = 1.0;  // the rate is what the sweep varies: constant throughout
  visit_lab_test(spec.test, [&]<class T>(const typename T::Params& p) {
    if constexpr (PlatenLoaded<T>) {
      typename T::Params q = p;
      T::set_loading(q, loading);
      spec.test = q;
    }
  });
}

void load_at_constant_speed(ExperimentSpec& spec) {
  visit_lab_test(spec.test, [&]<class T>(const typename T::Params& p) {
    if constexpr (PlatenLoaded<T>) {
      typename T::Params q = p;
      PlatenLoading loading = T::loading(p);
      loading.adaptive_speed_ratio = 1.0;
      T::set_loading(q, loading);
      spec.test = q;
    }
  });
}

double platen_speed(const ExperimentSpec& spec) {
  double speed = 0.0;
  visit_lab_test(spec.test, [&]<class T>(const typename T::Params& p) {
    if constexpr (PlatenLoaded<T>) speed = T::loading(p).platen_speed;
  });
  return speed;
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

// The dimension a library preset was calibrated in (its record's), 0 for none; the records are
// read once, not at every parse of an experiment.
int preset_dimension(const EmbeddedMaterial& m) {
  static const std::map<std::string_view, int> dimensions = [] {
    std::map<std::string_view, int> out;
    for (const EmbeddedMaterial& e : embedded_materials()) {
      const nlohmann::json r = nlohmann::json::parse(e.record, nullptr, false);
      out[e.name] = r.is_object() && r.contains("dimension") && r["dimension"].is_number_integer()
                        ? r["dimension"].get<int>()
                        : 0;
    }
    return out;
  }();
  const auto it = dimensions.find(m.name);
  return it == dimensions.end() ? 0 : it->second;
}

// A preset named in the file holds the micro-parameters of a 2D model or of a 3D one, which do
// not carry over to the other: on a sample of the other dimension it is refused, with the
// preset of the same rock calibrated in that dimension where the library has one.
//
// The built-in default's preset, calibrated in 3D, on a 2D experiment that names none keeps its
// values for the keys the file leaves out, but not its name: the run does not claim a
// calibration it lacks, and its resolved file (every key written) reads back as it ran.
void resolve_preset_dimension(ExperimentSpec& s, const toml::table& root,
                              const std::string& source) {
  const auto& all = embedded_materials();
  const auto m =
      std::find_if(all.begin(), all.end(), [&](const auto& e) { return e.name == s.preset; });
  if (m == all.end()) return;
  const int calibrated = preset_dimension(*m);
  if (calibrated == 0 || calibrated == s.dimension) return;
  if (!root.at_path("material.preset").is_string()) {
    s.preset = "custom";
    return;
  }
  auto rock = [](std::string_view name) {
    std::string n(name);
    if (const auto at = n.find("_2d"); at != std::string::npos) n.erase(at, 3);
    return n;
  };
  std::string other;
  for (const auto& e : all)
    if (preset_dimension(e) == s.dimension && rock(e.name) == rock(m->name))
      other = fmt::format("material.preset = \"{}\" (the same rock, calibrated in {}D), ", e.name,
                          s.dimension);
  throw InputError(source, "material.preset", "\"" + s.preset + "\"",
                   fmt::format("calibrated in {}D, and engine.dimension = {}: its micro-parameters "
                               "are those of a {}D model and do not carry over; use {}"
                               "engine.dimension = {}, or \"custom\" with laws of your own",
                               calibrated, s.dimension, calibrated, other, calibrated));
}

ExperimentSpec spec_from_table(toml::table root, const std::string& source,
                               const std::vector<std::string>& overrides) {
  apply_overrides(root, overrides);
  ExperimentSpec spec = default_experiment();
  spec.source = source;
  apply_table(spec, root, source);
  check_consistency(spec, source);
  resolve_preset_dimension(spec, root, source);
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
  for (std::string_view section : spec_sections()) {
    if (!section.empty()) out += "\n[" + std::string(section) + "]\n";
    for (const SpecField& f : spec_fields())
      if (f.section == section) out += std::string(f.key) + " = " + f.get(spec) + "\n";
    if (const RegistrySection* r = find_registry_section(section)) out += r->dump(spec);
  }
  return out;
}

std::string experiment_docs() {
  const ExperimentSpec d = default_experiment();
  std::string s =
      "# Experiment file reference\n\n"
      "Generated by `breccia docs` from the same tables that validate input: every key, its unit,\n"
      "default and allowed range. Experiment files are TOML; units are SI unless the unit column\n"
      "says otherwise. Any key can be overridden on the command line with\n"
      "`--set section.key=value` (for example `--set test.max_strain=0.01`).\n";
  for (std::string_view section : spec_sections()) {
    s += "\n## " + (section.empty() ? std::string("top level") : "[" + std::string(section) + "]") +
         "\n\n";
    s += "| key | type | unit | default | allowed | meaning |\n|---|---|---|---|---|---|\n";
    for (const SpecField& f : spec_fields())
      if (f.section == section)
        s += fmt::format("| `{}` | {} | {} | `{}` | {} | {} |\n", f.key, f.type(),
                         f.unit.empty() ? "-" : f.unit, f.get(d), f.allowed(), f.doc);
    if (const RegistrySection* r = find_registry_section(section))
      s += r->docs(r->section, r->selector);
    if (section == "test")
      s += "\nThe old `[loading]` table (platen_speed, ramp_time, max_strain, stop_fraction, "
           "confining_stress, servo_relaxation) is still read: it becomes the `[test]` of the "
           "registered test that runs at its confining stress and dimension (" +
           sweepable_tests<true>() +
           "). `--set loading.confining_stress=...` works the same way.\n";
  }
  return s;
}

}  // namespace breccia
