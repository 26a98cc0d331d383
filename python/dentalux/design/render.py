"""A designed crown rendered beside a natural incisor (``dentalux design --render DIR``).

The scene is the crown figure's (:func:`dentalux.scene.builtin.crown`): a natural incisor
(enamel over dentin) and, beside it, the same tooth crowned with the design's layers as
nested shells of the design's thicknesses (labially; lingually 2/3 of them, thinning to the
margin at the CEJ) on a preparation as deep as the crown, filled with the substrate
(``dentin``: the natural dentin; ``stump``: the darkened dentin of
:mod:`dentalux.design.substrates`), a cement layer as one more shell. Both teeth are read as
the figure reads them, which is an instrument's geometry in the image: two D65 lights 45°
left and right, the camera on the normal (45°/0°), a white tile in the plane of the labial
faces as L* = 100, and the CIELAB of the mean spectrum of a 2.5 mm square on each tooth's
labial middle third (``colour.json`` regions ``crown`` and ``natural``). The rendered ΔE00
between them is set beside the design's slab prediction (its ΔE00 to its target): they are
the same quantity when the target is the natural incisor's middle third
(:data:`NATURAL_STACK`) read through a 45°/0° instrument on the figure's black contrastor,
at the render's bands (docs/design.md, "Render").

Like every tissue figure, the render lowers g to 0.75 by the similarity relation (μs'
kept; docs/figures.md), so the layers' media are similarity-scaled copies of the design's
materials.
"""

from __future__ import annotations

import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

from dentalux import figures as F

# The natural incisor of the crown scene on its labial middle third (x = 0, 5 mm above the
# CEJ, dentalux.teeth.incisor), along the view: 0.9 mm enamel, 2.9 mm dentin and the
# lingual enamel, 2/3 of the labial by construction (0.66 mm along the view through the
# sloped lingual face; measured on the 0.1 mm mesh). As a design target: ``stack:`` + this.
NATURAL_STACK = "enamel:0.9/dentin:2.9/enamel:0.6"
# The substrates the render can put under a crown: media inside the preparation. An opaque
# core (zirconia, metal, reflectance:R) would be an opaque surface inside the crown's
# media, which scenes do not take; `none` has nothing to put there.
SUBSTRATES = ("dentin", "stump")
# The preparation of the procedural incisor is the natural dentin surface deepened to the
# crown's thickness; at 2 mm (3.3 mm labially and lingually together) about 1 mm of dentin
# is left in the 4.4 mm middle third.
MAX_TOTAL_MM = 2.0
# Default: the preview's settings at 160 x 120 px (121 pixels in a measured square), half its
# stored volume photons and 2 samples per pixel, the rendered ΔE00 uncertain by about 1.2
# (docs/design.md: more photons or samples barely help, more independent renders do);
# `quality="preview"` or "paper" is the figure's. The photon passes dominate its time: 160 x
# 120 took 115 s where 120 x 90 took 90 s (the same two shared cores, one run each), and
# crown.png shows it enlarged (ANNOTATED_MIN_WIDTH) with its labels outside the picture.
DRAFT = replace(F.QUALITIES["preview"], name="draft", resolution=(160, 120),
                teeth_photons=200_000, teeth_volume_stored=8_000_000, teeth_spp=2)
QUALITIES = {"draft": DRAFT, **F.QUALITIES}


#: crown.png is at least this wide [px]: the render enlarged by a whole factor (each pixel a
#: square block, nothing interpolated), so a draft can be judged on a screen
ANNOTATED_MIN_WIDTH = 640
#: the outline colour of each measured square and of its label (the label sits above the
#: picture, over its square's column, never on the teeth)
REGION_COLOURS = {"crown": "#1f77b4", "natural": "#d62728"}


def annotate(src, dst, regions: dict, text: str,
             min_width: int = ANNOTATED_MIN_WIDTH) -> dict:
    """``crown.png``: the render ``src`` enlarged by a whole factor to at least ``min_width``
    pixels, each measured square outlined in its colour, its name in the same colour in a
    band above the picture (over the square's column) and ``text`` in a band below: nothing
    is written on the picture but the outlines. Returns the layout in ``dst``'s pixels (for
    the tests): ``scale``, ``picture`` (x0, y0, x1, y1) and ``labels`` {name: box}."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    img = plt.imread(src)
    h, w = img.shape[:2]
    scale = max(1, -(-int(min_width) // w))
    big = np.repeat(np.repeat(img, scale, axis=0), scale, axis=1)
    band = 36  # px above (labels) and below (text)
    W, H = w * scale, h * scale + 2 * band
    dpi = 100
    fig = plt.figure(figsize=(W / dpi, H / dpi), dpi=dpi)
    ax = fig.add_axes((0, band / H, 1, h * scale / H))
    ax.imshow(big, interpolation="nearest")
    ax.set_xlim(-0.5, W - 0.5)
    ax.set_ylim(h * scale - 0.5, -0.5)
    ax.axis("off")
    labels = {}
    for name, (x0, y0, x1, y1) in regions.items():
        colour = REGION_COLOURS.get(name, "#ff7f0e")
        ax.add_patch(Rectangle((x0 * scale - 0.5, y0 * scale - 0.5), (x1 - x0) * scale,
                               (y1 - y0) * scale, fill=False, ec=colour, lw=2.0))
        labels[name] = fig.text((x0 + x1) / 2 * scale / W, 1 - band / 2 / H, name,
                                color=colour, fontsize=12, fontweight="bold", ha="center",
                                va="center")
    caption = fig.text(0.5, band / 2 / H, text, ha="center", va="center", fontsize=11)
    fig.savefig(dst, dpi=dpi)
    renderer = fig.canvas.get_renderer()

    def box(artist):  # display coordinates (origin bottom left) -> image rows from the top
        b = artist.get_window_extent(renderer)
        return (float(b.x0), float(H - b.y1), float(b.x1), float(H - b.y0))

    layout = {"scale": scale, "size": (W, H), "picture": (0.0, float(band), float(W),
                                                           float(band + h * scale)),
              "labels": {k: box(v) for k, v in labels.items()}, "caption": box(caption)}
    plt.close(fig)
    return layout


def get_quality(quality, field: str = "quality") -> F.Quality:
    """A :class:`dentalux.figures.Quality` or its name in :data:`QUALITIES`."""
    if isinstance(quality, F.Quality):
        return quality
    if quality not in QUALITIES:
        raise ValueError(f"{field} = {quality!r}: allowed {', '.join(QUALITIES)}")
    return QUALITIES[quality]


def check(out, substrate: str = "dentin", quality="draft", repeats: int = 1,
          field: str = "--render") -> Path:
    """Before any work: ``out`` must be a writable folder (created if missing, its render
    files replaced), the substrate one the render can put under a crown, the quality known
    and ``repeats`` in [1, 64]."""
    from dentalux.output_paths import check_out_dir

    if isinstance(repeats, bool) or not isinstance(repeats, int) or not 1 <= repeats <= 64:
        raise ValueError(f"{field}-repeats = {repeats!r} is out of range: allowed an integer "
                         "in [1, 64]")
    if substrate not in SUBSTRATES:
        raise ValueError(f"{field}: substrate = {substrate!r} cannot be rendered: the crown sits "
                         f"on the natural tooth; allowed {', '.join(SUBSTRATES)}")
    get_quality(quality, f"{field}-quality")
    return check_out_dir(out, field, overwrite=True)


def _medium(material, quality: F.Quality, bands) -> dict:
    from dentalux import dental
    from dentalux.design.forward import check_data

    m = dental._resolve_material(material)
    check_data(m, np.asarray(bands, float), "--render layer material")  # as the design does
    if quality.similarity_g is not None:  # as lower_anisotropy does for library media
        m = m.similar(quality.similarity_g, note="design render: fewer photons")
    return F._media_table(m, bands)


def _measure(cubes: list, regions: dict, wl, seed: int) -> dict:
    """CIELAB of each region's mean spectrum over ``cubes`` (one per independent render), ΔE00
    crown vs natural and its standard error: with two or more renders the jackknife over
    them; with one, the bootstrap over the regions' pixels (each region resampled on its
    own, as figures.crown_translucency does), which misses the noise that neighbouring
    pixels share through the photon maps (measured: 2-3 times too small at 32 M stored
    photons and 8 spp, about right at 8 M and 2 spp; docs/design.md)."""
    from dentalux.color import delta_e00, spectrum_to_Lab

    def region_pixels(cube):
        return {k: cube[y0:y1, x0:x1].reshape(-1, len(wl))
                for k, (x0, y0, x1, y1) in regions.items()}

    def region_means(cube):
        return {k: px.mean(axis=0) for k, px in region_pixels(cube).items()}

    def de(means):
        return float(delta_e00(spectrum_to_Lab(means["crown"], wl),
                               spectrum_to_Lab(means["natural"], wl)))

    runs = [region_means(c) for c in cubes]
    mean = {k: np.mean([r[k] for r in runs], axis=0) for k in regions}
    lab = {k: np.asarray(spectrum_to_Lab(v, wl)) for k, v in mean.items()}
    size = {k: (y1 - y0) * (x1 - x0) for k, (x0, y0, x1, y1) in regions.items()}
    boot = F.pixel_bootstrap_stderr(region_pixels(np.mean(cubes, axis=0)), de,
                                    np.random.default_rng(seed))
    out = {"lab": {k: v.tolist() for k, v in lab.items()}, "delta_e00": de(mean),
           "pixel_bootstrap_stderr": boot, "pixels": size,
           "renders": len(cubes), "delta_e00_per_render": [de(r) for r in runs]}
    if len(runs) > 1:
        n = len(runs)
        jack = [de({k: np.mean([r[k] for j, r in enumerate(runs) if j != i], axis=0)
                    for k in regions}) for i in range(n)]
        out["delta_e00_stderr"] = float(np.sqrt((n - 1) / n * np.sum((np.array(jack)
                                                                      - np.mean(jack)) ** 2)))
        out["stderr_method"] = f"jackknife over {n} independent renders (seeds)"
    else:
        out["delta_e00_stderr"] = out["pixel_bootstrap_stderr"]
        out["stderr_method"] = ("bootstrap over the regions' pixels (one render: misses the "
                                "noise neighbouring pixels share; give repeats >= 2)")
    return out


def render_crown(layers, out, substrate: str = "dentin", cement=None, quality="draft",
                 bands=F.PAPER_BANDS, seed: int = 1, repeats: int = 1,
                 threads: int | None = None, progress: bool | None = False,
                 predicted: dict | None = None) -> dict:
    """Render a crown of ``layers`` [(material, labial thickness [mm])] top to bottom (and an
    optional ``cement`` (material, mm) under them) on ``substrate`` beside the natural
    incisor into the folder ``out``; returns the measurement (module doc) and writes it to
    ``out/render.json`` with image.png, image.exr, spectral.exr, colour.json, radiance.npy
    and ``crown.png`` (the image with the measured squares and the ΔE00). ``repeats``
    independent renders (seeds ``seed`` ...) are averaged, and from two on their spread is
    the standard error (:func:`_measure`). ``predicted``
    (``delta_e00``, ``delta_e00_stderr``, ...): a prediction to set the rendered ΔE00
    beside (key ``rendered_minus_predicted``)."""
    from dentalux.dental import verdict
    from dentalux.design import substrates as subs
    from dentalux.output_paths import rebase, staged_dir
    from dentalux.outputs import colour_inputs, write_render_outputs
    from dentalux.render import render
    from dentalux.scene.load import scene_from_dict
    from dentalux.strict_json import dumps_strict

    t0 = time.perf_counter()
    out = check(out, substrate, quality, repeats)
    q = get_quality(quality)
    wl = [float(b) for b in bands]
    shells = list(layers) + ([tuple(cement)] if cement is not None else [])
    thick = [float(t) for _, t in shells]
    if not shells or sum(thick) > MAX_TOTAL_MM + 1e-9:
        raise ValueError(f"--render: the crown is {sum(thick):g} mm thick (layers and cement); "
                         f"the procedural incisor takes at most {MAX_TOTAL_MM:g} mm (limit the "
                         "design with --total)")
    media = [(_medium(m, q, wl), t) for m, t in shells]
    core = None if substrate == "dentin" else _medium(subs.layers(substrate)[0][0], q, wl)
    scene, regions = F.crown_scene(q, layers=media, core=core)
    tile = F.white_tile(scene, regions, q)
    scaling = F.lower_anisotropy(scene, q, wl)  # the natural tooth's enamel and dentin
    sc = scene_from_dict(scene)
    runs = [render(sc, integrator="vpm", bands=wl, seed=seed + i, correlated_bands=True,
                   threads=threads, progress=progress, **F._teeth_settings(q))
            for i in range(repeats)]
    result = replace(runs[0], radiance=np.mean([r.radiance for r in runs], axis=0))
    divisor, _, _ = colour_inputs(sc, wl)
    m = _measure([r.radiance / divisor / tile["white"] for r in runs], regions, wl, seed)
    with staged_dir(out, "--render") as stage:
        summary = write_render_outputs(sc, result, stage, regions=regions, white=tile["white"],
                                       write_json=False)
        text = f"ΔE00 {m['delta_e00']:.2f}"
        if predicted is not None:
            text += f" (slab {predicted['delta_e00']:.2f})"
        annotate(stage / "image.png", stage / "crown.png", regions, text)
        summary = rebase(summary, stage, out)
        summary["files"]["annotated_png"] = str(out / "crown.png")
        report = {
            "rendered": {**m, "verdict": verdict(m["delta_e00"])},
            "crown": {"layers": [{"material": str(getattr(mat, "name", mat)), "thickness_mm": t}
                                 for (mat, _), t in zip(shells, thick, strict=True)],
                      "cement": cement is not None, "substrate": substrate},
            "regions": regions, "white_tile": tile, "anisotropy_scaling": scaling,
            "quality": asdict(q), "bands_nm": wl, "seeds": [seed + i for i in range(repeats)],
            "files": {"png": summary["colour"]["files"]["png"],
                      "exr": summary["colour"]["files"]["exr"],
                      "spectral_exr": summary["colour"]["files"]["spectral_exr"],
                      "annotated_png": str(out / "crown.png"),
                      "render_json": str(out / "render.json")},
            "render": summary,
        }
        if predicted is not None:
            report["predicted"] = predicted
            report["rendered_minus_predicted"] = {
                "delta_e00": m["delta_e00"] - predicted["delta_e00"],
                "stderr": float(np.hypot(m["delta_e00_stderr"],
                                         predicted["delta_e00_stderr"]))}
        report["seconds"] = time.perf_counter() - t0
        (stage / "render.json").write_text(dumps_strict(report, indent=2))
    return report


def render_design(res, out, index: int = 0, **kwargs) -> dict:
    """Render design ``index`` (0: the best) of a :class:`dentalux.design.DesignResult`
    with :func:`render_crown` (``kwargs`` go there), the rendered ΔE00 beside the predicted
    one: the design's slab ΔE00 to its target (``predicted``, ``rendered_minus_predicted``
    in the returned dictionary and in ``out/render.json``)."""
    if not 0 <= index < len(res.designs):
        raise ValueError(f"design index = {index!r}: the result has {len(res.designs)} designs")
    d = res.designs[index]
    layers = list(zip(res.parts, d["thickness_mm"], strict=True))
    predicted = {
        "delta_e00": d["delta_e00"], "delta_e00_stderr": d["delta_e00_stderr"],
        "crown_lab": d["lab"], "target_lab": list(res.target.lab),
        "target": res.target.to_json(), "instrument": res.instrument["name"],
        "bands_nm": res.bands, "thickness_mm": d["thickness_mm"], "design_index": index,
        "note": "the design's slab ΔE00 to its target: the same quantity as the rendered one "
                f"when the target is stack:{NATURAL_STACK} read through a 45-0 instrument on "
                "a black backing at the render's bands (docs/design.md, Render)"}
    return render_crown(layers, out, substrate=res.substrate, cement=res.cement,
                        predicted=predicted, **kwargs)


__all__ = ["ANNOTATED_MIN_WIDTH", "DRAFT", "MAX_TOTAL_MM", "NATURAL_STACK", "QUALITIES",
           "SUBSTRATES", "annotate", "check", "get_quality", "render_crown", "render_design"]

