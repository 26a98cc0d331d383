"""``dentalux.render``: render a scene band by band with the Rust core.

All bands go to the core in one call,
``dentalux._core.render_bands(scene_json, settings_json, band_keys, progress)``
(docs/render-contract.md): the shapes are sent, decoded and put in a BVH once, and each band
brings its own media, surfaces and lights. It returns a float32 (bands, height, width)
radiance cube and a stats dict per band; ``RenderResult.radiance`` is (height, width, bands).

Randomness: the core derives every stream from (seed, band, batch/tile). ``band`` in the
settings is the wavelength rounded to the nearest nm, so a band renders the same whichever
other bands are requested with it.
"""

from __future__ import annotations

import difflib
import json
import os
import re
import time
from dataclasses import dataclass, field
from numbers import Integral, Real

import numpy as np

from dentalux import _core, limits
from dentalux.progress import bar
from dentalux.scene.load import as_scene
from dentalux.scene.resolve import Scene
from dentalux.scene.schema import RENDER_KEYS, SETTING_KEYS, validate_bands, validate_settings

# Settings passed through ``**options`` (the core's names, docs/render-contract.md): all but
# the named arguments of :func:`render`, ``band`` (one per wavelength) and ``threads``.
OPTIONS = tuple(k for k in SETTING_KEYS
                if k not in ("integrator", "spp", "photons", "seed", "band", "threads"))
# Ticks of the progress bar per band; the core's progress(done) is mapped onto them.
TICKS = 1000


def photons_traced(settings: dict) -> int:
    """Photons one pass of one band traces (the progress bar's unit besides pixels), as the
    core counts them (``Settings::photons_traced``)."""
    return _core.photons_traced(json.dumps(settings))


@dataclass
class RenderResult:
    """radiance: float32 (height, width, bands) [W/(m^2 sr nm), up to the lights' scale];
    bands: wavelengths [nm]; stats: timings, settings and the core's per-band stats."""

    radiance: np.ndarray
    bands: list[float]
    stats: dict = field(default_factory=dict)
    scene_hash: str = ""
    settings: dict = field(default_factory=dict)


def check_finite(image: np.ndarray, wavelength_nm: float) -> None:
    """Refuse a band image with inf or NaN pixels: some input overflowed float32 (a light's
    radiance or intensity, a transform's scale, a coefficient) and no image or JSON should
    be written from it."""
    bad = ~np.isfinite(image)
    if bad.any():
        raise ValueError(
            f"the render at {wavelength_nm:g} nm has {int(bad.sum())} non-finite pixel(s) "
            f"(inf or NaN) of {image.size}: an input overflows (the largest float32 is "
            f"{float(np.finfo(np.float32).max):.3g}); check the lights' radiance and "
            "intensity and the transforms' scale")


def spectral_warnings(sc: Scene, bands) -> list[str]:
    """What a spectral photon pass over ``bands`` should be told: media whose refractive
    index differs between the bands, where a refraction in one band is a direction the others
    cannot draw (docs/spectral-photons.md), so light refracted into them is carried by each
    band's own hero photons only."""
    out = []
    for name in sc.media_names:
        n = [sc.medium_at(name, wl)["n"] for wl in bands]
        if max(n) != min(n):
            out.append(f"spectral_photons: media.{name}'s refractive index differs between "
                       f"the bands ({min(n):g} to {max(n):g}), so walks refracted into or out "
                       "of it are not shared: each band keeps about 1/bands of those photons "
                       "and its colour is noisier than band-by-band passes")
    return out


def name_the_band(message: str, bands: list[float]) -> str:
    """A core error about ``bands[i]`` of a render_bands call, with the band named by its
    wavelength (the user never saw the call's band indices)."""
    m = re.match(r"bands\[(\d+)\](?:\.|: )(.*)", message, re.S)
    if m is None or int(m.group(1)) >= len(bands):
        return message
    return f"at {bands[int(m.group(1))]:g} nm: {m.group(2)}"


def core_render_bands():
    """The native ``render_bands``, or a clear error while the core lacks it."""
    fn = getattr(_core, "render_bands", None)
    if fn is None:
        raise RuntimeError(
            "dentalux._core.render_bands is not in this build; rebuild with `make build-prod`"
        )
    return fn


def _resolution(resolution) -> tuple[int, int] | None:
    """``(width, height)``, ``"WxH"`` or ``None``."""
    if resolution is None:
        return None
    if isinstance(resolution, str):
        parts = resolution.lower().split("x")
        try:
            w, h = (int(p) for p in parts)
        except ValueError:
            raise ValueError(f"resolution = {resolution!r}: expected WIDTHxHEIGHT, "
                             "e.g. 64x48") from None
    else:
        try:
            w, h = resolution
        except (TypeError, ValueError):
            raise ValueError(f"resolution = {resolution!r}: expected (width, height)") from None
    for name, x in (("width", w), ("height", h)):
        if isinstance(x, bool) or not isinstance(x, Integral) or x < 1:
            raise ValueError(f"resolution {name} = {x!r}: out of range, allowed integer >= 1")
    return int(w), int(h)


def build_settings(scene: Scene, integrator=None, spp=None, photons=None, seed=None,
                   threads=None, **options) -> dict:
    """The contract settings (without ``band``): arguments override the scene's
    ``[render]`` table, which overrides the defaults."""
    for key in options:
        if key not in OPTIONS:
            close = difflib.get_close_matches(key, OPTIONS, n=1, cutoff=0.6)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise ValueError(f"{key}: unknown render option; {hint}(allowed: "
                             f"{', '.join(OPTIONS)})")
    defaults = scene.render_defaults
    settings = {k: defaults[k] for k in RENDER_KEYS if k != "bands"}
    settings["integrator"] = scene.default_integrator
    given = {"integrator": integrator, "spp": spp, "photons": photons, "seed": seed,
             **options}
    settings.update({k: v for k, v in given.items() if v is not None})
    settings["threads"] = threads
    return validate_settings(settings, path="")


def plan(scene, integrator: str | None = None, spp: int | None = None,
         photons: int | None = None, bands=None, seed: int | None = None,
         threads: int | None = None, resolution=None, **options) -> dict:
    """Every check :func:`render` makes before the core starts, in one place: the scene, the
    bands (the colour range, distinct), the settings (the core's ranges) and the ceilings
    and memory of docs/limits.md. ``dentalux scene check`` calls it too, so that it never
    calls valid what ``dentalux render`` refuses. Returns the scene, bands, settings,
    resolution and texture pixels."""
    sc = as_scene(scene)
    band_list = validate_bands(sc.bands if bands is None else bands, "bands")
    settings = build_settings(sc, integrator=integrator, spp=spp, photons=photons, seed=seed,
                              threads=threads, **options)
    res = _resolution(resolution) or sc.resolution
    texels = sc.texels()
    limits.check_render(settings, res[0], res[1], len(band_list), texels)
    return {"scene": sc, "bands": band_list, "settings": settings, "resolution": res,
            "texels": texels}


def render(scene, integrator: str | None = None, spp: int | None = None,
           photons: int | None = None, bands=None, seed: int | None = None,
           threads: int | None = None, resolution=None, progress: bool | None = None,
           correlated_bands: bool = False, **options) -> RenderResult:
    """Render ``scene`` (a Scene, a dict or a TOML path) at ``bands`` [nm].

    integrator: one of ``scene.schema.INTEGRATORS`` (default: the scene's
    ``render.integrator``, else ``vpm`` for scenes with dielectric media and ``pm``
    otherwise). spp: samples per pixel; photons: photons for the surface map (the volume
    integrators take them from the volume pass); seed: random seed; threads: worker
    threads (default all cores; the image does not depend on it);
    resolution: (width, height) or "WxH", overriding the camera's. ``options``:
    volume_photons, volume_stored (photons the volume maps should hold: emission stops there,
    at most volume_photons), aim (fraction of volume photons aimed at the media, [0, 1)),
    k, surface_k (the surface map's; default k), radius [mm], surface_radius [mm] (the
    surface map's; default radius), step [mm],
    max_depth, passes, alpha, final_gather, kernel_layer (0 = the paper's spherical kernel),
    kernel_clip (clip the layer kernel by every face, not only the camera ray's entry and
    exit planes), spectral_photons (one photon pass for all bands), hero_camera (one camera
    path per pixel sample for all bands, with a throughput per band), pass_index (render
    pass p of a progressive render: its own photon maps and paths, the pixels' sub-pixel
    sequence continued where pass p − 1 stopped; the mean of passes 0..N−1 is what
    ``dentalux render --passes N`` shows).
    progress: True (a bar on stderr), False, None (a bar when stderr is a terminal) or a
    callable ``progress(done, total)``; an exception it raises stops the render and
    propagates. Sizes and counts are checked first (docs/limits.md): threads 1 ... 4 x the
    logical cores, photon and spp ceilings, and the memory the film and photon maps need.
    correlated_bands: give every band the same random streams (band key 0) instead of one
    per wavelength. Photon and camera paths then share their random numbers across bands
    (correlated sampling), so Monte Carlo noise is nearly the same in every band: it shows
    as grain in lightness instead of coloured blotches, and colour differences between
    regions are estimated with less variance. Each band is still unbiased.
    """
    t0 = time.perf_counter()
    p = plan(scene, integrator=integrator, spp=spp, photons=photons, bands=bands, seed=seed,
             threads=threads, resolution=resolution, **options)
    sc, band_list, settings, res, texels = (p["scene"], p["bands"], p["settings"],
                                            p["resolution"], p["texels"])
    render_bands = core_render_bands()
    w, h = res
    nb = len(band_list)
    spectral, together = limits.shared_bands(settings, nb)
    # Bands go to the core together, except in scenes with image textures: every band's
    # surfaces carry a texture's pixels, so those bands go one at a time (one copy in memory)
    # unless a spectral pass or hero camera paths need them all at once, which the memory
    # check then counts.
    groups = [list(range(nb))] if together or not texels else [[b] for b in range(nb)]
    # The core's progress(done) counts photons traced plus pixels finished, summed over the
    # bands of a call, photons once for a spectral pass (render.rs)
    per_pass = photons_traced(settings) * settings["passes"]

    def group_work(g: list[int]) -> int:
        return per_pass * (1 if spectral else len(g)) + w * h * len(g)

    work = max(1, sum(group_work(g) for g in groups))
    ticks = nb * TICKS
    t_load = time.perf_counter() - t0
    keys = [0 if correlated_bands else int(round(wl)) for wl in band_list]
    warnings = spectral_warnings(sc, band_list) if spectral else []
    settings_json = json.dumps({**settings, "band": 0})
    cubes, per_band = [], []
    with bar(ticks, f"render {nb} band(s)", progress) as cb:
        before = 0
        for g in groups:

            def tick(done: int, before: int = before) -> None:
                cb(min(ticks, int(ticks * (before + done) / work)))

            try:
                cube, stats_g = render_bands(sc.bands_json([band_list[b] for b in g], res),
                                             settings_json, [keys[b] for b in g],
                                             tick if cb is not None else None)
            except ValueError as exc:
                raise ValueError(name_the_band(str(exc), [band_list[b] for b in g])) from None
            cubes.append(np.asarray(cube, dtype=np.float32))
            per_band += list(stats_g)
            before += group_work(g)
        if cb is not None:
            cb(ticks)
    cube = np.concatenate(cubes) if len(cubes) > 1 else cubes[0]
    if cube.shape != (len(band_list), h, w):
        raise RuntimeError(f"render_bands returned a cube of shape {cube.shape}, "
                           f"expected {(len(band_list), h, w)}")
    for image, wl in zip(cube, band_list, strict=True):
        check_finite(image, wl)
    per_band = [{"wavelength_nm": wl, **dict(st)}
                for wl, st in zip(band_list, per_band, strict=True)]
    seconds = [st["seconds_total"] for st in per_band]
    radiance = np.ascontiguousarray(np.moveaxis(cube, 0, -1))
    stats = {
        "integrator": settings["integrator"],
        "resolution": [w, h],
        "threads": threads or os.cpu_count() or 1,
        "seconds_load": t_load,
        "seconds_per_band": seconds,
        "seconds_total": time.perf_counter() - t0,
        "bands": per_band,
        "warnings": warnings,
    }
    for key in ("photons_emitted", "photons_stored", "surface_photons", "volume_photons"):
        vals = [s[key] for s in per_band if isinstance(s.get(key), Real)]
        if vals:
            # a spectral pass's bands share their photons: they were traced and stored once
            stats[f"{key}_total"] = vals[0] if spectral else sum(vals)
    return RenderResult(radiance=radiance, bands=band_list, stats=stats, scene_hash=sc.hash,
                        settings=settings)
