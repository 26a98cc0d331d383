"""Executors: where the per-band, per-pass render tasks run.

A task is plain data, (key, scene JSON for one band, settings JSON) with key = (band index,
pass index), and its result is a numpy image. No Rust object crosses a process boundary.
Results are combined in key order, never in completion order, so the image is the same (to
the bit) whatever the number of workers or the order in which they finish. A task is a pure
function of its inputs (its random streams derive from seed, band and pass), so a task lost
with a killed worker is simply recomputed elsewhere with the same result: nothing is lost or
counted twice.

- :class:`LocalExecutor` (default): runs tasks one after another in this process; each task
  uses all cores through the Rust thread pool. Nothing extra to install.
- :class:`DaskExecutor`: ``dask.distributed`` (``pip install 'dentalux[cluster]'``), either a
  LocalCluster with N worker processes (``local:N``) or an existing scheduler
  (``tcp://HOST:PORT``). See docs/cluster.md.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

Key = tuple[int, int]


@dataclass(frozen=True)
class Task:
    """One unit of work: one band (and one progressive pass) of one render."""

    key: Key
    scene_json: str
    settings_json: str


def run_task(task: Task) -> tuple[np.ndarray, dict]:
    """Render one task with the native core; returns (image H×W float32, stats)."""
    from dentalux import _core

    image, stats = _core.render_band(task.scene_json, task.settings_json)
    return np.asarray(image, dtype=np.float32), dict(stats)


def combine(results: dict[Key, np.ndarray], n_bands: int) -> np.ndarray:
    """Average the passes of each band in pass order and stack bands: H×W×bands float32.

    The sum runs in float64 in a fixed order so the result does not depend on which worker
    finished first.
    """
    bands = []
    for b in range(n_bands):
        keys = sorted(k for k in results if k[0] == b)
        if not keys:
            raise ValueError(f"no result for band index {b}")
        acc = np.zeros(results[keys[0]].shape, dtype=np.float64)
        for k in keys:
            acc += results[k]
        bands.append((acc / len(keys)).astype(np.float32))
    return np.stack(bands, axis=-1)


class LocalExecutor:
    """Run tasks in this process, in key order."""

    name = "local"
    workers = 1  # tasks at a time
    task_threads = None  # each task uses the threads its settings ask for (default all)

    def map(
        self,
        tasks: Sequence[Task],
        fn: Callable[[Task], tuple[np.ndarray, dict]] = run_task,
        on_done: Callable[[int], None] | None = None,
    ) -> dict[Key, tuple[np.ndarray, dict]]:
        out = {}
        for i, task in enumerate(sorted(tasks, key=lambda t: t.key)):
            out[task.key] = fn(task)
            if on_done:
                on_done(i + 1)
        return out

    def close(self) -> None:
        pass


class DaskExecutor:
    """Run tasks on a Dask cluster: ``local:N`` starts a LocalCluster of N single-threaded
    worker processes; ``tcp://HOST:PORT`` connects to a running scheduler."""

    name = "dask"

    def __init__(self, address: str, threads_per_worker: int = 1):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError as exc:  # pragma: no cover - depends on the extra
            raise ValueError(
                "--cluster needs dask.distributed: pip install 'dentalux[cluster]'"
            ) from exc
        self.cluster = None
        if address.startswith("local:"):
            from dentalux.limits import WORKERS_PER_CORE, logical_cores, max_workers

            try:
                n = int(address.split(":", 1)[1])
            except ValueError:
                n = 0
            if n < 1:
                raise ValueError(f"cluster = {address!r}: 'local:N' needs an integer N >= 1")
            if n > max_workers():
                raise ValueError(
                    f"cluster = {address!r}: N is out of range: allowed 1 ... {max_workers()} "
                    f"workers ({WORKERS_PER_CORE} x the {logical_cores()} logical cores)")
            try:
                self.cluster = LocalCluster(
                    n_workers=n,
                    threads_per_worker=threads_per_worker,
                    processes=True,
                    dashboard_address=None,
                )
                self.client = Client(self.cluster)
            except BaseException:
                if self.cluster is not None:
                    self.cluster.close()
                raise
        elif address.startswith("tcp://"):
            check_reachable(address)
            try:
                self.client = Client(address, timeout="20s")
            except (OSError, TimeoutError) as exc:
                raise ValueError(f"cluster = {address!r}: cannot connect to a Dask scheduler "
                                 f"there ({exc})") from None
        else:
            raise ValueError(
                f"cluster = {address!r}: allowed 'local:N' or 'tcp://HOST:PORT'"
            )
        self.threads_per_worker = threads_per_worker
        # each task's Rust pool gets its worker's threads, so workers do not oversubscribe
        self.task_threads = threads_per_worker

    @property
    def workers(self) -> int:
        """Tasks the cluster runs at a time (worker threads, at least 1)."""
        return max(1, sum(self.client.nthreads().values()))

    def map(
        self,
        tasks: Sequence[Task],
        fn: Callable[[Task], tuple[np.ndarray, dict]] = run_task,
        on_done: Callable[[int], None] | None = None,
    ) -> dict[Key, tuple[np.ndarray, dict]]:
        from dask.distributed import as_completed

        ordered = sorted(tasks, key=lambda t: t.key)
        # pure=True + deterministic keys: a task lost with a worker is recomputed, not doubled
        futures = self.client.map(
            fn,
            ordered,
            key=[f"dentalux-{_task_token(t)}" for t in ordered],
            pure=True,
            retries=3,
        )
        done = 0
        for _ in as_completed(futures):
            done += 1
            if on_done:
                on_done(done)
        results = self.client.gather(futures)
        return {t.key: r for t, r in zip(ordered, results, strict=True)}

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _task_token(task: Task) -> str:
    import hashlib

    h = hashlib.sha256()
    for part in (repr(task.key), task.scene_json, task.settings_json):
        h.update(part.encode())
    return h.hexdigest()[:24]


def check_reachable(address: str, timeout: float = 5.0) -> None:
    """Refuse ``tcp://HOST:PORT`` at once when nothing listens there (instead of a
    20-second wait and an ``OSError`` traceback)."""
    import socket
    from urllib.parse import urlsplit

    try:
        parts = urlsplit(address)
        host, port = parts.hostname, parts.port
    except ValueError:
        host, port = None, None
    if not host or port is None:
        raise ValueError(f"cluster = {address!r}: expected tcp://HOST:PORT, e.g. "
                         "tcp://127.0.0.1:8786")
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        why = exc.strerror or str(exc) or type(exc).__name__
        raise ValueError(f"cluster = {address!r}: no Dask scheduler reachable at "
                         f"{host}:{port} ({why})") from None


def make_executor(cluster: str | None) -> LocalExecutor | DaskExecutor:
    """``None`` → local; ``local:N`` or ``tcp://HOST:PORT`` → Dask."""
    return LocalExecutor() if not cluster else DaskExecutor(cluster)


def band_tasks(
    scene_jsons: Iterable[str], settings: dict, passes: int = 1
) -> list[Task]:
    """Tasks for every band × pass. Pass p of band b gets ``pass_index`` p in its settings
    (progressive integrators shrink their radius by it; others use it only as a seed key)."""
    tasks = []
    for b, scene_json in enumerate(scene_jsons):
        for p in range(passes):
            s = dict(settings, band=b, pass_index=p)
            if passes > 1:
                s["passes"] = 1
            tasks.append(Task((b, p), scene_json, json.dumps(s, sort_keys=True)))
    return tasks
