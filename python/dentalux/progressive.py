"""Progressive rendering: independent passes as tasks, averaged in pass order, until a stop
rule is met (a number of passes, a time budget or a target relative error).

Each pass of each band is one task of :mod:`dentalux.distributed` (settings ``passes = 1``,
``pass_index = p``). For ``ppm`` pass p is pass p + 1 of the Knaus–Zwicker schedule, with its
own photon maps, seeds and radius (crates/dentalux-core/src/integrators/ppm.rs), so the mean
of passes 0..N−1 is bit for bit the in-process ``passes = N`` render. Other integrators give
every pass its own seed stream (own photon maps and paths); only the pixels' sub-pixel
positions continue one stratified sequence across passes.

Passes run in rounds through an executor; results are added in key order (band, pass) into
float64 running sums, so the image depends only on the number of passes, never on workers or
completion order, and memory holds one H×W sum (and sum of squares) per band, not the passes.

Error estimate (``error``, relative): passes have their own photon maps and paths, so the
variance of the mean image at a pixel is estimated by s²/N, with s² the sample variance of
the N pass images at that pixel. (Their sub-pixel positions continue one stratified sequence
per pixel, docs/render-contract.md: at edges the passes are slightly anti-correlated, and
s²/N overestimates the noise there — a conservative estimate.) The reported figure is,
per band, the root mean over pixels of s²/N divided by the mean radiance of the band's
image, and the largest over bands:

    error = max_b sqrt(mean_px(s_b²) / N) / mean_px(mean image_b)

It measures noise only. For ``ppm`` the bias of pass i shrinks like r_i² (Knaus & Zwicker);
the spread of the per-pass biases adds to s², so the estimate is slightly conservative, but
the remaining bias of the average is not in it.
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from dentalux.core_schema import SETTINGS_SCHEMA
from dentalux.distributed import LocalExecutor, Task

# Last pass the core accepts (integrators/settings.rs: MAX_PASSES − 1).
MAX_PASSES = SETTINGS_SCHEMA["max_passes"] - 1
# Passes needed before a target error can stop the render (s² from fewer is too unreliable).
MIN_PASSES_FOR_TARGET = 4


@dataclass(frozen=True)
class StopRule:
    """When to stop: after ``passes`` passes, after ``time_budget`` seconds (no new round is
    started that would not finish in time, at least one round runs), or when the relative
    error estimate falls to ``target_rmse`` (after at least 4 passes). Any combination; the
    first rule met stops. ``max_passes`` bounds every render."""

    passes: int | None = None
    time_budget: float | None = None
    target_rmse: float | None = None
    max_passes: int = MAX_PASSES

    def __post_init__(self):
        if self.passes is not None and not 1 <= self.passes <= MAX_PASSES:
            raise ValueError(f"passes = {self.passes}: out of range, allowed 1..{MAX_PASSES}")
        if self.time_budget is not None and not (self.time_budget > 0
                                                 and math.isfinite(self.time_budget)):
            raise ValueError(f"time_budget = {self.time_budget}: out of range, allowed > 0 s")
        if self.target_rmse is not None and not (0 < self.target_rmse < 1):
            raise ValueError(f"target_rmse = {self.target_rmse}: out of range, allowed (0, 1)")
        if not 1 <= self.max_passes <= MAX_PASSES:
            raise ValueError(f"max_passes = {self.max_passes}: allowed 1..{MAX_PASSES}")
        if self.passes is None and self.time_budget is None and self.target_rmse is None:
            raise ValueError("stop rule: give passes, time_budget or target_rmse")


@dataclass
class Accumulator:
    """Running float64 sum and sum of squares of the pass images of one band, in pass order."""

    total: np.ndarray
    squares: np.ndarray
    n: int = 0

    @classmethod
    def empty(cls, shape: tuple[int, int]) -> Accumulator:
        return cls(np.zeros(shape, np.float64), np.zeros(shape, np.float64))

    def add(self, image: np.ndarray) -> None:
        x = image.astype(np.float64)
        self.total += x
        self.squares += x * x
        self.n += 1

    def mean(self) -> np.ndarray:
        """The average of the passes, float32 (same arithmetic as distributed.combine)."""
        return (self.total / max(self.n, 1)).astype(np.float32)

    def relative_error(self) -> float:
        """sqrt(mean over pixels of s²/N) / mean radiance; inf with fewer than 2 passes."""
        if self.n < 2:
            return math.inf
        m = self.total / self.n
        var = np.maximum(self.squares / self.n - m * m, 0.0) * self.n / (self.n - 1)
        level = float(m.mean())
        if level <= 0:
            return 0.0 if float(var.max()) == 0 else math.inf
        return math.sqrt(float(var.mean()) / self.n) / level


@dataclass
class ProgressiveResult:
    """images: float32 (H, W) per band; stats per band (sums over passes, last radii); curve:
    (passes, seconds, error) after each round; stop: which rule ended the render."""

    images: list[np.ndarray]
    passes: int
    error: float
    stats: list[dict]
    curve: list[tuple[int, float, float]] = field(default_factory=list)
    stop: str = ""
    seconds: float = 0.0
    photons: int = 0


def pass_tasks(scene_jsons: Sequence[str], band_keys: Sequence[int], settings: dict,
               first: int, count: int) -> list[Task]:
    """Tasks for every band × pass ``first .. first+count−1``: key (band index, pass), the
    band's random-stream key ``band`` and ``pass_index = pass``, ``passes = 1``."""
    tasks = []
    for b, (scene_json, key) in enumerate(zip(scene_jsons, band_keys, strict=True)):
        for p in range(first, first + count):
            s = dict(settings, band=int(key), pass_index=p, passes=1)
            tasks.append(Task((b, p), scene_json, json.dumps(s, sort_keys=True)))
    return tasks


def _merge_stats(old: dict | None, new: dict) -> dict:
    """Per-band statistics over passes: counts and seconds add, memory is the largest pass's,
    radii and other figures are the last pass's."""
    if old is None:
        return dict(new)
    out = dict(new)
    for k in ("photons_emitted", "photons_stored", "rays", "seconds_total", "seconds_photons",
              "seconds_build", "seconds_camera", "pilot_photons"):
        if k in old or k in new:
            out[k] = old.get(k, 0) + new.get(k, 0)
    out["photon_map_bytes"] = max(old.get("photon_map_bytes", 0), new.get("photon_map_bytes", 0))
    return out


def _round_size(executor, n_bands: int) -> int:
    """Passes per round: enough tasks to keep every worker busy."""
    workers = int(getattr(executor, "workers", 1) or 1)
    return max(1, -(-workers // n_bands))


def run_passes(scene_jsons: Sequence[str], band_keys: Sequence[int], settings: dict,
               stop: StopRule, executor=None, progress: bool | None = None,
               photons_per_pass: int = 0,
               on_round: Callable[[int, float], None] | None = None) -> ProgressiveResult:
    """Render ``len(scene_jsons)`` bands pass by pass through ``executor`` (default: local)
    until ``stop``. ``photons_per_pass`` (per band) only feeds the progress bar."""
    executor = executor or LocalExecutor()
    n_bands = len(scene_jsons)
    accs: list[Accumulator | None] = [None] * n_bands
    stats: list[dict | None] = [None] * n_bands
    curve: list[tuple[int, float, float]] = []
    t0 = time.perf_counter()
    done, error, reason = 0, math.inf, ""
    limit = min(stop.max_passes, stop.passes or MAX_PASSES)
    base = _round_size(executor, n_bands)
    fixed = stop.time_budget is None and stop.target_rmse is None
    with _ProgressBar(stop, n_bands, photons_per_pass, progress) as bar:
        while True:
            count = limit - done if fixed else _next_round(stop, done, error,
                                                           time.perf_counter() - t0, base)
            count = min(count, limit - done)
            tasks = pass_tasks(scene_jsons, band_keys, settings, done, count)
            finished = done * n_bands

            def tick(k: int, finished: int = finished, error: float = error) -> None:
                bar.update((finished + k) / n_bands, error)

            results = executor.map(tasks, on_done=tick)
            for key in sorted(results):
                b = key[0]
                image, st = results[key]
                image = np.asarray(image, dtype=np.float32)
                if accs[b] is None:
                    accs[b] = Accumulator.empty(image.shape)
                accs[b].add(image)
                stats[b] = _merge_stats(stats[b], dict(st))
            done += count
            error = max(a.relative_error() for a in accs)
            elapsed = time.perf_counter() - t0
            curve.append((done, elapsed, error))
            bar.update(done, error)
            if on_round:
                on_round(done, error)
            if done >= limit:
                reason = "passes" if stop.passes is not None and done >= stop.passes \
                    else "max_passes"
                break
            if (stop.target_rmse is not None and done >= MIN_PASSES_FOR_TARGET
                    and error <= stop.target_rmse):
                reason = "target_rmse"
                break
            if stop.time_budget is not None and _next_round(stop, done, error, elapsed,
                                                            base) < 1:
                reason = "time_budget"
                break
    return ProgressiveResult(
        images=[a.mean() for a in accs], passes=done, error=error,
        stats=[dict(s, passes=done) for s in stats], curve=curve, stop=reason,
        seconds=time.perf_counter() - t0, photons=done * n_bands * photons_per_pass)


def _next_round(stop: StopRule, done: int, error: float, elapsed: float, base: int) -> int:
    """Passes in the next round: ``base`` (enough to keep the workers busy) at first; for a
    target error, the passes the 1/√N law predicts are still missing, at most doubling the
    passes done; for a time budget, no more than fit in the time left at the mean seconds
    per pass so far (0: stop)."""
    n = base
    if done and stop.target_rmse is not None and math.isfinite(error):
        missing = math.ceil(done * (error / stop.target_rmse) ** 2) - done
        n = min(max(missing, base), max(done, base))
    elif done:
        n = max(base, done)
    if done and stop.time_budget is not None:
        n = min(n, int((stop.time_budget - elapsed) / (elapsed / done)))
    return n


class _ProgressBar:
    """A rich bar on stderr (only when a person is watching) with passes, photons traced and
    the error estimate. Total: the passes when fixed, else the time budget, else open."""

    def __init__(self, stop: StopRule, n_bands: int, photons_per_pass: int,
                 enabled: bool | None):
        self.stop, self.n_bands, self.ppp = stop, n_bands, photons_per_pass
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.prog = None
        self.t0 = time.perf_counter()

    def __enter__(self) -> _ProgressBar:
        if not self.enabled:
            return self
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        self.prog = Progress(TextColumn("[bold]{task.description}"), BarColumn(),
                             TextColumn("{task.fields[info]}"), TimeElapsedColumn(),
                             transient=True)
        self.prog.__enter__()
        total = self.stop.passes if self.stop.time_budget is None else None
        self.task = self.prog.add_task("progressive", total=total, info="")
        return self

    def update(self, passes: float, error: float) -> None:
        if self.prog is None:
            return
        photons = passes * self.n_bands * self.ppp
        err = "-" if not math.isfinite(error) else f"{100 * error:.2f} %"
        info = f"passes {passes:.1f} · photons {photons:.3g} · error {err}"
        if self.stop.target_rmse is not None:
            info += f" (target {100 * self.stop.target_rmse:.2f} %)"
        if self.stop.time_budget is not None:
            done = min(time.perf_counter() - self.t0, self.stop.time_budget)
            self.prog.update(self.task, total=self.stop.time_budget, completed=done, info=info)
        else:
            self.prog.update(self.task, completed=passes, info=info)

    def __exit__(self, *exc) -> None:
        if self.prog is not None:
            self.prog.__exit__(*exc)


def render_progressive(scene, stop: StopRule, executor=None, integrator: str | None = None,
                       spp: int | None = None, photons: int | None = None, bands=None,
                       seed: int | None = None, threads: int | None = None, resolution=None,
                       progress: bool | None = None, correlated_bands: bool = False,
                       **options):
    """``dentalux.render`` pass by pass through an executor (default: local, in this
    process): same arguments, plus the stop rule. Returns a :class:`RenderResult` whose
    ``stats["progressive"]`` holds passes, photons, the error estimate (module docstring),
    the error curve, the stop reason and the last pass's radii [mm]."""
    from dentalux.render import RenderResult, _resolution, build_settings, photons_traced
    from dentalux.scene.load import as_scene
    from dentalux.scene.schema import validate_bands

    t0 = time.perf_counter()
    sc = as_scene(scene)
    band_list = validate_bands(sc.bands if bands is None else bands, "bands")
    settings = build_settings(sc, integrator=integrator, spp=spp, photons=photons, seed=seed,
                              threads=threads, **options)
    res = _resolution(resolution) or sc.resolution
    for key, what, flag in (("spectral_photons", "one photon pass", "--spectral-photons"),
                            ("hero_camera", "camera paths", "--hero-camera")):
        if settings.get(key) and len(band_list) > 1:
            raise ValueError(f"{key} = true: a progressive or distributed render runs one "
                             f"task per band and pass, which cannot share {what}; render "
                             "without --passes, --time-budget, --target-rmse and "
                             f"--cluster, or without {flag}")
    from dentalux.limits import check_render

    check_render(settings, res[0], res[1], len(band_list))
    executor = executor or LocalExecutor()
    task_threads = getattr(executor, "task_threads", None)
    if task_threads is not None:
        settings = dict(settings, threads=task_threads)
    scene_jsons = [sc.to_json(wl, res) for wl in band_list]
    keys = [0 if correlated_bands else int(round(wl)) for wl in band_list]
    traced = photons_traced(settings)
    t_load = time.perf_counter() - t0
    run_settings = {k: v for k, v in settings.items() if k != "passes"}
    out = run_passes(scene_jsons, keys, run_settings, stop, executor, progress=progress,
                     photons_per_pass=traced)
    per_band = [{"wavelength_nm": wl, **s} for wl, s in zip(band_list, out.stats, strict=True)]
    radii = {k: v for k, v in out.stats[-1].items() if k.endswith("_last")}
    prog = {
        "passes": out.passes, "stop": out.stop, "error_estimate": out.error,
        "photons_traced": out.photons, "seconds": out.seconds,
        "executor": getattr(executor, "name", type(executor).__name__),
        "workers": int(getattr(executor, "workers", 1) or 1),
        "radius_last": radii,
        "curve": [{"passes": p, "seconds": s, "error": e} for p, s, e in out.curve],
    }
    stats = {
        "integrator": settings["integrator"],
        "resolution": list(res),
        "threads": threads,
        "seconds_load": t_load,
        "seconds_per_band": [s.get("seconds_total", 0.0) for s in out.stats],
        "seconds_total": time.perf_counter() - t0,
        "bands": per_band,
        "progressive": prog,
    }
    radiance = np.stack(out.images, axis=-1).astype(np.float32, copy=False)
    from dentalux.render import check_finite

    for b, wl in enumerate(band_list):
        check_finite(radiance[:, :, b], wl)
    return RenderResult(radiance=radiance, bands=band_list, stats=stats, scene_hash=sc.hash,
                        settings=dict(settings, passes=out.passes))
