"""Cornell box render speed and BVH speed on a 1 M-triangle mesh (issue 4, performance).

1. The built-in Cornell box (``scenes/cornell.toml``: coloured side walls, a ceiling light, a
   diffuse box and sphere) at 512 x 512, one band (540 nm), rendered through
   `dentalux._core.render_band` with the resolved-scene JSON of docs/render-contract.md:
   seconds per phase, rays per second (camera + shadow rays), photons per second, for the
   photon-mapped `pm` integrator and for the `path` reference.
2. `cargo run --release --example bvh_bench`: BVH build seconds and nearest-hit rays per
   second on a jittered UV sphere of about one million triangles.

The machine may be shared: the load average is printed so that a reader can judge the noise.

    .venv/bin/python benchmarks/render_cornell.py [--spp 4] [--photons 200000] [--threads N]
        [--skip-bvh]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import time
from pathlib import Path

from dentalux import _core
from dentalux.scene.builtin import scene_file
from dentalux.scene.load import load_scene

ROOT = Path(__file__).resolve().parents[1]


def cornell(width: int = 512, height: int = 512) -> str:
    """The built-in Cornell box (``scenes/cornell.toml``, :mod:`dentalux.scene.builtin`) as
    the resolved one-band scene JSON of docs/render-contract.md, at 540 nm."""
    return load_scene(scene_file("cornell")).to_json(540.0, (width, height))


def render(integrator: str, spp: int, photons: int, threads: int | None) -> dict:
    settings = {"integrator": integrator, "spp": spp, "photons": photons, "k": 64,
                "radius": None, "seed": 1, "band": 0, "threads": threads, "max_depth": 64,
                "final_gather": False}
    t0 = time.perf_counter()
    image, stats = _core.render_band(cornell(), json.dumps(settings))
    wall = time.perf_counter() - t0
    return {
        "integrator": integrator,
        "spp": spp,
        "photons": stats["photons_emitted"],
        "seconds": round(wall, 3),
        "seconds_photons": round(stats["seconds_photons"], 3),
        "seconds_camera": round(stats["seconds_camera"], 3),
        "rays": stats["rays"],
        "rays_per_second": round(stats["rays"] / max(stats["seconds_camera"], 1e-9)),
        "photons_per_second": round(stats["photons_emitted"]
                                    / max(stats["seconds_photons"], 1e-9)),
        "mean_radiance": float(image.mean()),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--photons", type=int, default=200_000)
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--skip-bvh", action="store_true")
    args = ap.parse_args()
    print(f"load average: {os.getloadavg()}  cpus: {os.cpu_count()}")
    for integrator in ("pm", "path"):
        row = render(integrator, args.spp, args.photons if integrator == "pm" else 0,
                     args.threads)
        print(json.dumps(row))
    if not args.skip_bvh:
        out = subprocess.run(
            ["cargo", "run", "--quiet", "--release", "-p", "dentalux-core", "--example",
             "bvh_bench", "--", "--triangles", "1000000", "--rays", "1000000"],
            cwd=ROOT, check=True, capture_output=True, text=True)
        print(out.stdout.strip())


if __name__ == "__main__":
    main()
