"""Time each of the paper's figures and record its peak memory.

Each figure renders in its own process (so peak memory is per figure). Prints a table and
writes benchmarks/figures-QUALITY.json. The `paper` quality uses the paper's photon counts
(100 M volume photons) and takes hours on a 2-core machine.

    .venv/bin/python benchmarks/figures.py --quality preview [--only fig3,crown]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from dentalux.figures import FIGURES, QUALITIES

CHILD = """
import json, resource, sys, time
from dentalux.figures import make_figures
t = time.perf_counter()
make_figures(sys.argv[1], quality=sys.argv[2], only=[sys.argv[3]], log=lambda *_: None)
print(json.dumps({"seconds": time.perf_counter() - t,
                  "peak_rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quality", default="preview", choices=list(QUALITIES))
    ap.add_argument("--only", default=",".join(FIGURES))
    ap.add_argument("--out", default=None, help="keep the figures here (default: discarded)")
    args = ap.parse_args()
    rows = {}
    with tempfile.TemporaryDirectory() as scratch:
        tmp = args.out or scratch
        for fig in args.only.split(","):
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", CHILD, tmp, args.quality, fig],
                                 check=True, capture_output=True, text=True)
            rows[fig] = json.loads(out.stdout.strip().splitlines()[-1])
            rows[fig]["wall_seconds_with_startup"] = time.perf_counter() - t0
            rows[fig]["load_average_1min_at_end"] = os.getloadavg()[0]
            rows[fig]["date_utc"] = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
            print(f"{fig:8s} {rows[fig]['seconds']:8.1f} s   peak "
                  f"{rows[fig]['peak_rss_bytes'] / 2**20:7.0f} MiB", flush=True)
    # merge into earlier runs of other figures (paper quality is timed one figure at a time)
    path = Path(__file__).with_name(f"figures-{args.quality}.json")
    if path.exists():
        rows = {**json.loads(path.read_text())["figures"], **rows}
    total = sum(r["seconds"] for r in rows.values())
    print(f"total    {total:8.1f} s   ({args.quality}, all figures on record)")
    path.write_text(json.dumps({"quality": args.quality, "figures": rows,
                                "total_seconds": total}, indent=2))


if __name__ == "__main__":
    main()
