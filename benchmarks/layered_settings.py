"""The layered solver's discretisation against its CPU, in one run (one thread).

For each case (specimen through an instrument's lit region and window) the solver's readings
over black, over white (R_b 0.9) and in transmission, at 41 bands, are computed with the
default settings (stack.NODES_PER_INTERVAL, ORDER, K_NODES, MODES_BY_K) and with candidate
settings, and compared with a reference solved with finer ones (more nodes per interval,
more spatial frequencies, four more azimuthal modes everywhere). It prints the largest
relative difference of each setting from the reference over bands and channels, and the
CPU-s of each solve: how far a cheaper setting moves the reading, and what it saves.
The solver's stated accuracy is stack.ACCURACY; its discretisation part was 0.16 % on discs.

    .venv/bin/python benchmarks/layered_settings.py [--bands 41]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from dentalux import instrument, materials
from dentalux.reading import engine, layered
from dentalux.reading.layered import stack
from threadpoolctl import threadpool_limits

CASES = {
    "enamel 1 mm, probe": ([("enamel", 1.0)], "contact-probe-3mm"),
    "dentin 2 mm, probe": ([("dentin", 2.0)], "contact-probe-3mm"),
    "stack 0.6/0.9, probe": ([("enamel", 0.6), ("dentin", 0.9)], "contact-probe-3mm"),
    "stack 0.6/0.9, 45-0": ([("enamel", 0.6), ("dentin", 0.9)], "45-0"),
    "enamel 1 mm, fibre probe": ([("enamel", 1.0)], "fibre-probe"),
    "stack 0.6/0.9, d/8": ([("enamel", 0.6), ("dentin", 0.9)], "d8-benchtop-sav"),
    "stack 0.6/0.9, noncontact": ([("enamel", 0.6), ("dentin", 0.9)], "noncontact"),
}
DEFAULT = dict(per_interval=stack.NODES_PER_INTERVAL, ks=stack.K_NODES,
               modes=stack.MODES_BY_K)
# the 14 spatial frequencies of before 7 Dec 2026 (fourth session)
K_14 = (0.0, 0.1, 0.25, 0.5, 0.8, 1.2, 1.8, 2.7, 4.0, 6.0, 9.0, 14.0, 21.0, 32.0)
# finer in every direction: nodes, spatial frequencies (both sets and the 14's midpoints, a
# reference that does not move with the default), modes (+4: the azimuthal truncation
# alternates in sign between odd and even mode counts, so one more mode is no reference)
_MID = tuple(sorted(set(K_14) | set(stack.K_NODES)
                    | {0.5 * (a + b) for a, b in zip(K_14[:-1], K_14[1:], strict=True)}))


def _more_modes(extra: int) -> tuple:
    return tuple((k, m + extra) for k, m in stack.MODES_BY_K)


REFERENCE = dict(per_interval=(12, 9), ks=_MID, modes=_more_modes(4))
CANDIDATES = {
    "modes +1": dict(DEFAULT, modes=_more_modes(1)),
    "modes +2": dict(DEFAULT, modes=_more_modes(2)),
    # the setting before 7 Dec 2026 (third session): 6 modes at k 1.8-9 /mm
    "6 modes at k 1.8-9": dict(DEFAULT, modes=((0.0, 1), (0.3, 3), (1.5, 4), (12.0, 6),
                                               (np.inf, 4))),
    "5 modes past k 1.5": dict(DEFAULT, modes=((0.0, 1), (0.3, 3), (1.5, 4), (12.0, 5),
                                               (np.inf, 5))),
    "4 modes past k 1.5": dict(DEFAULT, modes=((0.0, 1), (0.3, 3), (1.5, 4), (np.inf, 4))),
    "14 spatial frequencies": dict(DEFAULT, ks=K_14),
    "nodes (7, 5)": dict(DEFAULT, per_interval=(7, 5)),
    "nodes (10, 8)": dict(DEFAULT, per_interval=(10, 8)),
}


def readings(parts, inst, wl, settings) -> tuple[np.ndarray, float]:
    """(3, bands) over black, over white and transmitted, and the solve's CPU-s."""
    bs = engine.stacks([(materials.get(m), t) for m, t in parts], wl)
    cone, lit, view, pairs = engine._regions(inst)
    start = time.process_time()
    sums = []
    for indices, members in engine.by_indices(bs).items():
        group = [bs[i] for i in members]
        res = layered.responses(group, 1.0, 1.0, cone, ks=settings["ks"],
                                modes_by_k=settings["modes"],
                                per_interval=settings["per_interval"])
        local = layered.local_parts(group, 1.0, 1.0)
        first = float(engine._core.fresnel_reflectance([1.0], 1.0, indices[0])[0])
        sums.append(layered.order_sums(res, local, first, lit, view, engine.MAX_ORDER,
                                       engine.WINDOW_KEYS, pairs))
    cpu = time.process_time() - start
    s = np.concatenate(sums)[:, None]  # (bands, 1 replicate, orders, keys)
    key = "viewed_cone_reflectance" if inst.spec.cone_deg else "viewed_reflectance"
    zero, white = np.zeros(len(wl)), np.full(len(wl), 0.9)
    out = [engine._polynomial(s, key, rb)[0] for rb in (zero, white)]
    out.append(engine._polynomial(s, "viewed_transmittance", zero)[0])
    return np.array(out), cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bands", type=int, default=41)
    args = ap.parse_args()
    wl = np.linspace(380.0, 780.0, args.bands)
    rows = {"default": DEFAULT, **CANDIDATES}
    print(f"{'case':24s} {'setting':22s} {'max |rel. diff|':>16s} {'CPU-s':>7s}"
          f" {'ref CPU-s':>9s}")
    with threadpool_limits(limits=1, user_api="blas"):
        for case, (parts, name) in CASES.items():
            inst = instrument.get(name)
            ref, ref_cpu = readings(parts, inst, wl, REFERENCE)
            for label, settings in rows.items():
                got, cpu = readings(parts, inst, wl, settings)
                rel = np.max(np.abs(got - ref) / np.abs(ref))
                print(f"{case:24s} {label:22s} {100 * rel:15.3f}% {cpu:7.2f} {ref_cpu:9.2f}")


if __name__ == "__main__":
    main()
