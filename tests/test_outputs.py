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
        png = os.path.join(folder, "stress_strain.png")
        with open(png, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"


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
        expected = ["stress_strain.png", "crack_maps.png", "event_magnitudes.png",
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
        # The catalogue files the figures come from.
        summary = json.load(open(os.path.join(folder, "summary.json")))
        ae = summary["acoustic_emission"]
        events = open(os.path.join(folder, "events.csv")).read().strip().splitlines()
        assert len(events) - 1 == ae["events"] > 10
        assert summary["energy_budget"]["classification"] in ("good", "warning")
        assert summary["fragments"]["count"] >= 1
