#pragma once
// The Python module breccia._core: the engine, the run layer and the experiment parser as the
// `breccia` command uses them, bound with pybind11. The Python package (python/breccia) builds
// its friendlier API on these.
#include <pybind11/pybind11.h>

namespace breccia::python {

void bind_experiment(pybind11::module_& m);
void bind_run(pybind11::module_& m);
void bind_simulation(pybind11::module_& m);
void bind_sample(pybind11::module_& m);

}  // namespace breccia::python
