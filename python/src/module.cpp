#include "module.hpp"

#include <pybind11/stl.h>

#include "breccia/analysis/rate_dependence.hpp"
#include "breccia/core/allocator.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/spec/experiment.hpp"
#include "breccia/version.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_core, m) {
  breccia::configure_allocator();
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
  m.def(
      "fit_rate_dependence",
      [](const std::vector<double>& rate, const std::vector<double>& ucs) {
        const breccia::analysis::ExponentialRateFit f =
            breccia::analysis::fit_rate_dependence(rate, ucs);
        return py::dict(py::arg("valid") = f.valid, py::arg("flag") = f.flag,
                        py::arg("points") = f.points, py::arg("a") = f.a, py::arg("b") = f.b,
                        py::arg("a_se") = f.a_se, py::arg("b_se") = f.b_se, py::arg("rms") = f.rms,
                        py::arg("a_log") = f.a_log, py::arg("b_log") = f.b_log,
                        py::arg("three_valid") = f.three_valid, py::arg("c3") = f.c3,
                        py::arg("a3") = f.a3, py::arg("b3") = f.b3, py::arg("rms3") = f.rms3,
                        py::arg("dynamic_increase") = f.dynamic_increase);
      },
      py::arg("rate"), py::arg("ucs"),
      "UCS = a exp(b rate) and UCS = c + a exp(b rate) (docs/analysis.md §11); the sweeps' fit");
  breccia::python::bind_experiment(m);
  breccia::python::bind_run(m);
  breccia::python::bind_simulation(m);
  breccia::python::bind_sample(m);
}
