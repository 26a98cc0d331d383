"""Where the error of averaged vpm passes is on the Fig. 3 scene: noise, bias, and a map.

Needs the truth cache of `render_discs_truth.py --truth-cache FILE` (volpath-nee, two
halves, so its own noise is known). Averages N independent vpm passes (same seeds as that
benchmark), splits the error against the truth into noise (the spread of the passes) and
bias (the rest), reports the share of the squared bias in the 15 % steepest pixels of the
truth, and writes a PNG of the error smoothed over 5 × 5 pixels.

`--regions-from A.npz` (an earlier run's `--save`) also reads this run's relative difference
from the truth over the regions where that run's 7 × 7 pixel means read more than 3 % dark
and more than 3 % bright (`--rows Y0:Y1` keeps only those rows), beside that run's own (which
is biased by its own noise, since its regions were chosen on it; this run's is not).

    .venv/bin/python benchmarks/render_discs_bias.py --truth-cache truth.npz --passes 32 \\
        [--photons 2000000 --k 50 --spp 4] [--no-kernel-clip] [--integrator vpm-full] \\
        [--surface-radius MM] [--surface-k K] [--png bias.png] [--save A.npz] [--regions-from A.npz]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from render_discs import passes, scene_dict
from scipy.ndimage import uniform_filter

BOX = 7  # pixels per side of the means the regions are chosen on
LEVEL = 0.03  # their threshold on the relative difference


def relative_means(img: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """(img − truth) / truth on BOX × BOX pixel means."""
    return uniform_filter(img - truth, BOX) / np.maximum(uniform_filter(truth, BOX), 1e-12)


def regions(earlier: np.ndarray, img: np.ndarray, truth: np.ndarray, rows: str | None) -> None:
    """Print the relative difference from the truth of ``earlier`` and of ``img`` over the
    regions where ``earlier``'s BOX × BOX means read more than LEVEL dark or bright."""
    rel = relative_means(earlier, truth)
    keep = np.ones(truth.shape, bool)
    if rows:
        y0, y1 = (int(v) for v in rows.split(":"))
        keep[:] = False
        keep[y0:y1] = True
    for name, mask in ((f"< -{LEVEL:.0%}", rel < -LEVEL), (f"> +{LEVEL:.0%}", rel > LEVEL)):
        mask &= keep
        if not mask.any():
            continue
        a, b = ((m - truth)[mask].sum() / truth[mask].sum() for m in (earlier, img))
        print(f"  region {name} in the earlier run ({int(mask.sum())} px): earlier {a:+.4f}, "
              f"this run {b:+.4f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--truth-cache", required=True)
    ap.add_argument("--resolution", default="128x96")
    ap.add_argument("--passes", type=int, default=32)
    ap.add_argument("--photons", type=int, default=2_000_000)
    ap.add_argument("--k", type=int, default=50)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--surface-photons", type=int, default=None,
                    help="photons for the surface map (default: --photons; taken from the "
                         "volume pass up to that count)")
    ap.add_argument("--integrator", default="vpm")
    ap.add_argument("--kernel-clip", action=argparse.BooleanOptionalAction, default=True,
                    help="render option kernel_clip (default on, as the core's)")
    ap.add_argument("--independent", action="store_true",
                    help="independent seeds per pass (the film does not continue its "
                         "sub-pixel sequence across passes)")
    ap.add_argument("--aim", type=float, default=None,
                    help="fraction of photons aimed at the discs (default: the core's, 0)")
    ap.add_argument("--volume-stored", type=int, default=None,
                    help="photons the volume maps should hold (--photons is then the cap "
                         "on emission)")
    ap.add_argument("--surface-radius", type=float, default=None,
                    help="render option surface_radius [mm] (default: the core's cap)")
    ap.add_argument("--surface-k", type=int, default=None,
                    help="render option surface_k (default: --k)")
    ap.add_argument("--seed", type=int, default=3000, help="seed of the passes")
    ap.add_argument("--regions-from", default=None,
                    help="NPZ of an earlier --save: read the bias over its > 3 %% regions")
    ap.add_argument("--rows", default=None, help="Y0:Y1, the rows --regions-from keeps")
    ap.add_argument("--png", default=None)
    ap.add_argument("--save", default=None,
                    help="NPZ file: keep the mean image and its per-pixel variance")
    args = ap.parse_args()
    z = np.load(args.truth_cache)
    truth, var_t = z["truth"], z["var_t"]
    level = float(truth.mean())
    res = tuple(int(v) for v in args.resolution.split("x"))
    if truth.shape != res[::-1]:
        raise SystemExit(f"--truth-cache holds a {truth.shape[1]}x{truth.shape[0]} truth, "
                         f"not {args.resolution}")
    extra = {k: v for k, v in (("aim", args.aim), ("volume_stored", args.volume_stored),
                                ("surface_radius", args.surface_radius),
                                ("surface_k", args.surface_k)) if v is not None}
    img, var, done, wall = passes(scene_dict(False), res, args.passes, args.seed, args.photons,
                                  args.k, args.spp, args.surface_photons or args.photons,
                                  integrator=args.integrator, kernel_clip=args.kernel_clip,
                                  independent=args.independent, **extra)
    if args.save:
        np.savez(args.save, img=img, var=var, passes=done, wall=wall)
    err = img - truth
    total = np.sqrt(max(float(np.mean(err ** 2) - var_t.mean()), 0.0)) / level
    noise = float(np.sqrt(var.mean())) / level
    bias = np.sqrt(max(total ** 2 - noise ** 2, 0.0))
    b2 = err ** 2 - var - var_t  # per-pixel squared bias, unbiased
    grad = np.hypot(*np.gradient(uniform_filter(truth, 3)))
    steep = np.argsort(grad.ravel())[::-1][: grad.size * 15 // 100]
    print(f"{args.integrator} {args.photons}:{args.k}:{args.spp} clip={args.kernel_clip}: "
          f"{done} passes, {wall:.1f} s; rel. RMSE {total:.4f} = noise {noise:.4f} (+) bias "
          f"{bias:.4f}; mean {err.mean() / level:+.4f}; steepest 15 % hold "
          f"{b2.ravel()[steep].sum() / b2.sum():.2f} of the bias²")
    if args.regions_from:
        regions(np.load(args.regions_from)["img"], img, truth, args.rows)
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        if args.regions_from:
            # the truth and both runs' relative differences, on the regions' BOX × BOX means
            earlier = np.load(args.regions_from)["img"]
            fig, ax = plt.subplots(1, 3, figsize=(15, 3.9))
            this = f"{args.photons}:{args.k}:{args.spp} x {done} passes"
            for axis, (m, name) in zip(ax[1:], ((earlier, Path(args.regions_from).name),
                                                (img, this)), strict=True):
                im = axis.imshow(relative_means(m, truth), cmap="RdBu_r", vmin=-0.06, vmax=0.06)
                axis.set_title(f"(vpm − truth) / truth, {BOX} × {BOX} means\n{name}", fontsize=9)
            plt.colorbar(im, ax=ax[1:], shrink=0.85)
        else:
            fig, ax = plt.subplots(1, 2, figsize=(10, 4))
            im = ax[1].imshow(uniform_filter(err, 5) / level, cmap="RdBu_r", vmin=-0.1, vmax=0.1)
            ax[1].set_title("vpm − truth, 5 × 5 mean, / image mean")
            plt.colorbar(im, ax=ax[1])
        ax[0].imshow(truth, cmap="gray", vmin=0, vmax=np.percentile(truth, 99.5))
        ax[0].set_title("truth (volpath-nee)")
        fig.savefig(args.png, dpi=80, bbox_inches="tight")


if __name__ == "__main__":
    main()
