"""Run-folder outputs that other programs read: ParaView snapshots (read back with meshio, a VTK
reader from Debian's python3-meshio) and the stress-strain PNG."""
import json
import os
import subprocess
import tempfile
import xml.etree.ElementTree as ET

import meshio

CLI = os.environ["BRECCIA_CLI"]
SOURCE = os.environ["BRECCIA_SOURCE_DIR"]


# The micro-parameters the small sample was written for (the old default), so that these runs
# break bonds at the strains they stop at whatever the default preset becomes.
MATERIAL = ["--set", 'material.preset="custom"', "--set", 'contact.law="hertz_mindlin"',
            "--set", "contact.shear_modulus=29e9", "--set", "contact.poisson_ratio=0.33",
            "--set", "contact.friction=0.4", "--set", "bond.modulus=8e9",
            "--set", "bond.tensile_strength=30e6", "--set", "bond.cohesion=300e6"]


def run_small(out):
    cmd = [CLI, "run", "--quiet", "--output", out,
           "--set", 'sample.source="file"',
           "--set", f'sample.file="{SOURCE}/tests/data/ucs-small.geom"',
           "--set", "engine.density_scaling=100", "--set", "loading.platen_speed=0.2",
           "--set", "loading.max_strain=0.008", "--set", "output.snapshot_strain_interval=0.004"
           ] + MATERIAL
    r = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return r.stdout.strip().splitlines()[-1]


def test_snapshots_and_plot_are_readable():
    with tempfile.TemporaryDirectory() as out:
        folder = run_small(out)
        summary = json.load(open(os.path.join(folder, "summary.json")))
        snaps = os.path.join(folder, "snapshots")
        for kind in ("particles", "bonds", "cracks"):
            root = ET.parse(os.path.join(snaps, f"{kind}.pvd")).getroot()
            files = [d.get("file") for d in root.iter("DataSet")]
            assert len(files) == summary["snapshots"] >= 3
            times = [float(d.get("timestep")) for d in root.iter("DataSet")]
            assert times == sorted(times)
        first = meshio.read(os.path.join(snaps, "particles_00000.vtu"))
        assert len(first.points) == summary["particles"]
        for name in ("radius", "velocity", "displacement", "broken_bonds", "tag"):
            assert name in first.point_data, name
        assert first.point_data["velocity"].shape == (summary["particles"], 3)
        assert (first.point_data["radius"] > 0).all()
        last = sorted(f for f in os.listdir(snaps) if f.startswith("particles_"))[-1]
        final = meshio.read(os.path.join(snaps, last))
        # Every broken bond counts at both of its particles.
        assert final.point_data["broken_bonds"].sum() == 2 * summary["bonds_broken"]
        bonds = meshio.read(os.path.join(snaps, "bonds_00000.vtu"))
        assert sum(len(c.data) for c in bonds.cells) == summary["bonds_initial"]
        cracks = meshio.read(os.path.join(snaps, last.replace("particles", "cracks")))
        assert len(cracks.points) == summary["bonds_broken"]
        check_mechanical_fields(final, meshio.read(os.path.join(snaps, last.replace(
            "particles", "bonds"))), cracks, summary)
        check_paraview_renders(snaps, summary, out)
        check_wall_table(folder)
        png = os.path.join(folder, "stress_strain.png")
        with open(png, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def check_mechanical_fields(particles, bonds, cracks, summary):
    """The fields ParaView users colour and glyph by: grains with their rotation, angular
    velocity and stress tensor; bonds with their loads and breakage index; cracks with the
    normal and radius of their plane."""
    import numpy as np
    n = summary["particles"]
    assert particles.point_data["rotation"].shape == (n, 3)
    assert particles.point_data["angular_velocity"].shape == (n, 3)
    stress = particles.point_data["stress_pa"]
    assert stress.shape == (n, 9)
    tensors = stress.reshape(n, 3, 3)
    assert np.allclose(tensors, tensors.transpose(0, 2, 1), rtol=0, atol=1e-6 * abs(stress).max())
    # The sample was loaded along z to past its peak: its grains carry net axial compression, of
    # the order of the axial stresses the test recorded (volume-weighted mean over the grains).
    volume = 4.0 / 3.0 * np.pi * particles.point_data["radius"] ** 3
    mean_zz = (volume * tensors[:, 2, 2]).sum() / volume.sum()
    assert mean_zz > 0
    # Rotations are angles in [0, pi] about unit axes.
    assert (np.linalg.norm(particles.point_data["rotation"], axis=1) <= np.pi + 1e-9).all()
    intact = sum(len(c.data) for c in bonds.cells)
    assert intact == summary["bonds_initial"] - summary["bonds_broken"]
    for name in ("law", "normal_force_n", "shear_force_n", "twisting_moment_nm",
                 "bending_moment_nm", "sigma_pa", "tau_pa", "breakage_index"):
        assert name in bonds.cell_data, name
        assert len(bonds.cell_data[name][0]) == intact, name
    index = bonds.cell_data["breakage_index"][0]
    # Intact bonds hold: each is below its strength, and a loaded sample has some close to it.
    assert (index >= 0).all() and (index < 1).all()
    assert index.max() > 0.3
    assert (bonds.cell_data["shear_force_n"][0] >= 0).all()
    normals = cracks.point_data["normal"]
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert (cracks.point_data["radius_m"] > 0).all()


def check_wall_table(folder):
    """walls.csv logs every wall at every history row; its platens push the grains with the
    forces history.csv reports as the platen forces (compression-positive along the load)."""
    import csv
    history = list(csv.DictReader(open(os.path.join(folder, "history.csv"))))
    walls = list(csv.DictReader(open(os.path.join(folder, "walls.csv"))))
    assert len(walls) == len(history) > 3
    for h, w in zip(history, walls):
        assert h["step"] == w["step"]
        assert float(w["wall0_platen_bottom_fz_n"]) == float(h["platen_force_bottom_n"])
        assert -float(w["wall1_platen_top_fz_n"]) == float(h["platen_force_top_n"])
    assert float(walls[-1]["wall0_platen_bottom_work_j"]) > 0.0
    manifest = json.load(open(os.path.join(folder, "manifest.json")))
    assert "walls.csv" in manifest["files"]


def virtual_display():
    """Starts Debian's Xvfb on a free display and waits until it accepts connections (pvbatch
    needs an X server to render). Returns the process and the DISPLAY value. The server does not
    reset when its last client leaves (-noreset): the readiness probe below is such a client, and
    so is pvbatch's first connection, and a connection made while the server resets fails (on a
    loaded machine, nearly always)."""
    import socket
    import time
    for number in range(90, 200):
        if not os.path.exists(f"/tmp/.X{number}-lock"):
            break
    path = f"/tmp/.X11-unix/X{number}"
    server = subprocess.Popen(["Xvfb", f":{number}", "-screen", "0", "1024x768x24",
                               "-nolisten", "tcp", "-noreset"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)

    def accepts():
        # A socket file alone may be a dead server's, left behind: ready means it answers.
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
            try:
                probe.connect(path)
                return True
            except OSError:
                return False

    for _ in range(600):
        if server.poll() is not None or accepts():
            break
        time.sleep(0.1)
    assert server.poll() is None and accepts(), "Xvfb did not start"
    return server, f":{number}"


def check_paraview_renders(snaps, summary, out):
    """Debian's ParaView (pvbatch, under a virtual X server) opens the last snapshot, draws the
    grains by axial stress, the bonds by breakage index and the cracks as discs, and reads the
    same fields back."""
    import shutil
    for tool in ("pvbatch", "Xvfb"):
        assert shutil.which(tool), f"{tool} is missing (scripts/bootstrap installs it)"
    png = os.path.join(out, "paraview.png")
    # Should pvbatch still lose its connection ("bad X server connection"), another display is
    # tried (twice); any other failure fails at once.
    for attempt in range(3):
        server, display = virtual_display()
        try:
            r = subprocess.run(["pvbatch", os.path.join(SOURCE, "tests", "paraview_render.py"),
                                snaps, png], capture_output=True, text=True, timeout=300,
                               env={**os.environ, "DISPLAY": display})
        finally:
            server.terminate()
            server.wait()
        if r.returncode == 0 or "bad X server connection" not in r.stdout + r.stderr:
            break
    assert r.returncode == 0, (r.stdout + r.stderr)[:3000]
    seen = json.loads([line for line in r.stdout.splitlines() if line.startswith("{")][-1])
    assert seen["bonds"] == summary["bonds_initial"] - summary["bonds_broken"]
    assert seen["cracks"] == summary["bonds_broken"] > 0
    assert seen["disc_points"] > seen["cracks"]  # each crack drawn as a disc of many points
    assert 0.3 < seen["breakage_index"][1] < 1.0
    assert seen["stress_zz_pa"][1] > 0.0
    with open(png, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    import matplotlib.image
    picture = matplotlib.image.imread(png)
    colours = {tuple(p) for p in picture.reshape(-1, picture.shape[-1])[::7].tolist()}
    assert len(colours) > 50, "the picture shows coloured bonds and grains, not a blank view"


def assert_chromium_loads_every_image(folder, count):
    """Opens a copy of report.html in headless Chromium with a script that, once the page has
    loaded, writes how many images it holds and which failed to decode into the DOM."""
    import shutil
    chromium = shutil.which("chromium")
    assert chromium, "chromium is missing (scripts/bootstrap installs it)"
    probe = ("<script>window.addEventListener('load', () => {"
             "const imgs = [...document.images];"
             "document.body.setAttribute('data-images', imgs.length);"
             "document.body.setAttribute('data-broken', imgs.filter("
             "i => !(i.complete && i.naturalWidth > 0)).map(i => i.alt).join(',') || 'none');"
             "});</script>")
    page = open(os.path.join(folder, "report.html")).read()
    check = os.path.join(folder, "report-check.html")
    with open(check, "w") as f:
        f.write(page.replace("</body>", probe + "</body>"))
    with tempfile.TemporaryDirectory() as profile:
        r = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu",
                            "--disable-dev-shm-usage",
                            f"--user-data-dir={profile}", "--virtual-time-budget=10000",
                            "--dump-dom", "file://" + check],
                           capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    assert f'data-images="{count}"' in r.stdout, r.stdout[:300]
    assert 'data-broken="none"' in r.stdout


def test_report_renders_every_figure():
    """The report of a small run through the peak: every figure exists, is a real PNG of
    reasonable size and is not blank, and report.html embeds them all."""
    import matplotlib.image as mpimg
    with tempfile.TemporaryDirectory() as out:
        cmd = [CLI, "run", "--quiet", "--output", out,
               "--set", 'sample.source="file"',
               "--set", f'sample.file="{SOURCE}/tests/data/ucs-small.geom"',
               "--set", "engine.density_scaling=100", "--set", "output.plot=false",
               "--set", "output.snapshot_strain_interval=0"] + MATERIAL
        folder = subprocess.run(cmd, capture_output=True, text=True,
                                check=True).stdout.strip().splitlines()[-1]
        r = subprocess.run([CLI, "report", folder], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
        expected = ["stress_strain.png", "crack_maps.png", "crack_field_3d.png",
                    "event_magnitudes.png",
                    "b_value_d2.png", "gutenberg_richter.png", "hudson.png",
                    "energy_budget.png", "indicators.png", "fragment_sizes.png"]
        page = open(os.path.join(folder, "report.html")).read()
        for name in expected:
            path = os.path.join(folder, "report", name)
            assert os.path.getsize(path) > 15000, name
            img = mpimg.imread(path)
            assert img.shape[0] > 300 and img.shape[1] > 400, name
            assert img[..., :3].std() > 0.05, f"{name} looks blank"
            assert f"alt='{name}'" in page, name
        # The summary table reads as text with units: no Python list or bool reprs, and it
        # names the sample, the loading and the run that made it.
        table = page[page.index("<table>"):page.index("</table>")]
        for repr_text in ("[&#x27;", "['", "False", "True", "None"):
            assert repr_text not in table, repr_text
        for row in ("<th>sample</th>", "<th>loading</th>", "<th>run</th>", " MPa", " GPa"):
            assert row in table, row
        assert_chromium_loads_every_image(folder, len(expected))
        # The catalogue files the figures come from.
        summary = json.load(open(os.path.join(folder, "summary.json")))
        ae = summary["acoustic_emission"]
        events = open(os.path.join(folder, "events.csv")).read().strip().splitlines()
        assert len(events) - 1 == ae["events"] > 10
        # Whether b falls toward failure is read from the windows up to the peak, and reported.
        trend = ae["b_value_before_peak"]
        assert trend["flag"] in ("", "no_peak", "no_window_before_peak", "too_few_windows")
        assert "<th>b-value before the peak</th>" in table
        assert summary["energy_budget"]["classification"] in ("good", "warning")
        assert summary["fragments"]["count"] >= 1


def test_the_report_carries_the_calibration_record_of_a_library_rock():
    """A run of a calibrated preset reports its record (targets, achieved, verdicts, how to
    reproduce it) and says so when the run overrides calibrated values."""
    with tempfile.TemporaryDirectory() as out:
        rows = {}
        for label, extra in (("as calibrated", []), ("overridden", ["--set", "bond.modulus=9e9"])):
            cmd = [CLI, "run", "--quiet", "--output", out, "--set", 'sample.source="file"',
                   "--set", f'sample.file="{SOURCE}/tests/data/ucs-small.geom"',
                   "--set", "engine.density_scaling=100", "--set", "loading.max_strain=0.002",
                   "--set", "output.plot=false", "--set", "output.snapshot_strain_interval=0",
                   "--set", 'material.preset="berea"', *extra]
            folder = subprocess.run(cmd, capture_output=True, text=True,
                                    check=True).stdout.strip().splitlines()[-1]
            manifest = json.load(open(os.path.join(folder, "manifest.json")))
            assert manifest["material"]["preset"] == "berea"
            assert manifest["material"]["parameters_as_calibrated"] == (label == "as calibrated")
            subprocess.run([CLI, "report", folder], capture_output=True, check=True)
            page = open(os.path.join(folder, "report.html")).read()
            start = page.index("<th>calibration</th>")
            rows[label] = page[start:page.index("</tr>", start)]
        row = rows["as calibrated"]
        for text in ("preset berea", "UCS 96.41 MPa", "against 95 MPa", "met",
                     "examples/calibrate-berea.toml"):
            assert text in row, text
        assert "overrides" not in row
        assert "overrides some of the preset" in rows["overridden"]


def test_a_slab_test_report_draws_its_own_figures_and_a_thickness_sweep_its_trends():
    """An impact on a tiny slab: the report has the ball's figures (no stress-strain curve),
    reads as text, and loads in Chromium; a sweep over the slab's thickness plots its trends."""
    with tempfile.TemporaryDirectory() as out:
        path = os.path.join(out, "impact.toml")
        with open(path, "w") as f:
            f.write('name = "impact"\n[engine]\ndensity_scaling = 1\nlocal_damping = 0\n'
                    '[sample]\nshape = "slab"\nwidth = 0.004\ndepth = 0.004\n'
                    'slab_thickness = 0.0015\nradius_min = 0.2e-3\nradius_max = 0.3e-3\n'
                    '[test]\nkind = "impact"\nprojectile_diameter = 1e-3\nimpact_speed = 60\n'
                    'standoff = 0.02e-3\nduration = 6e-6\n'
                    '[output]\nsnapshot_strain_interval = 0\n')
        r = subprocess.run([CLI, "run", "--quiet", "--output", out, path],
                           capture_output=True, text=True, check=True)
        folder = r.stdout.strip().splitlines()[-1]
        figures = ["impact.png", "impact_energy.png", "impact_cracks.png", "crack_field_3d.png",
                   "fragment_sizes.png"]
        page = open(os.path.join(folder, "report.html")).read()
        for name in figures:
            assert os.path.getsize(os.path.join(folder, "report", name)) > 10000, name
            assert f"alt='{name}'" in page, name
        assert not os.path.exists(os.path.join(folder, "stress_strain.png"))
        table = page[page.index("<table>"):page.index("</table>")]
        for repr_text in ("['", "False", "True", "None"):
            assert repr_text not in table, repr_text
        assert "<th>result</th>" in table and "m/s" in table
        assert_chromium_loads_every_image(folder, len(figures))
        text = subprocess.run([CLI, "summarise", folder], capture_output=True, text=True,
                              check=True).stdout
        assert "ball 1 mm" in text and "fragments:" in text
        r = subprocess.run([CLI, "sweep", path, "--jobs", "1", "--output", out, "--over",
                            "sample.slab_thickness", "1.2e-3", "1.5e-3"],
                           capture_output=True, text=True, check=True)
        sweep_folder = r.stdout.strip().splitlines()[-1]
        sweep = json.load(open(os.path.join(sweep_folder, "sweep.json")))
        assert sweep["variable"] == "sample.slab_thickness"
        assert [e["value"] for e in sweep["runs"]] == ["1.2e-3", "1.5e-3"]
        assert max(e["cracks_scaled"] for e in sweep["runs"]) == 1.0
        assert "max_indentation_m" in sweep["runs"][0]["metrics"]
        assert os.path.exists(os.path.join(sweep_folder, "report", "parameter_trends.png"))
        # A bad key or value is refused before any run, with the experiment's own message.
        bad = subprocess.run([CLI, "sweep", path, "--output", out, "--over",
                              "sample.slab_thicknes", "1e-3"], capture_output=True, text=True)
        assert bad.returncode != 0 and "slab_thicknes" in bad.stderr


def test_a_direct_tension_report_gives_the_tensile_strength_and_where_it_broke():
    """A direct tension run of the small sample: the report names sigma_t = F/A with the grips
    and the share of the cracks next to them, and reads as text."""
    with tempfile.TemporaryDirectory() as out:
        cmd = [CLI, "run", "--quiet", "--output", out, "--set", 'sample.source="file"',
               "--set", f'sample.file="{SOURCE}/tests/data/ucs-small.geom"',
               "--set", "engine.density_scaling=100", "--set", 'test.kind="direct_tension"',
               "--set", "test.platen_speed=0.1", "--set", "test.max_strain=0.01",
               "--set", "output.plot=false", "--set", "output.snapshot_strain_interval=0"
               ] + MATERIAL
        folder = subprocess.run(cmd, capture_output=True, text=True,
                                check=True).stdout.strip().splitlines()[-1]
        summary = json.load(open(os.path.join(folder, "summary.json")))
        assert summary["test_kind"] == "direct_tension" and summary["bonds_broken"] > 0
        # Pulled, the sample narrows: the lateral strain's sign makes Poisson's ratio positive.
        assert 0.0 < summary["poisson_ratio"] < 0.5
        subprocess.run([CLI, "report", folder], capture_output=True, check=True)
        page = open(os.path.join(folder, "report.html")).read()
        assert "<th>direct tensile strength</th><td>sigma_t = F/A = " in page
        assert f"{summary['tensile_strength_mpa']:.2f} MPa" in page
        assert "next to the grips" in page
