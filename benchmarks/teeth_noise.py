"""Noise of the teeth figures (issue 16): the crown figure's scene rendered as the figure
renders it (preview counts, three bands, correlated streams) with several seeds. The
per-pixel noise of L*, a*, b* over each measured region is the spread of the first two
renders' difference over √2 (the difference holds noise only, so the regions need not be
flat); the spread of the region means over the seeds, and of the figure's ΔE00 between the
crown and the natural tooth, says how far the figure's reported colours move with the seed.
Prints CPU seconds (user + system of this process) per render.

    .venv/bin/python benchmarks/teeth_noise.py [--spp 8] [--k 400] [--stored 16000000]
        [--resolution 320x240] [--seeds 2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from dentalux import figures as F
from dentalux.color import delta_e00, system
from dentalux.outputs import colour_inputs
from dentalux.render import render
from dentalux.scene import scene_from_dict


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    q = F.QUALITIES["preview"]
    ap.add_argument("--spp", type=int, default=q.teeth_spp)
    ap.add_argument("--k", type=int, default=q.teeth_k)
    ap.add_argument("--stored", type=int, default=q.teeth_volume_stored)
    ap.add_argument("--resolution", default=None, help="WxH (default: the preview's)")
    ap.add_argument("--seeds", type=int, default=2, help="renders, seeds 1, 2, ... (>= 2)")
    a = ap.parse_args()
    if a.resolution:
        w, h = (int(x) for x in a.resolution.split("x"))
        q = F.Quality(**{**F.asdict(q), "resolution": (w, h)})
    scene, regions = F.crown_scene(q)
    tile = F.white_tile(scene, regions, q)
    F.lower_anisotropy(scene, q)
    sc = scene_from_dict(scene)
    bands = F.PAPER_BANDS
    settings = {**F._teeth_settings(q), "spp": a.spp, "k": a.k, "volume_stored": a.stored}
    cs = system("D65", "2")
    divisor, _, _ = colour_inputs(sc, bands)
    labs, cpus = [], []
    for seed in range(1, max(a.seeds, 2) + 1):
        c0 = time.process_time()
        res = render(sc, integrator="vpm", bands=bands, seed=seed, correlated_bands=True,
                     progress=False, **settings)
        cpus.append(time.process_time() - c0)
        rel = res.radiance / divisor / tile["white"]
        labs.append({name: np.array([cs.spectrum_to_Lab(p, bands) for p in
                                     rel[y0:y1, x0:x1].reshape(-1, len(bands))])
                     for name, (x0, y0, x1, y1) in regions.items()})
    print(f"crown figure {q.resolution[0]}x{q.resolution[1]}, spp {a.spp}, k {a.k}, "
          f"{a.stored} volume photons stored, {len(labs)} seeds; CPU-s per render "
          + ", ".join(f"{c:.0f}" for c in cpus))
    means = [{name: lab[name].mean(axis=0) for name in regions} for lab in labs]
    for name in regions:
        d = labs[0][name] - labs[1][name]
        sd = d.std(axis=0, ddof=1) / np.sqrt(2)
        m = np.array([mm[name] for mm in means])
        msd = m.std(axis=0, ddof=1)
        print(f"  {name:8s} {len(d):5d} px: per-pixel sd L* {sd[0]:.2f} a* {sd[1]:.2f} "
              f"b* {sd[2]:.2f}; region mean {m[:, 0].mean():.2f}/{m[:, 1].mean():.2f}/"
              f"{m[:, 2].mean():.2f}, its sd over seeds {msd[0]:.2f}/{msd[1]:.2f}/{msd[2]:.2f}")
    if {"natural", "crown"} <= set(regions):
        de = np.array([float(delta_e00(m["natural"], m["crown"])) for m in means])
        print("  dE00 crown vs natural per seed: " + ", ".join(f"{v:.2f}" for v in de)
              + f"; mean {de.mean():.2f}, sd {de.std(ddof=1):.2f}")


if __name__ == "__main__":
    main()
