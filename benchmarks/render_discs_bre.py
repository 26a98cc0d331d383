"""The beam radiance estimate against eq. 11's march on the paper's Fig. 3 scene (issue 16).

Error of each integrator's averaged passes against the unbiased truth of
`render_discs_truth.py --truth-cache FILE` (volpath-nee; build it once, outside the
repository), as CPU-seconds grow: CPU-seconds are user + system time of this process (the
renders run in its threads), so a shared machine's load does not inflate them; wall seconds
are printed beside them. Error: sqrt(max(mean (I − T)² − mean var(T), 0)) / mean(T) over the
whole image, as render_discs_truth.py measures it. Passes of one seed with pass_index 0, 1, …
(`dentalux render --passes`); for `ppm` those are the passes of its radius schedule, so its
bias shrinks as they grow. The time to 5 %, 2 % and 1 % is read off the curve (log-log
interpolation between the passes that bracket it; "> N" when the budget ran out first).

    .venv/bin/python benchmarks/render_discs_bre.py --truth-cache /tmp/discs_truth_128x96.npz \\
        [--configs bre:1000000:8:4,vpm:4000000:200:4,ppm-beam:1000000:8:4] [--budget 120]
        [--surface-k 50] [--aim 0.5 --surface-photons 170000]

`--radius-curve 1.6,0.8,0.4,0.2` also measures bre's per-pixel bias against the truth at each
disc radius (passes' own noise and the truth's removed from the squared error: bias² =
mean (I − T)² − mean var(T) − mean var(I), var(I) from the spread of the passes), and
`--plot FILE` draws the error curves and the bias curve.

A configuration is integrator:volume_photons:k:spp[:radius]; `ppm-beam` is ppm with
volume_estimator = "beam", `ppm` the same with eq. 11's march; radius [mm] is the `radius`
setting (bre: the disc radius; ppm: the first pass's), absent for the scene's default.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import time

import numpy as np
from render_discs import render, scene_dict


def cpu_seconds() -> float:
    """User + system CPU time of this process so far [s]."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def time_to(curve: list[tuple[float, float]], target: float) -> str:
    """CPU-seconds at which the error curve [(cpu, error)] first reaches ``target``."""
    prev = None
    for cpu, err in curve:
        if err <= target:
            if prev is None or prev[1] <= 0 or err <= 0:
                return f"{cpu:.0f}"
            (c0, e0) = prev
            # log-log interpolation: error ~ cpu^slope between the two passes
            slope = math.log(err / e0) / math.log(cpu / c0)
            return f"{c0 * (target / e0) ** (1 / slope):.0f}" if slope < 0 else f"{cpu:.0f}"
        prev = (cpu, err)
    return f"> {curve[-1][0]:.0f}" if curve else "n/a"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--truth-cache", required=True)
    ap.add_argument("--configs", default="bre:1000000:8:4,vpm:4000000:200:4")
    ap.add_argument("--budget", type=float, default=120.0, help="CPU-seconds per configuration")
    ap.add_argument("--max-passes", type=int, default=256)
    ap.add_argument("--seed", type=int, default=4000)
    ap.add_argument("--surface-k", type=int, default=None,
                    help="render option surface_k for every configuration (default: k)")
    ap.add_argument("--aim", type=float, default=None,
                    help="aim this fraction of the volume photons at the discs; a "
                         "configuration's photons are then the volume photons stored per pass "
                         "(volume_stored; at most 25x as many emitted)")
    ap.add_argument("--surface-photons", type=float, default=None,
                    help="photons emitted for the surface map per pass (default: a "
                         "configuration's photons)")
    ap.add_argument("--radius-curve", default="", help="disc radii [mm] for bre's bias curve")
    ap.add_argument("--curve-passes", type=int, default=16)
    ap.add_argument("--curve-photons", type=int, default=1_000_000)
    ap.add_argument("--plot", default=None, help="PNG of the error and bias curves")
    args = ap.parse_args()
    z = np.load(args.truth_cache)
    truth, var_t = z["truth"], z["var_t"]
    res = (truth.shape[1], truth.shape[0])
    level = float(truth.mean())
    scene = scene_dict(False)
    print(f"# discs.toml at 540 nm, {res[0]}x{res[1]}; truth {args.truth_cache} (mean "
          f"{level:.5f}, own per-pixel noise {np.sqrt(var_t.mean()) / level:.4f}); "
          f"load average {os.getloadavg()}")

    def err(img):
        return float(np.sqrt(max(np.mean((img - truth) ** 2) - var_t.mean(), 0.0))) / level

    print("| config | passes | CPU s | wall s | rel. RMSE | mean vs truth |")
    print("|---|---|---|---|---|---|")
    summary, curves = [], {}
    for c, conf in enumerate(filter(None, args.configs.split(","))):
        name, photons, k, spp, *radius = conf.split(":")
        integrator, extra = name, ({"radius": float(radius[0])} if radius else {})
        if args.surface_k:
            extra["surface_k"] = args.surface_k
        n = int(float(photons))
        extra["photons"] = int(args.surface_photons) if args.surface_photons else n
        extra["volume_photons"] = n
        if args.aim is not None:
            extra.update(aim=args.aim, volume_stored=n, volume_photons=25 * n)
        if name == "ppm-beam":
            integrator = "ppm"
            extra["volume_estimator"] = "beam"
        total, curve, walls = None, [], []
        cpu0, wall0 = cpu_seconds(), time.perf_counter()
        for p in range(args.max_passes):
            img, _, _ = render(scene, res, integrator=integrator, spp=int(spp), k=int(k),
                               seed=args.seed + 100 * c, pass_index=p, **extra)
            total = img if total is None else total + img
            n = p + 1
            cpu, wall = cpu_seconds() - cpu0, time.perf_counter() - wall0
            mean = total / n
            e = err(mean)
            curve.append((cpu, e))
            walls.append((wall, e))
            if n & (n - 1) == 0:
                print(f"| {conf} | {n} | {cpu:.1f} | {wall:.1f} | {e:.4f} "
                      f"| {(mean.mean() - level) / level:+.4f} |", flush=True)
            if cpu * (n + 1) / n > args.budget:
                break
        summary.append((conf, [time_to(curve, t) for t in (0.05, 0.02, 0.01)],
                        time_to(walls, 0.02), curve[-1]))
        curves[conf] = curve
    print("\n| config | CPU s to 5 % | to 2 % | to 1 % | wall s to 2 % | last (CPU s, error) |")
    print("|---|---|---|---|---|---|")
    for conf, times, wall2, last in summary:
        print(f"| {conf} | {' | '.join(times)} | {wall2} | ({last[0]:.0f}, {last[1]:.4f}) |")
    bias = []
    if args.radius_curve:
        print("\n| bre radius [mm] | per-pixel bias | passes' own noise | image mean vs truth |")
        print("|---|---|---|---|")
    for r in (float(x) for x in filter(None, args.radius_curve.split(","))):
        imgs = [render(scene, res, integrator="bre", spp=4, volume_photons=args.curve_photons,
                       photons=args.curve_photons, radius=r, seed=args.seed + 7, pass_index=p)[0]
                for p in range(args.curve_passes)]
        m = np.mean(imgs, axis=0)
        var_m = np.var(imgs, axis=0, ddof=1) / len(imgs)
        b2 = np.mean((m - truth) ** 2) - var_t.mean() - var_m.mean()
        b = float(np.sqrt(max(b2, 0.0))) / level
        bias.append((r, b))
        print(f"| {r:g} | {b:.4f} | {np.sqrt(var_m.mean()) / level:.4f} "
              f"| {(m.mean() - level) / level:+.4f} |", flush=True)
    if args.plot:
        plot(args.plot, curves, bias, res)


def plot(path: str, curves: dict, bias: list, res: tuple[int, int]) -> None:
    """Error against CPU-seconds per configuration, and bre's bias against its radius."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2 if bias else 1, figsize=(11 if bias else 6, 4), squeeze=False)
    for conf, curve in curves.items():
        ax[0, 0].loglog(*zip(*curve, strict=True), marker=".", label=conf)
    for e in (0.05, 0.02):
        ax[0, 0].axhline(e, color="grey", lw=0.5)
    ax[0, 0].set(xlabel="CPU-seconds", ylabel="relative RMSE per pixel vs volpath-nee",
                 title=f"Fig. 3 discs, 540 nm, {res[0]}x{res[1]}")
    ax[0, 0].legend(fontsize=7)
    if bias:
        ax[0, 1].plot(*zip(*bias, strict=True), marker="o")
        ax[0, 1].set(xlabel="bre disc radius [mm]", ylabel="per-pixel bias (noise removed)",
                     title="bre: bias against radius", ylim=(0, None))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
