"""Where a world point lands on the film: image regions (the crown figure's measured squares,
a user's ``[regions]`` placed by a 3-D point) must use the render's own camera, whose image
right is forward × up (a camera looking along +z with +y up sees +x on the left). The core
does the projection (``Camera::project``, the inverse of its camera rays), so the convention
has one home.
"""

from __future__ import annotations

import json

import numpy as np

from dentalux import _core
from dentalux.scene.resolve import camera_contract
from dentalux.scene.schema import validate_camera


def project(camera: dict, points) -> np.ndarray:
    """Pixel positions (x, y) of world ``points`` [mm], shape (n, 3), on the film of a scene
    description's ``camera`` (position, look_at, up, fov_deg, resolution); x from the left,
    y from the top. A point behind the camera gives (nan, nan)."""
    cam = validate_camera(camera)
    contract = camera_contract(cam, *cam["resolution"])
    pts = np.atleast_2d(np.asarray(points, float))
    if pts.shape[-1] != 3:
        raise ValueError(f"points: expected shape (n, 3), got {pts.shape}")
    out = _core.camera_project(json.dumps(contract), [tuple(p) for p in pts.tolist()])
    return np.array([p if p is not None else (np.nan, np.nan) for p in out], float)


def square_region(camera: dict, centre, half_mm: float, facing=(0.0, 0.0, -1.0)) -> list[int]:
    """The pixel rectangle [x0, y0, x1, y1) covering a square of half-size ``half_mm`` [mm]
    centred on world point ``centre`` in the plane whose normal is ``facing`` (towards the
    camera), clipped to the film."""
    c = np.asarray(centre, float)
    n = np.asarray(facing, float) / np.linalg.norm(facing)
    u = np.cross(n, [0.0, 1.0, 0.0] if abs(n[1]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    corners = [c + half_mm * (su * u + sv * v) for su in (-1, 1) for sv in (-1, 1)]
    xy = project(camera, corners)
    if np.isnan(xy).any():
        raise ValueError(f"region centre {c.tolist()}: behind the camera")
    w, h = validate_camera(camera)["resolution"]
    x0, y0 = np.floor(xy.min(axis=0)).astype(int)
    x1, y1 = np.ceil(xy.max(axis=0)).astype(int)
    return [max(0, int(x0)), max(0, int(y0)), min(int(w), int(x1)), min(int(h), int(y1))]
