"""Wall and CPU seconds of the precision issue's one reading: the stack enamel 0.6 / dentin
0.9 mm, substrate none, 41 bands, through the default instrument, from Python and from the
command line, in one run (2 cores).

- ``python``: ``dental.read`` in a warm process with the solver's cache cleared, best of
  ``--repeats``; beside it the same with every spatial frequency solved
  (``window.nodes_for`` bypassed), for the ratio;
- ``command line``: ``dentalux shade --layer ... --json`` as a new process running the
  source tree this script imports (PYTHONPATH set to it), best of ``--repeats``, and
  ``dentalux --help`` (the start-up alone); ``--against DIR`` times another tree's ``python``
  folder (say a worktree of the commit before) in the same run, the two alternating.

The goal (issue 39) is a reading in at most 2 s wall. Start-up depends on Python's
bytecode cache: a source tree run with PYTHONDONTWRITEBYTECODE set compiles the package's
modules on every call (about 0.2 s more); an installed wheel has them compiled. The command
line is timed both ways: as the environment runs it, and with the bytecode kept (in a
temporary PYTHONPYCACHEPREFIX that a first call fills), as an installed wheel runs.

    .venv/bin/python benchmarks/reading_time.py [--repeats 3] [--against DIR]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import dentalux
from dentalux import dental, instrument
from dentalux.reading import engine
from dentalux.reading.layered import stack, window

SPECIMEN = [("enamel", 0.6), ("dentin", 0.9)]
COMMAND = ["shade", "--layer", "enamel:0.6", "--layer", "dentin:0.9", "--substrate", "none",
           "--json"]


def in_process(repeats: int) -> tuple[float, float, dict]:
    best = (float("inf"), float("inf"))
    m = None
    for _ in range(repeats):
        engine._SOLVED.clear()
        wall, cpu = time.perf_counter(), time.process_time()
        m = dental.read(SPECIMEN)
        best = min(best, (time.perf_counter() - wall, time.process_time() - cpu))
    return best[0], best[1], m


def command_line(args: list[str], repeats: int, trees: list[str],
                 pycache: str | None = None) -> list[float]:
    """Best wall seconds of ``dentalux ARGS`` run from each source tree, the trees
    alternating; ``pycache``: a folder that keeps the compiled modules between calls (a first
    call, untimed, fills it)."""
    exe = shutil.which("dentalux") or os.path.join(os.path.dirname(sys.executable), "dentalux")
    envs = []
    for tree in trees:
        env = {**os.environ, "PYTHONPATH": tree}
        if pycache:
            env.pop("PYTHONDONTWRITEBYTECODE", None)
            env["PYTHONPYCACHEPREFIX"] = pycache
            subprocess.run([exe, *args], check=True, stdout=subprocess.DEVNULL, env=env)
        envs.append(env)
    best = [float("inf")] * len(trees)
    for _ in range(repeats):
        for i, env in enumerate(envs):
            start = time.perf_counter()
            subprocess.run([exe, *args], check=True, stdout=subprocess.DEVNULL, env=env)
            best[i] = min(best[i], time.perf_counter() - start)
    return best


def show(label: str, times: list[float]) -> None:
    against = f"   (against: {times[1]:5.2f} s)" if len(times) > 1 else ""
    print(f"command line, {label:16s} {times[0]:5.2f} s wall{against}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--against", help="another source tree's python folder, timed alongside")
    args = ap.parse_args()
    trees = [str(Path(dentalux.__file__).parents[1])] + ([args.against] if args.against else [])
    name = instrument.DEFAULT
    cone, lit, view, pairs = engine._regions(instrument.get(name))
    nodes = window.nodes_for(window.as_pairs(lit, view, pairs))
    dental.read(SPECIMEN, bands=[450.0, 550.0, 650.0])  # imports and caches warm
    wall, cpu, m = in_process(args.repeats)
    chosen = window.nodes_for
    window.nodes_for = lambda pairs, ks=stack.K_NODES: tuple(ks)
    try:
        wall_all, cpu_all, m_all = in_process(args.repeats)
    finally:
        window.nodes_for = chosen
    print(f"instrument {name}: {len(nodes)} of {len(stack.K_NODES)} spatial frequencies solved")
    print(f"python, those nodes   {wall:5.2f} s wall  {cpu:5.2f} CPU-s  "
          f"L*a*b* white {tuple(round(x, 4) for x in m.lab_white)}  TP00 {m.tp00:.4f}")
    print(f"python, every node    {wall_all:5.2f} s wall  {cpu_all:5.2f} CPU-s  "
          f"L*a*b* white {tuple(round(x, 4) for x in m_all.lab_white)}  TP00 {m_all.tp00:.4f}")
    print(f"  CPU ratio every node / those nodes: {cpu_all / cpu:.2f}")
    show("shade", command_line(COMMAND, args.repeats, trees))
    with tempfile.TemporaryDirectory(prefix="reading-time-") as pycache:
        show("shade, bytecode", command_line(COMMAND, args.repeats, trees, pycache))
    show("--help", command_line(["--help"], args.repeats, trees))
    print(f"(this tree: {trees[0]}" + (f"; against: {trees[1]}" if args.against else "")
          + f"; the environment writes bytecode: {not sys.dont_write_bytecode})")


if __name__ == "__main__":
    main()
