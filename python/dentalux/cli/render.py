"""``dentalux render SCENE.toml --out DIR``: render a scene band by band.

Writes ``DIR/radiance.npy`` (float32, height x width x bands), ``DIR/render.json`` (scene
hash, bands, settings, timings, photon counts, peak memory) and a grey PNG preview per band
(``DIR/band_540nm.png``, all bands on one exposure). When the colour module provides
``dentalux.color.write_images``, the colour images are written too.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import typer

from dentalux.outputs import peak_memory_bytes, write_render_outputs
from dentalux.render import render
from dentalux.scene.load import load_scene


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
    warn = None if as_json else (lambda msg: print(msg, file=sys.stderr))
    summary = write_render_outputs(scene, result, out, scene_file=str(scene_file), warn=warn)
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
