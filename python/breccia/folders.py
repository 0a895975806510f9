"""Run, sweep and calibration folders read back as pandas DataFrames, numpy arrays and dicts.

A run folder's tables:
    history      one row per recorded step: strains, stresses (Pa), platen forces, crack counts,
                 energies (J)
    cracks       one row per broken bond: time, place, mode, forces, energy
    events       acoustic-emission events: cracks clustered, magnitudes, moment tensors
    indicators   per strain window: b-value, D2, shear fraction, MCvar, AEvar, damage index
    fragments    fragments at the end: particles, mass, class
    b_value_windows, d2_windows   the windows behind the indicator series
and summary (summary.json) and manifest (manifest.json) as dicts.
"""
import json
import os

import pandas as pd


def _read_json(path):
    with open(path) as f:
        return json.load(f)


class _Folder:
    # The file that makes a folder one of its kind, and the kind's name for errors.
    MARKER, KIND = None, None

    def __init__(self, path):
        self.path = os.path.abspath(os.fspath(path))
        if not os.path.isdir(self.path):
            raise FileNotFoundError(f"{self.path}: not a folder")
        if self.MARKER and not os.path.exists(self.file(self.MARKER)):
            raise FileNotFoundError(f"{self.path}: no {self.MARKER} (not a {self.KIND})")
        self._tables = {}

    def file(self, name):
        return os.path.join(self.path, name)

    def table(self, name):
        """A CSV table of the folder as a DataFrame ('history' or 'history.csv')."""
        file_name = name if name.endswith(".csv") else name + ".csv"
        if file_name not in self._tables:
            path = self.file(file_name)
            if not os.path.exists(path):
                present = sorted(f[:-4] for f in os.listdir(self.path) if f.endswith(".csv"))
                raise FileNotFoundError(f"{self.path}: no {file_name} (tables here: "
                                        f"{', '.join(present) or 'none'})")
            self._tables[file_name] = pd.read_csv(path)
        return self._tables[file_name]

    def arrays(self, name):
        """A CSV table as {column: numpy array}."""
        df = self.table(name)
        return {c: df[c].to_numpy() for c in df.columns}

    def __repr__(self):
        return f"{type(self).__name__}({self.path!r})"


class RunFolder(_Folder):
    """One run: `breccia.read(path)` or the value of `breccia.run(...)`."""

    MARKER, KIND = "manifest.json", "run folder"

    @property
    def manifest(self):
        return _read_json(self.file("manifest.json"))

    @property
    def status(self):
        """complete | interrupted | failed | running (a run killed on the way)."""
        return self.manifest.get("status", "unknown")

    @property
    def complete(self):
        return self.status == "complete"

    @property
    def summary(self):
        path = self.file("summary.json")
        if not os.path.exists(path):
            raise FileNotFoundError(f"{self.path}: no summary.json (the run's status is "
                                    f"{self.status}; an interrupted run continues with "
                                    "breccia.resume)")
        return _read_json(path)

    @property
    def dimension(self):
        """2 or 3, from the run's resolved experiment."""
        import tomllib
        with open(self.file("experiment.toml"), "rb") as f:
            return tomllib.load(f)["engine"]["dimension"]

    @property
    def experiment(self):
        """The run's resolved experiment (experiment.toml) as an Experiment."""
        from .experiment import Experiment
        return Experiment(self.file("experiment.toml"))

    history = property(lambda self: self.table("history"))
    cracks = property(lambda self: self.table("cracks"))
    events = property(lambda self: self.table("events"))
    indicators = property(lambda self: self.table("indicators"))
    fragments = property(lambda self: self.table("fragments"))
    b_value_windows = property(lambda self: self.table("b_value_windows"))
    d2_windows = property(lambda self: self.table("d2_windows"))

    def plot_stress_strain(self, ax=None, label=None):
        """Deviatoric stress (MPa) against axial strain (%) on `ax` (a new figure if None)."""
        import matplotlib.pyplot as plt
        if ax is None:
            _, ax = plt.subplots()
        h = self.history
        ax.plot(100 * h["axial_strain"], 1e-6 * h["deviatoric_stress_pa"],
                label=label or os.path.basename(self.path))
        ax.set_xlabel("axial strain (%)")
        ax.set_ylabel("deviatoric stress (MPa)")
        return ax

    def plot_crack_map(self, ax=None):
        """The cracks' positions across the loading axis (x) and along it (y in 2D, z in 3D),
        tensile and shear apart."""
        import matplotlib.pyplot as plt
        if ax is None:
            _, ax = plt.subplots()
        c = self.cracks
        axial = "y_m" if self.dimension == 2 else "z_m"
        for mode, colour in (("tensile", "tab:blue"), ("shear", "tab:red")):
            part = c[c["mode"] == mode]
            ax.scatter(1e3 * part["x_m"], 1e3 * part[axial], s=4, c=colour,
                       label=f"{mode} ({len(part)})")
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel(f"{axial[0]} (mm)")
        ax.legend(loc="upper right", fontsize="small")
        return ax

    def report(self):
        """Writes report.html and report/*.png; returns the path of report.html."""
        from . import report
        report.run_report(self.path)
        return self.file("report.html")


class SweepFolder(_Folder):
    """A sweep (confining stresses, strain rates, or the values of one key): its runs, trends
    and fits."""

    MARKER, KIND = "sweep.json", "sweep folder"

    @property
    def sweep(self):
        return _read_json(self.file("sweep.json"))

    status = property(lambda self: self.sweep.get("status", "unknown"))
    variable = property(lambda self: self.sweep.get("variable", "confining_stress"))
    mohr_coulomb = property(lambda self: self.sweep.get("mohr_coulomb"))
    hoek_brown = property(lambda self: self.sweep.get("hoek_brown"))
    trends = property(lambda self: self.table("trends"))

    @property
    def runs(self):
        """The sweep's run folders in its order."""
        return [RunFolder(self.file(r["folder"])) for r in self.sweep["runs"]]

    @property
    def results(self):
        """One row per run: sweep.json's per-run results."""
        return pd.DataFrame(self.sweep["runs"])

    def report(self):
        """Writes the sweep's report.html and figures; returns the path of report.html."""
        from . import report
        report.sweep_report(self.path)
        return self.file("report.html")


class CalibrationFolder(_Folder):
    """A `breccia calibrate` folder or an installed material (materials/<name>)."""

    MARKER, KIND = "convergence.csv", "calibration folder"

    trials = property(lambda self: self.table("convergence"))

    @property
    def record(self):
        return _read_json(self.file("record.json"))


def read(path):
    """A run, sweep or calibration folder, whichever `path` is."""
    p = os.fspath(path)
    for kind in (SweepFolder, CalibrationFolder, RunFolder):
        if os.path.exists(os.path.join(p, kind.MARKER)):
            return kind(p)
    raise FileNotFoundError(f"{p}: not a Breccia run, sweep or calibration folder "
                            "(no manifest.json, sweep.json or convergence.csv)")


__all__ = ["RunFolder", "SweepFolder", "CalibrationFolder", "read"]
