"""Built-in scenes as plain dicts (the TOML format's keys), like ``mi.cornell_box()``: the
Cornell box, the paper's Fig. 3 discs, Fig. 5's teeth in a Cornell box and the crown figure's
two incisors (which the figures, the design render and the benchmarks build from here).

``scenes/cornell.toml`` and ``scenes/discs.toml`` hold the same scenes as files; a test
checks that each resolves to the same render-contract JSON as its function here. The files
live in the package (``dentalux/scenes``, shipped in the wheel; the checkout's ``scenes/`` is
a link to that folder), so :func:`scene_file` finds them in any install.
"""

from __future__ import annotations

import math
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from dentalux.scene.project import square_region

SCENE_FILES = ("cornell", "discs")
"""Built-in scenes that also ship as TOML files (``dentalux/scenes/NAME.toml``)."""


def scene_file(name: str) -> Path:
    """The packaged TOML file of a built-in scene: ``scene_file("discs")`` is the path to
    give ``dentalux render`` or :func:`dentalux.load_scene` from any folder."""
    if name not in SCENE_FILES:
        raise ValueError(f"scene = {name!r}: allowed {', '.join(SCENE_FILES)}")
    path = Path(str(resources.files("dentalux") / "scenes" / f"{name}.toml"))
    if not path.is_file():
        raise FileNotFoundError(f"packaged scene {name}.toml is missing from {path.parent}")
    return path

# Spectral reflectances of the Cornell box walls (smooth red and green dyes, our own
# round numbers): linear interpolation between the points, 400-700 nm.
RED = {"wavelengths_nm": [400.0, 550.0, 580.0, 600.0, 700.0],
       "values": [0.05, 0.05, 0.2, 0.6, 0.65]}
GREEN = {"wavelengths_nm": [400.0, 480.0, 530.0, 580.0, 700.0],
         "values": [0.08, 0.15, 0.45, 0.15, 0.08]}

BOX_MM = 550.0


def cornell_box(resolution: tuple[int, int] = (256, 256)) -> dict:
    """A 550 mm Cornell box (y up, open towards -z) with a ceiling area light (D65), a
    diffuse tall box rotated 17 degrees and a diffuse sphere of radius 100 mm."""
    s = BOX_MM
    return {
        "scene": {"name": "cornell", "description": "Cornell box, 550 mm, diffuse box and "
                                                    "sphere"},
        "render": {"bands": [450.0, 540.0, 605.0], "integrator": "pm", "spp": 16,
                   "photons": 200_000},
        "camera": {"position": [275.0, 275.0, -800.0], "look_at": [275.0, 275.0, 0.0],
                   "up": [0.0, 1.0, 0.0], "fov_deg": 39.3, "resolution": list(resolution)},
        "surfaces": {
            "white": {"type": "lambertian", "reflectance": 0.75},
            "red": {"type": "lambertian", "reflectance": RED},
            "green": {"type": "lambertian", "reflectance": GREEN},
        },
        "shapes": [
            {"type": "quad", "name": "floor", "corner": [0.0, 0.0, 0.0], "u": [s, 0.0, 0.0],
             "v": [0.0, 0.0, s], "surface": "white"},
            {"type": "quad", "name": "ceiling", "corner": [0.0, s, 0.0], "u": [s, 0.0, 0.0],
             "v": [0.0, 0.0, s], "surface": "white"},
            {"type": "quad", "name": "back", "corner": [0.0, 0.0, s], "u": [s, 0.0, 0.0],
             "v": [0.0, s, 0.0], "surface": "white"},
            {"type": "quad", "name": "right", "corner": [0.0, 0.0, 0.0], "u": [0.0, 0.0, s],
             "v": [0.0, s, 0.0], "surface": "green"},
            {"type": "quad", "name": "left", "corner": [s, 0.0, 0.0], "u": [0.0, 0.0, s],
             "v": [0.0, s, 0.0], "surface": "red"},
            {"type": "box", "name": "tall box", "min": [-82.5, 0.0, -82.5],
             "max": [82.5, 330.0, 82.5], "surface": "white",
             "transform": {"rotate": {"axis": [0.0, 1.0, 0.0], "angle_deg": 17.0},
                           "translate": [170.0, 0.0, 380.0]}},
            {"type": "sphere", "name": "ball", "center": [390.0, 100.0, 160.0],
             "radius": 100.0, "surface": "white"},
        ],
        "lights": [
            {"type": "quad", "name": "ceiling light", "corner": [210.0, 549.0, 220.0],
             "u": [130.0, 0.0, 0.0], "v": [0.0, 0.0, 110.0], "radiance": 15.0,
             "spectrum": "D65"},
        ],
    }


def discs(material: str = "biomaterial-table1", resolution: tuple[int, int] = (512, 384)) -> dict:
    """The paper's Fig. 3 set-up (z up): two discs 10 mm wide and 5 mm thick of a library
    material on a checker ribbon (2.5 mm checks), the left one lying on it (a 0.01 mm air
    gap keeps the two surfaces apart), the right one 5 mm above it; a 40 mm square area
    light 70 mm up; the camera obliquely from above."""
    return {
        "scene": {"name": "discs", "description": "Fig. 3: discs on and 5 mm above a checker "
                                                  "ribbon"},
        "render": {"bands": [450.0, 540.0, 605.0], "integrator": "vpm", "spp": 16,
                   "photons": 200_000, "volume_photons": 1_000_000},
        "camera": {"position": [0.0, -40.0, 35.0], "look_at": [0.0, 0.0, 2.5],
                   "up": [0.0, 0.0, 1.0], "fov_deg": 30.0, "resolution": list(resolution)},
        "media": {"disc": {"material": material}},
        "surfaces": {
            "ribbon": {"type": "checker", "a": 0.85, "b": 0.05, "size": 2.5, "mapping": "xy"},
            "table": {"type": "lambertian", "reflectance": 0.25},
        },
        "shapes": [
            {"type": "quad", "name": "table", "corner": [-100.0, -100.0, -0.1],
             "u": [200.0, 0.0, 0.0], "v": [0.0, 200.0, 0.0], "surface": "table"},
            {"type": "quad", "name": "ribbon", "corner": [-25.0, -7.5, 0.0],
             "u": [50.0, 0.0, 0.0], "v": [0.0, 15.0, 0.0], "surface": "ribbon"},
            {"type": "cylinder", "name": "disc on the ribbon", "center": [-8.0, 0.0, 0.01],
             "axis": [0.0, 0.0, 1.0], "radius": 5.0, "height": 5.0,
             "inside": "disc", "outside": "air"},
            {"type": "cylinder", "name": "disc 5 mm above", "center": [8.0, 0.0, 5.0],
             "axis": [0.0, 0.0, 1.0], "radius": 5.0, "height": 5.0,
             "inside": "disc", "outside": "air"},
        ],
        "lights": [
            {"type": "quad", "name": "overhead", "corner": [-20.0, -40.0, 70.0],
             "u": [0.0, 40.0, 0.0], "v": [40.0, 0.0, 0.0], "radiance": 4.0,
             "spectrum": "D65"},
        ],
    }


BUILTIN = {"cornell": cornell_box, "discs": discs}


def cornell_teeth(resolution: tuple[int, int], tooth_resolution_mm: float,
                  box_mm: float = 60.0) -> dict:
    """Fig. 5: three procedural teeth (grid ``tooth_resolution_mm``) standing in a small
    Cornell box (y up, open towards -z)."""
    s = box_mm
    up = {"axis": [1.0, 0.0, 0.0], "angle_deg": -90.0}  # tooth +z (crown) -> +y, labial -> -z
    root = 13.3  # the teeth's roots reach 13 mm below the CEJ (teeth/incisor.py, molar.py)

    def tooth(model, x, z, turn):
        return {"type": "tooth", "model": model, "resolution": tooth_resolution_mm,
                "enamel": "enamel", "dentin": "dentin", "outside": "air",
                "transform": {"rotate": [up, {"axis": [0.0, 1.0, 0.0], "angle_deg": turn}],
                              "translate": [x, root, z]}}

    quad = {"type": "quad"}
    return {
        "scene": {"name": "cornell-teeth", "description": "Fig. 5: three teeth in a Cornell box"},
        "camera": {"position": [s / 2, s / 2, -2.1 * s], "look_at": [s / 2, s / 2 - 2, 0.0],
                   "up": [0.0, 1.0, 0.0], "fov_deg": 36.0,
                   "resolution": list(resolution)},
        "media": {"enamel": {"material": "enamel"}, "dentin": {"material": "dentin"}},
        "surfaces": {"white": {"type": "lambertian", "reflectance": 0.75},
                     "red": {"type": "lambertian", "reflectance": RED},
                     "green": {"type": "lambertian", "reflectance": GREEN}},
        "shapes": [
            {**quad, "name": "floor", "corner": [0, 0, 0], "u": [s, 0, 0], "v": [0, 0, s],
             "surface": "white"},
            {**quad, "name": "ceiling", "corner": [0, s, 0], "u": [s, 0, 0], "v": [0, 0, s],
             "surface": "white"},
            {**quad, "name": "back", "corner": [0, 0, s], "u": [s, 0, 0], "v": [0, s, 0],
             "surface": "white"},
            # the camera sees +x on its left (right = forward × up): red left, green right,
            # as in the Cornell box (and the built-in cornell_box())
            {**quad, "name": "left", "corner": [s, 0, 0], "u": [0, 0, s], "v": [0, s, 0],
             "surface": "red"},
            {**quad, "name": "right", "corner": [0, 0, 0], "u": [0, 0, s], "v": [0, s, 0],
             "surface": "green"},
            tooth("incisor", 0.27 * s, 0.45 * s, 15.0),
            tooth("molar", 0.52 * s, 0.55 * s, -10.0),
            tooth("incisor", 0.77 * s, 0.4 * s, -25.0),
        ],
        "lights": [{"type": "quad", "name": "ceiling light",
                    "corner": [0.35 * s, 0.995 * s, 0.35 * s], "u": [0.3 * s, 0, 0],
                    "v": [0, 0, 0.3 * s], "radiance": 12.0, "spectrum": "D65"}],
    }


def lights_45_0(centre, dist_mm: float, elevation_deg: float, size_mm: float,
                radiance: float) -> list[dict]:
    """Two square D65 quad lights facing ``centre`` from 45° left and right of the -z axis
    (the camera's direction), raised by ``elevation_deg``, ``dist_mm`` away."""
    e = math.radians(elevation_deg)
    lights = []
    for side in (-1.0, 1.0):
        # unit direction from the light towards the centre
        d = np.array([-side * math.cos(e) * math.sqrt(0.5), -math.sin(e),
                      math.cos(e) * math.sqrt(0.5)])
        u = np.array([1.0, 0.0, side]) / math.sqrt(2.0)  # horizontal, across d
        v = np.cross(d, u)
        if np.dot(np.cross(u, v), d) < 0:  # the emitting side (u × v) must face the centre
            u = -u
        u, v = u * size_mm, v / np.linalg.norm(v) * size_mm
        corner = np.asarray(centre, float) - dist_mm * d - (u + v) / 2
        lights.append({"type": "quad", "name": f"key {'left' if side < 0 else 'right'}",
                       "corner": corner.tolist(), "u": u.tolist(), "v": v.tolist(),
                       "radiance": radiance, "spectrum": "D65"})
    return lights


@lru_cache(maxsize=4)
def _crown_surfaces(layers_mm: tuple, resolution: float) -> list:
    from dentalux.teeth.incisor import crown_surfaces

    return crown_surfaces(layers_mm, resolution)


def crown(resolution: tuple[int, int], tooth_resolution_mm: float, layers=None,
          core=None) -> tuple[dict, dict]:
    """A natural incisor (image left) and the same tooth whose enamel volume is replaced by
    the biomaterial: a full-coverage crown on the natural dentin (image right). Returns the
    scene and the image regions (labial thirds of each crown) for the colour comparison.
    ``tooth_resolution_mm``: the teeth's grid spacing.

    ``layers``: the crown's shells instead, [(scene medium, labial thickness [mm])] top to
    bottom (a designed crown, :mod:`dentalux.design.render`), on a preparation as deep as
    their total (:func:`dentalux.teeth.incisor.crown_surfaces`) filled with ``core`` (a scene
    medium; None: the natural tooth's dentin). None: the figure's crown."""
    up = {"axis": [1.0, 0.0, 0.0], "angle_deg": -90.0}
    w, h = resolution

    def tooth(x, enamel_medium):
        return {"type": "tooth", "model": "incisor", "resolution": tooth_resolution_mm,
                "enamel": enamel_medium, "dentin": "dentin", "outside": "air",
                "transform": {"rotate": [up], "translate": [x, 0.0, 0.0]}}

    def layered_crown(media):
        # nested closed meshes: shell i lies between surface i and i + 1, the core inside
        # the last; each surface's outside is the shell above it (air for the outer one)
        shells = [f"crown {i + 1}" for i in range(len(layers))]
        media.update({name: dict(m) for name, (m, _) in zip(shells, layers, strict=True)})
        if core is not None:
            media["crown core"] = dict(core)
        inside = shells + ["dentin" if core is None else "crown core"]
        surfaces = _crown_surfaces(tuple(float(t) for _, t in layers),
                                   float(tooth_resolution_mm))
        place = {"rotate": [up], "translate": [-6.5, 0.0, 0.0]}  # as tooth(-6.5, ...)
        return [{"type": "mesh", "name": f"crown surface {i}", "positions": v,
                 "triangles": f, "inside": inside[i],
                 "outside": "air" if i == 0 else inside[i - 1], "transform": place}
                for i, (v, f) in enumerate(surfaces)]

    fov, eye_y, dist = 30.0, 3.0, 60.0
    scene = {
        "scene": {"name": "crown", "description": "biomaterial crown beside a natural incisor"},
        "camera": {"position": [0.0, eye_y, -dist], "look_at": [0.0, eye_y, 0.0],
                   "up": [0.0, 1.0, 0.0], "fov_deg": fov, "resolution": [w, h]},
        "media": {"enamel": {"material": "enamel"}, "dentin": {"material": "dentin"}},
        # a black contrastor behind the teeth, as in dental shade photography: light that
        # passes through the enamel-only incisal edge is lost, so the edge's translucency
        # shows (against a grey or white background it reads only as a greyer rim)
        "surfaces": {"backdrop": {"type": "black"}},
        "shapes": [
            {"type": "quad", "name": "backdrop", "corner": [-60.0, -40.0, 15.0],
             "u": [120.0, 0.0, 0.0], "v": [0.0, 80.0, 0.0], "surface": "backdrop"},
            # +x is on the image's left (see the regions below): natural left, crown right
            tooth(6.5, "enamel"),
        ],
        # 45°/0° geometry, as a dental spectrophotometer measures: two 16 mm square lights
        # 45° left and right of the labial faces' normal, 15° above it, 50 mm away; the
        # mirror highlights fall on the mesial and distal slopes of the curved faces, off the
        # measured middle third (one large light above the camera put its highlight there)
        "lights": lights_45_0([0.0, 5.0, -3.5], 50.0, 15.0, 16.0, 16.0),
    }
    if layers is None:
        scene["media"]["crown"] = {"material": "biomaterial-table1"}
        scene["shapes"].append(tooth(-6.5, "crown"))
    else:
        scene["shapes"] += layered_crown(scene["media"])
    # the measured squares on the labial faces (z ≈ -3.5 mm after the rotation), placed by
    # the render's own camera: it looks along +z with +y up, so +x (the natural tooth) is on
    # the image's left
    cam = scene["camera"]
    return scene, {name: square_region(cam, [x, 5.0, -3.5], 1.25)
                   for name, x in (("natural", 6.5), ("crown", -6.5))}
