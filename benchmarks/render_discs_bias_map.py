"""Where `vpm` differs from the unbiased truth on the paper's Fig. 3 scene, pixel by pixel.

Averages `vpm` passes for each configuration (`render_discs.passes`: one seed, pass_index
0, 1, ...) and sets them against the `volpath-nee` truth of
`render_discs_truth.py --truth-cache FILE` (its resolution is the render's). Prints the whole
image's mean and per-pixel error, and each configuration's relative difference over two
regions chosen on the first configuration's 7 × 7 pixel means: where it reads more than 3 %
dark, and where it reads more than 3 % bright. The first configuration's column over its
own regions is biased by its own noise; the others are not. `--plot FILE` draws the truth and
each configuration's relative difference (7 × 7 pixel means).

    .venv/bin/python benchmarks/render_discs_bias_map.py --truth-cache /tmp/truth_256x192.npz \\
        [--configs 4000000:200:4:48,16000000:200:4:12] [--plot FILE]

A configuration is photons:k:spp:passes (the surface map gets as many photons as the volume).
"""

from __future__ import annotations

import argparse

import numpy as np
from render_discs import passes, scene_dict
from scipy.ndimage import uniform_filter

BOX = 7  # pixels per side of the means the maps and regions are read on
LEVEL = 0.03  # the regions' threshold on the relative difference


def relative(img: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """(img − truth) / truth in BOX × BOX pixel means."""
    return uniform_filter(img - truth, BOX) / np.maximum(uniform_filter(truth, BOX), 1e-12)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--truth-cache", required=True)
    ap.add_argument("--configs", default="4000000:200:4:48,16000000:200:4:12")
    ap.add_argument("--seed", type=int, default=4000)
    ap.add_argument("--plot", default=None)
    a = ap.parse_args()
    z = np.load(a.truth_cache)
    truth, var_t = z["truth"], z["var_t"]
    res = (truth.shape[1], truth.shape[0])
    level = float(truth.mean())
    scene = scene_dict(False)
    print(f"# discs at 540 nm, {res[0]}x{res[1]}; truth {a.truth_cache} (own per-pixel noise "
          f"{np.sqrt(var_t.mean()) / level:.4f})")
    images = {}
    for i, cfg in enumerate(a.configs.split(",")):
        photons, k, spp, n = (int(v) for v in cfg.split(":"))
        mean, _, done, wall = passes(scene, res, n, a.seed + 1000 * i, photons, k, spp, photons)
        err = np.sqrt(max(np.mean((mean - truth) ** 2) - var_t.mean(), 0.0)) / level
        bias = mean.mean() / level - 1
        print(f"{cfg}: {done} passes, {wall:.0f} s wall; image mean {bias:+.4f}, per-pixel "
              f"error {err:.4f}")
        images[cfg] = mean
    first = relative(next(iter(images.values())), truth)
    regions = {f"reads < -{LEVEL:.0%} in the first": first < -LEVEL,
               f"reads > +{LEVEL:.0%} in the first": first > LEVEL}
    print("| region | pixels | " + " | ".join(images) + " |")
    print("|---|---|" + "---|" * len(images))
    for name, mask in regions.items():
        cells = [f"{(m - truth)[mask].sum() / truth[mask].sum():+.4f}" for m in images.values()]
        print(f"| {name} | {int(mask.sum())} | " + " | ".join(cells) + " |")
    if a.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(1, 1 + len(images), figsize=(5 * (1 + len(images)), 3.9))
        ax[0].imshow(truth, cmap="gray", vmin=0, vmax=np.percentile(truth, 99.5))
        ax[0].set_title("truth: volpath-nee, 540 nm")
        im = None
        for axis, (cfg, m) in zip(ax[1:], images.items(), strict=True):
            im = axis.imshow(relative(m, truth), cmap="RdBu_r", vmin=-0.06, vmax=0.06)
            axis.set_title(f"(vpm - truth) / truth, {BOX}x{BOX} px means\n"
                           f"photons:k:spp:passes {cfg}", fontsize=9)
        fig.colorbar(im, ax=ax[1:], shrink=0.85)
        for axis in ax:
            axis.axis("off")
        fig.savefig(a.plot, dpi=72, bbox_inches="tight")
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
