"""Build once, send once (issue 17): a multi-band render of a mesh scene, the bands sent to
the core one call each (the scene JSON with its shapes serialised, decoded and put in a BVH
per band, as `dentalux.render` did) against one `render_bands` call (shapes and BVH once).

Scene: the crown figure's two procedural incisors (`scene.builtin.crown`, preview meshes),
rendered with `vpm` at a small photon count so that the per-band fixed cost shows, and at the
figure's own settings (--figure) to show what it is worth there. Both ways give the same
image bits (checked here, and by tests/test_render_band.py); CPU-seconds are user + system of
this process (both ways run in one process, alternating, --repeats times).

    .venv/bin/python benchmarks/render_bands_build.py [--bands 16] [--repeats 3] [--figure]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from dentalux import _core
from dentalux.figures import QUALITIES, crown_scene
from dentalux.render import build_settings
from dentalux.scene import scene_from_dict


def cpu() -> float:
    return time.process_time()


def per_band(sc, settings, bands, res):
    out = []
    for wl in bands:
        image, _ = _core.render_band(sc.to_json(wl, res), json.dumps({**settings, "band": int(wl)}))
        out.append(image)
    return np.stack(out)


def once(sc, settings, bands, res):
    cube, _ = _core.render_bands(sc.bands_json(bands, res), json.dumps(settings),
                                 [int(wl) for wl in bands])
    return cube


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bands", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--resolution", default="64x48")
    ap.add_argument("--figure", action="store_true",
                    help="the preview crown figure's photon counts instead of a small render")
    a = ap.parse_args()
    q = QUALITIES["preview"]
    scene, _ = crown_scene(q)
    sc = scene_from_dict(scene)
    w, h = (int(x) for x in a.resolution.split("x"))
    bands = list(np.linspace(400.0, 700.0, a.bands))
    if a.figure:
        opts = dict(integrator="vpm", spp=q.teeth_spp, volume_photons=q.teeth_volume_photons,
                    volume_stored=q.teeth_volume_stored // 16, radius=q.teeth_radius_mm, seed=1)
    else:
        opts = dict(integrator="vpm", spp=1, photons=2000, volume_photons=20_000, seed=1)
    settings = build_settings(sc, **opts)
    triangles = sum(len(s.get("triangles", [])) for s in sc.resolve(540.0)["shapes"])
    json_mb = len(sc.to_json(540.0, (w, h))) / 1e6
    print(f"crown scene: {triangles} triangles, {json_mb:.1f} MB of scene JSON per band; "
          f"{a.bands} bands at {w}x{h}, {opts}")
    times = {"per band": [], "once": []}
    ref = None
    for _ in range(a.repeats):
        for name, fn in (("per band", per_band), ("once", once)):
            c0, t0 = cpu(), time.perf_counter()
            cube = fn(sc, settings, bands, (w, h))
            times[name].append((cpu() - c0, time.perf_counter() - t0))
            if ref is None:
                ref = cube
            assert np.array_equal(cube, ref), "the two ways differ"
    for name, ts in times.items():
        c = np.median([t[0] for t in ts])
        wall = np.median([t[1] for t in ts])
        print(f"{name:9s}: {c:7.2f} CPU-s, {wall:7.2f} s wall (median of {a.repeats})")
    ratio = np.median([t[0] for t in times["per band"]]) / np.median([t[0] for t in times["once"]])
    print(f"per band / once: {ratio:.2f}x CPU-s; images bit-identical")


if __name__ == "__main__":
    main()
