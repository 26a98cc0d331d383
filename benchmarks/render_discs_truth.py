"""Volume photon mapping against the truth on the paper's Fig. 3 scene (issue 5's target).

The reference is `volpath-nee` (unbiased: volpath with next-event estimation through the discs'
flat faces), rendered as two independent halves so its per-pixel variance is known and removed
from the squared error. vpm runs average passes (own photon maps and camera paths each; one
seed with pass_index 0, 1, ..., so each pixel's sub-pixel positions continue one stratified
sequence, as `dentalux render --passes` does; `--independent` for independent seeds).
Error: sqrt(mean over pixels (I − T)² − mean var(T)) / mean(T), whole image.
The time plain `volpath` and `volpath-nee` need for the same error is extrapolated from their
measured per-sample variance (t_spp · var_1spp / (e · mean)²).

    .venv/bin/python benchmarks/render_discs_truth.py [--ref-spp 2048] [--budget 60]
        [--configs 4000000:200:4,8000000:100:4,16000000:50:4]
        [--ppm 2000000:50:4:0.7,...]

`--ppm photons:k:spp:alpha` configurations run the `ppm` integrator (radii shrink by the
Knaus-Zwicker schedule, so its bias vanishes as passes grow) for 1, 2, 4, ... passes, each a
separate render whose own wall time is reported (the curve costs about twice its last point).
"""

from __future__ import annotations

import argparse
import os

import numpy as np
from render_discs import passes, render, scene_dict


def halves(scene, res, integrator, spp, seed):
    """Mean image, per-pixel variance of that mean, per-sample variance (pixel mean), s/spp."""
    a, _, ta = render(scene, res, integrator=integrator, spp=spp, seed=seed)
    b, _, tb = render(scene, res, integrator=integrator, spp=spp, seed=seed + 1)
    mean = 0.5 * (a + b)
    var_mean = (a - b) ** 2 / 4.0
    var_1spp = float(np.mean((a - b) ** 2) / 2.0 * spp)
    return mean, var_mean, var_1spp, (ta + tb) / (2 * spp)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--resolution", default="128x96")
    ap.add_argument("--ref-spp", type=int, default=2048, help="volpath-nee spp (two halves)")
    ap.add_argument("--budget", type=float, default=60.0, help="seconds per vpm configuration")
    ap.add_argument("--configs", default="4000000:200:4,8000000:100:4,16000000:50:4")
    ap.add_argument("--ppm", default="", help="photons:k:spp:alpha,... (ppm integrator)")
    ap.add_argument("--surface-photons", type=int, default=None,
                    help="photons for the surface map (default: as many as the volume "
                         "photons; the core takes them from the volume pass, so they cost "
                         "nothing up to that count)")
    ap.add_argument("--aim", type=float, default=None,
                    help="fraction of volume photons aimed at the discs (default: the core's)")
    ap.add_argument("--kernel-clip", action=argparse.BooleanOptionalAction, default=None,
                    help="render option kernel_clip (default: the core's, on)")
    ap.add_argument("--independent", action="store_true",
                    help="vpm passes with independent seeds (default: one seed, pass_index "
                         "0, 1, ...: the pixels' sub-pixel sequence continues across passes)")
    ap.add_argument("--truth-cache", default=None,
                    help="NPZ file: reuse the truth and the path tracers' variances stored "
                         "there by an earlier run with the same resolution and --ref-spp "
                         "(written when missing)")
    args = ap.parse_args()
    res = tuple(int(v) for v in args.resolution.split("x"))
    scene = scene_dict(False)
    print(f"# discs.toml at 540 nm, {args.resolution}; load average {os.getloadavg()}")
    cache = args.truth_cache and os.path.exists(args.truth_cache)
    if cache:
        z = np.load(args.truth_cache)
        truth, var_t = z["truth"], z["var_t"]
        t_nee, var_vp, t_vp, var_nee, t_nee2 = (float(v) for v in z["costs"])
        print(f"truth from {args.truth_cache}")
    else:
        truth, var_t, _, t_nee = halves(scene, res, "volpath-nee", args.ref_spp // 2, 7001)
    level = float(truth.mean())
    noise = float(np.sqrt(var_t.mean())) / level
    se_mean = float(np.sqrt(var_t.sum())) / truth.size / level
    print(f"truth: volpath-nee {args.ref_spp} spp ({t_nee * args.ref_spp:.0f} s), image mean "
          f"{level:.5f} (s.e. {se_mean:.4f} rel.), own per-pixel noise {noise:.4f} rel.")
    if not cache:
        # per-sample variance of both path tracers from short independent runs
        _, _, var_vp, t_vp = halves(scene, res, "volpath", 128, 9001)
        _, _, var_nee, t_nee2 = halves(scene, res, "volpath-nee", 128, 9101)
        if args.truth_cache:
            np.savez(args.truth_cache, truth=truth, var_t=var_t,
                     costs=np.array([t_nee, var_vp, t_vp, var_nee, t_nee2]))

    def cost(e):
        return (t_vp * var_vp / (e * level) ** 2, t_nee2 * var_nee / (e * level) ** 2)

    print(f"volpath 1-spp rel. sd {np.sqrt(var_vp) / level:.2f} ({t_vp:.4f} s/spp), "
          f"volpath-nee {np.sqrt(var_nee) / level:.2f} ({t_nee2:.4f} s/spp); 2 % per pixel: "
          f"{cost(0.02)[0]:.0f} s / {cost(0.02)[1]:.0f} s")

    def err(img):
        return float(np.sqrt(max(np.mean((img - truth) ** 2) - var_t.mean(), 0.0))) / level

    print("| photons/pass | k | spp | passes | seconds | rel. RMSE vs truth | mean vs truth "
          "| volpath s | volpath-nee s | speed-up vs volpath |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    aim = {} if args.aim is None else {"aim": args.aim}
    if args.kernel_clip is not None:
        aim["kernel_clip"] = args.kernel_clip
    for c, conf in enumerate(filter(None, args.ppm.split(","))):
        photons, k, spp, alpha = conf.split(":")
        n = 1
        while True:
            img, _, wall = render(scene, res, integrator="ppm", spp=int(spp), seed=5000 + c,
                                  volume_photons=int(float(photons)),
                                  photons=args.surface_photons or int(float(photons)),
                                  k=int(k), passes=n,
                                  alpha=float(alpha), **aim)
            e = err(img)
            t1, t2 = cost(e) if e > 0 else (float("inf"),) * 2
            print(f"| ppm {photons} a={alpha} | {k} | {spp} | {n} | {wall:.1f} | {e:.4f} "
                  f"| {(img.mean() - level) / level:+.4f} | {t1:.0f} | {t2:.0f} "
                  f"| {t1 / wall:.0f}x |", flush=True)
            if wall * 2 > args.budget:
                break
            n *= 2
    for c, conf in enumerate(filter(None, args.configs.split(","))):
        photons, k, spp = (int(float(x)) for x in conf.split(":"))

        def report(n, wall, img, photons=photons, k=k, spp=spp):
            if n & (n - 1):
                return
            e = err(img)
            t1, t2 = cost(e) if e > 0 else (float("inf"),) * 2
            print(f"| {photons} | {k} | {spp} | {n} | {wall:.1f} | {e:.4f} "
                  f"| {(img.mean() - level) / level:+.4f} | {t1:.0f} | {t2:.0f} "
                  f"| {t1 / wall:.0f}x |", flush=True)

        passes(scene, res, 4096, 3000 + 100 * c, photons, k, spp,
               args.surface_photons or photons,
               budget=args.budget, on_pass=report, independent=args.independent, **aim)


if __name__ == "__main__":
    main()
