// Samples from Python: pack and bond one as `breccia generate` does, and read a geometry file
// back as columns (the Python side makes DataFrames of them).
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "breccia/core/float_mode.hpp"
#include "breccia/run/sample_build.hpp"
#include "breccia/sample/geometry_file.hpp"
#include "module.hpp"

namespace py = pybind11;

namespace breccia::python {
namespace {

py::dict generate(const ExperimentSpec& spec, const std::string& path,
                  std::optional<py::function> log) {
  std::function<void(const std::string&)> logger = [&](const std::string& m) {
    if (!log) return;
    py::gil_scoped_acquire gil;
    (*log)(m);
  };
  GeneratedSample g;
  {
    py::gil_scoped_release release;
    const SubnormalsFlushed flushed;  // the engine's mode while it runs, Python's after
    g = write_sample(spec, path, "path", logger);
  }
  // The packing report as a Python dict, through its JSON text.
  return py::module_::import("json").attr("loads")(g.report.dump());
}

py::dict read_sample(const std::string& path) {
  GeometryData g;
  {
    py::gil_scoped_release release;
    g = read_geometry(path);
  }
  const std::size_t n = g.particles.size();
  py::array_t<std::uint64_t> tag(n);
  py::array_t<double> xyz({n, std::size_t{3}}), radius(n), density(n);
  py::list motion;
  for (std::size_t k = 0; k < n; ++k) {
    const ParticleSpec& p = g.particles[k];
    tag.mutable_at(k) = p.tag;
    for (py::ssize_t d = 0; d < 3; ++d) xyz.mutable_at(k, d) = p.position[static_cast<int>(d)];
    radius.mutable_at(k) = p.radius;
    density.mutable_at(k) = p.density;
    motion.append(p.motion == Motion::Free    ? "free"
                  : p.motion == Motion::Fixed ? "fixed"
                                              : "driven");
  }
  py::array_t<std::uint64_t> bonds({g.bonds.size(), std::size_t{2}});
  for (std::size_t k = 0; k < g.bonds.size(); ++k) {
    bonds.mutable_at(k, 0) = g.bonds[k].first;
    bonds.mutable_at(k, 1) = g.bonds[k].second;
  }
  return py::dict(py::arg("dimension") = g.dimension == Dimension::Two ? 2 : 3,
                  py::arg("thickness_m") = g.thickness, py::arg("tag") = tag,
                  py::arg("position_m") = xyz, py::arg("radius_m") = radius,
                  py::arg("density_kg_m3") = density, py::arg("motion") = motion,
                  py::arg("bonds") = bonds);
}

}  // namespace

void bind_sample(py::module_& m) {
  m.def("generate", &generate, py::arg("spec"), py::arg("path"), py::arg("log"));
  m.def("read_sample", &read_sample, py::arg("path"));
}

}  // namespace breccia::python
