"""Report sections of the slab and dynamic tests (impact, ...): tests that are not read as a
stress-strain curve. Each test kind has one function that draws its figures from the run folder's
tables and returns the rows of the report's table; breccia.report calls it for runs of that kind.
"""
import numpy as np
import matplotlib.pyplot as plt

from breccia import report_kit as R


def _time_us(hist):
    return R.col(hist, "time_s", 1e6)


def impact_section(folder, summary, hist, cracks, outdir, figures):
    """The ball's path, speed and contact force over time, its energy against the slab's, and a
    top view of the cracks around the impact point."""
    im = summary.get("impact", {})
    ball = im.get("projectile", {})
    t = _time_us(hist)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6.2), sharex=True)
    a1.plot(t, R.col(hist, "projectile_velocity_m_s"), color="k", lw=1.2)
    a1.axhline(0, color="0.6", lw=0.6)
    a1.set_ylabel("ball velocity (m/s, + away)")
    a1b = a1.twinx()
    a1b.plot(t, R.col(hist, "indentation_m", 1e3), color="tab:green", lw=1)
    a1b.set_ylabel("indentation (mm)", color="tab:green")
    a2.plot(t, R.col(hist, "projectile_contact_force_n"), color="tab:red", lw=1,
            label="on the ball")
    a2.plot(t, R.col(hist, "floor_force_n"), color="tab:blue", lw=1, label="on the floor")
    a2.set_ylabel("contact force (N)")
    a2.set_xlabel("time (us)")
    a2.legend(fontsize=7)
    a1.set_title(R.wrapped(
        f"Impact: {R.fmt(1e3 * ball.get('diameter_m', float('nan')), '{:g}')} mm ball at "
        f"{R.fmt(ball.get('speed_in_m_s'), '{:g}')} m/s; contact "
        f"{R.fmt(1e6 * im.get('contact_time_s', float('nan')), '{:.3g}')} us, deepest indentation "
        f"{R.fmt(1e3 * im.get('max_indentation_m', float('nan')), '{:.3g}')} mm"), fontsize=9)
    fig.tight_layout()
    R.save(fig, outdir, "impact.png", figures)

    fig, ax = plt.subplots(figsize=(7, 4.4))
    ax.plot(t, R.col(hist, "projectile_kinetic_j", 1e3), "k", lw=1.4, label="ball kinetic")
    for name, label, colour in (("boundary_work_j", "work on the slab", "tab:purple"),
                                ("kinetic_j", "slab kinetic", "tab:blue"),
                                ("released_by_breaks_j", "released by breaking bonds",
                                 "tab:orange"),
                                ("friction_j", "friction", "tab:red")):
        ax.plot(t, R.col(hist, name, 1e3), color=colour, lw=1, label=label)
    ax.set_xlabel("time (us)")
    ax.set_ylabel("energy (mJ)")
    ax.legend(fontsize=7)
    ax.set_title(R.wrapped(
        f"Energy of the impact: {R.fmt(1e3 * ball.get('kinetic_energy_in_j', float('nan')), '{:.3g}')}"
        f" mJ in; the ball's loss equals its work on the slab to "
        f"{R.fmt(ball.get('energy_balance_residual_relative'), '{:.1e}')}"), fontsize=9)
    fig.tight_layout()
    R.save(fig, outdir, "impact_energy.png", figures)

    if cracks:
        z = R.col(cracks, "z_m", 1e3)
        axis = 2 if np.ptp(z) > 0 else 1  # 2D runs keep every grain at z = 0
        x, y = R.col(cracks, "x_m", 1e3), R.col(cracks, "y_m", 1e3)
        depth = R.col(cracks, ["x_m", "y_m", "z_m"][axis], 1e3)
        fig, ax = plt.subplots(figsize=(6, 5.4))
        if axis == 2:
            sc = ax.scatter(x, y, c=depth, s=4, cmap="viridis")
            ax.set_ylabel("y (mm)")
            fig.colorbar(sc, ax=ax, label="height z (mm)")
            ax.set_aspect("equal")
        else:
            ax.scatter(x, y, s=4, c="tab:orange")
            ax.set_ylabel("y (mm, the impact axis)")
        ax.set_xlabel("x (mm)")
        ax.set_title(R.wrapped(
            f"Cracks seen from above: {len(cracks)}; half within "
            f"{R.fmt(1e3 * im.get('crack_reach_50_m', float('nan')), '{:.3g}')} mm of the impact "
            f"axis, 90 % within {R.fmt(1e3 * im.get('crack_reach_90_m', float('nan')), '{:.3g}')}"
            " mm"), fontsize=9)
        fig.tight_layout()
        R.save(fig, outdir, "impact_cracks.png", figures)
    return [("result", line) for line in im.get("headline", [])]


def _two_panels(hist, outdir, figures, name, x, xlabel, top, bottom, title):
    """Two stacked plots against one x column: `top` and `bottom` are lists of (column, scale,
    label, colour); the bottom panel also shows the cumulative cracks on a second axis."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6.2), sharex=True)
    xs = R.col(hist, x[0], x[1])
    for ax, series in ((a1, top), (a2, bottom)):
        for column, scale, label, colour in series:
            ax.plot(xs, R.col(hist, column, scale), color=colour, lw=1.1, label=label)
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    a2b = a2.twinx()
    a2b.plot(xs, R.col(hist, "broken_bonds"), color="tab:orange", lw=1, ls="--")
    a2b.set_ylabel("cumulative cracks", color="tab:orange")
    a2.set_xlabel(xlabel)
    a1.set_title(R.wrapped(title), fontsize=9)
    fig.tight_layout()
    R.save(fig, outdir, name, figures)


def cantilever_section(folder, summary, hist, cracks, outdir, figures):
    """Force against the rod's travel (the rod's and the vice's), and the cracks."""
    c = summary.get("cantilever", {})
    _two_panels(hist, outdir, figures, "cantilever.png", ("rod_travel_m", 1e3),
                "rod travel (mm)",
                [("rod_force_n", 1.0, "rod force (N)", "k"),
                 ("vice_force_n", 1.0, "load on the vice (N)", "tab:blue")],
                [("deviatoric_stress_pa", 1e-6, "root bending stress 6 F L / (b h^2) (MPa)",
                  "tab:red")],
                f"Cantilever: largest force {R.fmt(c.get('max_force_n'), '{:.4g}')} N, flexural "
                f"strength {R.fmt(1e-6 * c.get('flexural_strength_pa', float('nan')), '{:.3g}')}"
                f" MPa; {R.fmt(100 * c.get('cracks_near_root_share', float('nan')), '{:.0f}')} % "
                "of the cracks next to the vice")
    return [("result", line) for line in c.get("headline", [])]


def vibration_section(folder, summary, hist, cracks, outdir, figures):
    """The grip's displacement and force over the cycles, and the cracks."""
    v = summary.get("vibration", {})
    _two_panels(hist, outdir, figures, "vibration.png", ("cycles_done", 1.0), "cycles",
                [("face_displacement_m", 1e6, "grip displacement (um)", "k")],
                [("face_force_n", 1.0, "grip force on the slab (N)", "tab:blue")],
                f"Vibration: {R.fmt(v.get('frequency_hz'), '{:.5g}')} Hz, amplitude "
                f"{R.fmt(1e6 * v.get('amplitude_m', float('nan')), '{:.3g}')} um; "
                f"{R.fmt(v.get('cracks_per_cycle'), '{:.3g}')} cracks per cycle")
    return [("result", line) for line in v.get("headline", [])]


def abrasion_section(folder, summary, hist, cracks, outdir, figures):
    """The bulk friction coefficient and the abrader's forces against the distance slid."""
    a = summary.get("abrasion", {})
    _two_panels(hist, outdir, figures, "abrasion.png", ("slid_m", 1e3), "distance slid (mm)",
                [("bulk_friction", 1.0, "bulk friction coefficient", "k")],
                [("abrader_normal_force_n", 1.0, "normal force (N)", "tab:blue"),
                 ("abrader_shear_force_n", 1.0, "shear force (N)", "tab:red")],
                f"Abrasion: bulk friction {R.fmt(a.get('bulk_friction_mean'), '{:.3f}')} over "
                f"the second half; worn off "
                f"{R.fmt(1e3 * a.get('worn_mass_kg', float('nan')), '{:.3g}')} g")
    return [("result", line) for line in a.get("headline", [])]


def _number(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def parameter_sweep_report(folder, sweep):
    """A sweep over one key (breccia sweep --over): the scaled crack count (seed 001, figure
    16), the fragments and each of the test's sweep metrics against the key's value."""
    runs = [r for r in sweep["runs"] if r.get("status") == "complete"]
    outdir = R.os.path.join(folder, "report")
    R.os.makedirs(outdir, exist_ok=True)
    figures = []
    key = sweep.get("variable", "value")
    x = np.array([_number(r["value"]) for r in runs])
    panels = [("cracks_scaled", "cracks / most cracks (N / N_max)"),
              ("fragments", "fragments")]
    metric_names = sorted({m for r in runs for m in r.get("metrics", {})})
    panels += [(m, m.replace("_", " ")) for m in metric_names]
    cols = 2
    rows_n = (len(panels) + cols - 1) // cols
    fig, axes = plt.subplots(rows_n, cols, figsize=(9, 2.8 * rows_n), squeeze=False)
    for ax, (name, label) in zip(axes.flat, panels):
        y = np.array([_number(r.get(name, r.get("metrics", {}).get(name))) for r in runs])
        ax.plot(x, y, "ko-", ms=4)
        ax.set_xlabel(key)
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    fig.suptitle(R.wrapped(f"{sweep.get('experiment', '')}: {len(runs)} runs over {key}"),
                 fontsize=9)
    fig.tight_layout()
    R.save(fig, outdir, "parameter_trends.png", figures)
    table = [("experiment", sweep.get("experiment")), ("test", sweep.get("test_kind")),
             ("varied", key), ("runs", f"{len(runs)} complete of {len(sweep['runs'])}")]
    for r in sweep["runs"]:
        table.append((f"{key} = {r['value']}",
                      f"{r.get('status')}: {r.get('cracks')} cracks "
                      f"({R.fmt(r.get('cracks_scaled'), '{:.2f}')} of the most), "
                      f"{r.get('fragments', 'n/a')} fragments; run folder {r.get('folder')}"))
    R.write_html(folder, f"Breccia sweep report: {sweep.get('experiment', '')}", table,
                 figures, {**R.CAPTIONS, **CAPTIONS})
    return figures


# The report section of each slab or dynamic test kind.
SECTIONS = {"impact": impact_section, "cantilever": cantilever_section,
            "vibration": vibration_section, "abrasion": abrasion_section}

CAPTIONS = {
    "impact.png": "The ball: velocity, indentation and contact forces over time",
    "impact_energy.png": "Energy of the impact over time",
    "impact_cracks.png": "Cracks around the impact point",
    "parameter_trends.png": "Results against the swept key",
    "cantilever.png": "Force against the rod's travel, and the cracks",
    "vibration.png": "The grip's displacement and force over the cycles, and the cracks",
    "abrasion.png": "Bulk friction coefficient and the plate's forces against the distance slid",
}
