"""The cost of a reading through the fibre probe against today's contact probe, in one run:
CPU-seconds of a 41-band reading (380-780 nm every 10 nm) of the two-layer stack enamel 0.6 /
dentin 0.9 mm through ``fibre-probe`` (the layered solver, its white tile included, no noise)
and through ``contact-probe-3mm`` (the layered solver plus the Monte Carlo walk of its 10 mm
rim, the reading's only noise), with the standard errors of L*, a*, b* over white. Caches
are emptied between readings so that neither reuses the other's solves."""

from __future__ import annotations

import argparse
import dataclasses
import time

from dentalux import dental, instrument
from dentalux.reading import engine
from dentalux.reading import white_reference as tile_readings

STACK = [("enamel", 0.6), ("dentin", 0.9)]


def one(label: str, inst, photons: int) -> None:
    engine._SOLVED.clear()
    tile_readings._READ.clear()
    start = time.process_time()
    m = dental.read(STACK, instrument=inst, photons=photons)
    cpu = time.process_time() - start
    lab, err = m.lab_white, m.error("lab_white")
    print(f"{label:<34} {cpu:7.1f} CPU-s  L*a*b* {lab.L:6.2f} {lab.a:6.2f} {lab.b:6.2f}  "
          f"s.e. {err.L:.3f} {err.a:.3f} {err.b:.3f}  ({len(m.wavelengths_nm)} bands)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photons", type=int, default=20_000,
                        help="rim-walk photons per band of contact-probe-3mm")
    args = parser.parse_args()
    fibre = instrument.get("fibre-probe")
    one("fibre-probe (with its tile)", fibre, args.photons)
    one("fibre-probe, no tile", dataclasses.replace(fibre, white_reference=None),
        args.photons)
    one(f"contact-probe-3mm ({args.photons} rim photons)", instrument.get("contact-probe-3mm"),
        args.photons)
    one(f"contact-probe-3mm ({4 * args.photons} rim photons)",
        instrument.get("contact-probe-3mm"), 4 * args.photons)


if __name__ == "__main__":
    main()
