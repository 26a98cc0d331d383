"""``dentalux render SCENE.toml --out DIR``: render a scene band by band.

Writes ``DIR/radiance.npy`` (float32, height x width x bands), ``DIR/render.json`` (scene
hash, bands, settings, timings, photon counts, peak memory) and a grey PNG preview per band
(``DIR/band_540nm.png``, all bands on one exposure). When the colour module provides
``dentalux.color.write_images``, the colour images are written too.
"""

from __future__ import annotations

import inspect
import json
import resource
import sys
import time
from pathlib import Path

import numpy as np
import typer

from dentalux.render import render
from dentalux.scene.load import load_scene
from dentalux.scene.resolve import Scene, d65_relative


def parse_bands(text: str | None) -> list[float] | None:
    """``"450,540,605"`` -> [450.0, 540.0, 605.0] (nm)."""
    if text is None:
        return None
    try:
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"--bands = {text!r}: expected comma-separated wavelengths in nm, "
                         "e.g. 450,540,605") from None


def parse_resolution(text: str | None) -> tuple[int, int] | None:
    """``"64x48"`` -> (64, 48)."""
    if text is None:
        return None
    try:
        w, h = (int(p) for p in text.lower().split("x"))
    except ValueError:
        raise ValueError(f"--resolution = {text!r}: expected WIDTHxHEIGHT, e.g. 64x48") from None
    if w < 1 or h < 1:
        raise ValueError(f"--resolution = {text!r}: width and height must be >= 1")
    return w, h


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
    """What ``write_images`` needs: it expects radiance relative to an equal-energy light
    and applies the illuminant itself. When every light has the same named spectrum (D65 or
    flat), divide by that relative spectrum and name the illuminant (D65 or E); ``white`` is
    the brightest light's radiance scale. Otherwise the radiance is the stimulus itself
    (illuminant E, white 1)."""
    lights = scene.description["lights"]
    kinds = {lt["spectrum"] if isinstance(lt["spectrum"], str) else "table" for lt in lights}
    if kinds == {"D65"}:
        divisor = np.array([d65_relative(wl) for wl in bands])
        illuminant = "D65"
    elif kinds == {"flat"}:
        divisor = np.ones(len(bands))
        illuminant = "E"
    else:
        return np.ones(len(bands)), "E", 1.0
    white = max(lt.get("radiance", lt.get("intensity", 1.0)) for lt in lights)
    return divisor, illuminant, float(white)


def _write_images():
    """``dentalux.color.write_images`` when the colour module provides it, else None."""
    try:
        from dentalux import color
    except ImportError:
        return None
    return getattr(color, "write_images", None)


def render_command(
    scene_file: Path = typer.Argument(..., help="scene file (TOML)"),
    out: Path = typer.Option(..., "--out", help="output folder"),
    spp: int = typer.Option(None, help="samples per pixel (default: the scene's render.spp)"),
    photons: int = typer.Option(None, help="surface photons per band"),
    volume_photons: int = typer.Option(None, help="volume photons per band (vpm, vpm-full)"),
    bands: str = typer.Option(None, help="wavelengths [nm], e.g. 450,540,605"),
    resolution: str = typer.Option(None, help="WIDTHxHEIGHT in pixels, e.g. 128x96"),
    seed: int = typer.Option(None, help="random seed (default: the scene's, else 1)"),
    threads: int = typer.Option(None, help="worker threads (default: all cores)"),
    integrator: str = typer.Option(
        None, help="pm | path | vpm | vpm-full | volpath | ppm (default: from the scene)"
    ),
    k: int = typer.Option(None, help="nearest photons in a radiance estimate"),
    radius: float = typer.Option(None, help="maximum photon search radius [mm]"),
    step: float = typer.Option(None, help="ray-marching step inside media [mm]"),
    as_json: bool = typer.Option(False, "--json", help="print render.json on stdout"),
) -> None:
    """Render a scene to DIR/radiance.npy, DIR/render.json and PNG previews."""
    t0 = time.perf_counter()
    scene = load_scene(scene_file)
    band_list = parse_bands(bands)
    options = {k_: v for k_, v in (("volume_photons", volume_photons), ("k", k),
                                   ("radius", radius), ("step", step)) if v is not None}
    result = render(scene, integrator=integrator, spp=spp, photons=photons, bands=band_list,
                    seed=seed, threads=threads, resolution=parse_resolution(resolution),
                    progress=None if not as_json else False, **options)
    out.mkdir(parents=True, exist_ok=True)
    np.save(out / "radiance.npy", result.radiance)
    files = {"radiance": str(out / "radiance.npy"),
             "previews": write_previews(result.radiance, result.bands, out)}
    summary = {
        "scene": str(scene_file),
        "scene_name": scene.description["scene"]["name"],
        "scene_hash": result.scene_hash,
        "bands_nm": result.bands,
        "shape": list(result.radiance.shape),
        "settings": result.settings,
        "timings": {"load_s": result.stats["seconds_load"],
                    "per_band_s": result.stats["seconds_per_band"],
                    "total_s": None},
        "photons": {key: [b.get(key) for b in result.stats["bands"]]
                    for key in sorted({k_ for b in result.stats["bands"] for k_ in b
                                       if "photon" in k_})},
        "stats": result.stats["bands"],
        "peak_memory_bytes": None,
        "files": files,
    }
    write_images = _write_images()
    if write_images is not None:
        divisor, illuminant, white = colour_inputs(scene, result.bands)
        extra = {"white": white} if "white" in inspect.signature(write_images).parameters \
            else {}
        try:
            summary["colour"] = write_images(result.radiance / divisor, result.bands, out,
                                             illuminant=illuminant, regions=None,
                                             exposure=None, **extra)
        except ValueError as exc:  # e.g. too few bands for a colour image
            summary["colour_error"] = str(exc)
            if not as_json:
                print(f"warning: no colour image: {exc}", file=sys.stderr)
    summary["timings"]["total_s"] = time.perf_counter() - t0
    summary["peak_memory_bytes"] = peak_memory_bytes()
    (out / "render.json").write_text(json.dumps(summary, indent=2))
    if as_json:
        print(json.dumps(summary))
    else:
        mean = [float(x) for x in result.radiance.reshape(-1, len(result.bands)).mean(axis=0)]
        print(f"{scene_file}: {result.radiance.shape[1]}x{result.radiance.shape[0]} px, "
              f"bands {', '.join(f'{b:g}' for b in result.bands)} nm, "
              f"{result.settings['integrator']}, {summary['timings']['total_s']:.2f} s")
        print("mean radiance per band: " + ", ".join(f"{m:.4g}" for m in mean))
        print(f"wrote {out}/radiance.npy, render.json, previews"
              + (", colour images" if "colour" in summary else ""))


def register(app: typer.Typer) -> None:
    app.command("render")(render_command)
