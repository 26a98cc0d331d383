"""The scene description's key tables and the checks of its values (a dict, as read from TOML
or built in Python); :mod:`dentalux.scene.validate` applies them to a whole scene.

Every check names the key path of the offending value (``shapes[2].radius``), the allowed
range and, for an unknown key, the closest allowed key (``difflib``). The result is a
*normalised* description: all defaults filled in, names still unresolved (media, surfaces
and material-library names are resolved per wavelength band by ``resolve.py``).

Units: lengths in mm, angles in degrees, wavelengths in nm, coefficients in 1/mm.
The key reference with types, units and defaults is ``docs/scene-format.md``.
"""

from __future__ import annotations

import difflib
import math
from numbers import Integral, Real
from typing import Any

import numpy as np

from dentalux.core_schema import INTEGRATOR_INFO, SETTINGS_SCHEMA
from dentalux.limits import BAND_RANGE_NM, check_threads


class SceneError(ValueError):
    """A bad scene description. The message starts with the key path of the bad value."""


# ---------------------------------------------------------------------------------------
# Allowed keys and defaults (``REQUIRED`` marks keys without a default).

REQUIRED = object()

TOP_KEYS = ("scene", "render", "camera", "media", "surfaces", "shapes", "lights", "regions")

SCENE_KEYS = {"name": "", "description": "", "units": "mm"}

# The settings' keys, defaults and ranges, the integrator names and the pass bound live in
# the core (integrators/settings.rs, contract/mod.rs), read once by dentalux.core_schema.
# every settings key of the contract, in order: {name: {"kind", "default", ranges...}}
SETTING_KEYS = {k["name"]: k for k in SETTINGS_SCHEMA["keys"]}

# A scene's [render] table: the bands and the settings a scene may set. The integrator's
# default is derived from the scene (vpm with scattering media, else pm), hence None here.
RENDER_KEYS = {
    "bands": [450.0, 540.0, 605.0],
    **{name: None if name == "integrator" else k["default"]
       for name, k in SETTING_KEYS.items() if k["scene"]},
}

INTEGRATORS = tuple(i["name"] for i in INTEGRATOR_INFO)
# integrators that trace no photons
PATH_TRACERS = tuple(i["name"] for i in INTEGRATOR_INFO if not i["traces_photons"])

CAMERA_KEYS = {
    "position": REQUIRED,
    "look_at": REQUIRED,
    "up": [0.0, 1.0, 0.0],
    "fov_deg": 40.0,
    "resolution": [256, 256],
    "medium": "air",
}

MEDIUM_KEYS = {
    "material": None,
    "mua": None,
    "mus": None,
    "g": None,
    "fd": None,
    "n": None,
    "lobes": None,
}
# Values a medium takes when neither a key nor a material gives one (clear air).
MEDIUM_FALLBACK = {"mua": 0.0, "mus": 0.0, "g": 0.0, "fd": 0.0, "n": 1.0}

SURFACE_KEYS = {
    "lambertian": {"type": "lambertian", "reflectance": REQUIRED},
    "checker": {"type": "checker", "a": REQUIRED, "b": REQUIRED, "size": REQUIRED,
                "mapping": "xy"},
    "image": {"type": "image", "file": None, "data": None, "width": None, "height": None,
              "scale": 1.0, "mapping": "uv", "size": None},
    "black": {"type": "black"},
}

BOUNDARY_KEYS = {"surface": None, "inside": None, "outside": None, "transform": None,
                 "name": ""}

SHAPE_KEYS = {
    "sphere": {"center": [0.0, 0.0, 0.0], "radius": REQUIRED},
    "quad": {"corner": REQUIRED, "u": REQUIRED, "v": REQUIRED},
    "box": {"min": REQUIRED, "max": REQUIRED},
    "cylinder": {"center": [0.0, 0.0, 0.0], "axis": [0.0, 0.0, 1.0], "radius": REQUIRED,
                 "height": REQUIRED},
    "mesh": {"file": None, "positions": None, "triangles": None, "uvs": None},
}
SHAPE_ALIASES = {"rectangle": "quad"}
CLOSED_SHAPES = ("sphere", "box", "cylinder", "mesh")

LIGHT_KEYS = {
    "quad": {"corner": REQUIRED, "u": REQUIRED, "v": REQUIRED, "radiance": 1.0},
    "disc": {"center": REQUIRED, "normal": REQUIRED, "radius": REQUIRED, "radiance": 1.0},
    "point": {"position": REQUIRED, "intensity": 1.0},
    "spot": {"position": REQUIRED, "direction": REQUIRED, "intensity": 1.0,
             "cone_deg": 30.0, "falloff_deg": 5.0},
}
LIGHT_COMMON = {"spectrum": "D65", "name": ""}
LIGHT_SPECTRA = ("D65", "flat")

TRANSFORM_KEYS = {"scale": None, "rotate": None, "translate": None, "matrix": None}

# The colour range [nm] (BAND_RANGE_NM) lives with the other limits in dentalux.limits.


# ---------------------------------------------------------------------------------------
# Primitive checks


def fail(path: str, value: Any, why: str) -> SceneError:
    """Build the error for ``path = value: why``."""
    shown = repr(value)
    if len(shown) > 60:
        shown = shown[:57] + "..."
    return SceneError(f"{path} = {shown}: {why}")


def check_keys(d: Any, allowed, path: str) -> dict:
    """``d`` must be a table whose keys are all in ``allowed``; unknown keys get a
    did-you-mean suggestion."""
    if not isinstance(d, dict):
        raise fail(path or "scene", d, f"must be a table, got {type(d).__name__}")
    allowed = list(allowed)
    for key in d:
        if key not in allowed:
            where = f"{path}.{key}" if path else str(key)
            close = difflib.get_close_matches(str(key), allowed, n=1, cutoff=0.6)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise SceneError(
                f"{where}: unknown key; {hint}(allowed: {', '.join(allowed)})"
            )
    return d


def fill(d: dict, defaults: dict, path: str) -> dict:
    """Return ``d`` with defaults filled in; a missing required key is an error."""
    out = {}
    for key, default in defaults.items():
        if key in d:
            out[key] = d[key]
        elif default is REQUIRED:
            raise SceneError(f"{path}.{key}: missing (required)")
        else:
            out[key] = default
    return out


def number(value: Any, path: str, *, lo: float | None = None, hi: float | None = None,
           lo_open: bool = False, hi_open: bool = False, unit: str = "") -> float:
    """A finite real number in [lo, hi] (or open ends)."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise fail(path, value, f"must be a number{unit and ' [' + unit + ']'}, "
                                f"got {type(value).__name__}")
    x = float(value)
    if not math.isfinite(x):
        raise fail(path, value, "must be finite")
    below = lo is not None and (x <= lo if lo_open else x < lo)
    above = hi is not None and (x >= hi if hi_open else x > hi)
    if below or above:
        left = "-inf" if lo is None else f"{lo:g}"
        right = "inf" if hi is None else f"{hi:g}"
        rng = f"{'(' if lo_open or lo is None else '['}{left}, {right}" \
              f"{')' if hi_open or hi is None else ']'}"
        raise fail(path, value, f"out of range: allowed {rng}{unit and ' ' + unit}")
    return x


def positive(value: Any, path: str, unit: str = "mm") -> float:
    """A number > 0."""
    return number(value, path, lo=0.0, lo_open=True, unit=unit)


def integer(value: Any, path: str, *, lo: int | None = None) -> int:
    """An integer >= lo."""
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise fail(path, value, f"must be an integer, got {type(value).__name__}")
    if lo is not None and value < lo:
        raise fail(path, value, f"out of range: allowed integer >= {lo}")
    return int(value)


def string(value: Any, path: str, choices: tuple[str, ...] | None = None) -> str:
    """A string, optionally one of ``choices`` (with a did-you-mean)."""
    if not isinstance(value, str):
        raise fail(path, value, f"must be a string, got {type(value).__name__}")
    if choices is not None and value not in choices:
        close = difflib.get_close_matches(value, choices, n=1, cutoff=0.5)
        hint = f"did you mean '{close[0]}'? " if close else ""
        raise fail(path, value, f"{hint}allowed: {', '.join(choices)}")
    return value


def boolean(value: Any, path: str) -> bool:
    """A true/false value."""
    if not isinstance(value, bool):
        raise fail(path, value, f"must be true or false, got {type(value).__name__}")
    return value


def vec(value: Any, path: str, n: int = 3, unit: str = "mm") -> list[float]:
    """A list of ``n`` finite numbers."""
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        raise fail(path, value, f"must be a list of {n} numbers [{unit}]")
    if len(value) != n:
        raise fail(path, value, f"must be a list of {n} numbers [{unit}], got {len(value)}")
    return [number(x, f"{path}[{i}]", unit=unit) for i, x in enumerate(value)]


def direction(value: Any, path: str) -> list[float]:
    """A non-zero 3-vector (not normalised here)."""
    v = vec(value, path, unit="")
    if math.hypot(*v) < 1e-12:
        raise fail(path, value, "must be a non-zero direction")
    return v


def spectrum(value: Any, path: str, *, lo: float | None = None, hi: float | None = None,
             lo_open: bool = False, hi_open: bool = False, unit: str = "") -> float | dict:
    """A number, or a table ``{wavelengths_nm = [...], values = [...]}`` linearly
    interpolated between its points (at least one point; strictly increasing)."""
    if not isinstance(value, dict):
        return number(value, path, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open, unit=unit)
    check_keys(value, ("wavelengths_nm", "values"), path)
    d = fill(value, {"wavelengths_nm": REQUIRED, "values": REQUIRED}, path)
    wl, vals = d["wavelengths_nm"], d["values"]
    for key, arr in (("wavelengths_nm", wl), ("values", vals)):
        if isinstance(arr, (str, dict)) or not hasattr(arr, "__len__") or len(arr) == 0:
            raise fail(f"{path}.{key}", arr, "must be a non-empty list of numbers")
    if len(wl) != len(vals):
        raise fail(f"{path}.values", vals,
                   f"must have as many entries as wavelengths_nm ({len(wl)})")
    w = [number(x, f"{path}.wavelengths_nm[{i}]", lo=0.0, lo_open=True, unit="nm")
         for i, x in enumerate(wl)]
    if any(b <= a for a, b in zip(w, w[1:], strict=False)):
        raise fail(f"{path}.wavelengths_nm", wl, "must be strictly increasing")
    v = [number(x, f"{path}.values[{i}]", lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open,
                unit=unit)
         for i, x in enumerate(vals)]
    return {"wavelengths_nm": w, "values": v}


def spectrum_at(spec: float | dict, wavelength_nm: float, path: str) -> float:
    """Evaluate a validated :func:`spectrum` at one wavelength [nm]."""
    if not isinstance(spec, dict):
        return float(spec)
    w, v = spec["wavelengths_nm"], spec["values"]
    if len(w) == 1:
        return float(v[0])
    if not (w[0] <= wavelength_nm <= w[-1]):
        raise SceneError(
            f"{path}: the table covers {w[0]:g}-{w[-1]:g} nm, "
            f"not the band {wavelength_nm:g} nm"
        )
    return float(np.interp(wavelength_nm, w, v))


# ---------------------------------------------------------------------------------------
# Sections


def validate_transform(t: Any, path: str) -> dict | None:
    """``transform = {scale, rotate, translate}`` or ``{matrix}``; see transform.py."""
    if t is None:
        return None
    check_keys(t, TRANSFORM_KEYS, path)
    out: dict = {}
    if "matrix" in t:
        if len(t) > 1:
            raise SceneError(f"{path}: give either matrix or scale/rotate/translate, not both")
        m = t["matrix"]
        if isinstance(m, (str, dict)) or not hasattr(m, "__len__") or len(m) != 4:
            raise fail(f"{path}.matrix", m, "must be 4 rows of 4 numbers (row-major)")
        rows = [vec(r, f"{path}.matrix[{i}]", n=4, unit="") for i, r in enumerate(m)]
        if abs(np.linalg.det(np.array(rows)[:3, :3])) < 1e-12:
            raise fail(f"{path}.matrix", m, "is singular")
        return {"matrix": rows}
    if "scale" in t:
        s = t["scale"]
        if isinstance(s, Real) and not isinstance(s, bool):
            out["scale"] = [positive(s, f"{path}.scale", unit="")] * 3
        else:
            sv = vec(s, f"{path}.scale", unit="")
            out["scale"] = [positive(x, f"{path}.scale[{i}]", unit="")
                            for i, x in enumerate(sv)]
    if "rotate" in t:
        r = t["rotate"]
        items = [r] if isinstance(r, dict) else r
        if isinstance(items, str) or not hasattr(items, "__len__"):
            raise fail(f"{path}.rotate", r,
                       "must be a table {axis, angle_deg} or a list of such tables")
        rots = []
        for i, item in enumerate(items):
            p = f"{path}.rotate" if isinstance(r, dict) else f"{path}.rotate[{i}]"
            check_keys(item, ("axis", "angle_deg"), p)
            d = fill(item, {"axis": REQUIRED, "angle_deg": REQUIRED}, p)
            rots.append({"axis": direction(d["axis"], f"{p}.axis"),
                         "angle_deg": number(d["angle_deg"], f"{p}.angle_deg", unit="deg")})
        out["rotate"] = rots
    if "translate" in t:
        out["translate"] = vec(t["translate"], f"{path}.translate")
    return out


def validate_camera(c: Any) -> dict:
    """The pinhole camera."""
    check_keys(c, CAMERA_KEYS, "camera")
    d = fill(c, CAMERA_KEYS, "camera")
    d["position"] = vec(d["position"], "camera.position")
    d["look_at"] = vec(d["look_at"], "camera.look_at")
    d["up"] = direction(d["up"], "camera.up")
    d["fov_deg"] = number(d["fov_deg"], "camera.fov_deg", lo=0.0, hi=180.0, lo_open=True,
                          hi_open=True, unit="deg")
    res = d["resolution"]
    if isinstance(res, (str, dict)) or not hasattr(res, "__len__") or len(res) != 2:
        raise fail("camera.resolution", res, "must be [width, height] in pixels")
    d["resolution"] = [integer(x, f"camera.resolution[{i}]", lo=1) for i, x in enumerate(res)]
    d["medium"] = string(d["medium"], "camera.medium")
    view = np.subtract(d["look_at"], d["position"])
    if np.linalg.norm(view) < 1e-12:
        raise fail("camera.look_at", c["look_at"], "must differ from camera.position")
    cross = np.cross(view / np.linalg.norm(view), np.array(d["up"]) / np.linalg.norm(d["up"]))
    if np.linalg.norm(cross) < 1e-6:
        raise fail("camera.up", d["up"], "must not be parallel to the viewing direction")
    return d


def validate_lobes(lobes: Any, path: str) -> list[list[float]] | None:
    """Multi-lobe HG (eq. 8): a list of [weight, g], weights >= 0 summing to 1."""
    if lobes is None:
        return None
    if isinstance(lobes, (str, dict)) or not hasattr(lobes, "__len__") or len(lobes) == 0:
        raise fail(path, lobes, "must be a non-empty list of [weight, g] pairs")
    out = []
    for i, lobe in enumerate(lobes):
        w, g = vec(lobe, f"{path}[{i}]", n=2, unit="")
        number(w, f"{path}[{i}][0]", lo=0.0)
        number(g, f"{path}[{i}][1]", lo=-1.0, hi=1.0, lo_open=True, hi_open=True)
        out.append([w, g])
    total = sum(w for w, _ in out)
    if abs(total - 1.0) > 1e-6:
        raise fail(path, lobes, f"weights must sum to 1, got {total:g}")
    return out


def validate_medium(name: str, m: Any) -> dict:
    """A named homogeneous medium: coefficients as numbers/spectra and/or a material name."""
    path = f"media.{name}"
    check_keys(m, MEDIUM_KEYS, path)
    d = fill(m, MEDIUM_KEYS, path)
    if d["material"] is not None:
        d["material"] = string(d["material"], f"{path}.material")
    ranges = {
        "mua": dict(lo=0.0, unit="1/mm"),
        "mus": dict(lo=0.0, unit="1/mm"),
        "g": dict(lo=-1.0, hi=1.0, lo_open=True, hi_open=True),
        "fd": dict(lo=0.0, hi=1.0),
        "n": dict(lo=1.0),
    }
    for key, kw in ranges.items():
        if d[key] is not None:
            d[key] = spectrum(d[key], f"{path}.{key}", **kw)
    d["lobes"] = validate_lobes(d["lobes"], f"{path}.lobes")
    return d


def validate_surface(name: str, s: Any) -> dict:
    """A named opaque surface material."""
    path = f"surfaces.{name}"
    if not isinstance(s, dict):
        raise fail(path, s, "must be a table")
    kind = string(s.get("type", "lambertian"), f"{path}.type", tuple(SURFACE_KEYS))
    keys = SURFACE_KEYS[kind]
    check_keys(s, keys, path)
    d = fill(s, keys, path)
    d["type"] = kind
    refl = dict(lo=0.0, hi=1.0, unit="")
    if kind == "lambertian":
        d["reflectance"] = spectrum(d["reflectance"], f"{path}.reflectance", **refl)
    elif kind == "checker":
        d["a"] = spectrum(d["a"], f"{path}.a", **refl)
        d["b"] = spectrum(d["b"], f"{path}.b", **refl)
        d["size"] = positive(d["size"], f"{path}.size")
        d["mapping"] = string(d["mapping"], f"{path}.mapping", ("xy", "uv"))
    elif kind == "image":
        d["mapping"] = string(d["mapping"], f"{path}.mapping", ("xy", "uv"))
        d["scale"] = number(d["scale"], f"{path}.scale", lo=0.0, unit="")
        if d["size"] is not None:
            d["size"] = positive(d["size"], f"{path}.size")
        if (d["file"] is None) == (d["data"] is None):
            raise SceneError(f"{path}: give either file (an image) or data/width/height")
        if d["file"] is not None:
            d["file"] = string(d["file"], f"{path}.file")
            for k in ("width", "height"):
                if d[k] is not None:
                    raise SceneError(f"{path}.{k}: only with data (the file gives the size)")
        else:
            w = integer(d["width"] if d["width"] is not None else -1, f"{path}.width", lo=1)
            h = integer(d["height"] if d["height"] is not None else -1, f"{path}.height",
                        lo=1)
            data = d["data"]
            if isinstance(data, (str, dict)) or not hasattr(data, "__len__") \
                    or len(data) != w * h:
                raise fail(f"{path}.data", data,
                           f"must be a list of width*height = {w * h} reflectances")
            d["data"] = [number(x, f"{path}.data[{i}]", **refl) for i, x in enumerate(data)]
            d["width"], d["height"] = w, h
    return d


def _check_boundary(s: dict, d: dict, kind: str, path: str) -> dict:
    """Exactly one of ``surface`` (opaque) or ``inside`` (+ ``outside``) (dielectric)."""
    if d["surface"] is not None and (d["inside"] is not None or d["outside"] is not None):
        raise SceneError(
            f"{path}: give either surface (opaque) or inside/outside media (dielectric), "
            "not both"
        )
    if d["surface"] is not None:
        return {"kind": "opaque", "surface": string(d["surface"], f"{path}.surface")}
    if d["inside"] is None:
        if d["outside"] is not None:
            raise SceneError(f"{path}.inside: missing (a dielectric boundary needs it)")
        raise SceneError(
            f"{path}: missing boundary: give surface = NAME (opaque) or "
            "inside = MEDIUM (dielectric, with outside = MEDIUM, default 'air')"
        )
    if kind not in CLOSED_SHAPES:
        raise SceneError(f"{path}.inside: a {kind} is not closed; it can only be opaque "
                         "(give surface = NAME)")
    inside = string(d["inside"], f"{path}.inside")
    outside = string(d["outside"] if d["outside"] is not None else "air", f"{path}.outside")
    if inside == outside:
        raise fail(f"{path}.outside", outside, "must differ from inside")
    return {"kind": "dielectric", "inside": inside, "outside": outside}


def validate_shape(i: int, s: Any) -> dict:
    """One shape with its boundary and optional transform."""
    path = f"shapes[{i}]"
    if not isinstance(s, dict):
        raise fail(path, s, "must be a table")
    if "type" not in s:
        raise SceneError(f"{path}.type: missing (allowed: {', '.join(SHAPE_KEYS)})")
    kind = string(s["type"], f"{path}.type", tuple(SHAPE_KEYS) + tuple(SHAPE_ALIASES))
    kind = SHAPE_ALIASES.get(kind, kind)
    keys = {"type": kind, **SHAPE_KEYS[kind], **BOUNDARY_KEYS}
    check_keys(s, keys, path)
    d = fill(s, keys, path)
    d["type"] = kind
    d["name"] = string(d["name"], f"{path}.name")
    d["boundary"] = _check_boundary(s, d, kind, path)
    for k in ("surface", "inside", "outside"):
        d.pop(k)
    d["transform"] = validate_transform(d["transform"], f"{path}.transform")
    if kind == "sphere":
        d["center"] = vec(d["center"], f"{path}.center")
        d["radius"] = positive(d["radius"], f"{path}.radius")
    elif kind == "quad":
        d["corner"] = vec(d["corner"], f"{path}.corner")
        d["u"] = vec(d["u"], f"{path}.u")
        d["v"] = vec(d["v"], f"{path}.v")
        if np.linalg.norm(np.cross(d["u"], d["v"])) < 1e-12:
            raise fail(f"{path}.v", d["v"], "must not be parallel to u (zero area)")
    elif kind == "box":
        d["min"] = vec(d["min"], f"{path}.min")
        d["max"] = vec(d["max"], f"{path}.max")
        for a, (lo, hi) in enumerate(zip(d["min"], d["max"], strict=True)):
            if hi <= lo:
                raise fail(f"{path}.max[{a}]", hi, f"must exceed min[{a}] = {lo:g} "
                                                   "(negative or zero size)")
    elif kind == "cylinder":
        d["center"] = vec(d["center"], f"{path}.center")
        d["axis"] = direction(d["axis"], f"{path}.axis")
        d["radius"] = positive(d["radius"], f"{path}.radius")
        d["height"] = positive(d["height"], f"{path}.height")
    elif kind == "mesh":
        if (d["file"] is None) == (d["positions"] is None):
            raise SceneError(f"{path}: give either file (OBJ or PLY) or positions/triangles")
        if d["file"] is not None:
            d["file"] = string(d["file"], f"{path}.file")
            for k in ("triangles", "uvs"):
                if d[k] is not None:
                    raise SceneError(f"{path}.{k}: only with positions (the file gives them)")
        else:
            if d["triangles"] is None:
                raise SceneError(f"{path}.triangles: missing (required with positions)")
            # Fast path: a clean numeric table (lists or numpy arrays) is checked with
            # numpy; anything else goes through the per-entry checks for a precise message.
            pos = _table_array(d["positions"], "iuf", 3)
            if pos is None or not np.all(np.isfinite(pos)):
                pos = np.array([vec(p, f"{path}.positions[{j}]") for j, p in
                                enumerate(_seq(d["positions"], f"{path}.positions"))])
            d["positions"] = pos.astype(float)
            nv = len(pos)
            tri = _table_array(d["triangles"], "iu", 3)
            if tri is None or tri.min() < 0 or tri.max() >= nv:
                for j, t in enumerate(_seq(d["triangles"], f"{path}.triangles")):
                    if isinstance(t, (str, dict)) or not hasattr(t, "__len__") or len(t) != 3:
                        raise fail(f"{path}.triangles[{j}]", t, "must be 3 vertex indices")
                    idx = [integer(t[a], f"{path}.triangles[{j}][{a}]", lo=0)
                           for a in range(3)]
                    if max(idx) >= nv:
                        raise fail(f"{path}.triangles[{j}]", list(t),
                                   f"vertex index out of range (there are {nv} positions)")
                tri = np.asarray(d["triangles"])
            d["triangles"] = tri.astype(np.int64)
            if d["uvs"] is not None:
                uvs = _table_array(d["uvs"], "iuf", 2)
                if uvs is None or not np.all(np.isfinite(uvs)):
                    uvs = np.array([vec(p, f"{path}.uvs[{j}]", n=2, unit="") for j, p in
                                    enumerate(_seq(d["uvs"], f"{path}.uvs"))])
                if len(uvs) != nv:
                    raise fail(f"{path}.uvs", f"<{len(uvs)} entries>",
                               f"must have {nv} entries (one per position)")
                d["uvs"] = uvs.astype(float)
    return d


def _table_array(value: Any, kinds: str, cols: int) -> np.ndarray | None:
    """``value`` as an (n, cols) array when it is a non-empty numeric table whose dtype kind
    is in ``kinds`` (no strings, no booleans), else None."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError):
        return None
    if raw.ndim != 2 or raw.shape[1] != cols or raw.shape[0] == 0 or raw.dtype.kind not in kinds:
        return None
    # numpy reads [0, 1, true] as integers: a bool in a list is never an index or a number
    if not isinstance(value, np.ndarray) and any(
            isinstance(x, bool | np.bool_) for row in value for x in row):
        return None
    return raw


def _seq(value: Any, path: str) -> list:
    if isinstance(value, (str, dict)) or not hasattr(value, "__len__") or len(value) == 0:
        raise fail(path, value, "must be a non-empty list")
    return list(value)


def validate_light(i: int, s: Any) -> dict:
    """One light with its spectrum."""
    path = f"lights[{i}]"
    if not isinstance(s, dict):
        raise fail(path, s, "must be a table")
    if "type" not in s:
        raise SceneError(f"{path}.type: missing (allowed: {', '.join(LIGHT_KEYS)})")
    kind = string(s["type"], f"{path}.type", tuple(LIGHT_KEYS))
    keys = {"type": kind, **LIGHT_KEYS[kind], **LIGHT_COMMON}
    check_keys(s, keys, path)
    d = fill(s, keys, path)
    d["name"] = string(d["name"], f"{path}.name")
    if isinstance(d["spectrum"], str):
        d["spectrum"] = string(d["spectrum"], f"{path}.spectrum", LIGHT_SPECTRA)
    else:
        d["spectrum"] = spectrum(d["spectrum"], f"{path}.spectrum", lo=0.0)
    emit = "radiance" if kind in ("quad", "disc") else "intensity"
    unit = "W/(m^2 sr nm)" if emit == "radiance" else "W/(sr nm)"
    d[emit] = positive(d[emit], f"{path}.{emit}", unit=unit)
    if kind == "quad":
        d["corner"] = vec(d["corner"], f"{path}.corner")
        d["u"] = vec(d["u"], f"{path}.u")
        d["v"] = vec(d["v"], f"{path}.v")
        if np.linalg.norm(np.cross(d["u"], d["v"])) < 1e-12:
            raise fail(f"{path}.v", d["v"], "must not be parallel to u (zero area)")
    elif kind == "disc":
        d["center"] = vec(d["center"], f"{path}.center")
        d["normal"] = direction(d["normal"], f"{path}.normal")
        d["radius"] = positive(d["radius"], f"{path}.radius")
    elif kind == "point":
        d["position"] = vec(d["position"], f"{path}.position")
    elif kind == "spot":
        d["position"] = vec(d["position"], f"{path}.position")
        d["direction"] = direction(d["direction"], f"{path}.direction")
        d["cone_deg"] = number(d["cone_deg"], f"{path}.cone_deg", lo=0.0, hi=180.0,
                               lo_open=True, unit="deg")
        d["falloff_deg"] = number(d["falloff_deg"], f"{path}.falloff_deg", lo=0.0,
                                  hi=d["cone_deg"], unit="deg")
    return d


def validate_render(r: Any) -> dict:
    """Default render settings stored with the scene (overridable by the CLI and API)."""
    check_keys(r, RENDER_KEYS, "render")
    d = fill(r, RENDER_KEYS, "render")
    d["bands"] = validate_bands(d["bands"], "render.bands")
    return validate_settings(d, "render")


def validate_bands(bands: Any, path: str = "bands") -> list[float]:
    """Wavelength bands [nm]: a non-empty list of distinct numbers within 360-830 nm."""
    if isinstance(bands, Real) and not isinstance(bands, bool):
        bands = [bands]
    seq = _seq(bands, path)
    lo, hi = BAND_RANGE_NM
    out = [number(b, f"{path}[{i}]", lo=lo, hi=hi, unit="nm") for i, b in enumerate(seq)]
    if len({round(b) for b in out}) != len(out):
        raise fail(path, bands, "bands must be distinct (to the nearest nm)")
    return out


def validate_settings(d: dict, path: str = "settings") -> dict:
    """Integrator settings shared by ``[render]``, ``dentalux.render`` and the CLI, checked
    against the core's ranges (:data:`SETTING_KEYS`). Keys whose default is ``None``
    (radius, step, threads) and the integrator may be ``None``: derived later."""
    p = (lambda k: f"{path}.{k}") if path else (lambda k: k)
    out = dict(d)
    for key, spec in SETTING_KEYS.items():
        if key not in out:
            continue
        value, kind = out[key], spec["kind"]
        if value is None and (spec["default"] is None or kind == "integrator"):
            continue
        if kind == "integrator":
            out[key] = string(value, p(key), INTEGRATORS)
        elif kind == "integer":
            # pass_index: the upper bound (pass_index + passes < max_passes) is the core's
            out[key] = integer(value, p(key), lo=spec["lo"])
        elif kind == "positive":
            out[key] = positive(value, p(key), spec["unit"])
        elif kind == "real":
            out[key] = number(value, p(key), lo=spec["lo"], hi=spec["hi"],
                              lo_open=spec["lo_open"], hi_open=spec["hi_open"])
        elif kind == "boolean":
            out[key] = boolean(value, p(key))
        elif kind == "choice":
            out[key] = string(value, p(key), tuple(spec["values"]))
    if out.get("threads") is not None:
        check_threads(out["threads"], p("threads"))
    return out
