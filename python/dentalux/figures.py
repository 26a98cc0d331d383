"""The paper's figures, reproduced from one command (``dentalux figures --out DIR``).

- Fig. 2: D65 and the interpolated transmitted power of the Table 1 disc.
- Fig. 3: two discs of the Table 1 biomaterial on a checker ribbon, one on it and one 5 mm
  above it; rendered at the paper's stated 5 mm thickness and at the measured sample's
  0.5 mm (see docs/figures.md for why both).
- Fig. 4: the same with enamel whose optical thickness is scaled so that the disc transmits
  as much (D65-weighted total transmittance of the slab) as the biomaterial disc, as the
  paper did; the scale factor is recorded in the figure's JSON and in the material's
  provenance.
- Fig. 5: three procedural teeth (enamel over dentin) in a small Cornell box.
- A figure the paper did not have: a crown of the biomaterial on a dentin stump beside a
  natural incisor, with the ΔE00 between the two crowns printed on it.
- A side-by-side crop of Fig. 3 rendered with ``vpm`` and with the reference ``volpath``.

Every figure folder holds image.png, image.exr, spectral.exr, radiance.npy, colour.json and
figure.json (settings, timings, peak memory). Lengths in mm, wavelengths in nm.
"""

from __future__ import annotations

import copy
import json
import math
import shutil
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from dentalux import materials, natural_teeth, spectra
from dentalux.outputs import peak_memory_bytes, write_render_outputs
from dentalux.render import render
from dentalux.scene import builtin
from dentalux.scene.builtin import discs as discs_scene
from dentalux.scene.load import scene_from_dict
from dentalux.scene.project import square_region
from dentalux.scene.schema import PATH_TRACERS
from dentalux.slab import Layer, simulate

PAPER_BANDS = [450.0, 540.0, 605.0]


@dataclass(frozen=True)
class Quality:
    """Photon counts and image sizes of one quality level."""

    name: str
    resolution: tuple[int, int]
    spp: int
    # Photons emitted for the surface map (`photons`): the volume pass's first this many,
    # topped up by a surface pass where it emits fewer (docs/render-contract.md).
    photons: int
    # Volume photons stored per band in the disc scenes (the paper counts its 100 M photons as
    # collected, i.e. stored), half of them aimed at the discs (`aim` 0.5); at most
    # EMIT_CAP × this many are emitted.
    volume_photons: int
    tooth_resolution_mm: float
    crop_resolution: tuple[int, int]
    volpath_spp: int
    k: int
    # Largest gathering radius [mm]: below the 0.5 mm disc's thickness, so the gather sphere
    # stays mostly inside the medium (the core's default, derived from the mean photon
    # density, reaches 1.6 mm here and blurs the checker seen through the thin disc away).
    radius_mm: float
    # Teeth scenes: only the photons that hit the small teeth count, and enamel is ~1 mm
    # thick rather than 0.5 mm, so they take more photons and a larger radius.
    teeth_volume_photons: int
    teeth_radius_mm: float
    teeth_spp: int
    # Volume photons stored per band in the teeth scenes (the paper counts its 100 M photons
    # as collected, i.e. stored); `teeth_volume_photons` then caps the photons emitted.
    teeth_volume_stored: int = 0
    # Photons per volume estimate in the teeth scenes.
    teeth_k: int = 400
    # Surface photons emitted in the teeth scenes: their volume pass emits only about
    # 27 000 photons per million it stores in the teeth (540 nm), 2.7 M at the paper's
    # 100 M, so more than that would add a surface pass.
    teeth_photons: int = 1_000_000
    # Largest gathering radius of the surface photon map [mm], every scene: the media's
    # radii (tenths of a millimetre) left the light under the raised disc and on Fig. 5's
    # walls a few photons per estimate; 2 mm is above the k-th neighbour's distance there
    # (4 mm renders the same) and reads volpath-nee's level under the disc
    # (docs/notes/2026-12-06-figures-timing.md, "The surface map's radius").
    surface_radius_mm: float = 2.0
    # Photons per surface-map estimate in the disc scenes (`surface_k`): a quarter of `k`.
    # The map there holds only indirect light; at 128 × 96 and 512 × 384 the smaller kernel
    # halved the bias at the ribbon's edge and cut the time to 2 % per pixel
    # (docs/notes/2026-12-06-bre.md, "512 × 384, measured";
    # docs/notes/2026-12-06-figures-timing.md). None: `k`.
    surface_k: int | None = None
    # Tissue figures (Fig. 4's enamel, Fig. 5, the crown): anisotropy lowered to this g by the
    # similarity relation (μs' kept), as the paper scaled its teeth's anisotropy; None
    # renders the library's g (docs/figures.md).
    similarity_g: float | None = 0.75


QUALITIES = {
    # a few minutes for everything on a 2-core machine (what `make demo` runs); the discs store
    # 16 M volume photons with k 200: less colour noise in less time than 4 M with k 800
    # (benchmarks/chroma_noise.py, docs/notes/2026-12-06-figures-timing.md, "Photon counts")
    "preview": Quality("preview", (320, 240), 4, 1_000_000, 16_000_000, 0.3, (96, 72), 8192, 200,
                       0.3, 100_000_000, 1.0, 8, teeth_volume_stored=16_000_000,
                       surface_k=50),
    # the paper's 100 M volume photons; 4 M surface photons instead of its 1 M global ones:
    # they are the volume pass's first 4 M photons (it emits about 9 M to store 100 M in the
    # discs), so they cost no tracing, and at k 800 the paper's 1 M left the light under the
    # raised disc 5 % low at 450 nm, a k-NN blur that 4 M removes
    # (docs/notes/2026-12-06-figures-timing.md, "The surface map's photon count")
    "paper": Quality("paper", (512, 384), 16, 4_000_000, 100_000_000, 0.15, (192, 144), 16384,
                     800, 0.15, 1_000_000_000, 0.5, 16, teeth_volume_stored=100_000_000,
                     surface_k=200),
}


# Photons emitted per photon a figure asks to store, at most (a guard: a medium the light
# hardly reaches would otherwise keep the photon pass running).
EMIT_CAP = 25
# Fraction of a figure's volume photons aimed at its media (`aim`).
FIGURE_AIM = 0.5


def _media_table(material, bands) -> dict:
    """A scene medium with explicit per-band values from a Material (used for materials
    that are not in the library, such as a scaled copy)."""
    v = material.at(np.asarray(bands, float))
    table = {}
    for key in ("mua", "mus", "g", "fd", "n"):
        vals = np.atleast_1d(getattr(v, key)).astype(float).tolist()
        table[key] = {"wavelengths_nm": [float(b) for b in bands], "values": vals}
    return table


def disc_scene(medium: dict, thickness_mm: float, quality: Quality) -> dict:
    """The Fig. 3 set-up with discs of ``thickness_mm``: the left disc lies on the ribbon,
    the right one's underside is 5 mm above it (as in the paper)."""
    d = discs_scene(resolution=quality.resolution)
    d["media"] = {"disc": medium}
    for shape in d["shapes"]:
        if shape["type"] == "cylinder":
            shape["height"] = float(thickness_mm)
    d["camera"]["look_at"] = [0.0, 0.0, min(2.5, thickness_mm / 2 + 2.0)]
    return d


def transmittance_d65(material, thickness_mm: float, photons: int = 20_000,
                      seed: int = 3) -> float:
    """D65-weighted total transmittance of a disc (slab simulator, collimated normal light),
    from the paper's three bands reconstructed with the `hold` basis."""
    tt = []
    for wl in PAPER_BANDS:
        v = material.at(wl)
        r = simulate([Layer(mua=v.mua, mus=v.mus, g=v.g, n=v.n, thickness=thickness_mm,
                            fd=v.fd)], n_photons=photons, seed=seed, estimator="weighted")
        tt.append(r.total_transmittance)
    grid = spectra.FINE_GRID
    spectrum = np.interp(grid, PAPER_BANDS, tt)
    return float(spectra.weighted_mean(spectrum, grid))


def match_enamel_scale(target_tt: float, thickness_mm: float, enamel) -> float:
    """The factor s on enamel's μa and μs (its optical thickness) whose disc has the target
    D65 total transmittance: bisection on log s (transmittance falls monotonically with s)."""
    lo, hi = -6.0, 6.0
    for _ in range(22):
        mid = 0.5 * (lo + hi)
        tt = transmittance_d65(enamel.scaled(math.exp(mid), math.exp(mid)), thickness_mm)
        if tt > target_tt:
            lo = mid
        else:
            hi = mid
    return math.exp(0.5 * (lo + hi))


def disc_settings(quality: Quality) -> dict:
    """The figures' render settings at ``quality``: the disc scenes' (Fig. 3, Fig. 4, the
    crop); the teeth scenes override them with :func:`_teeth_settings`."""
    return dict(spp=quality.spp, photons=quality.photons,
                volume_photons=EMIT_CAP * quality.volume_photons,
                volume_stored=quality.volume_photons, aim=FIGURE_AIM, k=quality.k,
                radius=quality.radius_mm, surface_radius=quality.surface_radius_mm,
                surface_k=quality.surface_k)


def _render_figure(name: str, scene: dict, out: Path, quality: Quality, integrator: str = "vpm",
                   regions: dict | None = None, extra: dict | None = None,
                   bands=PAPER_BANDS, white: float | None = None, **overrides) -> dict:
    sc = scene_from_dict(scene)
    t0 = time.perf_counter()
    settings = disc_settings(quality)
    settings.update(overrides)
    if integrator in PATH_TRACERS:
        for key in ("volume_photons", "volume_stored", "aim", "photons", "k", "radius",
                    "surface_radius", "surface_k"):
            settings.pop(key, None)
    result = render(sc, integrator=integrator, bands=bands, seed=1, correlated_bands=True,
                    **settings)
    folder = out / name
    summary = write_render_outputs(sc, result, folder, regions=regions, white=white)
    summary.update({"figure": name, "quality": asdict(quality), **(extra or {})})
    summary["timings"]["figure_s"] = time.perf_counter() - t0
    summary["peak_memory_bytes"] = peak_memory_bytes()
    (folder / "figure.json").write_text(json.dumps(summary, indent=2, default=str))
    shutil.copyfile(folder / "image.png", out / f"{name}.png")
    return summary


def fig2(out: Path) -> dict:
    from dentalux.plots import fig2_spd

    paths = fig2_spd(out, stem="fig2_spd")
    return {"figure": "fig2_spd", "files": paths,
            "linear_only_fraction": spectra.linear_only_fraction()}


def fig3(out: Path, quality: Quality, thickness_mm: float) -> dict:
    name = f"fig3_biomaterial_{thickness_mm:g}mm"
    scene = disc_scene({"material": "biomaterial-table1"}, thickness_mm, quality)
    return _render_figure(name, scene, out, quality,
                          extra={"disc_thickness_mm": thickness_mm})


def fig4(out: Path, quality: Quality, thickness_mm: float) -> dict:
    bio = materials.get("biomaterial-table1")
    enamel = materials.get("enamel")
    if quality.similarity_g is not None:
        # lower g first, so the transparency is matched for the material that is rendered
        enamel = enamel.similar(quality.similarity_g, note="figures: fewer photons")
    target = transmittance_d65(bio, thickness_mm)
    s = match_enamel_scale(target, thickness_mm, enamel)
    scaled = enamel.scaled(
        mus_factor=s, mua_factor=s,
        note=f"optical thickness x {s:.4g} so that a {thickness_mm:g} mm disc transmits "
             f"{target:.4f} of D65 like the biomaterial (Fig. 4)")
    name = f"fig4_enamel_{thickness_mm:g}mm"
    scene = disc_scene(_media_table(scaled, PAPER_BANDS), thickness_mm, quality)
    return _render_figure(name, scene, out, quality, extra={
        "disc_thickness_mm": thickness_mm, "enamel_optical_thickness_factor": s,
        "target_d65_transmittance": target,
        "enamel_d65_transmittance": transmittance_d65(scaled, thickness_mm),
        "material_provenance": scaled.provenance})


def cornell_teeth_scene(quality: Quality) -> dict:
    """Fig. 5's scene (:func:`dentalux.scene.builtin.cornell_teeth`) at ``quality``."""
    return builtin.cornell_teeth(quality.resolution, quality.tooth_resolution_mm)


def _teeth_settings(quality: Quality) -> dict:
    return {"photons": quality.teeth_photons, "volume_photons": quality.teeth_volume_photons,
            "aim": FIGURE_AIM,
            "volume_stored": quality.teeth_volume_stored, "radius": quality.teeth_radius_mm,
            "surface_radius": quality.surface_radius_mm, "spp": quality.teeth_spp,
            "k": quality.teeth_k, "surface_k": None}


def lower_anisotropy(scene: dict, quality: Quality, bands=PAPER_BANDS) -> dict:
    """Replace every library medium of ``scene`` by its similarity-scaled copy at
    ``quality.similarity_g`` (in place); returns each medium's scaling record for the
    figure's JSON. With g ≈ 0.95 (dentin) a phase-weighted estimate over k photons counts
    about k (1 − g²)² / (1 + g²) of them (k / 200): the grain the paper avoided the same way."""
    g = quality.similarity_g
    if g is None:
        return {}
    records = {}
    for key, medium in scene["media"].items():
        if set(medium) != {"material"}:
            continue
        m = materials.get(medium["material"]).similar(g, note="figures: fewer photons")
        scene["media"][key] = _media_table(m, bands)
        records[key] = {"material": m.name, "scaling": m.provenance["scaling"]}
    return records


def fig5(out: Path, quality: Quality) -> dict:
    scene = cornell_teeth_scene(quality)
    scaling = lower_anisotropy(scene, quality)
    return _render_figure("fig5_teeth_cornell", scene, out, quality,
                          extra={"anisotropy_scaling": scaling}, **_teeth_settings(quality))


def crown_scene(quality: Quality, layers=None, core=None) -> tuple[dict, dict]:
    """The crown figure's scene and regions (:func:`dentalux.scene.builtin.crown`) at
    ``quality``."""
    return builtin.crown(quality.resolution, quality.tooth_resolution_mm, layers, core)


def white_tile(scene: dict, regions: dict, quality: Quality, z_mm: float = -3.5) -> dict:
    """Calibrate as a spectrophotometer does: the same scene without the teeth, a white
    Lambertian tile (reflectance 1) in the plane of the labial faces, rendered with `pm`
    (opaque surfaces only); returns the tile's radiance relative to the light's spectrum,
    averaged over the measured regions and bands: L* = 100 in the crown figure."""
    from dentalux.outputs import colour_inputs

    d = copy.deepcopy(scene)
    # no teeth: neither tooth entries nor a layered crown's meshes (dielectric, "inside")
    d["shapes"] = [s for s in d["shapes"] if s["type"] != "tooth" and "inside" not in s]
    d["media"] = {}
    d["surfaces"]["white_tile"] = {"type": "lambertian", "reflectance": 1.0}
    d["shapes"].append({"type": "quad", "name": "white tile", "corner": [-30.0, -30.0, z_mm],
                        "u": [60.0, 0.0, 0.0], "v": [0.0, 60.0, 0.0], "surface": "white_tile"})
    sc = scene_from_dict(d)
    result = render(sc, integrator="pm", bands=PAPER_BANDS, seed=2, spp=quality.teeth_spp,
                    photons=quality.teeth_photons // 4, progress=False)
    divisor, _, _ = colour_inputs(sc, PAPER_BANDS)
    rel = result.radiance / divisor
    values = [rel[y0:y1, x0:x1].mean(axis=(0, 1)) for x0, y0, x1, y1 in regions.values()]
    per_band = np.mean(values, axis=0)
    return {"white": float(per_band.mean()), "per_band": per_band.tolist(), "z_mm": z_mm}


def fig_crown(out: Path, quality: Quality) -> dict:
    from dentalux.color import delta_e00
    from dentalux.dental import verdict

    scene, regions = crown_scene(quality)
    tile = white_tile(scene, regions, quality)
    scaling = lower_anisotropy(scene, quality)
    summary = _render_figure("crown_vs_natural", scene, out, quality, regions=regions,
                             white=tile["white"],
                             extra={"anisotropy_scaling": scaling, "white_tile": tile},
                             **_teeth_settings(quality))
    labs = {k: np.array(v["lab"]) for k, v in summary["colour"]["regions"].items()}
    de = float(delta_e00(labs["natural"], labs["crown"]))
    summary["delta_e00"] = de
    summary["verdict"] = verdict(de)
    # the natural incisor's labial middle third against the published natural-tooth range
    rng = natural_teeth.reference_range("mid-incisal")
    summary["natural_range"] = rng
    summary["natural_in_range"] = natural_teeth.inside(labs["natural"], rng)
    _annotate(out / "crown_vs_natural" / "image.png", out / "crown_vs_natural.png", regions,
              f"ΔE00 = {de:.2f} ({summary['verdict']})")
    (out / "crown_vs_natural" / "figure.json").write_text(
        json.dumps(summary, indent=2, default=str))
    return summary


# the natural incisor's labial thirds: (height above the CEJ, labial face depth) [mm] in the
# crown scene (tooth z up, labial +y towards the camera after the -90 deg turn about x)
NATURAL_THIRDS = {"cervical": (1.7, -3.4), "middle": (5.0, -3.5), "incisal": (8.5, -1.9)}
BOOTSTRAP = 200  # resamples of a region's pixels for a standard error


def pixel_bootstrap_stderr(px: dict, stat, rng, n: int = BOOTSTRAP) -> float:
    """Standard error of ``stat(means)`` from the pixel spread: each region's pixels
    (``px``: name -> pixels x bands) resampled with replacement on its own, ``n`` times,
    ``stat`` applied to the dictionary of the resampled mean spectra."""
    boot = [stat({k: v[rng.integers(0, len(v), len(v))].mean(axis=0) for k, v in px.items()})
            for _ in range(n)]
    return float(np.std(boot, ddof=1))


def crown_translucency(quality: Quality, half_mm: float = 0.8, seed: int = 1,
                       bands=PAPER_BANDS) -> dict:
    """The natural incisor's translucency by thirds, read in the render as a TP: the crown
    scene over the black contrastor and over a white one (reflectance 0.85), both calibrated
    by the same white tile; TP = ΔE*ab between the two readings of each third. Returns
    {third: {"lab_black", "lab_white", "tp", "tp_stderr"}}, the regions and the tile."""
    from dentalux.color import delta_e76, spectrum_to_Lab
    from dentalux.outputs import colour_inputs

    scene, regions = crown_scene(quality)
    cam = scene["camera"]
    thirds = {name: square_region(cam, [6.5, y, z], half_mm)
              for name, (y, z) in NATURAL_THIRDS.items()}
    tile = white_tile(scene, regions, quality)
    lower_anisotropy(scene, quality, bands)
    cubes = {}
    for backdrop, surface in (("black", {"type": "black"}),
                              ("white", {"type": "lambertian", "reflectance": 0.85})):
        d = copy.deepcopy(scene)
        d["surfaces"]["backdrop"] = surface
        sc = scene_from_dict(d)
        result = render(sc, integrator="vpm", bands=bands, seed=seed, correlated_bands=True,
                        progress=False, **_teeth_settings(quality))
        divisor, _, _ = colour_inputs(sc, bands)
        cubes[backdrop] = result.radiance / divisor / tile["white"]
    wl = np.asarray(bands)
    rng = np.random.default_rng(seed)
    out = {}
    for name, (x0, y0, x1, y1) in thirds.items():
        px = {k: c[y0:y1, x0:x1].reshape(-1, len(bands)) for k, c in cubes.items()}
        lab = {k: np.asarray(spectrum_to_Lab(v.mean(axis=0), wl)) for k, v in px.items()}
        # the standard error of TP from the pixel spread (each backdrop resampled on its own)
        stderr = pixel_bootstrap_stderr(
            px, lambda m: delta_e76(spectrum_to_Lab(m["black"], wl),
                                    spectrum_to_Lab(m["white"], wl)), rng)
        out[name] = {"lab_black": lab["black"].tolist(), "lab_white": lab["white"].tolist(),
                     "tp": float(delta_e76(lab["black"], lab["white"])), "tp_stderr": stderr}
    return out | {"regions": thirds, "white_tile": tile}


def _annotate(src: Path, dst: Path, regions: dict, text: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    img = plt.imread(src)
    h, w = img.shape[:2]
    fig = plt.figure(figsize=(w / 100, h / 100 + 0.4), dpi=100)
    ax = fig.add_axes((0, 0, 1, h / (h + 40)))
    ax.imshow(img)
    for name, (x0, y0, x1, y1) in regions.items():
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec="w", lw=0.8))
        ax.text(x0, y0 - 3, name, color="w", fontsize=6)
    ax.axis("off")
    fig.text(0.5, 1 - 20 / (h + 40), text, ha="center", va="center", fontsize=7)
    fig.savefig(dst, dpi=100)
    plt.close(fig)


def vpm_vs_volpath(out: Path, quality: Quality, thickness_mm: float = 0.5) -> dict:
    """Fig. 3's disc on the ribbon at a small resolution with vpm and with the unbiased
    volpath; side by side with the relative RMSE of vpm against volpath."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    q = Quality(**{**asdict(quality), "resolution": quality.crop_resolution})
    scene = disc_scene({"material": "biomaterial-table1"}, thickness_mm, q)
    scene["camera"]["look_at"] = [-8.0, 0.0, thickness_mm / 2]
    scene["camera"]["fov_deg"] = 18.0
    bands = [540.0]
    a = _render_figure("crop_vpm", copy.deepcopy(scene), out, q, "vpm", bands=bands)
    b = _render_figure("crop_volpath", scene, out, q, "volpath", bands=bands,
                       spp=quality.volpath_spp)
    ra = np.load(out / "crop_vpm" / "radiance.npy")[..., 0]
    rb = np.load(out / "crop_volpath" / "radiance.npy")[..., 0]
    rel_rmse = float(np.sqrt(np.mean((ra - rb) ** 2)) / max(float(np.mean(rb)), 1e-30))
    top = float(np.percentile(np.concatenate([ra.ravel(), rb.ravel()]), 99)) or 1.0
    fig, axes = plt.subplots(1, 2, figsize=(7, 3))
    for ax, img, title, s in ((axes[0], ra, "vpm", a), (axes[1], rb, "volpath", b)):
        ax.imshow(np.clip(img / top, 0, 1) ** (1 / 2.2), cmap="gray", vmin=0, vmax=1)
        ax.set_title(f"{title}: {s['timings']['figure_s']:.0f} s", fontsize=8)
        ax.axis("off")
    fig.suptitle(f"540 nm, {thickness_mm:g} mm disc on the ribbon; relative RMSE of vpm "
                 f"vs volpath {100 * rel_rmse:.1f} %", fontsize=8)
    fig.savefig(out / "vpm_vs_volpath.png", dpi=120)
    plt.close(fig)
    return {"figure": "vpm_vs_volpath", "relative_rmse": rel_rmse,
            "vpm_s": a["timings"]["figure_s"], "volpath_s": b["timings"]["figure_s"]}


FIGURES = ("fig2", "fig3", "fig4", "fig5", "crown", "crop")


def make_figures(out_dir, quality: str | Quality = "preview", only=None, log=print) -> dict:
    """Render the figures named in ``only`` (default all of FIGURES) into ``out_dir`` at a
    quality level (a name of QUALITIES or a Quality); returns and writes ``figures.json``
    with each figure's summary."""
    if isinstance(quality, Quality):
        q = quality
    elif quality in QUALITIES:
        q = QUALITIES[quality]
    else:
        raise ValueError(f"quality = {quality!r}: allowed {', '.join(QUALITIES)}")
    if only is not None and not list(only):
        raise ValueError("only = []: names no figure (None renders all of them)")
    todo = list(FIGURES if only is None else only)
    for f in todo:
        if f not in FIGURES:
            raise ValueError(f"figure {f!r}: allowed {', '.join(FIGURES)}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    jobs = {
        "fig2": lambda: [fig2(out)],
        "fig3": lambda: [fig3(out, q, 5.0), fig3(out, q, 0.5)],
        "fig4": lambda: [fig4(out, q, 5.0), fig4(out, q, 0.5)],
        "fig5": lambda: [fig5(out, q)],
        "crown": lambda: [fig_crown(out, q)],
        "crop": lambda: [vpm_vs_volpath(out, q)],
    }
    report = {"quality": q.name, "figures": {}}
    for f in todo:
        t0 = time.perf_counter()
        log(f"rendering {f} ({quality}) ...")
        report["figures"][f] = jobs[f]()
        log(f"  {f} done in {time.perf_counter() - t0:.1f} s")
    (out / "figures.json").write_text(json.dumps(report, indent=2, default=str))
    return report
