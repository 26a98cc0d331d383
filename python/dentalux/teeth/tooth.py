"""A procedural tooth: two nested closed meshes and the checks that make them usable.

Frame (all teeth): millimetres; the long axis is +z with the crown up (incisal edge or
cusps at +z) and the cementoenamel junction (CEJ) in the plane z = 0; +y is the labial
(incisors) or buccal (molars) side; x runs mesio-distally. The root goes to -z.

Two boundaries, as the render contract wants them:

- ``enamel``: the outer surface of the whole tooth (air | enamel; inside = enamel). Over the
  crown it is the enamel surface; over the root it lies ``root_layer_mm`` outside the dentin.
- ``dentin``: the dentin surface (enamel | dentin; inside = dentin), strictly inside
  ``enamel``.

Over the root the gap between them is a thin layer (default 0.08 mm, thinner than root
cementum) that a scene fills with the enamel medium: it keeps the two surfaces disjoint, so
each can be one closed dielectric boundary with a fixed inside and outside.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from dentalux.teeth.mesh import (
    Mesh,
    area,
    edge_check,
    euler_characteristic,
    intersects,
    read_obj,
    signed_volume,
    vertex_normals,
    winding_number,
    write_obj,
)

FRAME = ("mm; long axis +z (crown up), CEJ at z = 0, +y labial/buccal, x mesio-distal, "
         "root towards -z")


class MeshError(ValueError):
    """A tooth mesh failed a check (open, mis-oriented, or the shells intersect)."""


@dataclass
class Tooth:
    """Two nested closed meshes (vertices [mm], faces) of one tooth; see the module doc."""

    name: str
    enamel: Mesh
    dentin: Mesh
    resolution: float
    targets: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    frame: str = FRAME

    def enamel_thickness(self) -> tuple[np.ndarray, np.ndarray]:
        """(enamel vertices, distance [mm] from each to the dentin surface). The dentin
        surface is sampled at its vertices, edge midpoints and face centroids, so distances
        are upper bounds, high by at most about a third of an edge length."""
        vd, fd = self.dentin
        tri = vd[fd]
        samples = np.concatenate([vd, tri.mean(axis=1), 0.5 * (tri[:, 0] + tri[:, 1]),
                                  0.5 * (tri[:, 1] + tri[:, 2]), 0.5 * (tri[:, 2] + tri[:, 0])])
        ve = self.enamel[0]
        dist, _ = cKDTree(samples).query(ve)
        return ve, dist

    def dimensions(self) -> dict:
        """Measured crown width (x), crown thickness (y), crown length (max z) and root
        length (-min z) [mm] from the enamel mesh."""
        ve = self.enamel[0]
        crown = ve[ve[:, 2] > 0]
        return {
            "crown_width_mm": float(np.ptp(crown[:, 0])),
            "crown_thickness_mm": float(np.ptp(crown[:, 1])),
            "crown_length_mm": float(crown[:, 2].max()),
            "root_length_mm": float(-ve[:, 2].min()),
        }

    def thickness_profile(self, bins: int = 10) -> list[dict]:
        """Median enamel thickness [mm] of the labial/buccal face (y > 0, |x| < 1.5 mm) in
        ``bins`` height bands from the CEJ to the top of the crown."""
        ve, t = self.enamel_thickness()
        top = ve[:, 2].max()
        sel = (ve[:, 1] > 0) & (np.abs(ve[:, 0]) < 1.5) & (ve[:, 2] >= 0)
        edges = np.linspace(0.0, top, bins + 1)
        out = []
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            m = sel & (ve[:, 2] >= lo) & (ve[:, 2] < hi)
            out.append({"z_mm": [float(lo), float(hi)],
                        "median_mm": float(np.median(t[m])) if m.any() else None})
        return out

    def check(self, samples: int = 100) -> dict:
        """Verify both meshes are closed and outward-oriented, the surfaces do not cross
        (every edge of each tested against the other's triangles) and sampled dentin
        vertices lie inside the enamel (generalised winding number ~ 1). With no crossing,
        one inside point already puts the whole connected dentin surface inside; the
        ``samples`` points guard against a detached piece. Returns statistics (counts,
        volumes, areas, enamel thickness, dimensions); raises :class:`MeshError`."""
        stats: dict = {"name": self.name, "resolution_mm": self.resolution}
        for part in ("enamel", "dentin"):
            v, f = getattr(self, part)
            ec = edge_check(f)
            vol = signed_volume(v, f)
            stats[part] = {"vertices": int(len(v)), "triangles": int(len(f)),
                           "volume_mm3": vol, "area_mm2": area(v, f),
                           "euler_characteristic": euler_characteristic(v, f), **ec}
            if not ec["closed"]:
                raise MeshError(f"{self.name}.{part}: not closed ({ec['boundary_edges']} "
                                f"boundary, {ec['nonmanifold_edges']} non-manifold edges)")
            if not ec["oriented"]:
                raise MeshError(f"{self.name}.{part}: inconsistent orientation "
                                f"({ec['repeated_directed_edges']} repeated directed edges)")
            if vol <= 0:
                raise MeshError(f"{self.name}.{part}: negative volume {vol:.3f} mm^3 "
                                "(normals point inward)")
        vd = self.dentin[0]
        pick = np.linspace(0, len(vd) - 1, min(samples, len(vd))).astype(int)
        w = winding_number(vd[pick], *self.enamel)
        crossings = intersects(self.dentin, self.enamel) + intersects(self.enamel, self.dentin)
        stats["nesting"] = {"dentin_samples": int(len(pick)),
                            "min_winding_number": float(w.min()),
                            "edge_triangle_crossings": int(crossings)}
        if w.min() < 0.5:
            raise MeshError(f"{self.name}: {int(np.sum(w < 0.5))} of {len(pick)} sampled dentin "
                            "vertices lie outside the enamel surface")
        if crossings:
            raise MeshError(f"{self.name}: enamel and dentin surfaces cross ({crossings} "
                            "edge-triangle intersections)")
        ve, t = self.enamel_thickness()
        crown = ve[:, 2] > 0
        stats["enamel_thickness_mm"] = {
            "crown_min": float(t[crown].min()), "crown_max": float(t[crown].max()),
            "root_median": float(np.median(t[~crown])) if (~crown).any() else None,
            "labial_profile": self.thickness_profile(),
        }
        stats["dimensions"] = self.dimensions()
        stats["targets"] = self.targets
        stats["triangles_total"] = stats["enamel"]["triangles"] + stats["dentin"]["triangles"]
        stats["frame"] = self.frame
        return stats

    @classmethod
    def from_obj(cls, enamel_path, dentin_path, name: str = "tooth") -> Tooth:
        """A tooth from two OBJ files (e.g. a scanned outer surface replacing the procedural
        one); run :meth:`check` before rendering it."""
        return cls(name=name, enamel=read_obj(enamel_path), dentin=read_obj(dentin_path),
                   resolution=float("nan"), params={"enamel": str(enamel_path),
                                                    "dentin": str(dentin_path)})

    def shapes(self, enamel: int, dentin: int, outside: int, transform=None) -> list[dict]:
        """The two dielectric boundaries as render-contract ``mesh`` shapes
        (docs/render-contract.md): ``enamel``, ``dentin`` and ``outside`` are media indices;
        ``transform`` an optional 4x4 object-to-world matrix (nested lists)."""
        out = []
        for (v, f), inside, outer in ((self.enamel, enamel, outside),
                                      (self.dentin, dentin, enamel)):
            shape = {"type": "mesh", "positions": v.tolist(), "triangles": f.tolist(),
                     "uvs": None,
                     "boundary": {"kind": "dielectric", "inside": int(inside),
                                  "outside": int(outer)}}
            if transform is not None:
                shape["transform"] = [list(map(float, row)) for row in transform]
            out.append(shape)
        return out

    def write(self, out_dir, stats: dict | None = None) -> dict:
        """Write ``enamel.obj``, ``dentin.obj`` (with area-weighted vertex normals for smooth
        shading) and ``tooth.json`` (dimensions, targets, mesh statistics, frame, parameters)
        into ``out_dir``; returns the JSON content."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        if stats is None:
            stats = self.check()
        head = f"dentalux procedural {self.name}; {self.frame}"
        write_obj(out / "enamel.obj", *self.enamel,
                  comment=f"{head}\nouter surface: inside enamel, outside air",
                  normals=vertex_normals(*self.enamel))
        write_obj(out / "dentin.obj", *self.dentin,
                  comment=f"{head}\ndentin surface: inside dentin, outside enamel",
                  normals=vertex_normals(*self.dentin))
        doc = {"tooth": self.name, "files": {"enamel": "enamel.obj", "dentin": "dentin.obj"},
               "boundaries": {"enamel.obj": {"inside": "enamel", "outside": "air"},
                              "dentin.obj": {"inside": "dentin", "outside": "enamel"}},
               "params": self.params, **stats}
        (out / "tooth.json").write_text(json.dumps(doc, indent=2), encoding="utf-8")
        return doc
