"""The Python package (python/breccia) over the same engine: imports from the build tree, runs
that match the command line's byte for byte, DataFrames with the documented columns, the
command line's messages as Python exceptions, interrupt and resume, and step-level access."""
import json
import os
import subprocess
import tempfile

import numpy as np
import pandas as pd
import pytest

import breccia

CLI = os.environ["BRECCIA_CLI"]
SOURCE = os.environ["BRECCIA_SOURCE_DIR"]

# A 2,266-grain UCS sample from a file, loaded through the peak to 0.8 % strain in about 5 s
# (the micro-parameters test_outputs.py uses, so that bonds break at this strain).
SMALL = [
    'sample.source="file"', f'sample.file="{SOURCE}/tests/data/ucs-small.geom"',
    "engine.density_scaling=100", "loading.platen_speed=0.2", "loading.max_strain=0.008",
    "output.snapshot_strain_interval=0", "output.plot=false", 'material.preset="custom"',
    'contact.law="hertz_mindlin"', "contact.shear_modulus=29e9", "contact.poisson_ratio=0.33",
    "contact.friction=0.4", "bond.modulus=8e9", "bond.tensile_strength=30e6",
    "bond.cohesion=300e6"]
TABLES = ["history", "cracks", "events", "indicators", "fragments", "b_value_windows",
          "d2_windows"]
# What differs between two identical runs: the clock.
TIMING = {"wall_seconds", "particle_steps_per_second", "loading_loop"}


def cli_run(out, overrides=SMALL, extra=()):
    cmd = [CLI, "run", "--quiet", "--output", out, *extra]
    for o in overrides:
        cmd += ["--set", o]
    r = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return r.stdout.strip().splitlines()[-1]


def read(path):
    with open(path, "rb") as f:
        return f.read()


def without_timing(summary):
    return {k: v for k, v in summary.items() if k not in TIMING}


def test_package_imports_from_the_build_tree():
    assert breccia.__file__.startswith(os.environ["BRECCIA_PYTHON_DIR"])
    out = subprocess.run([CLI, "version"], capture_output=True, text=True, check=True).stdout
    assert breccia.version in out
    assert "berea" in list(breccia.materials()["name"])


@pytest.fixture(scope="module")
def small_run():
    """SMALL run once from Python for the tests that read it, with its progress calls."""
    calls = []
    with tempfile.TemporaryDirectory() as out:
        run = breccia.run(breccia.Experiment(overrides=SMALL), output=out, progress=calls.append)
        yield run, calls


def test_a_run_from_python_matches_the_command_line_byte_for_byte(small_run):
    py, _ = small_run
    with tempfile.TemporaryDirectory() as out:
        cli = cli_run(os.path.join(out, "cli"))
        assert isinstance(py, breccia.RunFolder) and py.complete
        assert py.summary["bonds_broken"] > 0  # the run breaks bonds: the tables have rows
        for t in TABLES:
            assert read(os.path.join(cli, t + ".csv")) == read(py.file(t + ".csv")), t
        # The resolved experiments differ in the output directory alone.
        assert [line for line in read(os.path.join(cli, "experiment.toml")).splitlines()
                if not line.startswith(b"directory = ")] == \
            [line for line in read(py.file("experiment.toml")).splitlines()
             if not line.startswith(b"directory = ")]
        assert without_timing(json.load(open(os.path.join(cli, "summary.json")))) == \
            without_timing(py.summary)
        assert py.manifest["command"].startswith("python: breccia.run")


def test_dataframes_have_the_documented_columns(small_run):
    run, _ = small_run
    h = run.history
    assert isinstance(h, pd.DataFrame) and len(h) > 10
    for c in ("step", "time_s", "axial_strain", "deviatoric_stress_pa",
              "confining_stress_pa", "lateral_strain", "volumetric_strain",
              "broken_bonds", "tensile_cracks", "shear_cracks", "kinetic_j"):
        assert c in h.columns, c
    assert len(run.cracks) == run.summary["bonds_broken"]
    for c in ("step", "time_s", "x_m", "y_m", "z_m", "mode", "energy_j", "event_id"):
        assert c in run.cracks.columns, c
    assert set(run.cracks["mode"]) <= {"tensile", "shear"}
    for c in ("event_id", "cracks", "mw", "source_type"):
        assert c in run.events.columns, c
    for c in ("axial_strain", "b_value", "d2", "shear_fraction", "mc_var", "ae_var_j2",
              "damage_index"):
        assert c in run.indicators.columns, c
    for c in ("fragment_id", "particles", "mass_kg", "class"):
        assert c in run.fragments.columns, c
    arrays = run.arrays("history")
    assert isinstance(arrays["axial_strain"], np.ndarray)
    assert run.dimension == 3
    assert breccia.read(run.path).path == run.path


def test_bad_arguments_raise_the_command_lines_messages():
    r = subprocess.run([CLI, "run", "--set", "sample.bogus=1"], capture_output=True, text=True)
    assert r.returncode != 0
    cli_message = r.stderr.strip().splitlines()[-1].removeprefix("error: ")
    with pytest.raises(breccia.InputError) as e:
        breccia.Experiment(sample={"bogus": 1})
    assert str(e.value) == cli_message
    assert isinstance(e.value, ValueError)
    with pytest.raises(ValueError, match="engine.threads"):
        breccia.Experiment(engine={"threads": -3})
    with pytest.raises(ValueError, match="cannot open"):
        breccia.Experiment("/no/such/experiment.toml")
    with pytest.raises(TypeError, match="'sample.radius' = .*not a TOML value"):
        breccia.Experiment(sample={"radius": object()})
    with pytest.raises(TypeError, match="'bond.tensile_strength' = .*not a TOML value"):
        breccia.Experiment(overrides={"bond.tensile_strength": {1j}})
    with pytest.raises(FileNotFoundError, match="not a Breccia run"):
        breccia.read(SOURCE)


def test_experiments_from_a_dict_keywords_and_toml_text_agree():
    a = breccia.Experiment.from_dict({"sample": {"max_particles": 900}, "engine": {"seed": 5}})
    b = breccia.Experiment(sample={"max_particles": 900}, engine={"seed": 5})
    c = breccia.Experiment(overrides={"sample.max_particles": 900, "engine.seed": 5})
    d = breccia.Experiment.from_toml(a.to_toml())
    assert a.to_toml() == b.to_toml() == c.to_toml() == d.to_toml()
    assert a.seed == 5 and a["sample.max_particles"] == 900


def test_an_interrupted_run_resumes_from_python_to_the_uninterrupted_result(small_run):
    whole, calls = small_run
    with tempfile.TemporaryDirectory() as out:
        half = whole.manifest["consolidation_steps"] + whole.summary["steps"] // 2
        cut = breccia.run(breccia.Experiment(overrides=SMALL), output=os.path.join(out, "b"),
                          progress=False, stop_at_step=half)
        assert cut.status == "interrupted" and os.path.exists(cut.file("checkpoint.bin"))
        done = breccia.resume(cut.path, progress=False)
        assert done.complete
        for t in ("history", "cracks", "events"):
            assert read(whole.file(t + ".csv")) == read(done.file(t + ".csv")), t
        # The callback came every 250 ms and once at the end, in order.
        fractions = [c["fraction"] for c in calls]
        assert len(calls) >= 1 and fractions == sorted(fractions)
        assert calls[-1]["steps"] == whole.summary["steps"]
        assert {"axial_strain", "deviatoric_stress_pa", "cracks", "elapsed_s"} <= set(calls[-1])


def test_an_exception_in_the_progress_callback_stops_the_run_cleanly():
    class Stop(Exception):
        pass

    def stop(_):
        raise Stop("enough")

    with tempfile.TemporaryDirectory() as out:
        with pytest.raises(Stop):
            breccia.run(breccia.Experiment(overrides=SMALL + ["loading.max_strain=0.05"]),
                        output=out, progress=stop)
        [folder] = os.listdir(out)
        run = breccia.read(os.path.join(out, folder))
        assert run.status == "interrupted"  # marked, tables kept, resumable
        assert os.path.exists(run.file("checkpoint.bin")) and len(run.history) > 0


def test_step_level_access_sees_the_engine_state():
    sim = breccia.Simulation(breccia.Experiment(overrides=SMALL))
    n = sim.particle_count
    x = sim.positions
    assert x.shape == (n, 3) and sim.radii.shape == (n,) and (sim.radii > 0).all()
    assert not x.flags.writeable
    with pytest.raises(ValueError):
        x[0, 0] = 1.0
    before = np.array(x)
    t0, s0 = sim.time, sim.step_count
    sim.step(500)
    assert sim.step_count == s0 + 500
    assert sim.time == pytest.approx(t0 + 500 * sim.time_step, rel=1e-9)
    # The view is the engine's memory: it moved with the particles.
    assert not np.array_equal(before, x)
    row = sim.measure()
    assert row["axial_strain"] > 0 and row["deviatoric_stress_pa"] > 0
    # Total mass from the views equals the sample's (scaled) mass.
    assert sim.masses.sum() == pytest.approx(
        (sim.experiment["engine.density_scaling"] * 4 / 3 * np.pi * 2650 *
         (sim.radii ** 3)).sum(), rel=1e-12)
    assert sim.energy["boundary_work_j"] > 0
    assert list(sim.cracks.columns)[:7] == ["step", "time_s", "id1", "id2", "x_m", "y_m", "z_m"]
    with pytest.raises(breccia.InputError, match="local_damping"):
        sim.set_local_damping(1.5)
    for mu in (float("inf"), float("nan"), -0.1):
        with pytest.raises(breccia.InputError, match="set_contact_friction.*friction.*finite"):
            sim.set_contact_friction(mu)
    walls = len(sim.walls)
    top = float((x[:, 2] + sim.radii).max())
    sim.add_wall("lid", point=(0, 0, top + 1e-3), normal=(0, 0, -1))
    assert len(sim.walls) == walls + 1
    with pytest.raises(breccia.InputError, match="a name no other wall has"):
        sim.add_wall("lid", point=(0, 0, 1), normal=(0, 0, -1))
    sim.step(10)


def test_added_balls_and_rods_move_as_told():
    """A free projectile clear of the sample flies at its start velocity (no gravity, no
    contact); a prescribed rod moves at its velocity; bad shapes are refused by key."""
    sim = breccia.Simulation(breccia.Experiment(overrides=SMALL))
    x = sim.positions
    top = float((x[:, 2] + sim.radii).max())
    centre = (0.0, 0.0, top + 0.01)
    sim.add_sphere("ball", centre=centre, radius=1e-3, velocity=(0, 0, -2.0), mass=1e-4)
    sim.add_rod("nose", point=(0, 0, top + 0.02), axis=(0, 2, 0), radius=5e-4,
                velocity=(0.5, 0, 0))
    walls = sim.walls.set_index("name")
    assert walls.loc["ball", "shape"] == "sphere" and walls.loc["ball", "mass_kg"] == 1e-4
    assert walls.loc["nose", "shape"] == "rod"
    n = 200
    sim.step(n)
    walls = sim.walls.set_index("name")
    travel = n * sim.time_step
    assert walls.loc["ball", "point_m"][2] == pytest.approx(centre[2] - 2.0 * travel, rel=1e-12)
    assert walls.loc["ball", "contacts"] == 0 and walls.loc["nose", "contacts"] == 0
    assert walls.loc["nose", "point_m"][0] == pytest.approx(0.5 * travel, rel=1e-12)
    with pytest.raises(breccia.InputError, match="free projectile"):
        sim.set_wall_velocity("ball", (0, 0, 1))
    with pytest.raises(breccia.InputError, match="radius"):
        sim.add_sphere("b2", centre=(0, 0, 1), radius=0.0)
    with pytest.raises(breccia.InputError, match="mass"):
        sim.add_sphere("b2", centre=(0, 0, 1), radius=1e-3, mass=-1.0)
    with pytest.raises(breccia.InputError, match="axis"):
        sim.add_rod("r2", point=(0, 0, 1), axis=(0, 0, 0), radius=1e-3)
    with pytest.raises(breccia.InputError, match="centre"):
        sim.add_sphere("b2", centre=(0, float("nan"), 1), radius=1e-3)
    with pytest.raises(breccia.InputError, match="a name no other wall has"):
        sim.add_rod("ball", point=(0, 0, 1), axis=(0, 1, 0), radius=1e-3)


def test_ctrl_c_stops_a_python_run_with_a_checkpoint_and_raises_keyboard_interrupt():
    """SIGINT in the middle of breccia.run: the run stops between two steps, its folder is
    marked interrupted with a checkpoint, and the script gets KeyboardInterrupt naming it."""
    import signal
    import sys
    import textwrap
    script = textwrap.dedent(f"""
        import sys, breccia
        def started(p):
            print("started", flush=True)
        try:
            breccia.run(breccia.Experiment(overrides={SMALL + ["loading.max_strain=0.5"]!r}),
                        output=sys.argv[1], progress=started)
        except KeyboardInterrupt as e:
            print("interrupted;", " ".join(getattr(e, "__notes__", [])), flush=True)
        """)
    with tempfile.TemporaryDirectory() as out:
        child = subprocess.Popen([sys.executable, "-c", script, out], stdout=subprocess.PIPE,
                                 text=True, env=os.environ)
        assert child.stdout.readline().strip() == "started"
        child.send_signal(signal.SIGINT)
        rest, _ = child.communicate(timeout=120)
        assert child.returncode == 0
        assert "interrupted;" in rest and "breccia.resume(" in rest
        [folder] = [f for f in os.listdir(out) if f != "samples"]
        run = breccia.read(os.path.join(out, folder))
        assert run.status == "interrupted" and os.path.exists(run.file("checkpoint.bin"))


def test_the_python_example_runs_and_compares_two_presets():
    with tempfile.TemporaryDirectory() as out:
        r = subprocess.run(["/usr/bin/python3", f"{SOURCE}/examples/python/compare_presets.py",
                            out, "3"], capture_output=True, text=True, env=os.environ)
        assert r.returncode == 0, r.stderr
        assert os.path.getsize(os.path.join(out, "compare_presets.png")) > 20000
        rows = {line.split()[0]: line.split() for line in r.stdout.splitlines()
                if line.split() and line.split()[0] in ("berea", "lac_du_bonnet")}
        # The granite is stronger and stiffer than the sandstone.
        assert float(rows["lac_du_bonnet"][2]) > 1.5 * float(rows["berea"][2])
        assert float(rows["lac_du_bonnet"][3]) > 4 * float(rows["berea"][3])


def test_a_sweep_from_python_in_this_process_and_in_child_processes_agree():
    with tempfile.TemporaryDirectory() as out:
        here = breccia.sweep(breccia.Experiment(overrides=SMALL), confining_mpa=[0, 5],
                             output=os.path.join(out, "a"), jobs=1, progress=False)
        children = breccia.sweep(breccia.Experiment(overrides=SMALL), confining_mpa=[0, 5],
                                 output=os.path.join(out, "b"), jobs=2, progress=False)
        assert isinstance(here, breccia.SweepFolder) and here.status == "complete"
        a, b = here.results, children.results
        assert list(a["confining_stress_pa"]) == [0.0, 5e6]
        assert (a["status"] == "complete").all() and (b["status"] == "complete").all()
        # Results do not depend on where a run ran.
        assert list(a["sigma1_at_peak_pa"]) == list(b["sigma1_at_peak_pa"])
        assert a["sigma1_at_peak_pa"][1] > a["sigma1_at_peak_pa"][0]
        assert [r.complete for r in here.runs] == [True, True]
    with pytest.raises(breccia.InputError, match="confining_mpa, strain_rates or over"):
        breccia.sweep(breccia.Experiment(overrides=SMALL))
    with pytest.raises(breccia.InputError, match="allowed: \\(key, \\[values\\]\\)"):
        breccia.sweep(breccia.Experiment(overrides=SMALL), over=["bond.tensile_strength"])
    with pytest.raises(breccia.InputError, match="bond.tensile_strength"):
        breccia.sweep(breccia.Experiment(overrides=SMALL), over=("bond.tensile_strength", [-1.0]))
    # A scalar where a list belongs, a value with no TOML form, a number that is not one: each
    # names the argument, and nothing is written.
    with pytest.raises(breccia.InputError, match="over = .*must be a list"):
        breccia.sweep(breccia.Experiment(overrides=SMALL), over=("bond.tensile_strength", 3e6))
    with pytest.raises(breccia.InputError, match=r"over\[1\]\[1\].*not a TOML value"):
        breccia.sweep(breccia.Experiment(overrides=SMALL),
                      over=("bond.tensile_strength", [3e6, object()]))
    with pytest.raises(breccia.InputError, match="confining_mpa = 5: expected a list"):
        breccia.sweep(breccia.Experiment(overrides=SMALL), confining_mpa=5)
    with pytest.raises(breccia.InputError, match=r"strain_rates\[0\] = 'fast'"):
        breccia.sweep(breccia.Experiment(overrides=SMALL), strain_rates=["fast"])
    with pytest.raises(breccia.InputError, match="given twice"):
        breccia.sweep(breccia.Experiment(overrides=SMALL), confining_mpa=[5, 5])


def test_a_sweep_over_any_key_from_python():
    """over=(key, values) runs once per value, each value checked as an override; the sweep
    reads back with the values as the command writes them."""
    with tempfile.TemporaryDirectory() as out:
        done = breccia.sweep(breccia.Experiment(overrides=SMALL),
                             over=("bond.tensile_strength", [25e6, 30e6]), output=out,
                             progress=False)
        assert done.status == "complete" and done.variable == "bond.tensile_strength"
        assert [r["value"] for r in done.sweep["runs"]] == ["25000000.0", "30000000.0"]
        cracks = [r["cracks"] for r in done.sweep["runs"]]
        assert cracks[0] > cracks[1] > 0, "weaker bonds break more"


def test_resume_finishes_a_stopped_sweep():
    """A sweep stopped by the command (--stop-at-step) is finished by breccia.resume, which
    returns its SweepFolder; its one run continued in its own folder."""
    with tempfile.TemporaryDirectory() as out:
        cmd = [CLI, "sweep", "--jobs", "1", "--stop-at-step", "1000", "--output", out,
               "--confining-mpa", "0"]
        for o in SMALL:
            cmd += ["--set", o]
        r = subprocess.run(cmd, capture_output=True, text=True)
        assert r.returncode == 130, r.stderr
        folder = r.stdout.strip().splitlines()[-1]
        stopped = breccia.read(folder)
        assert stopped.status == "interrupted"
        names = [os.path.basename(r.path) for r in stopped.runs]
        with pytest.raises(breccia.InputError, match="jobs instead of threads"):
            breccia.resume(folder, threads=1)
        done = breccia.resume(folder, progress=False)
        assert isinstance(done, breccia.SweepFolder) and done.status == "complete"
        assert [os.path.basename(r.path) for r in done.runs] == names
        assert done.runs[0].complete and done.results["sigma1_at_peak_pa"][0] > 0


def test_a_sample_generated_from_python_is_the_commands_and_reads_back():
    tiny = ['sample.width=3e-3', 'sample.depth=3e-3', 'sample.height=6e-3']
    with tempfile.TemporaryDirectory() as out:
        cli = os.path.join(out, "cli.geom")
        cmd = [CLI, "generate", "--output", cli]
        for o in tiny:
            cmd += ["--set", o]
        subprocess.run(cmd, capture_output=True, check=True)
        py = os.path.join(out, "py.geom")
        report = breccia.generate(breccia.Experiment(overrides=tiny), py)
        assert read(cli) == read(py)
        particles, bonds = breccia.read_sample(py)
        assert len(particles) == report["particles"] > 100
        assert list(particles.columns) == ["tag", "x_m", "y_m", "z_m", "radius_m",
                                           "density_kg_m3", "motion"]
        assert len(bonds) == report["bonds"] and set(bonds.columns) == {"tag1", "tag2"}
        assert bonds.isin(set(particles["tag"])).all().all()
        with pytest.raises(breccia.InputError, match="cannot open"):
            breccia.read_sample(os.path.join(out, "missing.geom"))
        # Into a folder: refused by the argument's name, with nothing left behind.
        with pytest.raises(breccia.InputError, match="'path' = .*: a file to write, not a folder"):
            breccia.generate(breccia.Experiment(overrides=tiny), out)
        assert sorted(os.listdir(out)) == ["cli.geom", "cli.geom.json", "py.geom", "py.geom.json"]


def test_the_rate_law_fit_reproduces_the_worked_example():
    # docs/analysis.md §11: rates (0.1, 1, 10) /s, UCS (100.501, 105.127, 164.872) MPa -> a = 100 MPa,
    # b = 0.05 s.
    f = breccia.fit_rate_dependence([0.1, 1, 10], [100.501, 105.127, 164.872])
    assert f["valid"] and f["a"] == pytest.approx(100.0, abs=1e-3)
    assert f["b"] == pytest.approx(0.05, abs=1e-5)
    assert not breccia.fit_rate_dependence([1, 2], [5, 6])["valid"]
