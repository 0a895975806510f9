"""Runs, resumes, sweeps and step-level simulations through the compiled engine (breccia._core):
the same run layer the `breccia` command calls, so a run from Python writes the same run folder,
table for table, as the same run from the command line."""
import os
import sys

import pandas as pd

from . import _core
from .experiment import Experiment, toml_value
from .folders import RunFolder, SweepFolder

InputError = _core.InputError
version = _core.version
commit = _core.commit


def fit_rate_dependence(rates, ucs):
    """The strain-rate law of docs/analysis.md §11, as the rate sweeps fit it: UCS = a exp(b rate)
    (Levenberg-Marquardt from the log-linear start, with standard errors) and, from 4 rates,
    UCS = c + a exp(b rate). `ucs` in any unit (a and c come out in it); returns a dict."""
    return _core.fit_rate_dependence([float(r) for r in rates], [float(u) for u in ucs])


def materials():
    """The material presets as a DataFrame: name and description (with provenance)."""
    return pd.DataFrame(_core.material_presets(), columns=["name", "description"])


def _experiment(experiment, output, threads):
    if experiment is None:
        experiment = Experiment()
    elif isinstance(experiment, dict):
        experiment = Experiment.from_dict(experiment)
    elif not isinstance(experiment, Experiment):
        experiment = Experiment(experiment)  # a path
    changes = {}
    if output is not None:
        changes["output.directory"] = os.fspath(output)
    if threads is not None:
        changes["engine.threads"] = int(threads)
    return experiment.with_(changes) if changes else experiment


def _printer(log):
    if log is True:
        return lambda message: print(message, file=sys.stderr, flush=True)
    return log or None


def _progress(progress, experiment_progress=True):
    """(terminal bar, callback) for a `progress` argument: None = the bar when stderr is a
    terminal; True / False = the bar or nothing; a callable = called with a dict instead."""
    if callable(progress):
        return False, progress
    if progress is None:
        return experiment_progress and sys.stderr.isatty(), None
    return bool(progress), None


def _command(what):
    return f"python: breccia.{what} (breccia {version})"


def _checked(result, what):
    if result["interrupted_by_signal"]:
        e = KeyboardInterrupt()
        e.add_note(f"breccia.{what}: interrupted; what was recorded is kept in "
                   f"{result['folder']}, continue with breccia.resume('{result['folder']}')")
        raise e
    return result


def run(experiment=None, *, output=None, threads=None, progress=None, log=None, stop_at_step=0):
    """Runs an experiment (an Experiment, a TOML path, a dict of sections, or None for the
    default) into a new run folder under `output` (default: the experiment's
    output.directory) and returns it as a RunFolder.

    progress: None (a bar when stderr is a terminal), True, False, or a callable given a dict
    (fraction, axial_strain, deviatoric_stress_pa, cracks, steps, elapsed_s) every 250 ms.
    log: True prints the run's messages to stderr; a callable receives them.
    Ctrl-C stops the run between two steps with a checkpoint and raises KeyboardInterrupt.
    """
    exp = _experiment(experiment, output, threads)
    bar, callback = _progress(progress, exp["output.progress"])
    result = _core.run(exp._spec, bar, callback, _printer(log), int(stop_at_step), _command("run"))
    _checked(result, "run")
    return RunFolder(result["folder"])


def resume(folder, *, threads=None, progress=None, log=None, stop_at_step=0, jobs=1):
    """Continues an interrupted run from its checkpoint, in its folder (the result is the one
    the uninterrupted run gives), and returns the RunFolder; or finishes an interrupted sweep
    in its folder (runs that completed are kept, those with a checkpoint continue, the others
    start; `jobs` as for sweep) and returns the SweepFolder."""
    if os.path.exists(os.path.join(os.fspath(folder), "sweep-plan.json")):
        if threads is not None:
            raise InputError("resume: a sweep's runs keep the threads of their experiment; "
                             "give jobs instead of threads")
        bar, _ = _progress(progress)
        result = _core.resume_sweep(os.fspath(folder), int(jobs), bar, _printer(log),
                                    int(stop_at_step), _command("resume"))
        _checked(result, "resume")
        return SweepFolder(result["folder"])
    bar, callback = _progress(progress)
    result = _core.resume(os.fspath(folder), -1 if threads is None else int(threads), bar,
                          callback, _printer(log), int(stop_at_step), _command("resume"))
    _checked(result, "resume")
    return RunFolder(result["folder"])


def _number(name, k, value):
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError(f"sweep: {name}[{k}] = {value!r}: expected a number") from None


def sweep(experiment=None, *, confining_mpa=None, strain_rates=None, over=None, output=None,
          jobs=1, threads=None, progress=None, log=None):
    """Runs the experiment once per confining stress (MPa) or per strain rate (1/s) of its
    compression test, or once per value of any key (over=("sample.slab_thickness", [5e-3,
    1e-2]): any test), with the fits and trends; returns the SweepFolder. jobs: runs at once
    as child processes of the breccia command (0: as many as the cores allow; 1: one after
    another in this process). An interrupted sweep is finished by resume(folder)."""
    if sum(x is not None for x in (confining_mpa, strain_rates, over)) != 1:
        raise InputError("sweep: give confining_mpa, strain_rates or over (one of them)")
    key, values = "", []
    if over is not None:
        if (not isinstance(over, (tuple, list)) or len(over) != 2 or
                not isinstance(over[0], str)):
            raise InputError(f"sweep: over = {over!r}: allowed: (key, [values]), e.g. "
                             "(\"sample.slab_thickness\", [5e-3, 1e-2])")
        key, given = over
        if isinstance(given, (str, bytes, dict)) or not hasattr(given, "__iter__"):
            raise InputError(f"sweep: over = {over!r}: its values must be a list, e.g. "
                             f"({key!r}, [{given!r}, ...])")
        values = []
        for k, v in enumerate(given):
            try:
                values.append(toml_value(v))
            except TypeError as e:
                raise InputError(f"sweep: over[1][{k}] ({key}) = {e}") from None
    for name, given in (("confining_mpa", confining_mpa), ("strain_rates", strain_rates)):
        if given is not None and (isinstance(given, (str, bytes, dict)) or
                                  not hasattr(given, "__iter__")):
            raise InputError(f"sweep: {name} = {given!r}: expected a list of numbers, e.g. "
                             f"{name}=[{given!r}]")
    exp = _experiment(experiment, output, threads)
    bar, _ = _progress(progress, exp["output.progress"])
    confining = [1e6 * _number("confining_mpa", k, s) for k, s in enumerate(confining_mpa)] \
        if confining_mpa is not None else []
    rates = [_number("strain_rates", k, r) for k, r in enumerate(strain_rates)] \
        if strain_rates is not None else []
    result = _core.sweep(exp._spec, confining, rates, key, values, int(jobs), bar,
                         _printer(log), _command("sweep"))
    _checked(result, "sweep")
    return SweepFolder(result["folder"])


def generate(experiment=None, path=None, *, log=None):
    """Packs and bonds the experiment's sample ([sample] keys) as `breccia generate` does and
    writes it to `path` (a breccia-geometry file, with its packing report in path + ".json");
    returns the packing report. Use it with Experiment(sample={"source": "file", "file": path}).
    """
    if path is None:
        raise InputError("generate: 'path' = (none): the sample file to write")
    exp = _experiment(experiment, None, None)
    return _core.generate(exp._spec, os.fspath(path), _printer(log))


def read_sample(path):
    """A breccia-geometry file as (particles, bonds) DataFrames: tag, x_m, y_m, z_m, radius_m,
    density_kg_m3, motion; and tag1, tag2 of each bond."""
    g = _core.read_sample(os.fspath(path))
    xyz = g["position_m"]
    particles = pd.DataFrame({"tag": g["tag"], "x_m": xyz[:, 0], "y_m": xyz[:, 1],
                              "z_m": xyz[:, 2], "radius_m": g["radius_m"],
                              "density_kg_m3": g["density_kg_m3"], "motion": g["motion"]})
    particles.attrs.update(dimension=g["dimension"], thickness_m=g["thickness_m"])
    bonds = pd.DataFrame(g["bonds"], columns=["tag1", "tag2"])
    return particles, bonds


class Simulation:
    """Step-level access: the experiment's sample built and bonded, its test's boundaries in
    place and consolidated, ready to load, stepped by hand.

        sim = breccia.Simulation(breccia.Experiment("ucs.toml"))
        sim.step(5000)                  # the test's servo walls are steered at every step
        sim.measure()                   # the test's row: strains, stresses, platen forces
        x = sim.positions               # (n, 3) read-only numpy view of the engine's memory
        sim.add_wall("lid", point=(0, 0, 0.02), normal=(0, 0, -1), velocity=(0, 0, -0.01))
        sim.set_local_damping(0.1); sim.set_contact_friction(0.3)

    Array views (positions, radii, velocities, angular_velocities, forces, displacements,
    masses) share the engine's memory: they see every later step and stay valid while the
    simulation lives. Copy one (np.array(view)) to keep a snapshot.
    """

    def __init__(self, experiment=None, *, log=None):
        exp = _experiment(experiment, None, None)
        self.experiment = exp
        self._sim = _core.Simulation(exp._spec, _printer(log))

    def step(self, steps=1):
        """Takes `steps` steps (Ctrl-C stops between two steps with KeyboardInterrupt)."""
        if steps < 0:
            raise InputError(f"Simulation.step: 'steps' = {steps}: allowed: >= 0")
        self._sim.step(int(steps))
        return self

    def measure(self):
        return self._sim.measure()

    @property
    def cracks(self):
        """The broken bonds so far: step, time, ids, position, mode, released energy."""
        c = self._sim.crack_columns
        xyz = c.pop("position_m")
        df = pd.DataFrame(c)
        for k, axis in enumerate("xyz"):
            df.insert(4 + k, f"{axis}_m", xyz[:, k])
        return df

    @property
    def walls(self):
        return pd.DataFrame(self._sim.walls)

    def add_wall(self, name, point, normal, velocity=(0.0, 0.0, 0.0), ramp_s=0.0):
        """A rigid plane through `point` (m) facing the particles along `normal`, moving at
        `velocity` (m/s) reached over `ramp_s` seconds; takes effect at the next step."""
        return self._sim.add_wall(name, tuple(point), tuple(normal), tuple(velocity),
                                  float(ramp_s))

    def add_sphere(self, name, centre, radius, velocity=(0.0, 0.0, 0.0), mass=0.0, ramp_s=0.0):
        """A rigid ball of `radius` (m) centred at `centre` (m). With mass 0 it moves at
        `velocity` (m/s) reached over `ramp_s` seconds; with a mass (kg; 2D: per unit of the
        run's thickness, like the grains) it is a free projectile that starts at `velocity` and
        is then moved by its contact forces and gravity (it does not rotate)."""
        return self._sim.add_sphere(name, tuple(centre), float(radius), tuple(velocity),
                                    float(mass), float(ramp_s))

    def add_rod(self, name, point, axis, radius, velocity=(0.0, 0.0, 0.0), ramp_s=0.0):
        """A rigid rod (a loading nose or roller; 2D: a circle) of `radius` (m) whose axis runs
        through `point` (m) along `axis`, moving at `velocity` (m/s) reached over `ramp_s`
        seconds; the particles stay outside it."""
        return self._sim.add_rod(name, tuple(point), tuple(axis), float(radius),
                                 tuple(velocity), float(ramp_s))

    def set_wall_velocity(self, name, velocity):
        self._sim.set_wall_velocity(name, tuple(velocity))

    def set_contact_friction(self, mu):
        self._sim.set_contact_friction(float(mu))

    def set_local_damping(self, alpha):
        self._sim.set_local_damping(float(alpha))

    def __getattr__(self, name):
        # time, step_count, time_step, dimension, particle_count, intact_bonds, contacts,
        # energy, test, consolidation_steps and the array views.
        if name == "_sim":
            raise AttributeError(name)
        return getattr(self._sim, name)

    def __repr__(self):
        return (f"Simulation({self.experiment.name!r}: {self.particle_count} particles, "
                f"{self.intact_bonds} bonds, step {self.step_count}, t = {self.time:.6g} s)")
