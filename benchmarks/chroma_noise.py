"""Colour speckle of the preview figures (issue 16): the standard deviation of L*, a* and b*
over the pixels of a flat patch on the top of Fig. 3's raised disc (and Fig. 4's), rendered
as the figures render them (`figures.disc_scene`, preview photon counts, three bands,
correlated streams), with band-by-band photon passes and with one spectral photon pass
(`spectral_photons`: hero-band walks, balance-heuristic powers, shared camera streams).
The patch is flat and evenly lit, so its spread is noise; a* and b* spread is the coloured
speckle. Also prints each render's wall and CPU seconds (user + system of this process).

    .venv/bin/python benchmarks/chroma_noise.py [--figures fig3,fig4] [--half-mm 2.0]
        [--bands 450,540,605 | --bands 16] [--stored 4000000] [--resolution 320x240]
        [--k 800] [--radius 0.3] [--passes band,spectral]

``--bands 16``: 16 bands evenly over 400-700 nm (20 nm apart) instead of the figures' three.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from dentalux import figures as F
from dentalux import materials
from dentalux.color import system
from dentalux.outputs import colour_inputs
from dentalux.render import render
from dentalux.scene import scene_from_dict
from dentalux.scene.project import square_region


def scene_for(fig: str, q) -> dict:
    if fig == "fig3":
        return F.disc_scene({"material": "biomaterial-table1"}, 5.0, q)
    bio, enamel = materials.get("biomaterial-table1"), materials.get("enamel")
    if q.similarity_g is not None:
        enamel = enamel.similar(q.similarity_g, note="figures")
    s = F.match_enamel_scale(F.transmittance_d65(bio, 5.0), 5.0, enamel)
    return F.disc_scene(F._media_table(enamel.scaled(mus_factor=s, mua_factor=s, note="fig4"),
                                       F.PAPER_BANDS), 5.0, q)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--figures", default="fig3,fig4")
    ap.add_argument("--half-mm", type=float, default=2.0)
    ap.add_argument("--bands", default="450,540,605")
    ap.add_argument("--stored", type=int, default=None,
                    help="volume photons stored per pass (default: the preview figures')")
    ap.add_argument("--resolution", default=None, help="WxH (default: the preview's)")
    ap.add_argument("--k", type=int, default=None, help="photons per estimate (preview's)")
    ap.add_argument("--radius", type=float, default=None,
                    help="largest gathering radius [mm] (default: the preview's)")
    ap.add_argument("--passes", default="band,spectral",
                    help="photon passes to compare: band (band by band), spectral")
    a = ap.parse_args()
    q = F.QUALITIES["preview"]
    if a.resolution:
        w, h = (int(x) for x in a.resolution.split("x"))
        q = F.Quality(**{**F.asdict(q), "resolution": (w, h)})
    bands = ([float(b) for b in a.bands.split(",")] if "," in a.bands
             else list(np.linspace(400.0, 700.0, int(a.bands))))
    stored = a.stored or q.volume_photons
    cs = system("D65", "2")
    settings = dict(spp=q.spp, photons=q.photons, volume_photons=F.EMIT_CAP * stored,
                    volume_stored=stored, aim=F.FIGURE_AIM, k=a.k or q.k,
                    radius=a.radius or q.radius_mm)
    for fig in a.figures.split(","):
        d = scene_for(fig, q)
        sc = scene_from_dict(d)
        x0, y0, x1, y1 = square_region(d["camera"], [8.0, 0.0, 10.0], a.half_mm, (0, 0, 1))
        print(f"{fig}: patch {x1 - x0}x{y1 - y0} px on the raised disc's top "
              f"({2 * a.half_mm:g} mm square), {q.resolution[0]}x{q.resolution[1]}, "
              f"{len(bands)} bands, {stored} volume photons stored, k {settings['k']}, "
              f"radius <= {settings['radius']} mm")
        passes = {"band": False, "spectral": True}
        for spectral in (passes[p] for p in a.passes.split(",")):
            c0, t0 = time.process_time(), time.perf_counter()
            res = render(sc, integrator="vpm", bands=bands, seed=1,
                         correlated_bands=True, spectral_photons=spectral, progress=False,
                         **settings)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            divisor, _, white = colour_inputs(sc, bands)
            px = (res.radiance[y0:y1, x0:x1] / divisor / white).reshape(-1, len(bands))
            lab = np.array([cs.spectrum_to_Lab(p, bands) for p in px])
            sd = lab.std(axis=0, ddof=1)
            mean = lab.mean(axis=0)
            name = "spectral photons" if spectral else "band by band   "
            print(f"  {name}: sd L* {sd[0]:.2f} a* {sd[1]:.2f} b* {sd[2]:.2f}  "
                  f"(mean {mean[0]:.1f} / {mean[1]:.1f} / {mean[2]:.1f})  "
                  f"{wall:.0f} s wall, {cpu:.0f} CPU-s")


if __name__ == "__main__":
    main()
