"""``dentalux render SCENE.toml --out DIR``: render a scene band by band.

Writes ``DIR/radiance.npy`` (float32, height x width x bands), ``DIR/render.json`` (scene
hash, bands, settings, timings, photon counts, peak memory) and a grey PNG preview per band
(``DIR/band_540nm.png``, all bands on one exposure). When the colour module provides
``dentalux.color.write_images``, the colour images are written too.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import typer

from dentalux.output_paths import check_out_dir, rebase, staged_dir
from dentalux.outputs import dumps_strict, peak_memory_bytes, region_matcher, write_render_outputs
from dentalux.render import render
from dentalux.scene.load import load_scene
from dentalux.scene.schema import INTEGRATORS


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
    out: str = typer.Option(..., "--out", help="output folder: new or empty (see --overwrite)"),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="write into a non-empty --out folder, replacing the files "
                                   "of the same names"),
    spp: int = typer.Option(None, help="samples per pixel (default: the scene's render.spp)"),
    photons: int = typer.Option(
        None, help="photons per band for the surface map (vpm: the volume pass's first N)"),
    volume_photons: int = typer.Option(
        None, help="volume photons per band (vpm, vpm-full, ppm, bre)"),
    volume_stored: int = typer.Option(
        None, "--volume-stored",
        help="photons the volume maps should hold: emit until then (at most volume-photons)"),
    aim: float = typer.Option(
        None, help="fraction of the volume photons aimed at the media, in [0, 1) "
                   "(default 0; unbiased; pair with --volume-stored)"),
    bands: str = typer.Option(None, help="wavelengths [nm], e.g. 450,540,605"),
    resolution: str = typer.Option(None, help="WIDTHxHEIGHT in pixels, e.g. 128x96"),
    seed: int = typer.Option(None, help="random seed (default: the scene's, else 1)"),
    threads: int = typer.Option(None, help="worker threads (default: all cores)"),
    integrator: str = typer.Option(
        None, help=" | ".join(INTEGRATORS) + " (default: from the scene)"
    ),
    k: int = typer.Option(None, help="nearest photons in a radiance estimate"),
    surface_k: int = typer.Option(
        None, "--surface-k",
        help="nearest photons in an estimate of the surface photon map (default: --k)"),
    radius: float = typer.Option(None, help="maximum photon search radius [mm]"),
    surface_radius: float = typer.Option(
        None, help="maximum search radius of the surface photon map [mm] (default: --radius)"),
    step: float = typer.Option(None, help="march resolution inside media [mm]: a segment gets "
                               "half the points steps of this size would evaluate"),
    passes: int = typer.Option(None, help="progressive passes (ppm: Knaus-Zwicker passes; "
                               "others: independent seeds), one task per band and pass"),
    time_budget: float = typer.Option(None, "--time-budget",
                                      help="progressive: stop after about SECONDS"),
    target_rmse: float = typer.Option(
        None, "--target-rmse",
        help="progressive: stop when the estimated relative error (spread of the per-pass "
             "images) falls to X, e.g. 0.02"),
    alpha: float = typer.Option(None, help="ppm radius reduction alpha in (0, 1)"),
    kernel_layer: float = typer.Option(
        None, "--kernel-layer",
        help="half-height of the boundary-aligned density kernel over the gathering radius, "
             "in [0, 1]; 0 = the paper's sphere (default 0.3)"),
    kernel_clip: bool = typer.Option(
        None, "--kernel-clip/--no-kernel-clip",
        help="clip the density kernels by every face within them (a disc's rim, curved "
             "walls, a disc standing on the ribbon), not only by the camera ray's entry and "
             "exit planes (default: on)"),
    volume_estimator: str = typer.Option(
        None, "--volume-estimator",
        help="vpm, vpm-full, ppm: 'points' (eq. 11, ray marching) or 'beam' (the beam "
             "radiance estimate; what --integrator bre uses)"),
    spectral_photons: bool = typer.Option(
        None, "--spectral-photons/--no-spectral-photons",
        help="vpm, vpm-full, bre over several bands: one photon pass for all bands (hero-band "
             "walks with balance-heuristic powers) and shared camera paths, so noise is "
             "shared between bands (less coloured speckle) and photons are traced once "
             "(default: off; docs/spectral-photons.md)"),
    hero_camera: bool = typer.Option(
        None, "--hero-camera/--no-hero-camera",
        help="vpm, vpm-full, bre over several bands: one camera path per pixel sample for "
             "all bands, with a throughput per band (hero-wavelength camera paths), instead "
             "of one camera pass per band; holds every band's photon maps at once "
             "(default: off; docs/spectral-photons.md)"),
    match: str = typer.Option(
        None, "--match",
        help="a shade guide (see `dentalux shade --help`; an imported guide or a guide "
             "FILE.csv too): colour.json gives each measured region's nearest tabs with their "
             "ΔE00 and the instrument the guide was read with"),
    cluster: str = typer.Option(
        None, help="run the band x pass tasks on Dask: local:N (LocalCluster of N workers) "
                   "or tcp://HOST:PORT (a running scheduler)"),
    as_json: bool = typer.Option(False, "--json", help="print render.json on stdout"),
    allow_outside_paths: bool = typer.Option(
        False, "--allow-outside-paths",
        help="let the scene read mesh and image files outside its folder (absolute paths, "
             "'..', symbolic links leading out)"),
) -> None:
    """Render a scene to DIR/radiance.npy, DIR/render.json and PNG previews."""
    t0 = time.perf_counter()
    out = check_out_dir(out, "--out", overwrite=overwrite)
    scene = load_scene(scene_file, allow_outside_paths=allow_outside_paths)
    res = parse_resolution(resolution)
    if match is not None:
        if not scene.description.get("regions"):
            raise ValueError(f"--match {match}: the scene has no [regions] to measure")
        if res is not None and tuple(res) != tuple(scene.resolution):
            raise ValueError(f"--match {match}: the scene's regions are in its own pixels "
                             f"({scene.resolution[0]}x{scene.resolution[1]}); drop "
                             f"--resolution {resolution} to measure them")
        region_matcher(match)  # the guide is checked before the render starts
    band_list = parse_bands(bands)
    options = {k_: v for k_, v in (("volume_photons", volume_photons),
                                   ("volume_stored", volume_stored), ("aim", aim), ("k", k),
                                   ("surface_k", surface_k),
                                   ("radius", radius), ("surface_radius", surface_radius),
                                   ("step", step), ("alpha", alpha),
                                   ("kernel_layer", kernel_layer),
                                   ("kernel_clip", kernel_clip),
                                   ("volume_estimator", volume_estimator),
                                   ("spectral_photons", spectral_photons),
                                   ("hero_camera", hero_camera))
               if v is not None}
    common = dict(integrator=integrator, spp=spp, photons=photons, bands=band_list,
                  seed=seed, threads=threads, resolution=res,
                  progress=None if not as_json else False, **options)
    progressive = any(x is not None for x in (passes, time_budget, target_rmse, cluster))
    if progressive:
        result = _render_progressive(scene, passes, time_budget, target_rmse, cluster, common)
    else:
        result = render(scene, **common)
    warn = None if as_json else (lambda msg: print(msg, file=sys.stderr))
    with staged_dir(out, "--out") as stage:
        summary = write_render_outputs(scene, result, stage, scene_file=str(scene_file),
                                       warn=warn, write_json=False, match=match)
        summary = rebase(summary, stage, out)
        if progressive:
            summary["progressive"] = _finite(result.stats["progressive"])
            summary["radius_last"] = summary["progressive"]["radius_last"]
        summary["timings"]["total_s"] = time.perf_counter() - t0
        summary["peak_memory_bytes"] = peak_memory_bytes()
        (stage / "render.json").write_text(dumps_strict(summary, indent=2))
    if as_json:
        print(dumps_strict(summary))
    else:
        mean = [float(x) for x in result.radiance.reshape(-1, len(result.bands)).mean(axis=0)]
        print(f"{scene_file}: {result.radiance.shape[1]}x{result.radiance.shape[0]} px, "
              f"bands {', '.join(f'{b:g}' for b in result.bands)} nm, "
              f"{result.settings['integrator']}, {summary['timings']['total_s']:.2f} s")
        print("mean radiance per band: " + ", ".join(f"{m:.4g}" for m in mean))
        if progressive:
            pr = summary["progressive"]
            err = "n/a" if pr["error_estimate"] is None else f"{100 * pr['error_estimate']:.2f} %"
            radii = ", ".join(f"{k} {v:.4g} mm" for k, v in pr["radius_last"].items())
            print(f"{pr['passes']} passes ({pr['stop']}) on {pr['executor']} "
                  f"({pr['workers']} worker(s)), error estimate {err}"
                  + (f", last radius: {radii}" if radii else ""))
        for name, reg in summary.get("colour", {}).get("regions", {}).items():
            if "shade_match" in reg:
                tabs = ", ".join(f"{m['tab']} (ΔE00 {m['delta_e00']:.2f})"
                                 for m in reg["shade_match"])
                print(f"region {name}: L*a*b* {', '.join(f'{v:.1f}' for v in reg['lab'])}; "
                      f"nearest {match} tabs: {tabs}")
        print(f"wrote {out}/radiance.npy, render.json, previews"
              + (", colour images" if "colour" in summary else ""))


def _render_progressive(scene, passes, time_budget, target_rmse, cluster, common):
    """The band x pass tasks through the executor named by ``cluster`` (default local)."""
    from dentalux.distributed import make_executor
    from dentalux.progressive import StopRule, render_progressive

    if passes is None and time_budget is None and target_rmse is None:
        passes = scene.render_defaults.get("passes", 1)
    stop = StopRule(passes=passes, time_budget=time_budget, target_rmse=target_rmse)
    executor = make_executor(cluster)
    try:
        return render_progressive(scene, stop, executor=executor, **common)
    finally:
        executor.close()


def _finite(x):
    """JSON-safe copy: inf/nan floats become null."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    return x


def register(app: typer.Typer) -> None:
    app.command("render")(render_command)
