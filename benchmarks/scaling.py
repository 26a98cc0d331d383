"""Scaling of progressive renders over executors, and memory of ppm vs vpm.

1. The same ppm render (the discs scene, 3 bands x PASSES passes = one task each) with
   - the local executor, 1 thread (baseline) and 2 threads in one process;
   - a Dask LocalCluster with 1 and with 2 single-threaded workers.
   Prints wall time, speedup over the baseline, overhead per task (wall time minus the
   tasks' own render seconds, per task) and checks the images are identical.
2. Peak memory of ppm (PASSES passes of P photons) vs vpm (one map of PASSES x P photons:
   the same photons, the same noise level of the photon estimate) for the disc scene made of
   dentin (g = 0.93-0.96, unscaled): each render in its own process, peak RSS and photon-map
   bytes.

Run: .venv/bin/python benchmarks/scaling.py [--quick]
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import numpy as np
from dentalux.distributed import DaskExecutor, LocalExecutor
from dentalux.progressive import StopRule, render_progressive
from dentalux.scene.builtin import discs

QUICK = "--quick" in sys.argv
PASSES = 4 if QUICK else 8
RENDER = dict(integrator="ppm", spp=2, photons=20_000, volume_photons=50_000,
              resolution=(64, 48), bands=[450, 540, 605], progress=False)


def timed(executor, threads=None):
    t0 = time.perf_counter()
    r = render_progressive(discs(), StopRule(passes=PASSES), executor=executor, threads=threads,
                           **RENDER)
    wall = time.perf_counter() - t0
    task_s = sum(b["seconds_total"] for b in r.stats["bands"])
    return r.radiance, wall, task_s


def scaling() -> None:
    n_tasks = PASSES * len(RENDER["bands"])
    print(f"ppm discs 64x48, {len(RENDER['bands'])} bands x {PASSES} passes = {n_tasks} tasks, "
          f"{RENDER['volume_photons']} volume + {RENDER['photons']} surface photons per pass")
    timed(LocalExecutor(), threads=1)  # warm-up: imports, material library, scene build
    rows = []
    base, wall1, task1 = timed(LocalExecutor(), threads=1)
    rows.append(("local, 1 thread", 1, wall1, task1))
    img, wall, task = timed(LocalExecutor(), threads=2)
    rows.append(("local, 2 threads in one process", 1, wall, task))
    same = [np.array_equal(img, base)]
    for n in (1, 2):
        t0 = time.perf_counter()
        ex = DaskExecutor(f"local:{n}")
        start = time.perf_counter() - t0
        try:
            img, wall, task = timed(ex)
        finally:
            ex.close()
        rows.append((f"dask local:{n} (start-up {start:.1f} s, not counted)", n, wall, task))
        same.append(np.array_equal(img, base))
    print(f"{'executor':48s} {'wall s':>8s} {'speedup':>8s} {'task s':>8s} "
          f"{'overhead/task ms':>17s}")
    # overhead: wall time not spent inside the tasks' renders, per task (tasks running at a
    # time share the wall clock)
    for name, workers, wall, task in rows:
        overhead = (wall - task / workers) / n_tasks * 1e3
        print(f"{name:48s} {wall:8.2f} {wall1 / wall:8.2f} {task:8.2f} {overhead:17.1f}")
    print(f"images identical to the 1-thread local render: {all(same)}")


CHILD = """
import json, sys
from dentalux.outputs import peak_memory_bytes
from dentalux.render import render
from dentalux.scene.builtin import discs
kind, passes, photons = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
kw = dict(spp=1, photons=photons // 4, resolution=(32, 24), bands=[540], progress=False,
          threads=1)
if kind == "ppm":
    r = render(discs(material="dentin"), integrator="ppm", passes=passes,
               volume_photons=photons, **kw)
else:
    kw["photons"] *= passes
    r = render(discs(material="dentin"), integrator="vpm", volume_photons=photons * passes, **kw)
b = r.stats["bands"][0]
print(json.dumps({"peak": peak_memory_bytes(), "map": b["photon_map_bytes"],
                  "stored": b["photons_stored"], "s": r.stats["seconds_total"]}))
"""


def memory() -> None:
    passes, photons = (4, 500_000) if QUICK else (8, 2_000_000)
    print(f"\ndentin discs (g = 0.93-0.96 unscaled), 540 nm, {passes} x {photons} volume photons")
    # baseline: the same process rendering with 1000 photons (imports, scene, camera pass)
    base = json.loads(subprocess.run([sys.executable, "-c", CHILD, "ppm", "1", "1000"],
                                     capture_output=True, text=True, check=True).stdout)
    print(f"{'integrator':28s} {'peak RSS MB':>12s} {'above base':>13s} {'map MB':>8s} "
          f"{'stored':>10s} {'s':>7s}")
    for kind in ("ppm", "vpm"):
        out = subprocess.run([sys.executable, "-c", CHILD, kind, str(passes), str(photons)],
                             capture_output=True, text=True, check=True).stdout
        r = json.loads(out)
        name = (f"ppm {passes} passes of {photons}" if kind == "ppm"
                else f"vpm {passes * photons} photons")
        print(f"{name:28s} {r['peak'] / 1e6:12.1f} {(r['peak'] - base['peak']) / 1e6:13.1f} "
              f"{r['map'] / 1e6:8.1f} {r['stored']:10d} {r['s']:7.1f}")


if __name__ == "__main__":
    scaling()
    memory()
