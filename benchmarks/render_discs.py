"""Volume photon mapping on the paper's Fig. 3 scene (two 5 mm discs, scenes/discs.toml), at
540 nm: photon tracing rate, kd-tree build time, bytes per photon, render time, peak memory,
and how long the unbiased `volpath` needs for the error `vpm` reaches (issue 5).

Material: the library's `biomaterial-table1` (fitted to the paper's Table 1) by default;
`--stand-in` uses the issue's stand-in values at 540 nm (mua 0.17/mm, mus 5.9/mm, g 0.75,
n 1.54) instead.

Error measure: per-pixel relative RMSE, sqrt(mean (I - R)^2) / mean(R).
- volpath is unbiased, so its error is its noise: two independent halves A and B give the
  per-sample variance (E[(A - B)^2] = 2 var(half)), and the time volpath needs for an error e is
  t_spp * mean var_1spp / (e * mean)^2, measured, not guessed.
- volpath cannot give a 2 %-accurate per-pixel reference on two cores in reasonable time (its
  own estimate is printed), so vpm's error is measured against a converged vpm-full render R
  (--ref-photons, --ref-spp-vpm); R's image mean is checked against volpath's (printed with
  its standard error), and the tests (crates/dentalux-core/tests/volume_transport.rs) check
  per-pixel convergence to volpath on a small disc scene.
Targets (issue 5): vpm reaches 2 % relative RMSE at least 10x sooner than volpath; 100 M
photons fit in under 3 GB (--memory-photons 100000000). The per-pixel error against an
unbiased truth (volpath-nee, many samples) is benchmarks/render_discs_truth.py's: 1.86 % in
85 s at 128x96, 13x sooner than volpath (docs/notes/2026-12-02-vpm-convergence.md, fifth session).

The default resolution is 128x96 (the issue's 512x384 with --resolution 512x384; volpath's
reference then takes hours on two cores). Timings are wall-clock on a possibly shared machine;
the load average is printed.

    .venv/bin/python benchmarks/render_discs.py [--resolution 128x96] [--ref-spp 2048]
        [--ladder 250000:4,1000000:8,4000000:16] [--memory-photons 0] [--stand-in]

`--time-to` (error against wall time, averaging independent passes; see time_to()):

    .venv/bin/python benchmarks/render_discs.py --time-to [--budget 60]
        [--configs 1000000:200:4,4000000:200:4] [--ref 16000000:200:16:32]
"""

from __future__ import annotations

import argparse
import os
import resource
import time
from pathlib import Path

import dentalux
import numpy as np
from dentalux.scene.load import read_toml

SCENE = Path(__file__).resolve().parent.parent / "scenes" / "discs.toml"
STAND_IN = {"mua": 0.17, "mus": 5.9, "g": 0.75, "n": 1.54}
BAND = 540.0


def scene_dict(stand_in: bool) -> dict:
    """scenes/discs.toml as a dict, with the stand-in medium if asked."""
    d = read_toml(SCENE)
    if stand_in:
        d["media"]["disc"] = dict(STAND_IN)
    return d


def peak_rss_gb() -> float:
    """Peak resident memory of this process [GB] (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2


def render(scene: dict, res, **kw):
    """One band at 540 nm; returns (image, stats of the band, wall seconds)."""
    t = time.perf_counter()
    r = dentalux.render(scene, bands=[BAND], resolution=res, progress=False, **kw)
    return r.radiance[..., 0].astype(np.float64), r.stats["bands"][0], time.perf_counter() - t


def passes(scene: dict, res, n: int, seed0: int, photons: int, k: int, spp: int,
           surface: int, integrator: str = "vpm", budget: float | None = None,
           on_pass=None, independent: bool = False, **options):
    """Average ``n`` passes: seed seed0 with pass_index 0, 1, ... (each its own photon maps and
    camera paths; the sub-pixel positions continue one stratified sequence per pixel, as
    `dentalux render --passes` does), or with ``independent`` seeds seed0, seed0 + 1, ...
    (fully independent passes, as before the film continued its sequence). Stops early when
    the wall time so far plus one more pass would pass ``budget``. ``on_pass(count, seconds,
    mean image)`` after each pass. Returns (mean image, s²/n from the spread of the passes —
    the variance of the mean for independent passes, an overestimate otherwise — passes, wall
    seconds)."""
    total = sq = None
    wall = 0.0
    done = 0
    for p in range(n):
        if budget is not None and done and wall * (done + 1) / done > budget:
            break
        key = dict(seed=seed0 + p) if independent else dict(seed=seed0, pass_index=p)
        img, _, t = render(scene, res, integrator=integrator, spp=spp, volume_photons=photons,
                           photons=surface, k=k, **key, **options)
        wall += t
        done += 1
        total = img.copy() if total is None else total + img
        sq = img * img if sq is None else sq + img * img
        if on_pass:
            on_pass(done, wall, total / done)
    mean = total / done
    var = np.maximum(sq / done - mean * mean, 0.0) / max(done - 1, 1)
    return mean, var, done, wall


def time_to(args, scene: dict, res) -> None:
    """Relative RMSE of averaged vpm passes against a converged reference, as wall time grows.

    Reference R: the mean of many vpm passes (--ref photons:k:spp:passes) with more photons per
    pass than any run, so its bias (the k-NN sphere's radius, which shrinks like
    (k / photons)^(1/3)) is smaller; its own noise, mean over pixels of s²/N from the spread of
    its passes, is subtracted from the squared error. Its residual bias is estimated from a
    second reference with a quarter of the photons per pass: if the bias falls like r, i.e.
    photons^(-1/3), bias(R) ≈ |R − R/4| · 4^(-1/3) / (1 − 4^(-1/3)) ≈ 1.7 |R − R/4|.
    Error of a run: sqrt(max(mean (I − R)² − mean var(R), 0)) / mean(R), whole image.
    volpath: unbiased, its error is its noise; the time it needs for error e is extrapolated
    from its measured per-sample variance (two independent halves): t_spp · var_1spp / (e ·
    mean)² (heavy-tailed fireflies make this an optimistic estimate for volpath)."""
    rp, rk, rspp, rn = (int(float(x)) for x in args.ref.split(":"))
    # volpath: mean and per-sample variance
    half = max(1, args.ref_spp // 2)
    a, _, ta = render(scene, res, integrator="volpath", spp=half, seed=1001)
    b, _, tb = render(scene, res, integrator="volpath", spp=half, seed=2002)
    vp = 0.5 * (a + b)
    mean_vp = vp.mean()
    var_1spp = np.mean((a - b) ** 2) / 2.0 * half
    se_vp = np.sqrt(np.sum((a - b) ** 2) / 4.0) / vp.size
    t_spp = (ta + tb) / (2 * half)
    print(f"volpath: {2 * half} spp in {ta + tb:.1f} s, image mean {mean_vp:.5g} +- {se_vp:.2g} "
          f"({se_vp / mean_vp:.4f} rel.), 1-spp rel. sd {np.sqrt(var_1spp) / mean_vp:.3f}, "
          f"{t_spp:.4f} s per spp; 2 % needs {t_spp * var_1spp / (0.02 * mean_vp) ** 2:.0f} s")

    ref, var_ref, _, t_ref = passes(scene, res, rn, 100_000, rp, rk, rspp, args.surface_photons)
    mean_ref = ref.mean()
    noise_ref = np.sqrt(var_ref.mean()) / mean_ref
    print(f"reference R: vpm, {rn} passes of {rp} photons, k {rk}, {rspp} spp in {t_ref:.0f} s; "
          f"own noise {noise_ref:.4f} rel.; image mean {mean_ref:.5g}, "
          f"{(mean_ref - mean_vp) / mean_vp:+.4f} vs volpath (s.e. {se_vp / mean_vp:.4f})")
    ref4, var4, _, t4 = passes(scene, res, rn, 200_000, rp // 4, rk, rspp, args.surface_photons)
    d2 = np.mean((ref4 - ref) ** 2) - var4.mean() - var_ref.mean()
    diff = np.sqrt(max(d2, 0.0)) / mean_ref
    shrink = 4 ** (-1 / 3)
    print(f"R/4 ({rp // 4} photons per pass, {t4:.0f} s): image mean "
          f"{(ref4.mean() - mean_ref) / mean_ref:+.4f} vs R; per-pixel RMS difference "
          f"(noise removed) {diff:.4f}; estimated bias of R: mean "
          f"{(mean_ref - ref4.mean()) / mean_ref * shrink / (1 - shrink):+.4f}, "
          f"per-pixel RMS {diff * shrink / (1 - shrink):.4f}")

    def err(img):
        e2 = np.mean((img - ref) ** 2) - var_ref.mean()
        return np.sqrt(max(e2, 0.0)) / mean_ref

    print("| photons/pass | k | spp | passes | seconds | rel. RMSE | mean vs R "
          "| volpath s for same RMSE | speed-up |")
    print("|---|---|---|---|---|---|---|---|---|")
    for c, conf in enumerate(args.configs.split(",")):
        photons, k, spp = (int(float(x)) for x in conf.split(":"))
        pts = []

        def report(n, wall, img, photons=photons, k=k, spp=spp, pts=pts):
            if n & (n - 1):
                return  # powers of two only
            e = err(img)
            pts.append((wall, e))
            t_vp = t_spp * var_1spp / (e * mean_vp) ** 2 if e > 0 else float("inf")
            print(f"| {photons} | {k} | {spp} | {n} | {wall:.1f} | {e:.4f} "
                  f"| {(img.mean() - mean_ref) / mean_ref:+.4f} | {t_vp:.0f} "
                  f"| {t_vp / wall:.0f}x |", flush=True)

        passes(scene, res, 4096, 1000 * (c + 1), photons, k, spp, args.surface_photons,
               budget=args.budget, on_pass=report)
        if len(pts) >= 3:
            # err² = a / t + b²: noise falls like 1/t, b is the floor (bias vs R)
            t = np.array([p[0] for p in pts])
            e2 = np.array([p[1] ** 2 for p in pts])
            (a_, b2), *_ = np.linalg.lstsq(np.stack([1 / t, np.ones_like(t)], 1), e2, rcond=None)
            b = np.sqrt(max(b2, 0.0))
            t2 = a_ / (0.02**2 - b2) if b2 < 0.02**2 else float("inf")
            print(f"#   fit err² = {a_:.3g}/t + ({b:.4f})²: 2 % at {t2:.0f} s "
                  f"(volpath {t_spp * var_1spp / (0.02 * mean_vp) ** 2:.0f} s)", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resolution", default="128x96")
    ap.add_argument("--ref-spp", type=int, default=512, help="volpath samples/px (two halves)")
    ap.add_argument("--ref-photons", type=int, default=16_000_000,
                    help="volume photons of the converged vpm-full reference")
    ap.add_argument("--ref-spp-vpm", type=int, default=64, help="spp of the vpm-full reference")
    ap.add_argument("--ladder", default="250000:4,1000000:8,4000000:16",
                    help="vpm runs as volume_photons:spp pairs")
    ap.add_argument("--surface-photons", type=int, default=200_000)
    ap.add_argument("--memory-photons", type=int, default=0,
                    help="also trace this many volume photons and report memory")
    ap.add_argument("--stand-in", action="store_true", help="issue 5's stand-in medium")
    ap.add_argument("--time-to", action="store_true",
                    help="error against wall time by averaging independent vpm passes")
    ap.add_argument("--configs", default="1000000:200:4,4000000:200:4",
                    help="--time-to: runs as photons_per_pass:k:spp")
    ap.add_argument("--ref", default="16000000:200:16:32",
                    help="--time-to: reference as photons_per_pass:k:spp:passes")
    ap.add_argument("--budget", type=float, default=60.0, help="--time-to: seconds per run")
    args = ap.parse_args()
    w, h = (int(x) for x in args.resolution.lower().split("x"))
    res = (w, h)
    scene = scene_dict(args.stand_in)
    print(f"# discs.toml at {BAND} nm, {w}x{h}, material "
          f"{'stand-in ' + str(STAND_IN) if args.stand_in else 'biomaterial-table1 (library)'}")
    print(f"# cpus {os.cpu_count()}, load average {os.getloadavg()}")
    if args.time_to:
        time_to(args, scene, res)
        return

    # volpath: two independent halves give its noise per sample
    half = max(1, args.ref_spp // 2)
    a, _, ta = render(scene, res, integrator="volpath", spp=half, seed=1001)
    b, _, tb = render(scene, res, integrator="volpath", spp=half, seed=2002)
    vp = 0.5 * (a + b)
    mean_vp = vp.mean()
    var_half = np.mean((a - b) ** 2) / 2.0  # per-pixel variance of a half, image average
    var_1spp = var_half * half
    se_mean_vp = np.sqrt(np.sum((a - b) ** 2) / 4.0) / vp.size  # s.e. of the image mean
    t_spp = (ta + tb) / (2 * half)  # seconds per sample per pixel, whole image
    t_vp_2 = t_spp * var_1spp / (0.02 * mean_vp) ** 2
    print(f"volpath: {2 * half} spp in {ta + tb:.1f} s, image mean {mean_vp:.5g} "
          f"+- {se_mean_vp:.2g}, own rel. RMSE {np.sqrt(var_half / 2) / mean_vp:.4f}; "
          f"needs {t_vp_2:.0f} s for 2 % rel. RMSE")

    ref, st, t_ref = render(scene, res, integrator="vpm-full", spp=args.ref_spp_vpm, seed=3003,
                            volume_photons=args.ref_photons, photons=args.ref_photons // 4)
    mean_ref = ref.mean()
    print(f"reference: vpm-full {args.ref_photons} photons, {args.ref_spp_vpm} spp in "
          f"{t_ref:.1f} s, image mean {mean_ref:.5g} ({(mean_ref - mean_vp) / mean_vp:+.4f} "
          f"vs volpath, whose s.e. is {se_mean_vp / mean_vp:.4f})")

    print("| volume photons | spp | photons/s | build s | bytes/photon | stored | camera s "
          "| total s | rel. RMSE | volpath s for same RMSE | speed-up | peak RSS GB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for rung in args.ladder.split(","):
        photons, spp = (int(float(x)) for x in rung.split(":"))
        for integrator in ("vpm", "vpm-full"):
            img, st, wall = render(scene, res, integrator=integrator, spp=spp, seed=7,
                                   volume_photons=photons, photons=args.surface_photons)
            err = np.sqrt(np.mean((img - ref) ** 2)) / mean_ref
            t_vp = t_spp * var_1spp / (err * mean_vp) ** 2 if err > 0 else float("inf")
            rate = (photons + args.surface_photons) / max(st["seconds_photons"], 1e-9)
            print(f"| {integrator} {photons} | {spp} | {rate:.3g} | {st['seconds_build']:.2f} "
                  f"| {st['bytes_per_photon']} | {st['photons_stored']} "
                  f"| {st['seconds_camera']:.1f} | {wall:.1f} | {err:.4f} | {t_vp:.0f} "
                  f"| {t_vp / wall:.1f}x | {peak_rss_gb():.2f} |")

    if args.memory_photons > 0:
        before = peak_rss_gb()
        _, st, wall = render(scene, (8, 6), integrator="vpm-full", spp=1, seed=9,
                             volume_photons=args.memory_photons, photons=1000)
        print(f"memory: {args.memory_photons} photons emitted, {st['photons_stored']} stored, "
              f"maps {st['photon_map_bytes'] / 1e9:.2f} GB "
              f"({st['bytes_per_photon']} bytes/photon), tracing {st['seconds_photons']:.1f} s, "
              f"build {st['seconds_build']:.1f} s, peak RSS {peak_rss_gb():.2f} GB "
              f"(before {before:.2f} GB)")


if __name__ == "__main__":
    main()
