"""What a finished render leaves on disk: radiance.npy, grey previews per band, colour images
(image.png, image.exr, spectral.exr, colour.json via :func:`dentalux.color.write_images`)
and render.json. Shared by ``dentalux render`` and ``dentalux figures``."""

from __future__ import annotations

import resource
import sys
from pathlib import Path

import numpy as np

from dentalux.scene.resolve import Scene
from dentalux.strict_json import dumps_strict


def peak_memory_bytes() -> int:
    """Peak resident memory of this process [bytes] (Linux reports ru_maxrss in KiB)."""
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(rss if sys.platform == "darwin" else rss * 1024)


def write_previews(radiance: np.ndarray, bands: list[float], out: Path) -> dict[str, str]:
    """One 8-bit grey PNG per band, sRGB-encoded, with a common exposure: the 99th
    percentile of all bands maps to white (so relative brightness between bands is kept)."""
    from PIL import Image

    finite = radiance[np.isfinite(radiance)]
    top = float(np.percentile(finite, 99)) if finite.size else 0.0
    scale = 1.0 / top if top > 0 else 1.0
    files = {}
    for b, wl in enumerate(bands):
        x = np.clip(np.nan_to_num(radiance[:, :, b] * scale), 0.0, 1.0)
        srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
        name = f"band_{wl:g}nm.png"
        Image.fromarray((srgb * 255 + 0.5).astype(np.uint8), mode="L").save(out / name)
        files[f"{wl:g}"] = str(out / name)
    return files


def colour_inputs(scene: Scene, bands: list[float]) -> tuple[np.ndarray, str, float]:
    """What ``write_images`` needs, :meth:`Scene.illuminant`: it expects radiance relative
    to an equal-energy light and applies the illuminant itself, so the radiance is divided
    by the lights' relative spectrum (the factor the scene multiplied them by) and the
    illuminant named; ``white`` is the brightest light's radiance scale."""
    return scene.illuminant(bands)


def region_matcher(guide: str | None):
    """For a shade guide, the function that gives a measured region's nearest tabs
    (``shade_match``: tab and ΔE00, nearest first) and the geometry they were read in; None
    without a guide. Checks up front that the guide exists and has published values."""
    if guide is None:
        return None
    from dentalux.shade_guides import instruments_of, nearest

    nearest((50.0, 0.0, 0.0), guide)  # an unknown guide or one without values fails here
    read_with = instruments_of(guide)

    def extra(lab) -> dict:
        return {"shade_match": [{"tab": t, "delta_e00": de} for t, de in nearest(lab, guide)],
                "shade_match_guide": guide,
                "shade_match_geometry": "the render's own lights and camera, mean spectrum "
                                        "of the region",
                # the guide's tabs were read with an instrument, the region by the render's
                # camera: another geometry, said in the output (issue 41)
                "shade_match_guide_instrument": read_with}
    return extra


def write_render_outputs(scene: Scene, result, out: Path, regions: dict | None = None,
                         scene_file: str | None = None, warn=None,
                         white: float | None = None, write_json: bool = True,
                         match: str | None = None) -> dict:
    """Write radiance.npy, previews, colour images and render.json for a RenderResult;
    returns the render.json dictionary. ``white``: the radiance (relative to the light's
    spectrum) that counts as L* = 100, e.g. a white tile measured in the same geometry; the
    image is then exposed so that this white is display white. Default: the brightest
    light's radiance, with automatic exposure. ``write_json=False`` leaves render.json to a
    caller that adds to the dictionary first (it is then written once). ``match``: a shade
    guide whose nearest tabs (ΔE00) each measured region's entry in colour.json gets as
    ``shade_match``, read in the render's own geometry (its lights and camera)."""
    from dentalux.color import write_images

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    np.save(out / "radiance.npy", result.radiance)
    files = {"radiance": str(out / "radiance.npy"),
             "previews": write_previews(result.radiance, result.bands, out)}
    summary = {
        "scene": scene_file,
        "scene_name": scene.description["scene"]["name"],
        "scene_hash": result.scene_hash,
        "bands_nm": result.bands,
        "shape": list(result.radiance.shape),
        "settings": result.settings,
        "timings": {"load_s": result.stats["seconds_load"],
                    "per_band_s": result.stats["seconds_per_band"],
                    "render_s": result.stats["seconds_total"]},
        "photons": {key: [b.get(key) for b in result.stats["bands"]]
                    for key in sorted({k for b in result.stats["bands"] for k in b
                                       if "photon" in k})},
        "stats": result.stats["bands"],
        "warnings": list(result.stats.get("warnings", [])),
        "files": files,
        "files_read": scene.files_read() if hasattr(scene, "files_read") else [],
    }
    if warn:
        for w in summary["warnings"]:
            warn(f"warning: {w}")
    divisor, illuminant, light_white = colour_inputs(scene, result.bands)
    if regions is None and tuple(result.radiance.shape[1::-1]) == tuple(scene.resolution):
        regions = scene.description.get("regions") or None
    try:
        summary["colour"] = write_images(result.radiance / divisor, result.bands, out,
                                         illuminant=illuminant, regions=regions,
                                         exposure=None if white is None else 0.0,
                                         white=light_white if white is None else white,
                                         region_extra=region_matcher(match))
    except ValueError as exc:  # e.g. too few bands for a colour image
        summary["colour_error"] = str(exc)
        if warn:
            warn(f"warning: no colour image: {exc}")
    summary["peak_memory_bytes"] = peak_memory_bytes()
    if write_json:
        (out / "render.json").write_text(dumps_strict(summary, indent=2))
    return summary
