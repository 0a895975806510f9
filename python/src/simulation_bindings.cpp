// Step-level access for scripts: an experiment's sample and test built and consolidated, stepped
// by hand, its particle arrays read as numpy views of the engine's own memory (zero copy,
// read-only: the particle arrays never grow after the build, so a view stays valid while the
// simulation lives), walls added and parameters changed between stages.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <memory>

#include "breccia/core/float_mode.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/run/sample_build.hpp"
#include "module.hpp"

namespace py = pybind11;

namespace breccia::python {
namespace {

struct Scripted {
  ExperimentSpec spec;
  std::unique_ptr<Built> built;

  Simulation& sim() { return built->sim; }
  const Simulation& sim() const { return built->sim; }
};

std::unique_ptr<Scripted> make(const ExperimentSpec& spec, std::optional<py::function> log) {
  auto s = std::make_unique<Scripted>();
  s->spec = spec;
  if (spec.threads > 0) set_threads(static_cast<int>(spec.threads));
  std::function<void(const std::string&)> logger = [&](const std::string& m) {
    if (!log) return;
    py::gil_scoped_acquire gil;
    (*log)(m);
  };
  py::gil_scoped_release release;
  const SubnormalsFlushed flushed;  // the engine's mode while it runs, Python's after
  s->built = std::make_unique<Built>(build(spec, logger));
  return s;
}

// Steps the test (its servo walls steered before each step) in chunks, checking for Ctrl-C
// between chunks: the state is always between two steps when control returns to Python.
void step(Scripted& s, std::uint64_t n) {
  constexpr std::uint64_t chunk = 1000;
  for (std::uint64_t done = 0; done < n;) {
    const std::uint64_t todo = std::min(chunk, n - done);
    {
      py::gil_scoped_release release;
      const SubnormalsFlushed flushed;
      for (std::uint64_t k = 0; k < todo; ++k) {
        s.built->protocol->control(s.sim());
        s.sim().step();
      }
    }
    done += todo;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  }
}

// A read-only numpy view of `count` rows of `columns` doubles at `first`, rows `stride` bytes
// apart, kept alive by `owner`.
py::array view(const double* first, std::size_t count, std::size_t columns, std::size_t stride,
               py::handle owner) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(count)};
  std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(stride)};
  if (columns > 1) {
    shape.push_back(static_cast<py::ssize_t>(columns));
    strides.push_back(sizeof(double));
  }
  py::array a(py::dtype::of<double>(), shape, strides, first, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

py::array vectors(const std::vector<Vec3>& v, py::handle owner) {
  return view(&v.front().x, v.size(), 3, sizeof(Vec3), owner);
}

py::dict measure(const Scripted& s) {
  const AxialState a = s.built->protocol->measure(s.sim());
  return py::dict(py::arg("axial_strain") = a.strain, py::arg("axial_stress_pa") = a.stress,
                  py::arg("deviatoric_stress_pa") = a.deviatoric,
                  py::arg("confining_stress_pa") = a.confining_stress,
                  py::arg("lateral_strain") = a.lateral_strain,
                  py::arg("volumetric_strain") = a.volumetric_strain,
                  py::arg("platen_force_bottom_n") = a.force_bottom,
                  py::arg("platen_force_top_n") = a.force_top);
}

py::dict energy(const Simulation& sim) {
  const EnergyLedger& L = sim.ledger();
  return py::dict(
      py::arg("step") = L.step, py::arg("kinetic_j") = L.kinetic(),
      py::arg("bond_strain_j") = L.bond.total(), py::arg("contact_strain_j") = L.contact,
      py::arg("boundary_work_j") = L.boundary_work, py::arg("external_work_j") = L.external_work,
      py::arg("body_force_work_j") = L.body_force_work, py::arg("friction_j") = L.friction,
      py::arg("local_damping_j") = L.local_damping,
      py::arg("viscous_damping_j") = L.viscous_damping, py::arg("released_j") = L.released.total(),
      py::arg("broken_bonds") = L.broken_bonds, py::arg("residual_j") = L.residual,
      py::arg("residual_relative") = L.residual_relative);
}

// The crack catalogue as columns (the Python side makes a DataFrame of them).
py::dict cracks(const Simulation& sim) {
  const CrackCatalogue& c = sim.cracks();
  const std::size_t n = c.size();
  py::array_t<std::uint64_t> steps(n), id1(n), id2(n);
  py::array_t<double> time(n), energy_j(n), xyz({n, std::size_t{3}});
  py::list mode;
  std::size_t k = 0;
  for (const CrackRecord& r : c) {
    steps.mutable_at(k) = r.step;
    id1.mutable_at(k) = r.id1;
    id2.mutable_at(k) = r.id2;
    time.mutable_at(k) = r.time;
    energy_j.mutable_at(k) = r.energy.total();
    for (py::ssize_t d = 0; d < 3; ++d) xyz.mutable_at(k, d) = r.position[static_cast<int>(d)];
    mode.append(std::string(to_string(r.mode)));
    ++k;
  }
  return py::dict(py::arg("step") = steps, py::arg("time_s") = time, py::arg("id1") = id1,
                  py::arg("id2") = id2, py::arg("position_m") = xyz, py::arg("mode") = mode,
                  py::arg("energy_j") = energy_j);
}

py::list walls(const Simulation& sim) {
  py::list out;
  for (const Wall& w : sim.walls())
    out.append(py::dict(
        py::arg("name") = w.name,
        py::arg("shape") = w.shape == WallShape::Plane      ? "plane"
                           : w.shape == WallShape::Cylinder ? "cylinder"
                           : w.shape == WallShape::Sphere   ? "sphere"
                                                            : "rod",
        py::arg("radius_m") = w.radius, py::arg("mass_kg") = w.mass,
        py::arg("point_m") = std::array<double, 3>{w.point.x, w.point.y, w.point.z},
        py::arg("normal") = std::array<double, 3>{w.normal.x, w.normal.y, w.normal.z},
        py::arg("velocity_m_s") = std::array<double, 3>{w.velocity.x, w.velocity.y, w.velocity.z},
        py::arg("force_n") = std::array<double, 3>{w.force.x, w.force.y, w.force.z},
        py::arg("contacts") = w.contacts, py::arg("work_j") = w.work));
  return out;
}

Vec3 vec(const std::array<double, 3>& a) {
  return {a[0], a[1], a[2]};
}

// The checks of an added wall's inputs, each naming the call, the key and what is allowed.
void check_new_name(const Scripted& s, const std::string& where, const std::string& name) {
  for (const Wall& w : s.sim().walls())
    if (w.name == name) throw InputError(where, "name", name, "a name no other wall has");
}

Vec3 unit_direction(const std::string& where, const char* key, const std::array<double, 3>& d) {
  const double length = norm(vec(d));
  if (!(length > 0.0) || !std::isfinite(length))
    throw InputError(where, key, fmt::format("({}, {}, {})", d[0], d[1], d[2]),
                     "a finite non-zero vector");
  return vec(d) / length;
}

Vec3 finite_vec(const std::string& where, const char* key, const std::array<double, 3>& a) {
  if (!std::isfinite(a[0]) || !std::isfinite(a[1]) || !std::isfinite(a[2]))
    throw InputError(where, key, fmt::format("({}, {}, {})", a[0], a[1], a[2]),
                     "three finite numbers");
  return vec(a);
}

void check_positive(const std::string& where, const char* key, double v, const char* allowed) {
  if (!(v > 0.0) || !std::isfinite(v)) throw InputError(where, key, fmt::format("{}", v), allowed);
}

void check_ramp(const std::string& where, double ramp_s) {
  if (!(ramp_s >= 0.0) || !std::isfinite(ramp_s))
    throw InputError(where, "ramp_s", fmt::format("{}", ramp_s), "a time >= 0 s");
}

std::size_t add_wall(Scripted& s, const std::string& name, const std::array<double, 3>& point,
                     const std::array<double, 3>& normal, const std::array<double, 3>& velocity,
                     double ramp_s) {
  const std::string where = "add_wall('" + name + "')";
  check_new_name(s, where, name);
  check_ramp(where, ramp_s);
  Wall w =
      Wall::plane(name, finite_vec(where, "point", point), unit_direction(where, "normal", normal));
  w.target_velocity = finite_vec(where, "velocity", velocity);
  w.ramp = {s.sim().time(), ramp_s};
  return s.sim().add_wall(std::move(w));
}

// A rigid ball: prescribed (mass 0: moves at `velocity`, reached over ramp_s) or a free
// projectile (mass > 0 kg: starts at `velocity`, then moved by its contact forces and gravity).
std::size_t add_sphere(Scripted& s, const std::string& name, const std::array<double, 3>& centre,
                       double radius, const std::array<double, 3>& velocity, double mass,
                       double ramp_s) {
  const std::string where = "add_sphere('" + name + "')";
  check_new_name(s, where, name);
  check_positive(where, "radius", radius, "a length > 0 m");
  check_ramp(where, ramp_s);
  if (!(mass >= 0.0) || !std::isfinite(mass))
    throw InputError(where, "mass", fmt::format("{}", mass),
                     "0 (a ball moved at its velocity) or a mass > 0 kg (a free projectile)");
  Wall w = Wall::sphere(name, finite_vec(where, "centre", centre), radius, mass,
                        finite_vec(where, "velocity", velocity));
  if (mass == 0.0) {
    w.velocity = {};
    w.ramp = {s.sim().time(), ramp_s};
  }
  return s.sim().add_wall(std::move(w));
}

// A rigid rod (a loading nose or roller; 2D: a circle) along `axis`, moving at `velocity`.
std::size_t add_rod(Scripted& s, const std::string& name, const std::array<double, 3>& point,
                    const std::array<double, 3>& axis, double radius,
                    const std::array<double, 3>& velocity, double ramp_s) {
  const std::string where = "add_rod('" + name + "')";
  check_new_name(s, where, name);
  check_positive(where, "radius", radius, "a length > 0 m");
  check_ramp(where, ramp_s);
  Wall w = Wall::rod(name, finite_vec(where, "point", point), unit_direction(where, "axis", axis),
                     radius);
  w.target_velocity = finite_vec(where, "velocity", velocity);
  w.ramp = {s.sim().time(), ramp_s};
  return s.sim().add_wall(std::move(w));
}

Wall& wall_named(Simulation& sim, const std::string& name) {
  std::string names;
  for (Wall& w : sim.walls()) {
    if (w.name == name) return w;
    names += (names.empty() ? "" : ", ") + w.name;
  }
  throw InputError("simulation", "wall", name, "one of the walls: " + names);
}

void set_wall_velocity(Scripted& s, const std::string& name, const std::array<double, 3>& v) {
  Wall& w = wall_named(s.sim(), name);
  if (w.controlled)
    throw InputError("simulation", "wall", name,
                     "a wall the test steers (servo); set the velocity of a wall you added");
  if (w.free_body())
    throw InputError("simulation", "wall", name,
                     "a free projectile moves under its contact forces; set the velocity of a "
                     "prescribed wall");
  w.target_velocity = vec(v);
  w.ramp = {};
}

}  // namespace

namespace {

// The run's state and the boundaries a script adds and drives.
void bind_control(py::class_<Scripted>& c) {
  c.def(py::init(&make), py::arg("spec"), py::arg("log") = py::none())
      .def("step", &step, py::arg("steps") = 1)
      .def("measure", &measure)
      .def("add_wall", &add_wall, py::arg("name"), py::arg("point"), py::arg("normal"),
           py::arg("velocity") = std::array<double, 3>{0, 0, 0}, py::arg("ramp_s") = 0.0)
      .def("add_sphere", &add_sphere, py::arg("name"), py::arg("centre"), py::arg("radius"),
           py::arg("velocity") = std::array<double, 3>{0, 0, 0}, py::arg("mass") = 0.0,
           py::arg("ramp_s") = 0.0)
      .def("add_rod", &add_rod, py::arg("name"), py::arg("point"), py::arg("axis"),
           py::arg("radius"), py::arg("velocity") = std::array<double, 3>{0, 0, 0},
           py::arg("ramp_s") = 0.0)
      .def("set_wall_velocity", &set_wall_velocity, py::arg("name"), py::arg("velocity"))
      .def("set_contact_friction",
           [](Scripted& s, double mu) {
             // As the experiment file's contact.friction: finite and >= 0.
             if (!(mu >= 0.0) || !std::isfinite(mu))
               throw InputError("set_contact_friction", "friction", fmt::format("{}", mu),
                                "allowed: a finite number >= 0");
             s.sim().set_contact_friction(mu);
           })
      .def("set_local_damping", [](Scripted& s, double a) { s.sim().set_local_damping(a); })
      .def_property_readonly("test", [](const Scripted& s) { return s.built->protocol->label(); })
      .def_property_readonly("consolidation_steps",
                             [](const Scripted& s) { return s.built->consolidation_steps; })
      .def_property_readonly("time", [](const Scripted& s) { return s.sim().time(); })
      .def_property_readonly("step_count", [](const Scripted& s) { return s.sim().step_count(); })
      .def_property_readonly("time_step", [](const Scripted& s) { return s.sim().time_step(); })
      .def_property_readonly("dimension",
                             [](const Scripted& s) { return s.sim().particles().planar() ? 2 : 3; })
      .def_property_readonly("particle_count",
                             [](const Scripted& s) { return s.sim().particles().size(); })
      .def_property_readonly("intact_bonds",
                             [](const Scripted& s) { return s.sim().intact_bonds(); })
      .def_property_readonly("contacts",
                             [](const Scripted& s) { return s.sim().active_contacts(); })
      .def_property_readonly("energy", [](const Scripted& s) { return energy(s.sim()); })
      .def_property_readonly("crack_columns", [](const Scripted& s) { return cracks(s.sim()); })
      .def_property_readonly("walls", [](const Scripted& s) { return walls(s.sim()); });
}

// Numpy views of the particle arrays (no copies: each keeps the simulation alive).
void bind_particle_arrays(py::class_<Scripted>& c) {
  c.def_property_readonly("positions",
                          [](py::object self) {
                            const auto& p = self.cast<const Scripted&>().sim().particles();
                            return view(&p.pos_rad.front().x.x, p.size(), 3, sizeof(PosRad), self);
                          })
      .def_property_readonly("radii",
                             [](py::object self) {
                               const auto& p = self.cast<const Scripted&>().sim().particles();
                               return view(&p.pos_rad.front().r, p.size(), 1, sizeof(PosRad), self);
                             })
      .def_property_readonly("velocities",
                             [](py::object self) {
                               return vectors(self.cast<const Scripted&>().sim().particles().vel,
                                              self);
                             })
      .def_property_readonly("angular_velocities",
                             [](py::object self) {
                               return vectors(self.cast<const Scripted&>().sim().particles().angvel,
                                              self);
                             })
      .def_property_readonly("forces",
                             [](py::object self) {
                               return vectors(self.cast<const Scripted&>().sim().particles().force,
                                              self);
                             })
      .def_property_readonly(
          "displacements",
          [](py::object self) {
            return vectors(self.cast<const Scripted&>().sim().particles().displacement, self);
          })
      .def_property_readonly("masses",
                             [](py::object self) {
                               const auto& p = self.cast<const Scripted&>().sim().particles();
                               return view(p.mass.data(), p.size(), 1, sizeof(double), self);
                             })
      .def_property_readonly("tags", [](const Scripted& s) {
        const auto& t = s.sim().particles().tag;
        return py::array_t<std::uint64_t>(static_cast<py::ssize_t>(t.size()), t.data());
      });
}

}  // namespace

void bind_simulation(py::module_& m) {
  py::class_<Scripted> c(m, "Simulation");
  bind_control(c);
  bind_particle_arrays(c);
}

}  // namespace breccia::python
