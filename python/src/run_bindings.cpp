// Runs, resumes and sweeps through the run layer the command line uses. The engine runs with the
// GIL released; progress and log callbacks take it back. Ctrl-C during a run sets Breccia's
// interrupt flag (as in the command), so the run stops between two steps with a checkpoint.
#include <pybind11/functional.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <csignal>
#include <memory>
#include <optional>

#include "breccia/core/float_mode.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/run/run.hpp"
#include "module.hpp"

namespace py = pybind11;

namespace breccia::python {
namespace {

extern "C" void on_interrupt(int) {
  interrupt_flag().store(true);
}

// Routes SIGINT to Breccia's interrupt flag while a run is in C++ (Python's own handler would
// only run once control is back in the interpreter), and restores Python's handler after.
class InterruptScope {
 public:
  InterruptScope() {
    interrupt_flag().store(false);
    const py::object threading = py::module_::import("threading");
    active_ = threading.attr("current_thread")().is(threading.attr("main_thread")());
    if (!active_) return;
    struct sigaction action {};
    action.sa_handler = on_interrupt;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &previous_);
  }
  ~InterruptScope() {
    if (active_) sigaction(SIGINT, &previous_, nullptr);
  }
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
  bool interrupted() const { return interrupt_flag().load(); }

 private:
  bool active_ = false;
  struct sigaction previous_ {};
};

// The callbacks a run is given, and the first Python exception one of them raised: the run
// stops (cleanly, as on Ctrl-C) and the exception is raised again once it has.
struct Callbacks {
  std::optional<py::function> progress, log;
  std::unique_ptr<py::error_already_set> error;

  void attach(RunOptions& opt) {
    if (progress)
      opt.progress = [this](const RunProgress& p) {
        call(*progress, [&] {
          return py::dict(
              py::arg("fraction") = p.fraction, py::arg("axial_strain") = p.axial_strain,
              py::arg("deviatoric_stress_pa") = p.deviatoric_stress, py::arg("cracks") = p.cracks,
              py::arg("steps") = p.steps, py::arg("elapsed_s") = p.elapsed_seconds);
        });
      };
    if (log)
      opt.log = [this](const std::string& message) {
        call(*log, [&] { return py::str(message); });
      };
  }
  // Calls f(argument()) holding the GIL (the argument is a Python object: made under it too).
  template <class Argument>
  void call(const py::function& f, Argument&& argument) {
    py::gil_scoped_acquire gil;
    if (error) return;
    try {
      f(argument());
    } catch (py::error_already_set& e) {
      error = std::make_unique<py::error_already_set>(std::move(e));
      interrupt_flag().store(true);
    }
  }
  void rethrow() {
    if (error) throw *error;
  }
};

RunOptions options(bool progress_bar, std::uint64_t stop_at_step, const std::string& command) {
  RunOptions opt;
  opt.command_line = command;
  opt.interrupt = &interrupt_flag();
  opt.show_progress = progress_bar;
  opt.stop_at_step = stop_at_step;
  return opt;
}

py::dict to_dict(const RunResult& r) {
  return py::dict(
      py::arg("folder") = r.folder, py::arg("status") = r.status,
      py::arg("stop_reason") = r.stop_reason, py::arg("peak_stress_pa") = r.peak_stress,
      py::arg("strain_at_peak") = r.strain_at_peak, py::arg("youngs_modulus_pa") = r.youngs_modulus,
      py::arg("confining_stress_pa") = r.confining_stress,
      py::arg("sigma1_at_peak_pa") = r.sigma1_at_peak, py::arg("poisson_ratio") = r.poisson,
      py::arg("particles") = r.particles, py::arg("bonds") = r.bonds, py::arg("cracks") = r.cracks,
      py::arg("tensile_cracks") = r.tensile, py::arg("shear_cracks") = r.shear,
      py::arg("steps") = r.steps, py::arg("wall_seconds") = r.wall_seconds,
      py::arg("interrupted_by_signal") = false);
}

template <class Body>
py::dict guarded_run(Callbacks& callbacks, RunOptions& opt, Body&& body) {
  InterruptScope scope;
  callbacks.attach(opt);
  RunResult result;
  {
    py::gil_scoped_release release;
    const SubnormalsFlushed flushed;  // the engine's mode while it runs, Python's after
    result = body(opt);
  }
  callbacks.rethrow();
  py::dict d = to_dict(result);
  d["interrupted_by_signal"] = result.status == "interrupted" && scope.interrupted();
  return d;
}

py::dict run(const ExperimentSpec& spec, bool progress_bar, std::optional<py::function> progress,
             std::optional<py::function> log, std::uint64_t stop_at_step,
             const std::string& command) {
  Callbacks callbacks{std::move(progress), std::move(log), nullptr};
  RunOptions opt = options(progress_bar, stop_at_step, command);
  return guarded_run(callbacks, opt, [&](const RunOptions& o) { return run_experiment(spec, o); });
}

py::dict resume(const std::string& folder, int threads, bool progress_bar,
                std::optional<py::function> progress, std::optional<py::function> log,
                std::uint64_t stop_at_step, const std::string& command) {
  Callbacks callbacks{std::move(progress), std::move(log), nullptr};
  RunOptions opt = options(progress_bar, stop_at_step, command);
  return guarded_run(callbacks, opt, [&](const RunOptions& o) {
    return resume_run(folder, ResumeOptions{threads}, o);
  });
}

// Runs a sweep (new or resumed) with the GIL released; its folder, status and runs.
template <class Body>
py::dict guarded_sweep(std::optional<py::function> log, RunOptions& opt, int jobs, Body&& body) {
  Callbacks callbacks{std::nullopt, std::move(log), nullptr};
  opt.jobs = jobs;
  opt.executable = BRECCIA_CLI;
  InterruptScope scope;
  callbacks.attach(opt);
  SweepResult result;
  {
    py::gil_scoped_release release;
    result = body(opt);
  }
  callbacks.rethrow();
  py::list runs;
  for (const RunResult& r : result.runs) runs.append(to_dict(r));
  return py::dict(py::arg("folder") = result.folder, py::arg("status") = result.status,
                  py::arg("runs") = runs, py::arg("interrupted_by_signal") = scope.interrupted());
}

py::dict sweep(const ExperimentSpec& spec, const std::vector<double>& confining_pa,
               const std::vector<double>& strain_rates, const std::string& key,
               const std::vector<std::string>& values, int jobs, bool progress_bar,
               std::optional<py::function> log, const std::string& command) {
  RunOptions opt = options(progress_bar, 0, command);
  return guarded_sweep(std::move(log), opt, jobs, [&](const RunOptions& o) {
    if (!key.empty()) return run_parameter_sweep(spec, key, values, o);
    return strain_rates.empty() ? run_sweep(spec, confining_pa, o)
                                : run_rate_sweep(spec, strain_rates, o);
  });
}

py::dict resume_a_sweep(const std::string& folder, int jobs, bool progress_bar,
                        std::optional<py::function> log, std::uint64_t stop_at_step,
                        const std::string& command) {
  RunOptions opt = options(progress_bar, stop_at_step, command);
  return guarded_sweep(std::move(log), opt, jobs,
                       [&](const RunOptions& o) { return resume_sweep(folder, o); });
}

}  // namespace

void bind_run(py::module_& m) {
  m.def("run", &run, py::arg("spec"), py::arg("progress_bar"), py::arg("progress"), py::arg("log"),
        py::arg("stop_at_step"), py::arg("command"));
  m.def("resume", &resume, py::arg("folder"), py::arg("threads"), py::arg("progress_bar"),
        py::arg("progress"), py::arg("log"), py::arg("stop_at_step"), py::arg("command"));
  m.def("resume_sweep", &resume_a_sweep, py::arg("folder"), py::arg("jobs"),
        py::arg("progress_bar"), py::arg("log"), py::arg("stop_at_step"), py::arg("command"));
  m.def("sweep", &sweep, py::arg("spec"), py::arg("confining_pa"), py::arg("strain_rates"),
        py::arg("key"), py::arg("values"), py::arg("jobs"), py::arg("progress_bar"), py::arg("log"),
        py::arg("command"));
}

}  // namespace breccia::python
