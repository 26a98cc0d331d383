"""Built-in scenes as plain dicts (the TOML format's keys), like ``mi.cornell_box()``.

``scenes/cornell.toml`` and ``scenes/discs.toml`` hold the same scenes as files; a test
checks that each resolves to the same render-contract JSON as its function here. The files
live in the package (``dentalux/scenes``, shipped in the wheel; the checkout's ``scenes/`` is
a link to that folder), so :func:`scene_file` finds them in any install.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

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
