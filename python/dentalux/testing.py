"""Helpers for tests: a synthetic render task (importable by Dask workers) and statistics."""

from __future__ import annotations

import json
import time

import numpy as np

from dentalux.distributed import Task


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
