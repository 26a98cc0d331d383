"""Real renders on a Dask LocalCluster: the band x pass tasks give the image of the local
executor bit for bit, also when a worker is killed in the middle of the render."""

import os
import signal
from pathlib import Path

import numpy as np
import pytest
from dentalux.cli import main
from dentalux.distributed import DaskExecutor
from dentalux.progressive import StopRule, render_progressive

pytest.importorskip("dask.distributed")

DISCS = Path(__file__).resolve().parents[1] / "scenes" / "discs.toml"
ARGS = ["--integrator", "ppm", "--passes", "4", "--resolution", "16x12", "--spp", "1",
        "--photons", "2000", "--volume-photons", "5000", "--bands", "450,605", "--json"]


def _cli(out, *extra):
    with pytest.raises(SystemExit) as exc:
        main(["render", str(DISCS), "--out", str(out), *ARGS, *extra])
    assert exc.value.code == 0
    return np.load(out / "radiance.npy")


def test_cli_cluster_local2_equals_local_executor(tmp_path, capsys):
    local = _cli(tmp_path / "local")
    dask = _cli(tmp_path / "dask", "--cluster", "local:2")
    capsys.readouterr()
    assert dask.shape == (12, 16, 2) and np.all(np.isfinite(dask)) and dask.mean() > 0
    assert np.array_equal(local, dask)


class KillOnFirstResult:
    """Wrap a DaskExecutor: when the first task of the render finishes, SIGKILL the worker
    process that holds most work, while the other tasks are queued or running."""

    def __init__(self, ex: DaskExecutor):
        self.ex, self.killed = ex, []
        self.name, self.task_threads = ex.name, ex.task_threads

    @property
    def workers(self):
        return self.ex.workers

    def map(self, tasks, fn=None, on_done=None):
        def kill_then_report(k):
            if not self.killed:
                pids = self.ex.client.run(os.getpid)
                victim = sorted(pids)[0]
                os.kill(pids[victim], signal.SIGKILL)
                self.killed.append((pids[victim], k, len(tasks)))
            if on_done:
                on_done(k)

        kw = {} if fn is None else {"fn": fn}
        return self.ex.map(tasks, on_done=kill_then_report, **kw)


def test_killed_worker_mid_render_gives_the_identical_image():
    kw = dict(integrator="ppm", spp=2, photons=4000, volume_photons=10000, resolution=(16, 12),
              bands=[450, 540, 605], progress=False)
    reference = render_progressive(DISCS, StopRule(passes=6), **kw)
    ex = DaskExecutor("local:2")
    try:
        before = set(ex.client.run(os.getpid).values())
        killer = KillOnFirstResult(ex)
        image = render_progressive(DISCS, StopRule(passes=6), executor=killer, **kw)
        pid, first_done, n_tasks = killer.killed[0]
        assert first_done == 1 and n_tasks == 18  # killed with 17 of 18 tasks unfinished
        assert pid in before and pid not in set(ex.client.run(os.getpid).values())
    finally:
        ex.close()
    assert np.array_equal(image.radiance, reference.radiance)
    assert image.stats["progressive"]["passes"] == 6
