"""Breccia, a virtual rock-mechanics laboratory: bonded-particle DEM from Python.

    import breccia
    exp = breccia.Experiment("examples/brazilian.toml", sample={"max_particles": 5000})
    run = breccia.run(exp, output="runs")          # a RunFolder
    run.history.plot(x="axial_strain", y="deviatoric_stress_pa")
    sweep = breccia.sweep(exp, confining_mpa=[0, 5, 10])
    sim = breccia.Simulation(exp)                  # step-level access
    sim.step(1000); sim.positions                  # numpy view of the engine's arrays

The experiment, run, sweep and simulation functions use the compiled engine (breccia._core);
reading run folders (breccia.read) and the report and plots modules need only numpy, pandas and
matplotlib, so the command line can run them in an interpreter without the engine.
"""
from .experiment import Experiment
from .folders import CalibrationFolder, RunFolder, SweepFolder, read

# The engine's names load on first use (PEP 562).
_ENGINE = {"run", "resume", "sweep", "generate", "read_sample", "Simulation", "InputError",
           "materials", "fit_rate_dependence", "version", "commit"}


def __getattr__(name):
    if name in _ENGINE:
        from . import engine
        return getattr(engine, name)
    raise AttributeError(f"module 'breccia' has no attribute '{name}'")


__all__ = ["Experiment", "RunFolder", "SweepFolder", "CalibrationFolder", "read", *sorted(_ENGINE)]
