"""One instrument reading over 41 bands: seconds (wall and CPU) and the standard error of TP.

Target (issue: instrument model): < 10 s on 2 cores with a TP standard error < 0.3.
    python benchmarks/instrument.py [--photons N] [--instrument NAME]
"""

from __future__ import annotations

import argparse
import os
import time

from dentalux import dental


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--photons", type=int, default=dental.DEFAULT_PHOTONS)
    ap.add_argument("--instrument", default="contact-probe-3mm")
    ap.add_argument("--material", default="enamel")
    args = ap.parse_args()
    for inst in ("infinite", args.instrument):
        t0, c0 = time.perf_counter(), os.times()
        m = dental.metrics(args.material, 1.0, photons=args.photons, instrument=inst)
        c1 = os.times()
        cpu = (c1.user - c0.user) + (c1.system - c0.system)
        print(f"{inst:20s} {len(m.wavelengths_nm)} bands, {args.photons} photons/run: "
              f"{time.perf_counter() - t0:.2f} s wall, {cpu:.2f} CPU-s; TP {m.tp:.2f} "
              f"+- {m.stderr['tp']:.2f}, edge loss {m.edge_loss}")


if __name__ == "__main__":
    main()
