#include "module.hpp"

#include <pybind11/stl.h>

#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/io/experiment.hpp"
#include "breccia/version.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_core, m) {
  m.doc() = "Breccia's engine and run layer (use the breccia package, not this module)";
  // Bad input raises InputError, a ValueError whose message is the command line's, word for
  // word: where the value came from, the key, the value and what is allowed.
  py::register_exception<breccia::InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<breccia::Interrupted>(m, "Interrupted", PyExc_KeyboardInterrupt);
  m.attr("version") = breccia::kVersion;
  m.attr("commit") = breccia::kCommit;
  m.attr("cli") = BRECCIA_CLI;
  m.def("material_presets", &breccia::material_presets,
        "(name, description) of every material preset");
  m.def("experiment_docs", &breccia::experiment_docs,
        "reference documentation of every experiment key (Markdown)");
  breccia::python::bind_experiment(m);
  breccia::python::bind_run(m);
  breccia::python::bind_simulation(m);
  breccia::python::bind_sample(m);
}
