// Experiments from files, TOML text and overrides, through the command line's own parser: the
// same validation, the same messages.
#include <pybind11/stl.h>

#include "breccia/spec/experiment.hpp"
#include "module.hpp"

namespace py = pybind11;

namespace breccia::python {

void bind_experiment(py::module_& m) {
  py::class_<ExperimentSpec>(m, "Spec", "a validated, fully resolved experiment")
      .def("to_toml", &to_toml, "every key, defaults included, as TOML text")
      .def_readonly("source", &ExperimentSpec::source)
      .def_readonly("name", &ExperimentSpec::name)
      .def_readonly("dimension", &ExperimentSpec::dimension)
      .def_property_readonly("test_kind",
                             [](const ExperimentSpec& s) { return std::string(s.test_kind()); })
      .def_readonly("output_directory", &ExperimentSpec::output_directory)
      .def_property_readonly("seed", [](const ExperimentSpec& s) { return s.engine.seed; });
  m.def("load_experiment", &load_experiment, py::arg("path"), py::arg("overrides"),
        "reads a TOML experiment file and applies overrides ('section.key=value')");
  m.def("parse_experiment", &parse_experiment, py::arg("text"), py::arg("source"),
        py::arg("overrides"),
        "parses TOML text (errors name `source`) and applies overrides; empty text is the default");
}

}  // namespace breccia::python
