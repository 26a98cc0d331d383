"""Where the error of averaged vpm passes is on the Fig. 3 scene: noise, bias, and a map.

Needs the truth cache of `render_discs_truth.py --truth-cache FILE` (volpath-nee, two
halves, so its own noise is known). Averages N independent vpm passes (same seeds as that
benchmark), splits the error against the truth into noise (the spread of the passes) and
bias (the rest), reports the share of the squared bias in the 15 % steepest pixels of the
truth, and writes a PNG of the error smoothed over 5 × 5 pixels.

    .venv/bin/python benchmarks/render_discs_bias.py --truth-cache truth.npz --passes 32 \\
        [--photons 2000000 --k 50 --spp 4] [--no-kernel-clip] [--integrator vpm-full] \\
        [--png bias.png]
"""

from __future__ import annotations

import argparse

import numpy as np
from render_discs import passes, scene_dict
from scipy.ndimage import uniform_filter


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
    extra = {k: v for k, v in (("aim", args.aim), ("volume_stored", args.volume_stored))
             if v is not None}
    img, var, done, wall = passes(scene_dict(False), res, args.passes, 3000, args.photons,
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
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(1, 2, figsize=(10, 4))
        ax[0].imshow(truth, cmap="gray")
        ax[0].set_title("truth (volpath-nee)")
        im = ax[1].imshow(uniform_filter(err, 5) / level, cmap="RdBu_r", vmin=-0.1, vmax=0.1)
        ax[1].set_title("vpm − truth, 5 × 5 mean, / image mean")
        plt.colorbar(im, ax=ax[1])
        fig.savefig(args.png, dpi=80)


if __name__ == "__main__":
    main()
