"""Helpers for tests: a synthetic render task (importable by Dask workers) and statistics."""

from __future__ import annotations

import json
import time

import numpy as np

from dentalux.distributed import Task

#: a composite-like material unknown to a fit (constant g, as the readings fit assumes), for
#: round trips of ``fit --readings``: its tests and benchmarks/fit_readings.py
STAND_IN_COMPOSITE = """[materials.comp]
extrapolate = true
description = "a stand-in composite (made up for round trips)"
wavelength_nm = [400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0]
mua = [0.6, 0.3, 0.12, 0.05, 0.03, 0.02, 0.015]
mus = [14.0, 12.0, 11.0, 10.0, 9.0, 8.5, 8.0]
g = [0.8, 0.8, 0.8, 0.8, 0.8, 0.8, 0.8]
fd = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
n = [1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5]
[materials.comp.provenance]
kind = "derived"
source = "made up for round trips of the readings fit"
"""


def synthetic_task(task: Task) -> tuple[np.ndarray, dict]:
    """A deterministic stand-in for a render task: noise seeded by (seed, band, pass).

    ``settings["sleep"]`` seconds of wall time let a test kill a worker mid-render.
    """
    settings = json.loads(task.settings_json)
    time.sleep(float(settings.get("sleep", 0.0)))
    rng = np.random.default_rng([settings.get("seed", 0), *task.key])
    h, w = settings.get("height", 8), settings.get("width", 8)
    return rng.random((h, w), dtype=np.float32), {"key": list(task.key)}


def z_scores(a: np.ndarray, b: np.ndarray, se_a: np.ndarray, se_b: np.ndarray) -> np.ndarray:
    """Per-element z of the difference of two independent estimates."""
    return (a - b) / np.sqrt(np.maximum(se_a**2 + se_b**2, 1e-300))


def bands_from_band(render_band):
    """A ``_core.render_bands`` stand-in built from a ``render_band``-style fake: the
    multi-band scene is split into one contract scene per band, whose settings carry the
    band's key, and the fake's images are stacked into a (bands, height, width) cube; each
    band's stats get the ``seconds_total`` the core reports."""

    def render_bands(scene_json, settings_json, band_keys, progress=None):
        scene, settings = json.loads(scene_json), json.loads(settings_json)
        shared = {k: v for k, v in scene.items() if k != "bands"}
        images, stats = [], []
        for band, key in zip(scene["bands"], band_keys, strict=True):
            start = time.perf_counter()
            image, st = render_band(json.dumps({**shared, **band}),
                                    json.dumps({**settings, "band": key}), progress)
            images.append(np.asarray(image, dtype=np.float32))
            stats.append({"seconds_total": time.perf_counter() - start, **st})
        return np.stack(images), stats

    return render_bands
