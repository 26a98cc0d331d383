"""Wall and CPU seconds of the precision issue's one reading: the stack enamel 0.6 / dentin
0.9 mm, substrate none, 41 bands, through the default instrument, from Python and from the
command line, in one run (2 cores).

- ``python``: ``dental.read`` in a warm process with the solver's cache cleared, best of
  ``--repeats``; beside it the same with every spatial frequency solved
  (``window.nodes_for`` bypassed), for the ratio;
- ``command line``: ``dentalux shade --layer ... --json`` as a new process, best of
  ``--repeats``, and ``dentalux --help`` (the start-up alone).

The goal (issue 39) is a reading in at most 2 s wall. Start-up depends on Python's
bytecode cache: a source tree run with PYTHONDONTWRITEBYTECODE set compiles the package's
modules on every call (about 0.2 s more); an installed wheel has them compiled.

    .venv/bin/python benchmarks/reading_time.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import time

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


def command_line(args: list[str], repeats: int) -> float:
    exe = shutil.which("dentalux") or os.path.join(os.path.dirname(sys.executable), "dentalux")
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run([exe, *args], check=True, stdout=subprocess.DEVNULL)
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
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
    print(f"command line, shade   {command_line(COMMAND, args.repeats):5.2f} s wall")
    print(f"command line, --help  {command_line(['--help'], args.repeats):5.2f} s wall")
    print(f"(bytecode written: {not sys.dont_write_bytecode})")


if __name__ == "__main__":
    main()
