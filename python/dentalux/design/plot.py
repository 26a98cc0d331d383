"""The ΔE00 plane of a two-layer design: the fast model's ΔE00 to the target over both
thicknesses, the 0.8 (perceptibility) and 1.8 (acceptability) contours, the region outside
the total-thickness range greyed, and the designs marked (the best as a star)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dentalux import dental


def check_path(path: str, layers: int) -> Path:
    """A writable PNG path for a two-layer design, checked before any work
    (:func:`dentalux.output_paths.check_out_file`)."""
    from dentalux.output_paths import check_out_file

    if layers != 2:
        raise ValueError(f"--plot: the ΔE00 plane needs exactly 2 layers, {layers} given")
    return check_out_file(path, "--plot", (".png",))


def plane(result, path: str) -> Path:
    """Write the plot of ``result`` (a two-layer :class:`DesignResult`) to ``path``."""
    if result.plane is None:
        raise ValueError("plot: the ΔE00 plane exists only for two-layer designs")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = check_path(path, 2)
    x, y = (np.asarray(a) for a in result.plane["axes"])
    de = np.asarray(result.plane["delta_e00"])
    feasible = np.asarray(result.plane["feasible"])
    names = [lay["material"] for lay in result.layers]
    fig, ax = plt.subplots(figsize=(6.0, 4.8), dpi=120)
    mesh = ax.pcolormesh(x, y, de.T, shading="auto", cmap="viridis_r",
                         vmin=0.0, vmax=float(min(np.nanmax(de), max(3 * dental.AT,
                                                              np.nanmin(de) + 3))))
    fig.colorbar(mesh, ax=ax, label="ΔE00 to target (fast model, over white)")
    cs = ax.contour(x, y, de.T, levels=[dental.PT, dental.AT], colors=["white", "orange"],
                    linewidths=1.5)
    ax.clabel(cs, fmt={dental.PT: f"{dental.PT}", dental.AT: f"{dental.AT}"}, fontsize=8)
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
    src = result.target.source
    label = f"{src.get('guide')}:{src.get('tab')}" if src.get("kind") == "shade-guide" else \
        "L*a*b* {:.1f} {:.1f} {:.1f}".format(*result.target.lab)
    note = "" if np.nanmin(de[feasible]) <= dental.AT else \
        f" (no feasible design under {dental.AT}: min {np.nanmin(de[feasible]):.1f})"
    ax.set_title(f"target {label} on {result.substrate}, {result.instrument['name']}{note}",
                 fontsize=8)
    ax.legend(loc="best", fontsize=7)
    fig.tight_layout()
    from dentalux.output_paths import atomic_file

    try:
        with atomic_file(p, "--plot") as tmp:
            fig.savefig(tmp)
    finally:
        plt.close(fig)
    return p
