"""The ΔE00 of a design over its thicknesses, from the fast model (``design --plot``).

- One layer: ΔE00 to the target against the layer's thickness, the 0.8 (perceptibility) and
  1.8 (acceptability) thresholds as bands, thicknesses outside the total range greyed, the
  designs marked with their Monte Carlo ΔE00 ± 2 s.e. (the best as a star).
- Two layers: the plane of ΔE00 over both thicknesses, the 0.8 and 1.8 contours, the region
  outside the total-thickness range greyed, and the designs marked (the best as a star).

When no thickness inside the ranges reaches ΔE00 <= 1.8 (acceptable), the plot says so in
words across its middle ("no feasible design"), with the best ΔE00 found, and the plane's
colour scale starts at that best value, so it is not a flat field.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dentalux import dental

#: points of the one-layer curve
CURVE_POINTS = 201


def check_path(path: str, layers: int) -> Path:
    """A writable PNG path for a one- or two-layer design, checked before any work
    (:func:`dentalux.output_paths.check_out_file`)."""
    from dentalux.output_paths import check_out_file

    if layers not in (1, 2):
        raise ValueError(f"--plot: the ΔE00 curve or plane needs 1 or 2 layers, {layers} given")
    return check_out_file(path, "--plot", (".png",))


def _target_label(result) -> str:
    src = result.target.source
    if src.get("kind") == "shade-guide":
        return f"{src.get('guide')}:{src.get('tab')}"
    return "L*a*b* {:.1f} {:.1f} {:.1f}".format(*result.target.lab)


def infeasible_text(best: float) -> str:
    """The words on a plot where no thickness reaches an acceptable match."""
    return (f"no feasible design:\nthe best ΔE00 here is {best:.1f},\n"
            f"acceptable needs ≤ {dental.AT}")


def _no_feasible(ax, best: float) -> None:
    ax.text(0.5, 0.5, infeasible_text(best), transform=ax.transAxes, ha="center",
            va="center", fontsize=13, color="black", zorder=10,
            bbox={"boxstyle": "round,pad=0.5", "fc": "white", "ec": "#a11", "alpha": 0.9})


def _curve(result, fig, total):
    """The one-layer ΔE00 curve (module doc); ``total`` (min, max) [mm] or None."""
    surface = result.surface
    lo, hi = surface.ranges[0]
    t = np.linspace(lo, hi, CURVE_POINTS)
    lab = surface.metrics(surface.grid([t]))["lab_white"]
    from dentalux.color import delta_e00

    de = np.asarray(delta_e00(lab, np.asarray(result.target.lab)))
    feasible = np.ones_like(t, dtype=bool) if total is None else \
        (t >= total[0] - 1e-9) & (t <= total[1] + 1e-9)
    ax = fig.add_subplot()
    top = float(max(np.nanmax(de), dental.AT) * 1.1)
    ax.axhspan(0, dental.PT, color="#2e9e4a", alpha=0.15, lw=0,
               label=f"imperceptible (< {dental.PT})")
    ax.axhspan(dental.PT, dental.AT, color="#e0a000", alpha=0.15, lw=0,
               label=f"acceptable (≤ {dental.AT})")
    ax.plot(t, de, color="C0", lw=1.8, label="fast model")
    if not feasible.all():
        ax.fill_between(t, 0, top, where=~feasible, color="grey", alpha=0.35, lw=0,
                        label="outside the total range")
    for i, d in enumerate(result.designs):
        x, y = d["thickness_mm"][0], d["delta_e00"]
        ax.errorbar(x, y, yerr=2 * d["delta_e00_stderr"], fmt="*" if i == 0 else "o",
                    ms=14 if i == 0 else 7, color="red" if i == 0 else "pink", mec="black",
                    ecolor="black", capsize=3, zorder=5,
                    label=(f"best {x:.2f} mm, ΔE00 {y:.2f} ± {d['delta_e00_stderr']:.2f} "
                           "(Monte Carlo, ± 2 s.e.)" if i == 0 else None))
    ax.set_xlim(lo, hi)
    ax.set_ylim(0, top)
    ax.set_xlabel(f"{result.layers[0]['material']} thickness [mm]")
    ax.set_ylabel("ΔE00 to target (over white)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=7)
    best = float(np.nanmin(de[feasible])) if feasible.any() else float("nan")
    return ax, best


def _plane(result, fig, total=None):
    """The two-layer ΔE00 plane (module doc)."""
    x, y = (np.asarray(a) for a in result.plane["axes"])
    de = np.asarray(result.plane["delta_e00"])
    feasible = np.asarray(result.plane["feasible"])
    names = [lay["material"] for lay in result.layers]
    best = float(np.nanmin(de[feasible]))
    ax = fig.add_subplot()
    vmin = 0.0 if best <= dental.AT else best
    vmax = float(min(np.nanmax(de), max(3 * dental.AT, np.nanmin(de) + 3)))
    if vmax <= vmin:
        vmax = float(np.nanmax(de)) if np.nanmax(de) > vmin else vmin + 1.0
    mesh = ax.pcolormesh(x, y, de.T, shading="auto", cmap="viridis_r", vmin=vmin, vmax=vmax)
    fig.colorbar(mesh, ax=ax, label="ΔE00 to target (fast model, over white)")
    levels = [v for v in (dental.PT, dental.AT) if np.nanmin(de) < v < np.nanmax(de)]
    if levels:
        cs = ax.contour(x, y, de.T, levels=levels, colors=["white", "orange"][:len(levels)]
                        if levels[0] == dental.PT else ["orange"], linewidths=1.5)
        ax.clabel(cs, fmt={v: f"{v}" for v in levels}, fontsize=8)
    if not feasible.all():
        ax.contourf(x, y, (~feasible).T.astype(float), levels=[0.5, 1.5], colors="grey",
                    alpha=0.55)
    for i, d in enumerate(result.designs):
        t = d["thickness_mm"]
        ax.plot(t[0], t[1], marker="*" if i == 0 else "o", ms=14 if i == 0 else 7,
                color="red" if i == 0 else "pink", mec="black",
                label=(f"optimum {t[0]:.2f} / {t[1]:.2f} mm, ΔE00 {d['delta_e00']:.2f}"
                       if i == 0 else None))
    ax.set_xlabel(f"{names[0]} thickness [mm] (top)")
    ax.set_ylabel(f"{names[1]} thickness [mm]")
    ax.legend(loc="best", fontsize=7)
    return ax, best


def figure(result, total=None):
    """The matplotlib figure of ``result`` (a one- or two-layer :class:`DesignResult`);
    ``total``: the design's total range (``MIN-MAX`` or (min, max) [mm]), which greys the
    one-layer curve outside it (the two-layer plane carries its own)."""
    import matplotlib

    from dentalux.design import constraints

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    k = len(result.layers)
    if k == 2 and result.plane is None or k not in (1, 2) or k == 1 and result.surface is None:
        raise ValueError(f"plot: the ΔE00 curve or plane exists for one- or two-layer "
                         f"designs, this one has {k} layers")
    fig = plt.figure(figsize=(6.4, 5.2 if k == 1 else 4.8), dpi=120)
    if total is not None:
        total = constraints.check_total(total, [lay["range_mm"] for lay in result.layers])
    ax, best = (_curve if k == 1 else _plane)(result, fig, total)
    ax.set_title(f"target {_target_label(result)} on {result.substrate}, "
                 f"{result.instrument['name']}", fontsize=8)
    if not best <= dental.AT:  # NaN (nothing feasible) included
        _no_feasible(ax, best)
    fig.tight_layout()
    return fig


def plane(result, path: str, total=None) -> Path:
    """Write the plot of ``result`` (a one- or two-layer :class:`DesignResult`, its total
    range ``total``) to ``path``."""
    import matplotlib.pyplot as plt

    from dentalux.output_paths import atomic_file

    p = check_path(path, len(result.layers))
    fig = figure(result, total)
    try:
        with atomic_file(p, "--plot") as tmp:
            fig.savefig(tmp)
    finally:
        plt.close(fig)
    return p
