"""Figures (matplotlib, headless): the paper's Fig. 2 and its variants."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dentalux import spectra  # noqa: E402
from dentalux._lazy import colour  # noqa: E402


def fig2_spd(out_dir, stem: str = "fig2_spd", grid=None) -> dict[str, str]:
    """The paper's Fig. 2: the D65 SPD and the transmitted power D65(l) x TT(l).

    TT(l) is Table 1's total transmittance reconstructed in paper mode with every basis of
    :mod:`dentalux.spectra` (``zero`` = linear interpolation only). Writes ``stem.png`` and
    ``stem.svg`` to ``out_dir`` and returns their paths.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    g = spectra.FINE_GRID if grid is None else np.asarray(grid, float)
    d65 = np.asarray(colour.SDS_ILLUMINANTS["D65"][g], float)
    t = spectra.table1()
    target = spectra.table1_d65()["tt"]
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    ax.plot(g, d65, color="k", lw=1.5, label="D65 SPD")
    styles = {"zero": "-", "hold": ":", "constant": "--", "linear": "-."}
    for basis in spectra.BASES:
        rec = spectra.paper_reconstruction("tt", basis, grid=g)
        tt = rec(t["tt"])
        share = spectra.weighted_mean(tt, g)
        label = f"transmitted, {basis} ({100 * share:.2f} % of D65 power)"
        ax.plot(g, d65 * tt, styles[basis], lw=1.2, label=label)
    ax.plot(t["wavelength_nm"], np.asarray(colour.SDS_ILLUMINANTS["D65"][t["wavelength_nm"]])
            * t["tt"], "o", color="C3", label="measured bands (Table 1)")
    ax.set_xlabel("wavelength [nm]")
    ax.set_ylabel("relative spectral power (D65 = 100 at 560 nm)")
    ax.set_title(f"D65 and transmitted power, 0.5 mm disc (measured D65 TT {100 * target:.2f} %)",
                 fontsize=9)
    ax.set_xlim(g[0], g[-1])
    ax.set_ylim(0, 185)
    ax.legend(fontsize=7, loc="upper center", ncol=2)
    fig.tight_layout()
    paths = {"png": str(out / f"{stem}.png"), "svg": str(out / f"{stem}.svg")}
    fig.savefig(paths["png"], dpi=150)
    fig.savefig(paths["svg"])
    plt.close(fig)
    return paths
