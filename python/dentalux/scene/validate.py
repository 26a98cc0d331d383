"""Validation of a whole scene description: the primitive checks and key tables of
:mod:`dentalux.scene.schema` applied to every table, tooth entries expanded into their meshes
(:mod:`dentalux.scene.tooth`, which validates its meshes with the schema's shape check), and
the names that tables refer to checked against those defined.
"""

from __future__ import annotations

import difflib
from typing import Any

from dentalux.scene.schema import (
    MEDIUM_KEYS,
    SCENE_KEYS,
    TOP_KEYS,
    SceneError,
    check_keys,
    fail,
    fill,
    integer,
    string,
    validate_camera,
    validate_light,
    validate_medium,
    validate_render,
    validate_surface,
)
from dentalux.scene.tooth import expand_shape


def validate(raw: Any) -> dict:
    """Validate a whole scene description and return it normalised (defaults filled)."""
    check_keys(raw, TOP_KEYS, "")
    for key in ("camera", "shapes", "lights"):
        if key not in raw:
            raise SceneError(f"{key}: missing (required)")
    scene = fill(check_keys(raw.get("scene", {}), SCENE_KEYS, "scene"), SCENE_KEYS, "scene")
    string(scene["name"], "scene.name")
    string(scene["description"], "scene.description")
    string(scene["units"], "scene.units", ("mm",))
    out: dict = {"scene": scene, "render": validate_render(raw.get("render", {}))}
    out["camera"] = validate_camera(raw["camera"])

    media_raw = raw.get("media", {})
    if not isinstance(media_raw, dict):
        raise fail("media", media_raw, "must be a table of named media")
    media = {"air": {**{k: None for k in MEDIUM_KEYS}}} if "air" not in media_raw else {}
    for name, m in media_raw.items():
        media[name] = validate_medium(name, m)
    out["media"] = media

    surf_raw = raw.get("surfaces", {})
    if not isinstance(surf_raw, dict):
        raise fail("surfaces", surf_raw, "must be a table of named surfaces")
    out["surfaces"] = {name: validate_surface(name, s) for name, s in surf_raw.items()}

    shapes = raw["shapes"]
    if isinstance(shapes, (str, dict)) or not hasattr(shapes, "__len__"):
        raise fail("shapes", shapes, "must be a list of tables ([[shapes]])")
    # a tooth entry gives two meshes
    out["shapes"] = [m for i, s in enumerate(shapes) for m in expand_shape(i, s)]

    lights = raw["lights"]
    if isinstance(lights, (str, dict)) or not hasattr(lights, "__len__"):
        raise fail("lights", lights, "must be a list of tables ([[lights]])")
    if len(lights) == 0:
        raise SceneError("lights: the scene has no lights (add at least one [[lights]])")
    out["lights"] = [validate_light(i, s) for i, s in enumerate(lights)]

    out["regions"] = validate_regions(raw.get("regions", {}), out["camera"]["resolution"])
    _check_names(out)
    return out


def validate_regions(regions: Any, resolution) -> dict:
    """``[regions]``: named pixel rectangles ``[x0, y0, x1, y1]`` (x1, y1 exclusive) whose
    mean CIELAB ``dentalux render`` writes to colour.json (what a spectrophotometer's
    aperture would read there)."""
    if not isinstance(regions, dict):
        raise fail("regions", regions, "must be a table of named [x0, y0, x1, y1] rectangles")
    w, h = resolution
    out = {}
    for name, rect in regions.items():
        path = f"regions.{name}"
        if isinstance(rect, (str, dict)) or not hasattr(rect, "__len__") or len(rect) != 4:
            raise fail(path, rect, "must be [x0, y0, x1, y1] in pixels")
        x0, y0, x1, y1 = (integer(v, f"{path}[{j}]", lo=0) for j, v in enumerate(rect))
        if not (x0 < x1 <= w and y0 < y1 <= h):
            raise fail(path, list(rect), f"need x0 < x1 <= {w} and y0 < y1 <= {h} (the "
                                         "camera's resolution)")
        out[name] = [x0, y0, x1, y1]
    return out


def _undefined(kind: str, name: str, path: str, defined) -> SceneError:
    defined = list(defined)
    close = difflib.get_close_matches(name, defined, n=1, cutoff=0.6)
    hint = f"did you mean '{close[0]}'? " if close else ""
    listing = ", ".join(defined) if defined else "none"
    return fail(path, name, f"no {kind} of that name is defined; {hint}(defined: {listing})")


def _check_names(scene: dict) -> None:
    """Every medium and surface a shape or the camera names must be defined."""
    media, surfaces = scene["media"], scene["surfaces"]
    if scene["camera"]["medium"] not in media:
        raise _undefined("medium", scene["camera"]["medium"], "camera.medium", media)
    for i, s in enumerate(scene["shapes"]):
        b = s["boundary"]
        if b["kind"] == "opaque":
            if b["surface"] not in surfaces:
                raise _undefined("surface", b["surface"], f"shapes[{i}].surface", surfaces)
        else:
            for k in ("inside", "outside"):
                if b[k] not in media:
                    raise _undefined("medium", b[k], f"shapes[{i}].{k}", media)
