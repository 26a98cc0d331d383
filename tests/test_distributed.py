"""Executors: identical images whatever the worker count, order of completion or failures."""

import json
import os
import signal
import threading
import time

import numpy as np
import pytest
from dentalux.distributed import (
    DaskExecutor,
    LocalExecutor,
    Task,
    band_tasks,
    combine,
    make_executor,
)
from dentalux.testing import synthetic_task


def _tasks(n_bands=3, passes=4, sleep=0.0):
    settings = {"seed": 7, "height": 6, "width": 5, "sleep": sleep}
    return band_tasks([f"scene-{b}" for b in range(n_bands)], settings, passes=passes)


def _image(executor, tasks):
    results = executor.map(tasks, fn=synthetic_task)
    return combine({k: v[0] for k, v in results.items()}, n_bands=3)


def test_band_tasks_keys_and_settings():
    tasks = _tasks()
    assert [t.key for t in tasks] == [(b, p) for b in range(3) for p in range(4)]
    s = json.loads(tasks[5].settings_json)
    assert s["band"] == 1 and s["pass_index"] == 1 and s["passes"] == 1


def test_combine_averages_passes_in_key_order():
    r = {(0, 1): np.full((2, 2), 3.0), (0, 0): np.full((2, 2), 1.0), (1, 0): np.ones((2, 2))}
    img = combine(r, n_bands=2)
    assert img.shape == (2, 2, 2) and img.dtype == np.float32
    assert np.all(img[..., 0] == 2.0) and np.all(img[..., 1] == 1.0)
    with pytest.raises(ValueError, match="band index 2"):
        combine(r, n_bands=3)


def test_local_executor_is_order_independent():
    tasks = _tasks()
    a = _image(LocalExecutor(), tasks)
    b = _image(LocalExecutor(), list(reversed(tasks)))
    assert np.array_equal(a, b)


def test_bad_cluster_addresses_are_refused():
    for bad in ("local:0", "local:x", "udp://x:1"):
        with pytest.raises(ValueError, match="cluster"):
            make_executor(bad)


def test_dask_equals_local_and_survives_a_killed_worker():
    tasks = _tasks(sleep=0.4)
    reference = _image(LocalExecutor(), _tasks())
    ex = DaskExecutor("local:2")
    try:
        assert np.array_equal(_image(ex, _tasks()), reference)

        # kill one worker process while tasks are running; its tasks are recomputed
        pids = list(ex.client.run(os.getpid).values())
        killer = threading.Timer(1.0, lambda: os.kill(pids[0], signal.SIGKILL))
        killer.start()
        t0 = time.time()
        image = _image(ex, [Task(t.key, t.scene_json + " ", t.settings_json) for t in tasks])
        killer.join()
        assert time.time() - t0 > 1.0  # the kill happened during the render
        assert np.array_equal(image, reference)
    finally:
        ex.close()
