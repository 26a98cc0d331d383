"""A validated scene, resolved one wavelength band at a time into the render contract JSON
(``docs/render-contract.md``).

Geometry (meshes, transforms, indices) does not depend on the band and is built once.
Per band, ``Scene.resolve(wavelength_nm)`` evaluates media (numbers, spectra or material
library names), surface reflectances and light emission (D65 by default) at that
wavelength.

Light spectra: ``spectrum = "D65"`` is the CIE D65 relative spectral power distribution
(colour-science, 300-780 nm, 5 nm, linear interpolation) divided by its value at 560 nm, so
it is 1.0 at 560 nm; ``"flat"`` is 1.0 everywhere; a table is used as given. A light's
``radiance`` (or ``intensity``) multiplies that relative spectrum.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from dentalux import _core
from dentalux.scene import transform as tf
from dentalux.scene.meshes import MeshData, check_closed, load_mesh
from dentalux.scene.schema import MEDIUM_FALLBACK, SceneError, fail, spectrum_at
from dentalux.scene.validate import validate

_D65: tuple[np.ndarray, np.ndarray] | None = None


def d65_relative(wavelength_nm: float, path: str = "spectrum") -> float:
    """CIE D65 relative spectral power at ``wavelength_nm`` [nm], 1.0 at 560 nm."""
    global _D65
    if _D65 is None:
        import colour  # deferred: importing colour-science takes about a second

        sd = colour.SDS_ILLUMINANTS["D65"]
        w = np.asarray(sd.wavelengths, dtype=float)
        v = np.asarray(sd.values, dtype=float)
        _D65 = (w, v / float(np.interp(560.0, w, v)))
    w, v = _D65
    if not (w[0] <= wavelength_nm <= w[-1]):
        raise SceneError(f"{path} = 'D65': D65 is tabulated on {w[0]:g}-{w[-1]:g} nm, not at "
                         f"the band {wavelength_nm:g} nm; give a table instead")
    return float(np.interp(wavelength_nm, w, v))


def material_library():
    """The material library module ``dentalux.materials``, or ``None`` when unavailable."""
    try:
        from dentalux import materials
    except Exception:  # absent or half-written: report it where a name needs it
        return None
    return materials if hasattr(materials, "get") else None


def _material_at(name: str, wavelength_nm: float, path: str) -> dict:
    """mua, mus, g, fd, n (and lobes) of a library material at one band."""
    lib = material_library()
    if lib is None:
        if name == "air":
            return {**MEDIUM_FALLBACK, "lobes": None}
        raise fail(path, name, "the material library (dentalux.materials) is not available, "
                               "so material names cannot be resolved; give mua/mus/g/n")
    try:
        props = lib.get(name).at(float(wavelength_nm))
    except (KeyError, ValueError, LookupError) as exc:
        if name == "air":
            return {**MEDIUM_FALLBACK, "lobes": None}
        msg = exc.args[0] if exc.args else type(exc).__name__
        raise fail(path, name, f"{msg}") from None
    out = {k: float(getattr(props, k, MEDIUM_FALLBACK[k])) for k in MEDIUM_FALLBACK}
    lobes = getattr(props, "lobes", None)
    out["lobes"] = [[float(w), float(g)] for w, g in lobes] if lobes else None
    return out


def _check_medium_values(values: dict, path: str) -> None:
    """Re-check numbers that came from a library or a table at this band."""
    rules = {"mua": (0.0, math.inf), "mus": (0.0, math.inf), "g": (-1.0, 1.0),
             "fd": (0.0, 1.0), "n": (1.0, math.inf)}
    for key, (lo, hi) in rules.items():
        x = values[key]
        ok = math.isfinite(x) and lo <= x <= hi and not (key == "g" and abs(x) >= 1.0)
        if not ok:
            raise SceneError(f"{path}.{key} = {x!r}: out of range at this band "
                             f"(allowed {'(' if key == 'g' else '['}{lo:g}, {hi:g}"
                             f"{')' if key == 'g' or hi == math.inf else ']'})")


def _file_digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _array_digest(x):
    """JSON stand-in for a numpy array inside the description: dtype, shape and a digest."""
    if isinstance(x, np.ndarray):
        a = np.ascontiguousarray(x)
        return {"dtype": a.dtype.str, "shape": list(a.shape),
                "sha256": hashlib.sha256(a.tobytes()).hexdigest()}
    raise TypeError(f"not serialisable: {type(x).__name__}")


def to_plain(x):
    """JSON ``default=`` hook that writes numpy arrays as nested lists."""
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not serialisable: {type(x).__name__}")


def _identity_or(m: np.ndarray) -> list[list[float]]:
    return [[float(x) for x in row] for row in m]


def _contract_json(shape: dict) -> str:
    """A contract shape dict (mesh arrays as numpy) as the JSON the core reads."""
    return json.dumps(shape, separators=(",", ":"), default=to_plain)


def shape_contains(shape: dict, points) -> np.ndarray:
    """Whether each of ``points`` (n, 3) [mm] lies strictly inside ``shape``, one entry of the
    render contract's ``shapes``. The core decides (``_core.shape_contains``), so the scene
    checks and the render share one geometry; quads and meshes that are not watertight have
    no inside."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return np.array(_core.shape_contains(_contract_json(shape), pts.tolist()), dtype=bool)


def camera_contract(cam: dict, width: int, height: int) -> dict:
    """The render contract's camera object from a validated scene camera."""
    return {"position": cam["position"], "look_at": cam["look_at"], "up": cam["up"],
            "fov_deg": cam["fov_deg"], "width": int(width), "height": int(height)}


class Scene:
    """A validated scene that resolves to the render contract per wavelength band.

    ``description`` is the normalised dict (defaults filled), ``base_dir`` the folder that
    relative file names (meshes, textures) are read from.
    """

    def __init__(self, description: dict, base_dir: str | Path | None = None,
                 source: str | None = None, allow_outside_paths: bool = False):
        # validate() builds new containers and never mutates its input (tested), so no copy
        self.description = validate(description)
        self.base_dir = Path(base_dir) if base_dir is not None else Path.cwd()
        self.source = source
        d = self.description
        self.media_names = list(d["media"])
        self.surface_names = list(d["surfaces"])
        self.allow_outside_paths = bool(allow_outside_paths)
        self._files: dict[str, str] = {}
        self._file_names: dict[str, str] = {}
        self._hash: str | None = None
        self._images = self._load_images()
        self._shapes = [self._shape(i, s) for i, s in enumerate(d["shapes"])]
        self._shapes_json: str | None = None
        self._shape_texts: list[str | None] = [None] * len(self._shapes)
        self._shapes_plain: list | None = None
        self._check_camera()
        self._check_nesting()
        self._check_crossing()
        self._check_lights()
        # Resolve at every default band: unknown material names and tables that miss a
        # band fail here, at load time, rather than mid-render.
        for wl in d["render"]["bands"]:
            self._band(wl)

    # -- properties -----------------------------------------------------------------

    @property
    def resolution(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        w, h = self.description["camera"]["resolution"]
        return int(w), int(h)

    @property
    def bands(self) -> list[float]:
        """The scene's default wavelength bands [nm] (``render.bands``)."""
        return list(self.description["render"]["bands"])

    @property
    def render_defaults(self) -> dict:
        """The scene's ``[render]`` table (defaults for ``dentalux.render``)."""
        return dict(self.description["render"])

    @property
    def has_dielectrics(self) -> bool:
        """Whether any shape bounds a medium (then the volume integrators apply)."""
        return any(s["boundary"]["kind"] == "dielectric" for s in self.description["shapes"])

    @property
    def default_integrator(self) -> str:
        """``render.integrator``, else ``vpm`` with dielectric media and ``pm`` without."""
        given = self.description["render"]["integrator"]
        return given or ("vpm" if self.has_dielectrics else "pm")

    @property
    def hash(self) -> str:
        """SHA-256 of the normalised description and the bytes of every file it reads."""
        if self._hash is None:
            blob = json.dumps({"description": self.description, "files": self._files},
                              sort_keys=True, separators=(",", ":"), default=_array_digest)
            self._hash = hashlib.sha256(blob.encode()).hexdigest()
        return self._hash

    def summary(self) -> dict:
        """Counts and names, for ``dentalux scene check``."""
        d = self.description
        return {
            "name": d["scene"]["name"],
            "source": self.source,
            "hash": self.hash,
            "resolution": list(self.resolution),
            "bands_nm": self.bands,
            "integrator": self.default_integrator,
            "media": self.media_names,
            "surfaces": self.surface_names,
            "shapes": [s["type"] for s in d["shapes"]],
            "lights": [s["type"] for s in d["lights"]],
            "triangles": sum(len(s["triangles"]) for s in self._shapes if s["type"] == "mesh"),
        }

    # -- geometry (band independent) ---------------------------------------------------

    def _file(self, name: str, key: str, kind: str) -> Path:
        """The checked path of a mesh or image file (dentalux.scene.files)."""
        from dentalux.scene.files import scene_file

        f = scene_file(name, self.base_dir, key, kind, self.allow_outside_paths)
        self._file_names[key] = name
        return f

    def files_read(self) -> list[dict]:
        """Every file this scene read: its scene key, its name as the scene gives it and
        the SHA-256 of its bytes (``render.json``'s ``files_read``)."""
        return [{"key": k, "file": self._file_names.get(k), "sha256": v}
                for k, v in sorted(self._files.items())]

    def _load_images(self) -> dict[str, dict]:
        out = {}
        for name, s in self.description["surfaces"].items():
            if s["type"] != "image":
                continue
            path = f"surfaces.{name}.file"
            if s["file"] is None:
                out[name] = {"width": s["width"], "height": s["height"], "data": s["data"]}
                continue
            f = self._file(s["file"], path, "image")
            from PIL import Image

            from dentalux.limits import check_texture

            try:
                img = Image.open(f)
            except Exception as exc:
                raise fail(path, s["file"], f"cannot read the image ({exc})") from None
            check_texture(img.width, img.height, f"{path} = '{s['file']}'")
            try:
                img.load()
            except Exception as exc:
                raise fail(path, s["file"], f"cannot read the image ({exc})") from None
            grey = np.asarray(img.convert("F"), dtype=float) / 255.0
            self._files[path] = _file_digest(f)
            out[name] = {"width": int(grey.shape[1]), "height": int(grey.shape[0]),
                         "data": [float(x) for x in np.clip(grey, 0, 1).ravel()]}
        return out

    def texels(self) -> int:
        """Pixels of all image textures (band independent, but part of every band's
        surfaces in the contract scene)."""
        return sum(int(img["width"]) * int(img["height"]) for img in self._images.values())

    def _boundary(self, b: dict) -> dict:
        if b["kind"] == "opaque":
            return {"kind": "opaque", "surface": self.surface_names.index(b["surface"])}
        return {"kind": "dielectric", "inside": self.media_names.index(b["inside"]),
                "outside": self.media_names.index(b["outside"])}

    def _shape(self, i: int, s: dict) -> dict:
        path = f"shapes[{i}]"
        m = tf.compose(s["transform"])
        out: dict[str, Any] = {"type": s["type"]}
        if s["type"] == "quad":
            corner = tf.apply_point(m, s["corner"])
            u, v = tf.apply_vector(m, s["u"]), tf.apply_vector(m, s["v"])
            out.update(corner=corner.tolist(), u=u.tolist(), v=v.tolist())
        elif s["type"] == "sphere":
            out.update(center=s["center"], radius=s["radius"])
        elif s["type"] == "box":
            out.update(min=s["min"], max=s["max"])
        elif s["type"] == "cylinder":
            axis = np.asarray(s["axis"]) / np.linalg.norm(s["axis"])
            out.update(center=s["center"], axis=axis.tolist(), radius=s["radius"],
                       height=s["height"])
        elif s["type"] == "mesh":
            if s["file"] is not None:
                f = self._file(s["file"], f"{path}.file", "mesh")
                data = load_mesh(f, f"{path}.file", s["file"])
                self._files[f"{path}.file"] = _file_digest(f)
            else:
                data = MeshData(s["positions"], s["triangles"], s["uvs"])
            if s["boundary"]["kind"] == "dielectric":
                data = check_closed(data, path)
            # numpy arrays until serialised (see _plain_shapes and to_json)
            out.update(positions=data.positions, triangles=data.triangles, uvs=data.uvs)
        out["boundary"] = self._boundary(s["boundary"])
        if s["type"] != "quad":
            out["transform"] = _identity_or(m)
        return out

    def _shape_text(self, i: int) -> str:
        """Shape ``i`` as contract JSON, serialised once for the inside tests and to_json."""
        text = self._shape_texts[i]
        if text is None:
            text = self._shape_texts[i] = _contract_json(self._shapes[i])
        return text

    def _inside(self, i: int, points) -> np.ndarray:
        """Whether each of ``points`` (n, 3) lies strictly inside shape ``i`` (the core's test,
        as :func:`shape_contains`). A mesh is asked only about points within its bounds:
        nothing beyond them is inside, and serialising a tooth's mesh costs more than all the
        checks together."""
        pts = np.asarray(points, dtype=float).reshape(-1, 3)
        ask = np.ones(len(pts), dtype=bool)
        if self._shapes[i]["type"] == "mesh":
            c = self._corners(self._shapes[i])
            pad = 1e-9 * (1.0 + float(np.abs(c).max()))  # rounding of the transform
            ask = np.all((pts > c.min(axis=0) - pad) & (pts < c.max(axis=0) + pad), axis=1)
        out = np.zeros(len(pts), dtype=bool)
        if ask.any():
            out[ask] = _core.shape_contains(self._shape_text(i), pts[ask].tolist())
        return out

    def _check_camera(self) -> None:
        cam = self.description["camera"]
        inside = [bool(self._inside(i, [cam["position"]])[0]) for i in range(len(self._shapes))]
        for i, shape in enumerate(self._shapes):
            if not inside[i]:
                continue
            b = self.description["shapes"][i]["boundary"]
            if b["kind"] == "opaque":
                raise fail("camera.position", cam["position"],
                           f"inside the opaque shapes[{i}] ({shape['type']}); move the camera "
                           "out of it")
            if b["inside"] != cam["medium"] and not self._medium_ok(inside, cam["medium"]):
                raise fail("camera.medium", cam["medium"],
                           f"the camera is inside shapes[{i}], whose inside medium is "
                           f"'{b['inside']}'; set camera.medium = '{b['inside']}'")

    def _corners(self, shape: dict) -> np.ndarray:
        """The 8 world-space corners of a shape's object-space bounding box."""
        return self._box_points(shape, 2)

    def _box_points(self, shape: dict, n: int, interior: bool = False) -> np.ndarray:
        """World-space points of an n x n x n grid over a shape's object-space bounding box:
        its corners, or with ``interior`` the grid cells' centres (strictly inside the
        box, so shapes that only touch share none of them)."""
        if shape["type"] == "sphere":
            c, r = np.asarray(shape["center"]), shape["radius"]
            lo, hi = c - r, c + r
        elif shape["type"] == "box":
            lo, hi = np.asarray(shape["min"]), np.asarray(shape["max"])
        elif shape["type"] == "cylinder":
            c, a = np.asarray(shape["center"]), np.asarray(shape["axis"])
            ends = np.array([c, c + shape["height"] * a])
            # a disc of radius r about unit axis a spans r * sqrt(1 - a_i^2) along axis i
            ext = shape["radius"] * np.sqrt(np.clip(1 - a * a, 0, 1))
            lo, hi = ends.min(axis=0) - ext, ends.max(axis=0) + ext
        else:
            pos = np.asarray(shape["positions"])
            lo, hi = pos.min(axis=0), pos.max(axis=0)
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        t = (np.arange(n) + 0.5) / n if interior else np.linspace(0.0, 1.0, n)
        axes = [lo[a] + t * (hi[a] - lo[a]) for a in range(3)]
        box = np.array([[x, y, z] for x in axes[0] for y in axes[1] for z in axes[2]])
        return tf.apply_point(np.asarray(shape["transform"]), box)

    #: grid cells per axis that sample a shape's inside for the crossing check
    CROSSING_SAMPLES = 7

    def _check_crossing(self) -> None:
        """Two dielectric spheres, boxes or cylinders may nest or touch, but not overlap in
        part: their boundaries would cross, and a photon between them would be in two media
        at once. Detected by sampling each shape's inside on a 7 x 7 x 7 grid, so an
        overlap thinner than about a seventh of the smaller shape may pass; meshes are
        checked by the core's own nesting rules only (docs/scene-format.md)."""
        shapes, desc = self._shapes, self.description["shapes"]
        convex = [i for i, s in enumerate(desc) if s["boundary"]["kind"] == "dielectric"
                  and shapes[i]["type"] in ("sphere", "box", "cylinder")]
        corners = {i: self._corners(shapes[i]) for i in convex}
        for a, i in enumerate(convex):
            for j in convex[a + 1:]:
                ci, cj = corners[i], corners[j]
                if np.any(ci.max(axis=0) <= cj.min(axis=0)) or \
                        np.any(cj.max(axis=0) <= ci.min(axis=0)):
                    continue  # bounding boxes apart
                frac = []
                for k, other in ((i, j), (j, i)):
                    pts = self._box_points(shapes[k], self.CROSSING_SAMPLES, interior=True)
                    inside = pts[self._inside(k, pts)]
                    hits = int(np.count_nonzero(self._inside(other, inside)))
                    frac.append(hits / max(1, len(inside)))
                if max(frac) == 1.0 or max(frac) == 0.0:
                    continue  # nested (possibly sharing a face), apart or touching
                raise SceneError(
                    f"shapes[{i}] and shapes[{j}]: the two dielectric {desc[i]['type']} and "
                    f"{desc[j]['type']} overlap in part, so their boundaries cross; nest one "
                    "wholly inside the other or move them apart")

    def _check_lights(self) -> None:
        """Lights emit into the scene's ambient medium, so a light inside a dielectric shape
        (a point light inside a disc) is refused rather than traced in the wrong medium."""
        desc = self.description
        where = []
        for lt in desc["lights"]:
            if lt["type"] in ("point", "spot"):
                pos = np.asarray(lt["position"], float)
            elif lt["type"] == "disc":
                pos = np.asarray(lt["center"], float)
            else:
                pos = np.asarray(lt["corner"], float) + 0.5 * (np.asarray(lt["u"], float)
                                                               + np.asarray(lt["v"], float))
            where.append(pos)
        inside = {i: self._inside(i, where) for i, s in enumerate(desc["shapes"])
                  if s["boundary"]["kind"] == "dielectric"}
        for li in range(len(where)):
            for i in inside:
                if inside[i][li]:
                    raise SceneError(
                        f"lights[{li}]: lies inside shapes[{i}] (a dielectric "
                        f"{desc['shapes'][i]['type']}); lights emit into the ambient medium, "
                        "so place them outside every dielectric shape")

    def _volume(self, shape: dict) -> float:
        m = abs(np.linalg.det(np.asarray(shape["transform"])[:3, :3]))
        if shape["type"] == "sphere":
            return m * 4 / 3 * math.pi * shape["radius"] ** 3
        if shape["type"] == "box":
            return m * float(np.prod(np.subtract(shape["max"], shape["min"])))
        return m * math.pi * shape["radius"] ** 2 * shape["height"]

    def _check_nesting(self) -> None:
        """A dielectric shape lying wholly inside another dielectric sphere, box or cylinder
        (all convex, so containing the bounding-box corners is containing the shape) must
        name that container's inside medium as its outside medium (the innermost container
        when there are several)."""
        shapes, desc = self._shapes, self.description["shapes"]
        diel = [i for i, s in enumerate(desc) if s["boundary"]["kind"] == "dielectric"]
        for i in diel:
            corners = None
            containers = []
            for j in diel:
                if j == i or shapes[j]["type"] not in ("sphere", "box", "cylinder"):
                    continue
                if corners is None:
                    corners = self._corners(shapes[i])
                if self._inside(j, corners).all():
                    containers.append(j)
            if not containers:
                continue
            j = min(containers, key=lambda k: self._volume(shapes[k]))
            want = desc[j]["boundary"]["inside"]
            got = desc[i]["boundary"]["outside"]
            if got != want:
                raise fail(f"shapes[{i}].outside", got,
                           f"shapes[{i}] lies inside shapes[{j}], whose inside medium is "
                           f"'{want}'; set outside = '{want}'")

    def _medium_ok(self, inside: list[bool], medium: str) -> bool:
        """Whether some dielectric shape containing the camera (``inside``: per shape) has
        ``medium`` inside (nesting)."""
        for i, s in enumerate(self.description["shapes"]):
            b = s["boundary"]
            if b["kind"] == "dielectric" and b["inside"] == medium and inside[i]:
                return True
        return False

    # -- per band ---------------------------------------------------------------------

    def medium_at(self, name: str, wavelength_nm: float) -> dict:
        """One medium at one band in contract form (mua, mus [1/mm], n, phase)."""
        m = self.description["media"][name]
        path = f"media.{name}"
        if m["material"] is not None:
            values = _material_at(m["material"], wavelength_nm, f"{path}.material")
        else:
            values = {**MEDIUM_FALLBACK, "lobes": None}
        for key in MEDIUM_FALLBACK:
            if m[key] is not None:
                values[key] = spectrum_at(m[key], wavelength_nm, f"{path}.{key}")
        if m["lobes"] is not None:
            values["lobes"] = m["lobes"]
        _check_medium_values(values, path)
        return {"name": name, "mua": values["mua"], "mus": values["mus"], "n": values["n"],
                "phase": {"g": values["g"], "fd": values["fd"], "lobes": values["lobes"]}}

    def _surface_at(self, name: str, wavelength_nm: float) -> dict:
        s = self.description["surfaces"][name]
        path = f"surfaces.{name}"
        if s["type"] == "lambertian":
            return {"type": "lambertian",
                    "reflectance": spectrum_at(s["reflectance"], wavelength_nm,
                                               f"{path}.reflectance")}
        if s["type"] == "checker":
            return {"type": "checker", "a": spectrum_at(s["a"], wavelength_nm, f"{path}.a"),
                    "b": spectrum_at(s["b"], wavelength_nm, f"{path}.b"), "size": s["size"],
                    "mapping": s["mapping"]}
        if s["type"] == "image":
            img = self._images[name]
            data = img["data"] if s["scale"] == 1.0 else \
                [min(1.0, x * s["scale"]) for x in img["data"]]
            out = {"type": "image", "width": img["width"], "height": img["height"],
                   "data": data, "mapping": s["mapping"]}
            if s["size"] is not None:
                out["size"] = s["size"]
            return out
        return {"type": "black"}

    def light_relative(self, i: int, wavelength_nm: float) -> float:
        """Light ``i``'s relative spectrum at ``wavelength_nm``: the factor its radiance or
        intensity is multiplied by in the band's contract scene."""
        s = self.description["lights"][i]
        path = f"lights[{i}].spectrum"
        if s["spectrum"] == "D65":
            return d65_relative(wavelength_nm, path)
        if s["spectrum"] == "flat":
            return 1.0
        return spectrum_at(s["spectrum"], wavelength_nm, path)

    def illuminant(self, bands) -> tuple[np.ndarray, str, float]:
        """The light the render's colour is read under: (the lights' relative spectrum at
        ``bands``, the CIE illuminant it is, the brightest light's radiance scale) when every
        light has the same named spectrum (D65 or flat: E); else (ones, E, 1), the radiance
        then being the colour stimulus itself. Dividing a band's radiance by the first and
        the third gives the radiance factor against that light, the quantity the colour
        maths interpolates between bands (it is smooth where the light's spectrum is not)."""
        lights = self.description["lights"]
        kinds = {lt["spectrum"] if isinstance(lt["spectrum"], str) else "table"
                 for lt in lights}
        if len(kinds) != 1 or kinds == {"table"}:
            return np.ones(len(bands)), "E", 1.0
        rel = np.array([self.light_relative(0, wl) for wl in bands])
        white = max(lt.get("radiance", lt.get("intensity", 1.0)) for lt in lights)
        return rel, ("D65" if kinds == {"D65"} else "E"), float(white)

    def _light_at(self, i: int, wavelength_nm: float) -> dict:
        s = self.description["lights"][i]
        rel = self.light_relative(i, wavelength_nm)
        kind = s["type"]
        if kind == "quad":
            return {"type": "quad", "corner": s["corner"], "u": s["u"], "v": s["v"],
                    "radiance": s["radiance"] * rel}
        if kind == "disc":
            n = np.asarray(s["normal"]) / np.linalg.norm(s["normal"])
            return {"type": "disc", "center": s["center"], "normal": n.tolist(),
                    "radius": s["radius"], "radiance": s["radiance"] * rel}
        if kind == "point":
            return {"type": "point", "position": s["position"],
                    "intensity": s["intensity"] * rel}
        d = np.asarray(s["direction"]) / np.linalg.norm(s["direction"])
        return {"type": "spot", "position": s["position"], "direction": d.tolist(),
                "intensity": s["intensity"] * rel, "cone_deg": s["cone_deg"],
                "falloff_deg": s["falloff_deg"]}

    def _band(self, wavelength_nm: float, resolution: tuple[int, int] | None = None) -> dict:
        """Everything of the contract scene for one band [nm] except the shapes."""
        wl = float(wavelength_nm)
        cam = self.description["camera"]
        w, h = resolution if resolution is not None else self.resolution
        return {
            "camera": camera_contract(cam, w, h),
            "ambient_medium": self.media_names.index(cam["medium"]),
            "media": [self.medium_at(n, wl) for n in self.media_names],
            "surfaces": [self._surface_at(n, wl) for n in self.surface_names],
            "lights": [self._light_at(i, wl) for i in range(len(self.description["lights"]))],
        }

    def _plain_shapes(self) -> list[dict]:
        """The shapes with mesh arrays as nested lists (built once)."""
        if self._shapes_plain is None:
            self._shapes_plain = [
                {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in s.items()}
                for s in self._shapes
            ]
        return self._shapes_plain

    def resolve(self, wavelength_nm: float, resolution: tuple[int, int] | None = None) -> dict:
        """The render-contract scene dict for one band [nm] (plain lists, JSON-ready)."""
        return {**self._band(wavelength_nm, resolution), "shapes": self._plain_shapes()}

    def _shapes_text(self) -> str:
        """The shapes as JSON (band independent, and large for meshes): serialised once."""
        if self._shapes_json is None:
            # json.dumps(self._shapes)'s bytes, from the texts the inside tests serialised
            texts = [self._shape_text(i) for i in range(len(self._shapes))]
            self._shapes_json = "[" + ",".join(texts) + "]"
        return self._shapes_json

    def to_json(self, wavelength_nm: float, resolution: tuple[int, int] | None = None) -> str:
        """:meth:`resolve` as the JSON string ``render_band`` takes."""
        head = json.dumps(self._band(wavelength_nm, resolution), separators=(",", ":"))
        return head[:-1] + ',"shapes":' + self._shapes_text() + "}"

    def bands_json(self, bands, resolution: tuple[int, int] | None = None) -> str:
        """The multi-band scene JSON ``render_bands`` takes (docs/render-contract.md): the
        camera, ambient medium and shapes once, and each band's media, surfaces and lights
        in ``bands``, so the core decodes the shapes and builds their BVH once."""
        parts = [self._band(wl, resolution) for wl in bands]
        head = {k: parts[0][k] for k in ("camera", "ambient_medium")}
        head["bands"] = [{k: p[k] for k in ("media", "surfaces", "lights")} for p in parts]
        text = json.dumps(head, separators=(",", ":"))
        return text[:-1] + ',"shapes":' + self._shapes_text() + "}"
