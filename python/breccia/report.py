"""Self-contained report of a Breccia run or sweep folder: report.html with the figures embedded,
and the figures as PNG under report/.

Usage: python3 -m breccia.report FOLDER (or breccia.report.main(folder))
Run folder: stress-strain with cracks by mode and stages, crack maps by stage (a central section
for 3D samples), event magnitudes over strain, b-value and D2 over strain, Gutenberg-Richter plot,
Hudson source-type plot, energy budget over strain, indicator series, fragment sizes, and the
failure predictor's forecast where `breccia predict apply` has written one.
Sweep folder: Mohr-Coulomb envelope and trends with confinement.
Needs Debian's python3-matplotlib (and numpy).
"""
import csv
import json
import math
import os
import sys

import matplotlib

import matplotlib.pyplot as plt
import numpy as np

from breccia import predict, slab_report
from breccia.report_kit import (CAPTIONS, Table, col, fmt, fmt_range, read_csv, save, wrapped,
                                write_html)

STAGE_COLOURS = {1: "#e8f4e8", 2: "#fff4d6", 3: "#fde2e2", 4: "#e4e4f4"}
STAGE_NAMES = {1: "I initiation", 2: "II nucleation", 3: "III rupture", 4: "IV sliding"}
MODE_COLOURS = {"tensile": "tab:orange", "shear": "tab:red"}


def shade_stages(ax, summary):
    st = summary.get("stages", {}).get("by_stage", [])
    for k, s in enumerate(st, start=1):
        a, b = s.get("axial_strain_from"), s.get("axial_strain_to")
        if a is None or b is None or b <= a:
            continue
        ax.axvspan(a * 100, b * 100, color=STAGE_COLOURS[k], zorder=0, lw=0)
        ax.text((a + b) / 2 * 100, 0.98, ["I", "II", "III", "IV"][k - 1], ha="center",
                va="top", fontsize=7, transform=ax.get_xaxis_transform(), color="0.35")


def stress_strain(folder, summary, hist, outdir, figures):
    e = col(hist, "axial_strain", 100)
    q = col(hist, "deviatoric_stress_pa", 1e-6)
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    shade_stages(ax, summary)
    ax.plot(e, q, "k-", lw=1.6, label="q vs axial strain")
    ax.plot(col(hist, "lateral_strain", 100), q, "b--", lw=0.9, label="q vs lateral strain")
    ax.plot(col(hist, "volumetric_strain", 100), q, "g:", lw=0.9, label="q vs volumetric strain")
    ax.set_xlabel("strain (%), compression positive")
    ax.set_ylabel("deviatoric stress q (MPa)")
    ax2 = ax.twinx()
    ax2.plot(e, col(hist, "tensile_cracks"), color=MODE_COLOURS["tensile"], lw=1.2,
             label="tensile cracks")
    ax2.plot(e, col(hist, "shear_cracks"), color=MODE_COLOURS["shear"], lw=1.2,
             label="shear cracks")
    ax2.set_ylabel("cumulative microcracks")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, loc="upper left", fontsize=7)
    ax.set_title("Stress-strain curve, cracks by mode, deformation stages (shaded)", fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "stress_strain.png", figures)


def run_dimension(summary):
    """2 or 3, as the run's summary records it (older summaries: 2 for a biaxial test only)."""
    return summary.get("dimension", 2 if summary.get("test", "").startswith("biaxial") else 3)


def crack_maps(summary, cracks, outdir, figures):
    if not cracks:
        return
    dim = run_dimension(summary)
    # A test on a disc reports it (disc_diameter_m): its face is drawn whole, loaded along y.
    disc = "disc_diameter_m" in summary
    x = col(cracks, "x_m", 1e3)
    y = col(cracks, "y_m", 1e3)
    z = col(cracks, "z_m", 1e3)
    stage = col(cracks, "stage")
    mode = np.asarray(cracks.column("mode"))
    if disc:
        # The disc's face (x-y), loaded along y; every crack through the thickness projected.
        keep = np.ones(len(x), bool)
        horiz, vert = x, y
        section = "disc face (x-y plane), all cracks through the thickness; load along y"
    elif dim == 3:
        yc = 0.5 * (np.nanmin(y) + np.nanmax(y))
        half = 0.25 * (np.nanmax(y) - np.nanmin(y))
        keep = np.abs(y - yc) <= half
        horiz, vert = x, z
        section = f"central section |y - {yc:.2f} mm| <= {half:.2f} mm (x-z plane)"
    else:
        keep = np.ones(len(x), bool)
        horiz, vert = x, y
        section = "x-y plane"
    fig, axes = plt.subplots(1, 4, figsize=(11, 4.2), sharex=True, sharey=True)
    for k, ax in enumerate(axes, start=1):
        sel = keep & (stage == k)
        for m in ("tensile", "shear"):
            idx = sel & (mode == m)
            ax.scatter(horiz[idx], vert[idx], s=4, c=MODE_COLOURS[m], label=m)
        ax.set_title(f"{STAGE_NAMES[k]} ({int(sel.sum())})", fontsize=8)
        if disc:  # the disc's outline, centred on the cracks' mid-range
            r = 0.5e3 * summary.get("disc_diameter_m", 0.0)
            xc = 0.5 * (np.nanmin(x) + np.nanmax(x))
            yc = 0.5 * (np.nanmin(y) + np.nanmax(y))
            t = np.linspace(0, 2 * np.pi, 200)
            ax.plot(xc + r * np.cos(t), yc + r * np.sin(t), color="0.6", lw=0.8)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
    axes[0].set_ylabel("axial coordinate (mm)")
    axes[0].legend(fontsize=7, loc="lower left")
    fig.suptitle(f"Microcracks by stage, coloured by mode; {section}", fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "crack_maps.png", figures)


def crack_field_3d(summary, cracks, outdir, figures):
    """Every microcrack of a 3D run in perspective from two sides, tensile and shear apart, so
    a shear band or axial splitting shows as a surface (the crack maps show one section)."""
    if not cracks or "disc_diameter_m" in summary or run_dimension(summary) == 2 or \
            not any(col(cracks, "z_m")):
        return
    x, y, z = col(cracks, "x_m", 1e3), col(cracks, "y_m", 1e3), col(cracks, "z_m", 1e3)
    tensile = np.asarray(cracks.column("mode")) == "tensile"
    fig = plt.figure(figsize=(11, 5.5))
    for k, azimuth in enumerate((-60, 30), start=1):
        ax = fig.add_subplot(1, 2, k, projection="3d")
        # Shear cracks drawn last and larger: they are the few, and the band's signature.
        for sel, m, size in ((tensile, "tensile", 3), (~tensile, "shear", 12)):
            ax.scatter(x[sel], y[sel], z[sel], s=size, c=MODE_COLOURS[m], depthshade=True,
                       label=f"{m} ({int(sel.sum())})")
        ax.view_init(elev=15, azim=azimuth)
        ax.set_box_aspect((np.ptp(x) or 1, np.ptp(y) or 1, np.ptp(z) or 1))
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_zlabel("z (mm)")
        ax.set_title(f"seen from azimuth {azimuth} deg", fontsize=9)
    fig.axes[0].legend(fontsize=8, loc="upper left")
    fig.suptitle(wrapped(f"All {len(cracks)} microcracks in 3D, coloured by mode (load along z)"),
                 fontsize=10)
    save(fig, outdir, "crack_field_3d.png", figures)


def magnitudes(summary, events, hist, outdir, figures):
    if not events:
        return
    e = col(events, "axial_strain_first", 100)
    mw = col(events, "mw")
    fig, ax = plt.subplots(figsize=(7.5, 4))
    shade_stages(ax, summary)
    for m in ("tensile", "shear"):
        idx = np.asarray(events.column("dominant_mode")) == m
        ax.scatter(e[idx], mw[idx], s=10, c=MODE_COLOURS[m], label=f"{m}-dominated events")
    mc = summary.get("acoustic_emission", {}).get("completeness_magnitude")
    if mc is not None:
        ax.axhline(mc, color="0.4", ls="--", lw=0.8, label=f"M_c = {mc:.2f}")
    ax.set_xlabel("axial strain (%)")
    ax.set_ylabel("moment magnitude M_w")
    ax2 = ax.twinx()
    ax2.plot(col(hist, "axial_strain", 100), col(hist, "deviatoric_stress_pa", 1e-6), "k-",
             lw=0.8, alpha=0.6)
    ax2.set_ylabel("q (MPa)")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title(f"Acoustic-emission events ({len(events)}) over strain", fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "event_magnitudes.png", figures)


def b_before_peak_text(ae):
    """Whether the b-value falls toward failure: its windows up to the peak (summary.json's
    acoustic_emission.b_value_before_peak)."""
    t = ae.get("b_value_before_peak")
    if t is None:
        return "n/a (not in this run's summary)"
    flag = t.get("flag")
    if flag == "no_peak":
        return "n/a (no peak)"
    if flag == "no_window_before_peak":
        return ("no window: fewer events above the completeness magnitude precede the peak "
                "than a window holds")

    def pct(v):
        return fmt(100 * v if v is not None else None, "{:.3f}")

    text = (f"from {fmt(t.get('first_b'))} at {pct(t.get('first_axial_strain'))} % strain to "
            f"{fmt(t.get('at_peak_b'))} at {pct(t.get('at_peak_axial_strain'))} % over "
            f"{t.get('windows')} window{'' if t.get('windows') == 1 else 's'}")
    rho = t.get("spearman_rho")
    if rho is None:
        return text + " (too few for a trend)"
    trend = "falls" if rho <= -0.5 else "rises" if rho >= 0.5 else "shows no clear trend"
    return text + f"; Spearman rho {rho:.2f}: b {trend} toward the peak"


def b_and_d2(summary, bwin, dwin, ind, outdir, figures):
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7.5, 5.6), sharex=True)
    for ax in (a1, a2):
        shade_stages(ax, summary)
    if bwin:
        eb, b, sb = col(bwin, "axial_strain", 100), col(bwin, "b_value"), col(bwin, "sigma")
        a1.errorbar(eb, b, yerr=sb, fmt="o-", ms=3, lw=0.8, label="event windows")
    if ind:
        a1.plot(col(ind, "axial_strain", 100), col(ind, "b_value"), "-", color="tab:purple",
                lw=0.8, label="strain windows (extended to the minimum count)")
    peak = summary.get("axial_strain_at_peak")
    if peak is not None and summary.get("peak_reached"):
        for ax in (a1, a2):
            ax.axvline(100 * peak, color="k", ls=":", lw=0.8)
        a1.text(100 * peak, 0.02, " peak", fontsize=7, transform=a1.get_xaxis_transform())
    a1.set_ylabel("b-value")
    a1.legend(fontsize=7)
    if dwin:
        a2.plot(col(dwin, "axial_strain", 100), col(dwin, "d2"), "o-", ms=3, lw=0.8,
                label="crack-count windows")
    if ind:
        a2.plot(col(ind, "axial_strain", 100), col(ind, "d2"), "-", color="tab:green", lw=0.8,
                label="strain windows")
    a2.set_ylabel("correlation dimension D2")
    a2.set_xlabel("axial strain (%)")
    a2.legend(fontsize=7)
    ae = summary.get("acoustic_emission", {})
    b_all = ae.get("b_value", {})
    d_all = ae.get("d2", {})
    a1.set_title(wrapped(
        f"b-value: whole test {fmt(b_all.get('b'))} +- {fmt(b_all.get('sigma'))} "
        f"({b_all.get('flag') or 'ok'}); before the peak: {b_before_peak_text(ae)}"), fontsize=8)
    a2.set_title(f"D2 of the crack midpoints: whole test {fmt(d_all.get('d2'))}", fontsize=8)
    fig.tight_layout()
    save(fig, outdir, "b_value_d2.png", figures)


def resolved_experiment(folder):
    """The run's resolved experiment (manifest.json) as a dict; empty if unreadable."""
    try:
        import tomllib
        manifest = json.load(open(os.path.join(folder, "manifest.json")))
        return manifest, tomllib.loads(manifest.get("resolved_experiment", ""))
    except (OSError, ValueError, ImportError):
        return {}, {}


def sample_text(spec, summary):
    s, eng = spec.get("sample", {}), spec.get("engine", {})
    planar = eng.get("dimension") == 2
    if s.get("shape") in ("cylinder",):
        size = f"{fmt(s.get('diameter', 0) * 1e3, '{:g}')} mm diameter x " \
               f"{fmt(s.get('height', 0) * 1e3, '{:g}')} mm"
    elif s.get("shape") == "disk":
        size = f"{fmt(s.get('diameter', 0) * 1e3, '{:g}')} mm diameter"
    else:
        dims = [s.get("width", 0), s.get("height", 0)] if planar else \
            [s.get("width", 0), s.get("depth", 0), s.get("height", 0)]
        size = " x ".join(fmt(d * 1e3, "{:g}") for d in dims) + " mm"
    source = s.get("source", "?")
    how = {"generate": f"packed by {s.get('packing', '?')}", "lattice": "regular lattice",
           "file": "read from a geometry file"}.get(source, source)
    radii = (f"; radii {fmt(s.get('radius_min', 0) * 1e6, '{:g}')}-"
             f"{fmt(s.get('radius_max', 0) * 1e6, '{:g}')} um") if source == "generate" else ""
    return (f"{'2D' if planar else '3D'} {s.get('shape', '?')}, {size} ({how}{radii}); "
            f"{summary.get('particles')} grains, {summary.get('bonds_initial')} bonds"
            + (f" ({summary['bond_sites_initial']} bonded elements)"
               if summary.get("bond_sites_initial", summary.get("bonds_initial"))
               != summary.get("bonds_initial") else ""))


TARGET_NAMES = {"youngs_modulus": "E", "uniaxial_strength": "UCS", "tensile_strength": "TS",
                "poisson_ratio": "nu", "cohesion": "C", "friction_angle_deg": "phi",
                "crack_initiation_ratio": "sigma_ci / UCS", "critical_strain": "peak strain"}


def quantity(value, unit, like=None):
    """A value of a calibration record in the unit a rock mechanic reads (that of `like`, when
    given: a spread in the unit of its mean)."""
    if unit == "Pa":
        giga = abs(like if like is not None else value) >= 1e9
        return f"{value * 1e-9:.4g} GPa" if giga else f"{value * 1e-6:.4g} MPa"
    if unit == "deg":
        return f"{value:.3g} deg"
    return f"{value:.3g}"


def calibration_text(material):
    """The preset's calibration record in one paragraph: each target, lab against achieved
    (mean +/- s.d. over the verification seeds), error and verdict; how to reproduce it."""
    r = material["record"]
    parts = []
    for v in r.get("verdicts", []):
        err = (f"{100 * v['error']:+.1f} %" if v.get("relative")
               else f"{v['error']:+.2f} {'' if v['unit'] == '-' else v['unit']}".rstrip())
        parts.append(f"{TARGET_NAMES.get(v['target'], v['target'])} "
                     f"{quantity(v['mean'], v['unit'])} +/- {quantity(v['sd'], v['unit'], v['mean'])} "
                     f"against {quantity(v['value'], v['unit'])} ({v.get('source', '?')}): "
                     f"{err}, {'met' if v.get('met') else 'MISSED'}")
    sample = r.get("calibration_sample", {})
    text = (f"preset {material['preset']} ({r.get('rock', '?')}): " + "; ".join(parts) +
            f". Verified on {sample.get('particles', '?')} grains over packing seeds "
            f"{', '.join(map(str, r.get('verify_seeds', [])))}; reproduce with `breccia calibrate "
            f"{r.get('calibration_file', '?')}` (breccia {r.get('version', '?')}, "
            f"{r.get('commit', '?')}).")
    if material.get("parameters_as_calibrated") is False:
        text += (" This run overrides some of the preset's calibrated values: the record "
                 "describes the preset, not these parameters.")
    return text


def summary_rows(folder, summary):
    """The report's table: what was tested, on what, how, and the headline results, in words
    and units (never a Python repr)."""
    manifest, spec = resolved_experiment(folder)
    ae = summary.get("acoustic_emission", {})
    eb = summary.get("energy_budget", {})
    qs = summary.get("quasi_static", {})
    rows = [("test", f"{summary.get('test')} at sigma_3 = "
                     f"{fmt(summary.get('confining_stress_pa', 0) * 1e-6, '{:g}')} MPa "
                     f"({summary.get('status')}: {summary.get('stop_reason')})")]
    if spec:
        mat, con, bond = spec.get("material", {}), spec.get("contact", {}), spec.get("bond", {})
        rows.append(("rock", f"material preset {mat.get('preset', '?')}; "
                             f"{con.get('law', '?')} contacts, {bond.get('law', '?')} bonds"))
        rows.append(("sample", sample_text(spec, summary)))
    if manifest and (manifest.get("material") or {}).get("record"):
        rows.append(("calibration", calibration_text(manifest["material"])))
    elastic = ""
    if summary.get("elastic_speed_m_per_s"):
        where = summary.get("slow_down_axial_strain")
        elastic = (f"; {fmt(summary['elastic_speed_m_per_s'], '{:g}')} m/s before the first cracks, "
                   + (f"slowed down from {fmt(100 * where, '{:.3g}')} % axial strain"
                      if where is not None else "never slowed down"))
    adaptive = summary.get("adaptive_loading")
    if adaptive:
        elastic = (f"; adaptive up to {fmt(adaptive['speed_ratio'], '{:g}')} times that, "
                   f"fastest {fmt(adaptive['largest_speed_m_per_s'], '{:.3g}')} m/s")
    rows.append(("loading", f"platens at {fmt(summary.get('platen_speed_m_per_s'), '{:g}')} m/s "
                            f"(strain rate {fmt(summary.get('strain_rate_per_s'), '{:.3g}')} /s"
                            f"{elastic}), "
                            f"density scaling {fmt(summary.get('density_scaling'), '{:g}')}, "
                            f"time step {fmt(summary.get('time_step_s'), '{:.3g}')} s, "
                            f"{summary.get('steps')} steps"))
    if "tensile_strength_reading" in summary:
        # A tensile test says how it reads its strength: its name, formula and specimen.
        t = summary["tensile_strength_reading"]
        rows.append((t["name"], f"sigma_t = {t['formula']} = "
                                f"{fmt(summary.get('tensile_strength_mpa'))} MPa (peak force "
                                f"{fmt(summary.get('peak_force_n'), '{:.1f}')} N, "
                                f"{t['specimen']})"))
    else:
        rows.append(("peak deviatoric stress",
                     f"{fmt(summary.get('peak_deviatoric_stress_mpa'))} MPa at axial strain "
                     f"{fmt(100 * (summary.get('axial_strain_at_peak') or float('nan')), '{:.3f}')} %"))
    rows += [
        ("Young's modulus E_t50 / Poisson's ratio",
         f"{fmt((summary.get('youngs_modulus_pa') or float('nan')) * 1e-9)} GPa / "
         f"{fmt(summary.get('poisson_ratio'), '{:.3f}')}"),
        ("microcracks", f"{summary.get('bonds_broken')} ({summary.get('cracks_tensile')} tensile, "
                        f"{summary.get('cracks_shear')} shear)"),
        ("acoustic emission", f"{ae.get('events')} events (largest {ae.get('largest_event_cracks')} "
                              f"cracks); b-value {fmt(ae.get('b_value', {}).get('b'))} over the "
                              f"test, {fmt_range(ae.get('b_value_window_range'))} in its windows"),
        ("b-value before the peak", b_before_peak_text(ae)),
        ("correlation dimension D2 (crack midpoints)",
         f"{fmt(ae.get('d2', {}).get('d2'))} over the test, "
         f"{fmt_range(ae.get('d2_window_range'))} in its windows"),
        ("energy balance", f"{eb.get('classification', 'n/a')} (largest relative residual "
                           f"{fmt(eb.get('residual_relative_max_after_1pct_work'), '{:.2e}')})"),
        ("quasi-static before the peak",
         ("yes" if qs.get("ok") else "no") +
         f": platen force imbalance {fmt(qs.get('max_platen_force_imbalance_before_peak'), '{:.3g}')}"
         f" (limit 0.05), kinetic / strain energy "
         f"{fmt(qs.get('max_kinetic_to_strain_energy_before_peak'), '{:.3g}')} (limit 0.001)")]
    if manifest:
        rows.append(("run", f"breccia {manifest.get('version')} ({manifest.get('commit')}), "
                            f"seed {manifest.get('seed')}, "
                            f"{manifest.get('threads')} thread{'' if manifest.get('threads') == 1 else 's'}, "
                            f"{fmt(summary.get('wall_seconds'), '{:.0f}')} s on "
                            f"{manifest.get('machine')}"))
    return rows


def gutenberg_richter(summary, events, outdir, figures):
    mw = np.sort(col(events, "mw")[np.isfinite(col(events, "mw"))]) if events else np.array([])
    if len(mw) == 0:
        return
    n_ge = len(mw) - np.arange(len(mw))
    fig, ax = plt.subplots(figsize=(6, 4.4))
    ax.semilogy(mw, n_ge, "ko", ms=3, label="N(>= M)")
    bins = np.arange(math.floor(mw.min() * 10) / 10, mw.max() + 0.1, 0.1)
    hist, edges = np.histogram(mw, bins=bins)
    ax.semilogy(0.5 * (edges[1:] + edges[:-1]), np.where(hist > 0, hist, np.nan), "s",
                color="0.6", ms=3, label="per 0.1 bin")
    ae = summary.get("acoustic_emission", {})
    b = ae.get("b_value", {})
    mc = ae.get("completeness_magnitude")
    if b.get("b") is not None and mc is not None:
        m = np.linspace(mc, mw.max(), 20)
        ax.semilogy(m, 10 ** (b["a"] - b["b"] * m), "r-",
                    label=f"log N = {b['a']:.2f} - {b['b']:.2f} M (M >= {mc:.2f})")
        ax.axvline(mc, color="0.4", ls="--", lw=0.8)
    ax.set_xlabel("moment magnitude M_w")
    ax.set_ylabel("number of events")
    ax.legend(fontsize=7)
    ax.set_title(f"Gutenberg-Richter plot ({len(mw)} events)", fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "gutenberg_richter.png", figures)


def hudson(events, outdir, figures):
    if not events:
        return
    u, v = col(events, "hudson_u"), col(events, "hudson_v")
    if not np.isfinite(u).any():  # 2D: Hudson coordinates are undefined
        return
    fig, ax = plt.subplots(figsize=(5.6, 5.2))
    frame = np.array([(0, 1), (4 / 3, 1 / 3), (0, -1), (-4 / 3, -1 / 3), (0, 1)])
    ax.plot(frame[:, 0], frame[:, 1], "k-", lw=1)
    ax.plot([-1, 1], [0, 0], "k-", lw=0.5)
    ax.plot([0, 0], [-1, 1], "k-", lw=0.5)
    refs = {"DC": (0, 0), "+ISO": (0, 1), "-ISO": (0, -1), "+CLVD": (-1, 0), "-CLVD": (1, 0),
            "+crack": (-4 / 9, 5 / 9), "-crack": (4 / 9, -5 / 9), "+dipole": (-2 / 3, 1 / 3),
            "-dipole": (2 / 3, -1 / 3)}
    for name, (a, b) in refs.items():
        ax.plot(a, b, "k+", ms=6)
        ax.annotate(name, (a, b), fontsize=7, xytext=(3, 3), textcoords="offset points")
    for m in ("tensile", "shear"):
        idx = np.asarray(events.column("dominant_mode")) == m
        ax.scatter(u[idx], v[idx], s=9, c=MODE_COLOURS[m], alpha=0.7,
                   label=f"{m}-dominated events")
    ax.set_xlim(-1.45, 1.45)
    ax.set_ylim(-1.1, 1.1)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title("Hudson source-type plot (u, v); opening = upper left", fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "hudson.png", figures)


def energy_budget(summary, hist, outdir, figures):
    e = col(hist, "axial_strain", 100)
    bond = sum(col(hist, f"bond_{c}_j") for c in
               ("tension", "compression", "shear", "bending", "twisting"))
    # Work of the walls and platens, and of the loads on grains (membranes) where recorded.
    loads = col(hist, "external_load_work_j")
    work = col(hist, "boundary_work_j") + np.where(np.isfinite(loads), loads, 0.0)
    series = [("external work", work, "k", "-"),
              ("bond strain energy", bond, "tab:blue", "-"),
              ("contact strain energy", col(hist, "contact_strain_j"), "tab:cyan", "-"),
              ("kinetic", col(hist, "kinetic_j"), "tab:olive", "-"),
              ("friction", col(hist, "friction_j"), "tab:brown", "-"),
              ("damping", col(hist, "local_damping_j") + col(hist, "viscous_damping_j"),
               "tab:gray", "-"),
              ("released by breaks", col(hist, "released_by_breaks_j"), "tab:red", "-"),
              ("deleted springs", col(hist, "deleted_springs_j"), "tab:pink", "-"),
              ("residual", col(hist, "energy_residual_j"), "m", ":")]
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    shade_stages(ax, summary)
    for name, y, colour, style in series:
        ax.plot(e, y * 1e3, color=colour, ls=style, lw=1.2, label=name)
    eb = summary.get("energy_budget", {})
    ax.set_xlabel("axial strain (%)")
    ax.set_ylabel("energy (mJ)")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title(wrapped(f"Energy budget (balance: {eb.get('classification', 'n/a')}, largest "
                         f"relative residual "
                         f"{fmt(eb.get('residual_relative_max_after_1pct_work'), '{:.2e}')})"),
                 fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "energy_budget.png", figures)


def indicators(summary, ind, outdir, figures):
    if not ind:
        return
    e = col(ind, "axial_strain", 100)
    fig, axes = plt.subplots(4, 1, figsize=(7.5, 7.5), sharex=True)
    panels = [("shear_fraction", "shear fraction"), ("mc_var", "MCvar (cracks^2)"),
              ("ae_var_j2", "AEvar (J^2)"), ("damage_index", "damage index")]
    for ax, (c, label) in zip(axes, panels):
        shade_stages(ax, summary)
        ax.plot(e, col(ind, c), "-", lw=1)
        ax.set_ylabel(label, fontsize=8)
    axes[-1].set_xlabel("axial strain (%)")
    axes[0].set_title("Indicator series in trailing strain windows (NaN = too few cracks)",
                      fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "indicators.png", figures)


# The predictor's two targets as failure_predictions.csv names them: name, unit drawn, scale.
FORECAST_TARGETS = (("stress_to_failure_mpa", "stress to failure", "MPa", 1.0),
                    ("strain_to_failure", "strain to failure", "%", 100.0))


def forecast_scores(preds, summary):
    """R^2 and RMSE of each target over the forecast's windows up to the peak, where the run's
    peak gives actual values (an empty dict otherwise)."""
    if not preds or not summary.get("peak_reached"):
        return {}
    pre = col(preds, "axial_strain") <= summary.get("axial_strain_at_peak", float("nan"))
    scores = {}
    for target, _, _, scale in FORECAST_TARGETS:
        y = col(preds, f"actual_{target}", scale)[pre]
        p = col(preds, f"predicted_{target}", scale)[pre]
        keep = np.isfinite(y) & np.isfinite(p)
        if keep.sum() >= 2:
            scores[target] = (predict.r2(y[keep], p[keep]), predict.rmse(y[keep], p[keep]),
                              int(keep.sum()))
    return scores


def failure_forecast(summary, preds, outdir, figures):
    """The failure predictor's forecast along the run (`breccia predict apply` writes
    failure_predictions.csv): predicted beside actual stress and strain to failure."""
    if not preds:
        return
    e = col(preds, "axial_strain", 100)
    scores = forecast_scores(preds, summary)
    # "To failure" has a meaning only up to the peak: after it the actual values are not drawn.
    pre = e <= 100 * summary.get("axial_strain_at_peak", float("nan"))
    fig, axes = plt.subplots(2, 1, figsize=(7.5, 5.6), sharex=True)
    for ax, (target, name, unit, scale) in zip(axes, FORECAST_TARGETS):
        shade_stages(ax, summary)
        ax.plot(e[pre], col(preds, f"actual_{target}", scale)[pre], "k-", lw=1.2, label="actual")
        ax.plot(e, col(preds, f"predicted_{target}", scale), ".", ms=3, color="tab:blue",
                label="forecast")
        if summary.get("peak_reached"):
            ax.axvline(100 * summary["axial_strain_at_peak"], color="tab:red", ls="--", lw=0.8,
                       label="peak")
        ax.axhline(0.0, color="grey", lw=0.5)
        ax.set_ylabel(f"{name} ({unit})", fontsize=8)
        if target in scores:
            r2, err, n = scores[target]
            ax.set_title(f"R^2 {fmt(r2, '{:.2f}')}, RMSE {fmt(err, '{:.3g}')} over {n} "
                         "windows before the peak", fontsize=8)
        ax.legend(fontsize=7)
    axes[-1].set_xlabel("axial strain (%)")
    fig.suptitle("Failure forecast of the predictor (breccia predict apply)", fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "failure_forecast.png", figures)


def fragment_sizes(summary, frags, outdir, figures):
    if not frags:
        return
    m = np.sort(col(frags, "mass_kg") * 1e3)[::-1]
    n_ge = np.arange(1, len(m) + 1)
    fig, ax = plt.subplots(figsize=(6, 4.4))
    ax.loglog(m, n_ge, "ko", ms=3)
    if len(m):
        ax.axvline(0.1 * m[0], color="tab:blue", ls="--", lw=0.8, label="0.1 x largest")
        ax.axvline(0.9 * m[0], color="tab:red", ls="--", lw=0.8, label="0.9 x largest")
    f = summary.get("fragments", {})
    ax.set_xlabel("fragment mass (g)")
    ax.set_ylabel("number of fragments N(>= m)")
    ax.legend(fontsize=7)
    ax.set_title(wrapped(f"Fragments after the test: {f.get('count', len(m))} "
                         f"({f.get('single_particle_debris', 'n/a')} single grains), largest "
                         f"{fmt(100 * f.get('largest_fraction_of_total', float('nan')), '{:.1f}')}"
                         " % of the mass"), fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "fragment_sizes.png", figures)


def slab_test_report(folder, summary, hist, cracks, outdir):
    """Slab and dynamic tests (breccia.slab_report): their own figures and rows, then the
    crack field, fragments and energy ledger every run has."""
    figures = []
    kind = summary.get("test_kind")
    rows = [("test", f"{summary.get('test')} ({summary.get('status')}: "
                     f"{summary.get('stop_reason')})")]
    rows += slab_report.SECTIONS[kind](folder, summary, hist, cracks, outdir, figures)
    crack_field_3d(summary, cracks, outdir, figures)
    fragment_sizes(summary, read_csv(os.path.join(folder, "fragments.csv")), outdir, figures)
    rows += [r for r in summary_rows(folder, summary) if r[0] in SHARED_ROWS]
    for w in summary.get("warnings", []):
        rows.append(("warning", w))
    write_html(folder, f"Breccia report: {summary.get('experiment', '')}", rows, figures,
               {**CAPTIONS, **slab_report.CAPTIONS})
    return figures


def forecast_rows(preds, summary):
    if not preds:
        return []
    scores = forecast_scores(preds, summary)
    text = ", ".join(f"{name} R^2 {fmt(scores[t][0], '{:.2f}')} (RMSE "
                     f"{fmt(scores[t][1], '{:.3g}')} {unit})"
                     for t, name, unit, _ in FORECAST_TARGETS if t in scores)
    return [("failure forecast", f"{len(preds)} windows (failure_predictions.csv); " +
             (text + " over the windows before the peak" if text else
              "no actual values beside it (the run has no peak)"))]


# The rows of summary_rows that slab and dynamic tests share with compression tests.
SHARED_ROWS = ("rock", "sample", "calibration", "microcracks", "acoustic emission",
               "energy balance", "run")


CRACK_COLUMNS = ("x_m", "y_m", "z_m", "mode", "stage")
EVENT_COLUMNS = ("axial_strain_first", "mw", "dominant_mode", "hudson_u", "hudson_v")


def run_report(folder):
    summary = json.load(open(os.path.join(folder, "summary.json")))
    hist = read_csv(os.path.join(folder, "history.csv"))
    if not hist:
        sys.exit(f"{folder}/history.csv has no rows")
    # Only the columns the figures draw: a large run's catalogues have hundreds of thousands of rows.
    cracks = read_csv(os.path.join(folder, "cracks.csv"), CRACK_COLUMNS)
    events = read_csv(os.path.join(folder, "events.csv"), EVENT_COLUMNS)
    outdir = os.path.join(folder, "report")
    os.makedirs(outdir, exist_ok=True)
    if "headline" in summary.get(summary.get("test_kind"), {}):
        return slab_test_report(folder, summary, hist, cracks, outdir)
    figures = []
    stress_strain(folder, summary, hist, outdir, figures)
    crack_maps(summary, cracks if "stage" in cracks else Table({}, 0), outdir, figures)
    crack_field_3d(summary, cracks, outdir, figures)
    magnitudes(summary, events, hist, outdir, figures)
    b_and_d2(summary, read_csv(os.path.join(folder, "b_value_windows.csv")),
             read_csv(os.path.join(folder, "d2_windows.csv")),
             read_csv(os.path.join(folder, "indicators.csv")), outdir, figures)
    gutenberg_richter(summary, events, outdir, figures)
    hudson(events, outdir, figures)
    energy_budget(summary, hist, outdir, figures)
    indicators(summary, read_csv(os.path.join(folder, "indicators.csv")), outdir, figures)
    fragment_sizes(summary, read_csv(os.path.join(folder, "fragments.csv")), outdir, figures)
    preds = read_csv(os.path.join(folder, "failure_predictions.csv"))
    failure_forecast(summary, preds, outdir, figures)
    rows = summary_rows(folder, summary)
    rows += forecast_rows(preds, summary)
    cp = summary.get("crack_pattern", {})
    if cp.get("quarter_shares_along_axis"):
        rows.append(("cracks per quarter along the load",
                     " / ".join(fmt(v) for v in cp["quarter_shares_along_axis"]) +
                     " (from the bottom platen)"))
    if cp.get("brazilian"):
        b = cp["brazilian"]
        rows.append(("split", f"{fmt(100 * b.get('all_in_band_share', 0), '{:.0f}')} % of the "
                              f"cracks within {fmt(b.get('band_half_width_fraction_of_radius'))} R "
                              f"of the loaded diameter (first 20 %: "
                              f"{fmt(100 * b.get('early_in_band_share', 0), '{:.0f}')} %, "
                              f"{fmt(100 * b.get('early_tensile_share', 0), '{:.0f}')} % tensile)"))
    if cp.get("direct_tension"):
        d = cp["direct_tension"]
        rows.append(("break", f"{fmt(100 * d.get('next_to_grips_share', 0), '{:.0f}')} % of the "
                              "cracks in the two tenths of the free length next to the grips "
                              "(a uniform scatter: 20 %)"))
    for w in summary.get("warnings", []):
        rows.append(("warning", w))
    write_html(folder, f"Breccia report: {summary.get('experiment', '')}", rows, figures,
               CAPTIONS)
    return figures


def nan_if_none(v):
    return float("nan") if v is None else float(v)


def indicator_row_at(rows, strain):
    """The indicator row of the last window that ends at or before `strain` (the state at it)."""
    best = None
    for r in rows:
        try:
            if float(r["axial_strain"]) <= strain + 1e-12:
                best = r
        except (KeyError, ValueError):
            pass
    return best or {}


def run_trends(folder, entry):
    """One test of a sweep as the numbers its trends plot: strengths at the stage boundaries,
    crack modes, damage index, b-value and D2 at failure, and the energy partition at the end."""
    run = os.path.join(folder, entry["folder"])
    summary = json.load(open(os.path.join(run, "summary.json")))
    ind = read_csv(os.path.join(run, "indicators.csv"))
    peak = summary.get("axial_strain_at_peak") or 0.0
    at_peak = indicator_row_at(ind, peak)
    num = lambda row, k: float(row[k]) if row.get(k) not in (None, "", "nan") else float("nan")
    t = {"confining_stress_mpa": entry["confining_stress_pa"] * 1e-6,
         "peak_q_mpa": entry["peak_deviatoric_stress_pa"] * 1e-6,
         "sigma1_at_peak_mpa": entry["sigma1_at_peak_pa"] * 1e-6,
         "axial_strain_at_peak": peak,
         "crack_initiation_mpa": nan_if_none(summary.get("crack_initiation_stress_pa")) * 1e-6,
         "crack_damage_mpa": nan_if_none(summary.get("crack_damage_stress_pa")) * 1e-6,
         "youngs_modulus_gpa": nan_if_none(entry.get("youngs_modulus_pa")) * 1e-9,
         "cracks": summary.get("bonds_broken", 0)}
    # Where stages I-III end (docs/analysis.md §8), as axial strain; NaN where a stage is missing.
    stages = summary.get("stages", {}).get("by_stage", [])
    for k, label in enumerate(("I", "II", "III")):
        end = stages[k].get("axial_strain_to") if k < len(stages) else None
        t[f"stage_{label}_end_strain"] = nan_if_none(end)
    cracks = summary.get("cracks_tensile", 0) + summary.get("cracks_shear", 0)
    t["shear_fraction_end"] = summary.get("cracks_shear", 0) / cracks if cracks else float("nan")
    cum = num(at_peak, "cumulative_cracks")
    t["shear_fraction_at_peak"] = num(at_peak, "cumulative_shear") / cum if cum > 0 else float("nan")
    t["damage_index_at_peak"] = num(at_peak, "damage_index")
    t["porosity_at_peak"] = num(at_peak, "porosity")
    t["b_value_at_peak"] = num(at_peak, "b_value")
    t["d2_at_peak"] = num(at_peak, "d2")
    end = summary.get("energy_budget", {}).get("at_end", {})
    w = end.get("external_work_j") or float("nan")
    bond = end.get("bond_strain_j", {}).get("total", 0.0)
    t["fracture_share"] = end.get("released_by_breaks_j", float("nan")) / w
    t["friction_share"] = end.get("friction_j", float("nan")) / w
    t["strain_energy_share"] = (bond + end.get("contact_strain_j", 0.0)) / w
    t["damping_share"] = end.get("damping_j", float("nan")) / w
    t["axial_strain_at_end"] = end.get("axial_strain", float("nan"))
    return t


def write_trends_csv(folder, trends):
    if not trends:
        return
    path = os.path.join(folder, "trends.csv")
    with open(path + ".tmp", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(trends[0].keys()))
        w.writeheader()
        for t in trends:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in t.items()})
    os.replace(path + ".tmp", path)


def trend_figures(trends, outdir, figures):
    s3 = np.array([t["confining_stress_mpa"] for t in trends])
    get = lambda k: np.array([t[k] for t in trends], dtype=float)
    fig, ax = plt.subplots(2, 3, figsize=(12, 7))
    a = ax[0, 0]
    a.plot(s3, get("peak_q_mpa"), "ko-", label="peak q")
    a.plot(s3, get("crack_damage_mpa"), "s--", color="tab:purple", label="crack damage q_cd")
    a.plot(s3, get("crack_initiation_mpa"), "^--", color="tab:green", label="crack initiation q_ci")
    a.set_ylabel("deviatoric stress q (MPa)")
    a.set_title("Strength and stage boundaries", fontsize=9)
    a.legend(fontsize=7)
    a = ax[0, 1]
    a.plot(s3, 100 * get("shear_fraction_end"), "ro-", label="whole test")
    a.plot(s3, 100 * get("shear_fraction_at_peak"), "r^--", label="up to the peak")
    a.set_ylabel("shear cracks (%)")
    a.set_title("Shear-crack fraction", fontsize=9)
    a.legend(fontsize=7)
    a = ax[0, 2]
    a.plot(s3, get("damage_index_at_peak"), "bo-")
    a.axhline(0, color="0.6", lw=0.8)
    a.set_ylabel("damage index at the peak")
    a.set_title("Damage index (n - n0) / n0 at the peak: > 0 dilatant", fontsize=9)
    a = ax[1, 0]
    for key, label, c in (("fracture_share", "fracture (bond breaks)", "tab:red"),
                          ("friction_share", "friction", "tab:orange"),
                          ("strain_energy_share", "strain energy", "tab:blue"),
                          ("damping_share", "damping", "0.5")):
        a.plot(s3, 100 * get(key), "o-", color=c, label=label)
    a.set_ylabel("% of external work (end of test)")
    a.set_title("Energy partition", fontsize=9)
    a.legend(fontsize=7)
    a = ax[1, 1]
    a.plot(s3, get("b_value_at_peak"), "ko-", label="b-value")
    a.set_ylabel("b-value at failure")
    if np.all(np.isnan(get("b_value_at_peak"))):
        a.text(0.5, 0.5, "no b-value at the peak:\ntoo few events in its window", ha="center",
               va="center", transform=a.transAxes, fontsize=8, color="0.4")
    a2 = a.twinx()
    a2.plot(s3, get("d2_at_peak"), "gs--", label="D2")
    a2.set_ylabel("D2 at failure", color="g")
    a.set_title("b-value and D2 at failure (window ending at the peak)", fontsize=9)
    a = ax[1, 2]
    a.plot(s3, get("youngs_modulus_gpa"), "bo-")
    a.set_ylabel("E_t50 (GPa)")
    a3 = a.twinx()
    a3.plot(s3, get("cracks"), "r^-")
    a3.set_ylabel("cracks", color="r")
    a.set_title("Modulus and crack count", fontsize=9)
    for a in ax.flat:
        a.set_xlabel("sigma3 (MPa)")
    fig.suptitle("Trends with confinement", fontsize=10)
    fig.tight_layout()
    save(fig, outdir, "trends.png", figures)


def stress_oscillation(hist):
    """Largest |q - q_smooth| before the peak over the peak, q_smooth a centred moving average
    over 5 history rows: how far the stress rings around its trend (inertia at high rates)."""
    q = col(hist, "deviatoric_stress_pa")
    if len(q) < 7 or not np.isfinite(q).any():
        return float("nan")
    ip = int(np.nanargmax(q))
    if ip < 6:
        return float("nan")
    smooth = np.convolve(q, np.ones(5) / 5, mode="same")
    band = slice(2, ip - 2)  # rows with a full window, up to the peak
    return float(np.nanmax(np.abs(q[band] - smooth[band])) / q[ip])


def number_or_nan(v):
    return float("nan") if v is None else float(v)


def rate_curves(folder, runs, fit, outdir, figures):
    """The stress-strain curves and damage ratios of a rate sweep's runs (rate_curves.png); one
    row per run for rates.csv: rate, UCS, dynamic increase, damage, failure plane, planarity,
    stress oscillation."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4.2))
    table = []
    for r in runs:
        hist = read_csv(os.path.join(folder, r["folder"], "history.csv"))
        eps = col(hist, "axial_strain", 100)
        broken, intact = col(hist, "broken_bonds"), col(hist, "intact_bonds")
        label = f"{r['strain_rate_per_s']:.3g} /s"
        a1.plot(eps, col(hist, "deviatoric_stress_pa", 1e-6), lw=1, label=label)
        a2.plot(eps, 100 * broken / np.maximum(broken + intact, 1), lw=1, label=label)
        fp = r.get("failure_plane", {})
        table.append([r["strain_rate_per_s"], r["peak_deviatoric_stress_pa"] * 1e-6,
                      r["peak_deviatoric_stress_pa"] / fit["a_pa"] if fit.get("valid") else
                      float("nan"), r.get("damage_ratio_percent", float("nan")),
                      number_or_nan(fp.get("angle_from_normal_plane_deg")),
                      number_or_nan(fp.get("planarity")), stress_oscillation(hist)])
    a1.set_xlabel("axial strain (%)")
    a1.set_ylabel("deviatoric stress (MPa)")
    a1.set_title("Stress-strain curves", fontsize=9)
    a2.set_xlabel("axial strain (%)")
    a2.set_ylabel("damage ratio D (% of the bonds broken)")
    a2.set_title("Damage ratio over strain", fontsize=9)
    for a in (a1, a2):
        a.legend(fontsize=7)
    fig.tight_layout()
    save(fig, outdir, "rate_curves.png", figures)
    return table


def rate_sweep_report(folder, sweep):
    """A strain-rate sweep: UCS against the rate with its fit (docs/analysis.md §11), the stress-strain
    curves, the damage ratio over strain, and the failure plane against the rate."""
    runs = [r for r in sweep["runs"] if r.get("status") == "complete"]
    outdir = os.path.join(folder, "report")
    os.makedirs(outdir, exist_ok=True)
    figures = []
    rate = np.array([r["strain_rate_per_s"] for r in runs])
    ucs = np.array([r["peak_deviatoric_stress_pa"] for r in runs]) * 1e-6
    fit = sweep.get("rate_dependence", {})
    fig, ax = plt.subplots(figsize=(6, 4.6))
    ax.plot(rate, ucs, "ko", label="tests")
    if fit.get("valid") and len(rate):
        x = np.geomspace(rate.min(), rate.max(), 100)
        ax.plot(x, fit["a_pa"] * 1e-6 * np.exp(fit["b_s"] * x), "r-",
                label=f"UCS = a exp(b rate): a = {fit['a_pa'] * 1e-6:.1f} MPa, "
                      f"b = {fit['b_s']:.4g} s")
        three = fit.get("three_parameter", {})
        if three.get("valid"):
            ax.plot(x, (three["c_pa"] + three["a_pa"] * np.exp(three["b_s"] * x)) * 1e-6, "b--",
                    label=f"c + a exp(b rate): quasi-static {three['quasi_static_pa'] * 1e-6:.1f} MPa")
    ax.set_xscale("log")
    ax.set_xlabel("strain rate (1/s)")
    ax.set_ylabel("UCS (MPa)")
    ax.legend(fontsize=7)
    ax.set_title(wrapped("UCS against strain rate" + ("" if fit.get("valid") else
                                                       f" (no fit: {fit.get('flag')})")), fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "rate_dependence.png", figures)
    table = rate_curves(folder, runs, fit, outdir, figures)
    fig, ax = plt.subplots(figsize=(6, 4.2))
    t = np.array(table) if table else np.zeros((0, 7))
    if len(t):
        ax.plot(t[:, 0], t[:, 4], "ko-")
    ax.set_xscale("log")
    ax.set_xlabel("strain rate (1/s)")
    ax.set_ylabel("failure plane to the plane normal to the load (deg)")
    ax.set_title(wrapped("Failure plane of the crack midpoints (principal components; 90 = axial "
                         "splitting)"), fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "failure_plane.png", figures)
    with open(os.path.join(folder, "rates.csv.tmp"), "w") as f:
        f.write("strain_rate_per_s,ucs_mpa,dynamic_increase_factor,damage_ratio_percent,"
                "failure_plane_deg,planarity,stress_oscillation_relative\n")
        for row in table:
            f.write(",".join(fmt(v, "{:.6g}") for v in row) + "\n")
    os.replace(os.path.join(folder, "rates.csv.tmp"), os.path.join(folder, "rates.csv"))
    rows = [("experiment", sweep.get("experiment")), ("tests", len(runs)),
            ("sample length along the load", f"{fmt(sweep.get('sample_length_m', 0) * 1e3)} mm"),
            ("rate law UCS = a exp(b rate)",
             f"a = {fmt((fit.get('a_pa') or float('nan')) * 1e-6)} +- "
             f"{fmt((fit.get('a_standard_error_pa') or float('nan')) * 1e-6)} MPa, b = "
             f"{fmt(fit.get('b_s'), '{:.4g}')} +- {fmt(fit.get('b_standard_error_s'), '{:.2g}')} s"
             if fit.get("valid") else f"no fit ({fit.get('flag')})"),
            ("stress oscillation", "largest |q - its 5-row moving average| before the peak, "
                                   "over the peak (rates.csv)"),
            ("rate table", "rates.csv in the sweep folder (one row per test)")]
    write_html(folder, f"Breccia strain-rate sweep: {sweep.get('experiment', '')}", rows, figures,
               CAPTIONS)
    return figures


def sweep_report(folder):
    sweep = json.load(open(os.path.join(folder, "sweep.json")))
    if sweep.get("variable") == "strain_rate":
        return rate_sweep_report(folder, sweep)
    if sweep.get("variable") != "confining_stress":
            return slab_report.parameter_sweep_report(folder, sweep)
    runs = [r for r in sweep["runs"] if r.get("status") == "complete"]
    outdir = os.path.join(folder, "report")
    os.makedirs(outdir, exist_ok=True)
    figures = []
    s3 = np.array([r["confining_stress_pa"] for r in runs]) * 1e-6
    s1 = np.array([r["sigma1_at_peak_pa"] for r in runs]) * 1e-6
    fig, ax = plt.subplots(figsize=(6, 4.6))
    ax.plot(s3, s1, "ko", label="tests (sigma1 at peak)")
    x = np.linspace(0, max(s3.max() if len(s3) else 1, 1) * 1.1, 50)
    mc = sweep.get("mohr_coulomb", {})
    if mc.get("valid"):
        ax.plot(x, mc["ucs_intercept_pa"] * 1e-6 + mc["k"] * x, "r-",
                label=f"Mohr-Coulomb: c = {mc['cohesion_pa'] * 1e-6:.2f} MPa, "
                      f"phi = {mc['friction_angle_deg']:.1f} deg")
    hb = sweep.get("hoek_brown", {})
    if hb.get("valid"):
        sci, mi = hb["sigma_ci_pa"] * 1e-6, hb["m_i"]
        ax.plot(x, x + sci * np.sqrt(mi * x / sci + 1), "b--",
                label=f"Hoek-Brown: sigma_ci = {sci:.1f} MPa, m_i = {mi:.2f}")
    ax.set_xlabel("sigma3 (MPa)")
    ax.set_ylabel("sigma1 at peak (MPa)")
    ax.legend(fontsize=7)
    ax.set_title("Strength envelope", fontsize=9)
    fig.tight_layout()
    save(fig, outdir, "mohr_coulomb.png", figures)
    trends = [run_trends(folder, r) for r in runs]
    write_trends_csv(folder, trends)
    trend_figures(trends, outdir, figures)
    rows = [("experiment", sweep.get("experiment")), ("tests", len(runs)),
            ("Mohr-Coulomb", f"C = {fmt((mc.get('cohesion_pa') or float('nan')) * 1e-6)} MPa, "
                             f"phi = {fmt(mc.get('friction_angle_deg'), '{:.1f}')} deg, "
                             f"R^2 = {fmt(mc.get('r2'), '{:.3f}')}" if mc.get("valid") else
             f"no fit ({mc.get('flag')})"),
            ("Hoek-Brown", f"sigma_ci = {fmt((hb.get('sigma_ci_pa') or float('nan')) * 1e-6)} MPa, "
                           f"m_i = {fmt(hb.get('m_i'))}, rms residual "
                           f"{fmt((hb.get('rms_residual_pa') or float('nan')) * 1e-6)} MPa"
             if hb.get("valid") else f"no fit ({hb.get('flag')})"),
            ("trend table", "trends.csv in the sweep folder (one row per test)")]
    write_html(folder, f"Breccia sweep report: {sweep.get('experiment', '')}", rows, figures,
               CAPTIONS)
    return figures


def main(folder):
    if os.path.exists(os.path.join(folder, "sweep.json")):
        figures = sweep_report(folder)
    elif os.path.exists(os.path.join(folder, "summary.json")):
        figures = run_report(folder)
    else:
        sys.exit(f"{folder}: neither summary.json nor sweep.json (not a finished run folder)")
    print(os.path.join(folder, "report.html"))
    for f in figures:
        print(os.path.join(folder, "report", f))


if __name__ == "__main__":
    matplotlib.use("Agg")  # files only; a notebook importing the module keeps its backend
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
