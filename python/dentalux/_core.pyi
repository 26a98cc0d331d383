"""Type stubs of the private native module (see crates/dentalux-py)."""

from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

__version__: str
# facts Python reads instead of keeping copies (crates/dentalux-py/src/lib.rs)
SLAB_MAX_PROFILE_BINS: int
SLAB_SCALAR_KEYS: list[str]
PHOTON_BYTES: int
SLAB_MAX_BACKING_ORDER: int
SLAB_WINDOW_KEYS: list[str]
# random-stream keys of the reading engine's diffuse and transmitted runs (dentalux.reading)
DIFFUSE_RUN_KEY: int
TRANSMITTED_RUN_KEY: int
RIM_RUN_KEY: int
SLAB_MIN_BATCH: int
SLAB_MIN_RIM_BATCH: int

# One layer as Python passes it: dentalux.slab.Layer's fields in their order (mua, mus, g, n,
# thickness, fd, lobes), built by Layer.as_tuple.
LayerTuple = tuple[float, float, float, float, float, float, list[tuple[float, float]] | None]
# An instrument window: (illuminated inner radius, illuminated radius, viewed inner radius,
# viewed radius, specimen radius [mm], backing reflectance, detector cone (low, high) [deg]
# or None). Inner radii 0 are discs; others make rings (annuli).
WindowTuple = tuple[float, float, float, float, float, float, tuple[float, float] | None]

def slab_simulate(
    layers: list[LayerTuple],
    n_photons: int,
    seed: int,
    n_above: float = 1.0,
    n_below: float = 1.0,
    incidence: str = "normal",
    angle_deg: float = 0.0,
    estimator: str = "analog",
    threads: int | None = None,
    band: int = 0,
    radial: tuple[int, float] | None = None,
    angular_bins: int | None = None,
    window: WindowTuple | None = None,
    progress: Callable[[int], None] | None = None,
    lanes: bool = True,
) -> dict: ...
def slab_read_bands(
    bands: list[list[LayerTuple]],
    band_keys: list[int],
    n_photons: int,
    seed: int,
    window: WindowTuple,
    max_order: int,
    survival: float,
    n_above: float = 1.0,
    n_below: float = 1.0,
    incidence: str = "normal",
    angle_deg: float = 0.0,
    estimator: str = "weighted",
    threads: int | None = None,
    progress: Callable[[int], None] | None = None,
    past_rim_only: bool = False,
) -> dict[str, Any]: ...
def slab_read_spectral(
    bands: list[list[LayerTuple]],
    n_photons: int,
    seed: int,
    key: int,
    window: WindowTuple,
    max_order: int,
    survival: float,
    n_above: float = 1.0,
    n_below: float = 1.0,
    incidence: str = "normal",
    angle_deg: float = 0.0,
    threads: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> dict[str, Any]: ...
def phase_sample_cos(
    n: int, g: float, fd: float = 0.0, lobes: list[tuple[float, float]] | None = None, seed: int = 0
) -> list[float]: ...
def phase_eval(
    cos_theta: list[float],
    g: float,
    fd: float = 0.0,
    lobes: list[tuple[float, float]] | None = None,
) -> list[float]: ...
def render_band(
    scene_json: str,
    settings_json: str,
    progress: Callable[[int], None] | None = None,
) -> tuple[npt.NDArray[np.float32], dict[str, float | int | str]]: ...
def render_bands(
    scene_json: str,
    settings_json: str,
    band_keys: list[int],
    progress: Callable[[int], None] | None = None,
) -> tuple[npt.NDArray[np.float32], list[dict[str, float | int | str]]]: ...
def camera_project(
    camera_json: str,
    points: list[tuple[float, float, float]],
) -> list[tuple[float, float] | None]: ...
def shape_contains(
    shape_json: str,
    points: list[tuple[float, float, float]],
) -> list[bool]: ...
def mesh_topology(
    positions: list[tuple[float, float, float]],
    triangles: list[tuple[int, int, int]],
) -> tuple[str, int, bool]: ...
def fresnel_reflectance(cos_i: list[float], eta_i: float, eta_t: float) -> list[float]: ...
def cone_fraction(lo_deg: float, hi_deg: float) -> float: ...
def bessel_j(order: int, x: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
def settings_schema() -> str: ...
def photons_traced(settings_json: str) -> int: ...
def panic_in_worker() -> None: ...
