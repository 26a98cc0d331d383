"""The ``tooth`` shape: one scene entry that expands to a tooth's two dielectric boundaries.

```toml
[[shapes]]
type = "tooth"
model = "incisor"        # incisor | molar (procedural, dentalux.teeth), or give files:
# enamel_file = "scan_enamel.obj"; dentin_file = "scan_dentin.obj"
resolution = 0.2         # mm, grid spacing of the procedural mesh
enamel = "enamel"        # medium inside the outer surface (a crown: e.g. "crown")
dentin = "dentin"        # medium inside the dentin surface
outside = "air"          # medium around the tooth
transform = { translate = [0.0, 0.0, 0.0] }
```

It becomes a mesh ``NAME enamel`` (inside ``enamel``, outside ``outside``) and a mesh
``NAME dentin`` (inside ``dentin``, outside ``enamel``), both with the entry's transform. The
procedural teeth's frame and the thin layer over the root are described in docs/teeth.md.
"""

from __future__ import annotations

import difflib
from functools import lru_cache

from dentalux.scene.schema import SceneError, validate_shape

TOOTH_KEYS = {"type": "tooth", "name": "tooth", "model": None, "enamel_file": None,
              "dentin_file": None, "resolution": 0.2, "enamel": "enamel", "dentin": "dentin",
              "outside": "air", "transform": None}
MODELS = ("incisor", "molar")


@lru_cache(maxsize=8)
def _procedural(model: str, resolution: float):
    from dentalux import teeth

    return getattr(teeth, model)(resolution=resolution)


def _geometry(path: str, d: dict) -> list[dict]:
    """Mesh keys of the two surfaces: inline arrays for a procedural tooth, file names
    (read later relative to the scene file, like any mesh) for a scanned one."""
    files = (d["enamel_file"], d["dentin_file"])
    if d["model"] is not None:
        if any(f is not None for f in files):
            raise SceneError(f"{path}: give either model or enamel_file/dentin_file")
        if d["model"] not in MODELS:
            raise SceneError(f"{path}.model = {d['model']!r}: allowed {', '.join(MODELS)}")
        res = d["resolution"]
        if isinstance(res, bool) or not isinstance(res, int | float) or not 0.05 <= res <= 1.0:
            raise SceneError(f"{path}.resolution = {res!r}: out of range, allowed [0.05, 1] mm")
        tooth = _procedural(d["model"], float(res))
        return [{"positions": v, "triangles": f} for v, f in (tooth.enamel, tooth.dentin)]
    if any(f is None for f in files):
        raise SceneError(f"{path}: give model (incisor | molar) or both enamel_file and "
                         "dentin_file")
    return [{"file": f} for f in files]


def expand_shape(i: int, s) -> list[dict]:
    """Validate shape ``i``; a ``tooth`` entry gives its two validated mesh shapes."""
    if not (isinstance(s, dict) and s.get("type") == "tooth"):
        return [validate_shape(i, s)]
    path = f"shapes[{i}]"
    for key in s:
        if key not in TOOTH_KEYS:
            close = difflib.get_close_matches(key, TOOTH_KEYS, n=1, cutoff=0.6)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise SceneError(f"{path}.{key}: unknown key; {hint}(allowed: "
                             f"{', '.join(TOOTH_KEYS)})")
    d = {**TOOTH_KEYS, **s}
    enamel, dentin = _geometry(path, d)
    parts = ((enamel, d["enamel"], d["outside"], "enamel"),
             (dentin, d["dentin"], d["enamel"], "dentin"))
    out = []
    for geometry, inside, outside, part in parts:
        mesh = {"type": "mesh", "name": f"{d['name']} {part}", **geometry,
                "inside": inside, "outside": outside}
        if d["transform"] is not None:
            mesh["transform"] = d["transform"]
        out.append(validate_shape(i, mesh))
    return out
