"""The slab simulator: what a spectrophotometer with an integrating sphere measures.

A stack of homogeneous layers (infinite in x and y) lit from above by a collimated beam or by
diffuse light. The photon transport runs in the Rust core; this module validates nothing
itself beyond types (the core names the field and its allowed range) and packages results.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import asdict, dataclass, field
from numbers import Real

from dentalux import _core, limits
from dentalux.progress import bar

# the result's scalar keys, in the core's order (integrators/slab.rs SCALAR_KEYS)
SCALARS = tuple(_core.SLAB_SCALAR_KEYS)


@dataclass(frozen=True)
class Layer:
    """One homogeneous layer.

    mua, mus: absorption and scattering coefficients [1/mm]; g: HG asymmetry in (-1, 1);
    n: refractive index (>= 1); thickness [mm]; fd: isotropic fraction of eq. 10 in [0, 1];
    lobes: optional ((weight, g), ...) for a multi-lobe HG phase function (eq. 8), which then
    replaces g and fd.
    """

    mua: float
    mus: float
    g: float = 0.0
    n: float = 1.0
    thickness: float = 1.0
    fd: float = 0.0
    lobes: tuple[tuple[float, float], ...] | None = None

    def as_tuple(self, index: int) -> tuple:
        for name in ("mua", "mus", "g", "n", "thickness", "fd"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, Real):
                raise ValueError(
                    f"layers[{index}].{name} = {value!r}: must be a number"
                )
        lobes = limits.check_lobes(self.lobes, f"layers[{index}].lobes")
        # the binding's layer tuple: the fields in their order (_core.pyi LayerTuple)
        return (
            float(self.mua),
            float(self.mus),
            float(self.g),
            float(self.n),
            float(self.thickness),
            float(self.fd),
            lobes,
        )


@dataclass
class SlabResult:
    """Fractions of the incident power, each with its standard error in ``stderr``.

    ``diffuse_reflectance`` is everything that leaves the top except the first-surface
    specular reflection (as MCML's Rd), so it includes unscattered light reflected back by
    the lower interfaces.
    """

    specular_reflectance: float
    diffuse_reflectance: float
    total_reflectance: float
    unscattered_transmittance: float
    diffuse_transmittance: float
    total_transmittance: float
    absorbed: float
    absorbed_per_layer: list[float]
    stderr: dict[str, float]
    photons: int
    seconds: float
    photons_per_second: float
    threads: int
    radial_reflectance: list[float] = field(default_factory=list)
    radial_transmittance: list[float] = field(default_factory=list)
    angular_reflectance: list[float] = field(default_factory=list)
    angular_transmittance: list[float] = field(default_factory=list)
    window: dict[str, float] = field(default_factory=dict)
    window_stderr: dict[str, float] = field(default_factory=dict)
    #: "lanes" (photons stepped together in vector lanes) or "scalar" (one at a time)
    walk: str = "scalar"

    def to_dict(self) -> dict:
        """The result as the command line's JSON contract has it (``walk`` is not part of
        the contract)."""
        d = asdict(self)
        d.pop("walk")
        if not self.window:  # only a run with an instrument window has these tallies
            d.pop("window")
            d.pop("window_stderr")
        return d


def parse_incidence(incidence: str) -> tuple[str, float]:
    """``normal`` | ``diffuse`` | ``angle:DEG`` -> (kind, degrees)."""
    if incidence in ("normal", "diffuse"):
        return incidence, 0.0
    if isinstance(incidence, str) and incidence.startswith("angle:"):
        try:
            deg = float(incidence.split(":", 1)[1])
        except ValueError:
            deg = math.nan
        if not (0.0 <= deg < 90.0):
            raise ValueError(
                f"incidence = {incidence!r}: the angle must be a number in [0, 90) degrees"
            )
        return "angle", deg
    raise ValueError(
        f"incidence = {incidence!r}: allowed 'normal', 'diffuse' or 'angle:DEG'"
    )


def window_tuple(window: tuple | None) -> tuple | None:
    """The core's seven-element window tuple from ``window`` (the seven elements, or the
    five-element form of two discs: inner radii 0)."""
    if window is None:
        return None
    if not isinstance(window, (tuple, list)) or len(window) not in (5, 7):
        raise ValueError(f"window = {window!r}: expected (illuminated_inner_radius, "
                         "illuminated_radius, viewed_inner_radius, viewed_radius, "
                         "specimen_radius, backing, cone) or (illuminated_radius, "
                         "viewed_radius, specimen_radius, backing, cone)")
    if len(window) == 5:
        a, b, spec, backing, cone = window
        return (0.0, a, 0.0, b, spec, backing, cone)
    return tuple(window)


def simulate(
    layers: list[Layer],
    n_photons: int = 100_000,
    seed: int = 0,
    n_above: float = 1.0,
    n_below: float = 1.0,
    incidence: str = "normal",
    estimator: str = "analog",
    threads: int | None = None,
    radial: tuple[int, float] | None = None,
    angular_bins: int | None = None,
    band: int = 0,
    window: tuple | None = None,
    progress: bool | None = False,
    walk: str = "auto",
) -> SlabResult:
    """Simulate a layered slab lit from above; see :class:`SlabResult`.

    ``radial=(bins, r_max_mm)`` adds R(r), T(r) per unit area [1/mm^2]; ``angular_bins``
    adds exit-angle histograms over [0, 90) degrees. ``window=(illuminated_inner_radius,
    illuminated_radius, viewed_inner_radius, viewed_radius, specimen_radius, backing, cone)``
    puts an instrument's lit region, window [mm], backing reflectance and detector cone
    ((low, high) degrees or None) into the run (see :mod:`dentalux.instrument`): photons
    enter uniformly over the lit disc (inner radius 0) or ring, and an exit is read when its
    distance from the centre lies in [viewed_inner_radius, viewed_radius]. The five-element
    form ``(illuminated_radius, viewed_radius, specimen_radius, backing, cone)`` is the two
    discs. Its tallies come back in ``window``. The same ``seed`` gives the same numbers for
    any ``threads``.

    ``walk="auto"`` steps photons together in vector lanes where that walk applies (the
    weighted estimator with no window and no radial or angular profile), on every CPU to
    the same bits; ``walk="scalar"`` walks one photon at a time (the reference the lanes
    are tested against). ``SlabResult.walk`` says which ran.
    """
    if walk not in ("auto", "scalar"):
        raise ValueError(f"walk = {walk!r}: allowed 'auto' or 'scalar'")
    if isinstance(layers, Layer):
        layers = [layers]
    layers = limits.check_layers(layers)
    tuples = []
    for i, layer in enumerate(layers):
        if not isinstance(layer, Layer):
            raise ValueError(f"layers[{i}] must be a dentalux.Layer, got {type(layer).__name__}")
        tuples.append(layer.as_tuple(i))
    n_photons = limits.check_slab(n_photons, threads, radial[0] if radial else None,
                                  angular_bins, seed=seed, band=band)
    seed = int(seed)
    window = window_tuple(window)
    kind, deg = parse_incidence(incidence)
    # rayon's default pool follows the CPUs this process may run on
    n_threads = threads or (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                            else os.cpu_count() or 1)
    start = time.perf_counter()
    with bar(n_photons, "photons", progress) as cb:
        raw = _core.slab_simulate(
            tuples,
            n_photons,
            seed,
            n_above=float(n_above),
            n_below=float(n_below),
            incidence=kind,
            angle_deg=deg,
            estimator=estimator,
            threads=threads,
            band=band,
            radial=radial,
            angular_bins=angular_bins,
            window=window,
            progress=cb,
            lanes=walk == "auto",
        )
    seconds = time.perf_counter() - start
    return SlabResult(
        **{k: raw[k] for k in SCALARS},
        absorbed_per_layer=raw["absorbed_per_layer"],
        stderr=raw["stderr"],
        photons=raw["photons"],
        seconds=seconds,
        photons_per_second=raw["photons"] / seconds if seconds > 0 else math.inf,
        threads=n_threads,
        radial_reflectance=raw["radial_reflectance"],
        radial_transmittance=raw["radial_transmittance"],
        angular_reflectance=raw["angular_reflectance"],
        angular_transmittance=raw["angular_transmittance"],
        window=raw.get("window", {}),
        window_stderr=raw.get("window_stderr", {}),
        walk=raw["walk"],
    )
