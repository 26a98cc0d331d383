"""Colour speckle of the preview figures (issue 16): the standard deviation of L*, a* and b*
over the pixels of a flat patch on the top of Fig. 3's raised disc (and Fig. 4's), or on the
ribbon in its shadow (`--patch under`), or on Fig. 5's ceiling (`--patch ceiling`): the last
two are lit only by the surface photon map's light. Rendered
as the figures render them (`figures.disc_scene`, the quality's photon counts, three bands,
correlated streams), with band-by-band photon passes and with one spectral photon pass
(`spectral_photons`: hero-band walks, balance-heuristic powers, shared camera streams), and
with hero-wavelength camera paths (`hero_camera`: one camera path for all bands).
The patch is flat and evenly lit, so its spread is noise; a* and b* spread is the coloured
speckle. Also prints each render's wall and CPU seconds (user + system of this process).

    .venv/bin/python benchmarks/chroma_noise.py [--figures fig3,fig4,fig5]
        [--quality preview|paper] [--patch top,under,ceiling,wall] [--half-mm 2.0]
        [--bands 450,540,605 | --bands 16] [--stored 4000000] [--resolution 320x240]
        [--k 800] [--spp 4] [--radius 0.3] [--surface-radius 1.0]
        [--passes band,spectral,hero,spectral-hero]

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

# Flat patches: centre [mm], half-size [mm], normal towards the camera. `top`: the raised
# disc's top. `under`: the ribbon under it inside one check, where every point sees none of
# the overhead light past the disc's underside (its umbra, worked out from the light's
# corners) and the camera sees it through the 5 mm gap. `ceiling`: Fig. 5's ceiling beside
# the light, lit only by the walls (the surface map's light); `wall`: its back wall, top
# left, lit by the light and the other walls.
PATCHES = {"top": ([8.0, 0.0, 10.0], 2.0, (0, 0, 1)),
           "under": ([8.6, -0.95, 0.0], 0.7, (0, 0, 1)),
           "ceiling": ([12.0, 60.0, 30.0], 5.0, (0, -1, 0)),
           "wall": ([12.0, 45.0, 60.0], 5.0, (0, 0, -1))}


# --passes: (spectral_photons, hero_camera)
PASSES = {"band": (False, False), "spectral": (True, False), "hero": (False, True),
          "spectral-hero": (True, True)}
PASS_NAMES = {"band": "band by band", "spectral": "spectral photons",
              "hero": "band-by-band photons, hero camera paths",
              "spectral-hero": "spectral photons, hero camera paths"}


def scene_for(fig: str, q) -> dict:
    if fig == "fig5":
        d = F.cornell_teeth_scene(q)
        F.lower_anisotropy(d, q)
        return d
    if fig == "fig3":
        return F.disc_scene({"material": "biomaterial-table1"}, 5.0, q)
    bio, enamel = materials.get("biomaterial-table1"), materials.get("enamel")
    if q.similarity_g is not None:
        enamel = enamel.similar(q.similarity_g, note="figures")
    s = F.match_enamel_scale(F.transmittance_d65(bio, 5.0), 5.0, enamel)
    return F.disc_scene(F._media_table(enamel.scaled(mus_factor=s, mua_factor=s, note="fig4"),
                                       F.PAPER_BANDS), 5.0, q)


def settings_for(fig: str, q, a) -> dict:
    """The figure's own settings (figures._render_figure, figures._teeth_settings), with the
    options given on the command line in their place."""
    if fig == "fig5":
        s = F._teeth_settings(q)
        s["volume_stored"] = a.stored or s["volume_stored"]
    else:
        s = F.disc_settings(q)
        if a.stored:
            s.update(volume_photons=F.EMIT_CAP * a.stored, volume_stored=a.stored)
    for key in ("spp", "k", "radius", "surface_radius"):
        if getattr(a, key) is not None:
            s[key] = getattr(a, key)
    return s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--figures", default="fig3,fig4", help="fig3, fig4, fig5")
    ap.add_argument("--quality", default="preview", choices=sorted(F.QUALITIES))
    ap.add_argument("--patch", default="top",
                    help="patches, comma-separated: " + ", ".join(sorted(PATCHES)))
    ap.add_argument("--half-mm", type=float, default=None,
                    help="the patch's half-size [mm] (default: the patch's own)")
    ap.add_argument("--bands", default="450,540,605")
    ap.add_argument("--stored", type=int, default=None,
                    help="volume photons stored per pass (default: the figure's)")
    ap.add_argument("--resolution", default=None, help="WxH (default: the quality's)")
    ap.add_argument("--k", type=int, default=None, help="photons per estimate (figure's)")
    ap.add_argument("--spp", type=int, default=None, help="camera samples per pixel (figure's)")
    ap.add_argument("--radius", type=float, default=None,
                    help="largest gathering radius [mm] (default: the figure's)")
    ap.add_argument("--surface-radius", type=float, default=None,
                    help="largest gathering radius of the surface map [mm] (figure's)")
    ap.add_argument("--passes", default="band,spectral",
                    help="passes to compare: band (band by band), spectral (one spectral "
                         "photon pass), hero (band-by-band photons, hero camera paths), "
                         "spectral-hero")
    a = ap.parse_args()
    q = F.QUALITIES[a.quality]
    if a.resolution:
        w, h = (int(x) for x in a.resolution.split("x"))
        q = F.Quality(**{**F.asdict(q), "resolution": (w, h)})
    bands = ([float(b) for b in a.bands.split(",")] if "," in a.bands
             else list(np.linspace(400.0, 700.0, int(a.bands))))
    cs = system("D65", "2")
    patches = {}
    for name in a.patch.split(","):
        if name not in PATCHES:
            ap.error(f"--patch {name}: allowed {', '.join(sorted(PATCHES))}")
        centre, half, facing = PATCHES[name]
        patches[name] = (centre, a.half_mm or half, facing)
    for fig in a.figures.split(","):
        d = scene_for(fig, q)
        sc = scene_from_dict(d)
        settings = settings_for(fig, q, a)
        boxes = {n: square_region(d["camera"], c, h, f) for n, (c, h, f) in patches.items()}
        for n, (x0, y0, x1, y1) in boxes.items():
            print(f"{fig}: patch '{n}' {x1 - x0}x{y1 - y0} px ({2 * patches[n][1]:g} mm "
                  "square)")
        print(f"  {q.resolution[0]}x{q.resolution[1]}, {len(bands)} bands, "
              f"{settings['volume_stored']} volume photons stored, k {settings['k']}, "
              f"spp {settings['spp']}, radius <= {settings['radius']} mm, surface radius <= "
              f"{settings['surface_radius']} mm")
        divisor, _, white = colour_inputs(sc, bands)
        for kind in a.passes.split(","):
            if kind not in PASSES:
                ap.error(f"--passes {kind}: allowed {', '.join(PASSES)}")
            spectral, hero = PASSES[kind]
            c0, t0 = time.process_time(), time.perf_counter()
            res = render(sc, integrator="vpm", bands=bands, seed=1,
                         correlated_bands=True, spectral_photons=spectral, hero_camera=hero,
                         progress=False, **settings)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            name = PASS_NAMES[kind]
            print(f"  {name}: {wall:.0f} s wall, {cpu:.0f} CPU-s")
            for n, (x0, y0, x1, y1) in boxes.items():
                px = (res.radiance[y0:y1, x0:x1] / divisor / white).reshape(-1, len(bands))
                lab = np.array([cs.spectrum_to_Lab(p, bands) for p in px])
                sd = lab.std(axis=0, ddof=1)
                mean = lab.mean(axis=0)
                print(f"    {n}: sd L* {sd[0]:.2f} a* {sd[1]:.2f} b* {sd[2]:.2f}  "
                      f"(mean {mean[0]:.1f} / {mean[1]:.1f} / {mean[2]:.1f})")


if __name__ == "__main__":
    main()
