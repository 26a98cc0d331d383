"""The report's charts (matplotlib, headless), each returned as a base64 PNG data URI.

- :func:`spectra`: reflectance over the black and white backings and total transmittance of
  each disc, per band (from :func:`dentalux.dental.metrics`, read as ``shade`` reads it);
- :func:`optics`: μa and μs′ of each material against wavelength (the library's
  interpolation, :meth:`dentalux.materials.Material.at`; dots at the known wavelengths);
- :func:`tp_thickness`: TP00 and TP of each material against disc thickness.
"""

from __future__ import annotations

import base64
import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

#: wavelengths [nm] of the μa / μs′ curves (the colour range the metrics integrate)
OPTICS_GRID = np.arange(380.0, 781.0, 5.0)
DPI = 110


def _uri(fig) -> dict:
    """A closed figure as ``{"src": data URI, "width", "height"}`` (pixels)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    w, h = (int(round(x * DPI)) for x in fig.get_size_inches())
    plt.close(fig)
    src = "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")
    return {"src": src, "width": w, "height": h}


def spectra(labelled, where: str) -> dict:
    """Reflectance (over black, over white) and transmittance against wavelength, for each
    ``(label, DentalMetrics)``, read in ``where`` (the geometry's short name)."""
    fig, (ax_r, ax_t) = plt.subplots(1, 2, figsize=(9.0, 4.0), layout="constrained")
    for i, (label, m) in enumerate(labelled):
        wl, sp, c = np.asarray(m.wavelengths_nm), m.spectra, f"C{i}"
        ax_r.plot(wl, sp["over_black"], "o-", color=c, ms=3, lw=1.2, label=f"{label}, black")
        ax_r.plot(wl, sp["over_white"], "s--", color=c, ms=3, lw=1.2, label=f"{label}, white")
        ax_t.plot(wl, sp["transmitted"], "o-", color=c, ms=3, lw=1.2)
    ax_r.set(title="Reflectance over the backings", xlabel="wavelength [nm]", ylabel="R")
    ax_t.set(title="Transmittance (disc in air)", xlabel="wavelength [nm]", ylabel="T")
    for ax in (ax_r, ax_t):
        ax.grid(alpha=0.3)
    fig.legend(*ax_r.get_legend_handles_labels(), loc="outside lower center", fontsize=7,
               ncol=min(4, 2 * len(labelled)))
    return {"id": "spectra", "caption": "Reflectance over the black (solid) and white "
            f"(dashed) backings and transmittance per band ({where}).", **_uri(fig)}


def optics(materials) -> dict:
    """μa and μs′ [1/mm] against wavelength for each ``(label, Material)``."""
    fig, (ax_a, ax_s) = plt.subplots(1, 2, figsize=(9.0, 3.4), layout="constrained")
    for i, (label, mat) in enumerate(materials):
        o, c = mat.at(OPTICS_GRID), f"C{i}"
        known = mat.at(mat.wavelength_nm)
        ax_a.plot(OPTICS_GRID, o.mua, color=c, lw=1.2, label=label)
        ax_a.plot(mat.wavelength_nm, np.atleast_1d(known.mua), "o", color=c, ms=4)
        ax_s.plot(OPTICS_GRID, o.mus_reduced, color=c, lw=1.2, label=label)
        ax_s.plot(mat.wavelength_nm, np.atleast_1d(known.mus_reduced), "o", color=c, ms=4)
    ax_a.set(title="Absorption μa", xlabel="wavelength [nm]", ylabel="μa [1/mm]")
    ax_s.set(title="Reduced scattering μs′ = μs (1 − g_eff)", xlabel="wavelength [nm]",
             ylabel="μs′ [1/mm]")
    for ax in (ax_a, ax_s):
        ax.set_xlim(OPTICS_GRID[0], OPTICS_GRID[-1])
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    return {"id": "optics", "caption": "Optical coefficients used (lines: the library's "
            "interpolation; dots: the material's known wavelengths).", **_uri(fig)}


def tp_thickness(series, thickness: float, where: str) -> dict:
    """TP00 (solid) and TP (dashed) against thickness for each ``(label, [(t, tp, tp00)])``;
    the report's thickness is marked."""
    fig, ax = plt.subplots(figsize=(6.0, 3.6), layout="constrained")
    for i, (label, pts) in enumerate(series):
        t, tp, tp00 = (np.asarray(x, float) for x in zip(*pts, strict=True))
        ax.plot(t, tp00, "o-", color=f"C{i}", ms=4, label=f"{label}, TP00")
        ax.plot(t, tp, "s--", color=f"C{i}", ms=3, alpha=0.7, label=f"{label}, TP")
    ax.axvline(thickness, color="0.5", lw=0.8, ls=":")
    ax.set(title=f"Translucency against thickness ({where})", xlabel="thickness [mm]",
           ylabel="TP00, TP")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return {"id": "tp-thickness", "caption": f"TP00 and TP against disc thickness ({where}); "
            f"the dotted line marks {thickness:g} mm.", **_uri(fig)}
