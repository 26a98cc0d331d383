"""The documented limits on what a user may ask for, and the checks that enforce them.

Every ceiling lives here once: the command-line help, the checks and ``docs/limits.md``
read these constants. A check raises ``ValueError`` (exit code 2 from the command line)
whose message names the field, the value and the allowed range, and for sizes the memory
the request would need next to the memory available, so that nothing is allocated,
started or spawned before an input that cannot work is refused.
"""

from __future__ import annotations

import math
import os
from numbers import Integral, Real

from dentalux import _core
from dentalux.core_schema import INTEGRATOR_INFO

# The colour range [nm]: the CIE colour-matching functions are defined on 360-830 nm (D65
# on 300-830 nm). One rule for every command (docs/limits.md): a band lies in this range
# and, for a material, in its data range unless the material allows extrapolation
# (check_bands_in).
BAND_RANGE_NM = (360.0, 830.0)

# --- counts -------------------------------------------------------------------------------
#: worker threads: 1 ... THREADS_PER_CORE x the logical cores of this machine
THREADS_PER_CORE = 4
#: photons one ``dentalux slab`` run may launch (about 3 hours on 2 cores at 10 M/s)
MAX_SLAB_PHOTONS = 100_000_000_000
#: photons per Monte Carlo evaluation of ``dentalux fit --model mc`` (a fit runs
#: tens to hundreds of evaluations)
MAX_FIT_PHOTONS = 100_000_000
#: CPU-seconds a reading sized by a requested precision (``--precision``) may take: a
#: request beyond it is refused up front with the estimate
MAX_READING_CPU_SECONDS = 3_600.0
#: photons per band of a render: ``photons``, ``volume_photons`` and ``volume_stored``
MAX_RENDER_PHOTONS = 10_000_000_000
#: samples per pixel of a render
MAX_SPP = 1_000_000
#: rings of ``dentalux slab --radial-bins`` and bins of ``--angle-bins``
MAX_RADIAL_BINS = _core.SLAB_MAX_PROFILE_BINS  # the core's ceiling (integrators/slab.rs)
MAX_ANGLE_BINS = 100_000
#: pixels of a rendered image (width x height), e.g. 8192 x 8192
MAX_PIXELS = 67_108_864
#: pixels of an image texture a scene reads (e.g. 4096 x 4096)
MAX_TEXTURE_PIXELS = 16_777_216
#: Dask workers of ``--cluster local:N``: 1 ... this many per logical core
WORKERS_PER_CORE = 2
#: bands of one reading (``shade``, ``report``, ``design``: ``--bands full:STEP`` or a list):
#: 380-780 nm every 0.1 nm; each band is two or three Monte Carlo runs
MAX_READING_BANDS = 4_001
#: nodes per layer of ``dentalux design``'s fast model (default 6, 4, 3 for 1, 2, 3 layers;
#: the spline through them is already finer than the Monte Carlo noise at 6)
MAX_DESIGN_NODES = 64
#: photons one ``design`` search may trace for its fast model (nodes^layers x bands x runs x
#: photons): about 3 hours at PHOTON_RATE
MAX_DESIGN_PHOTONS = 100_000_000_000
#: photons one reading (``shade``, ``report``, ``dental.read``) may trace over all its bands
#: (photons x bands): about 3 hours at PHOTON_RATE
MAX_READING_PHOTONS = 100_000_000_000
#: photons per second assumed for the estimates in refusals (a 2-core machine, slab walk)
PHOTON_RATE = 10_000_000
#: grid nodes of a procedural tooth (``tooth --resolution``): the signed-distance fields and
#: marching cubes take about TOOTH_NODE_SECONDS each on 2 cores (a molar at 0.1 mm: 3.2 M
#: nodes, 31 s; at 0.07 mm: 9.1 M, 75 s), so this is under 2 minutes
MAX_TOOTH_NODES = 10_000_000
TOOTH_NODE_SECONDS = 1e-5

# --- memory -------------------------------------------------------------------------------
#: a request may use at most this fraction of the memory available when it starts
MEMORY_FRACTION = 0.8
#: bytes one stored photon takes in a photon map (the core's record: position, power, direction)
PHOTON_BYTES = _core.PHOTON_BYTES
# integrators that fill volume photon maps (the core's list)
VOLUME_INTEGRATORS = tuple(i["name"] for i in INTEGRATOR_INFO if i["traces_volume_photons"])
#: bytes per pixel and band of a render (the core's film, the radiance cube, previews)
PIXEL_BAND_BYTES = 48
#: bytes per pixel of the colour images (XYZ, sRGB, EXR buffers in float64)
PIXEL_COLOUR_BYTES = 256
#: bytes per grid node of a procedural tooth (signed-distance fields in float64)
TOOTH_NODE_BYTES = 96
#: bytes per texel of an image texture once decoded (a Python float list, JSON, the core)
TEXEL_BYTES = 128


def logical_cores() -> int:
    """Logical cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def max_threads() -> int:
    """The most worker threads a command accepts (THREADS_PER_CORE x logical cores)."""
    return THREADS_PER_CORE * logical_cores()


def max_workers() -> int:
    """The most Dask workers ``--cluster local:N`` accepts."""
    return WORKERS_PER_CORE * logical_cores()


def as_int(value, name: str, lo: int | None = None, hi: int | None = None,
           unit: str = "") -> int:
    """An integer (Python or numpy) within [lo, hi]; ``name`` is the argument or option
    named in the error. bool and non-integral floats are refused; a float that is an exact
    integer (1e6) is accepted."""
    if isinstance(value, bool) or value is None:
        raise TypeError(f"{name} = {value!r}: must be an integer")
    if isinstance(value, Integral):
        n = int(value)
    elif isinstance(value, Real) and math.isfinite(float(value)) \
            and float(value) == int(float(value)):
        n = int(float(value))
    else:
        raise TypeError(f"{name} = {value!r}: must be an integer, got {type(value).__name__}")
    if (lo is not None and n < lo) or (hi is not None and n > hi):
        left = "-inf" if lo is None else f"{lo:,}"
        right = "inf" if hi is None else f"{hi:,}"
        raise ValueError(f"{name} = {value!r} is out of range: allowed {left} ... {right}"
                         + (f" {unit}" if unit else ""))
    return n


def check_threads(threads, name: str = "threads") -> int | None:
    """``None`` (all cores) or 1 ... :func:`max_threads`."""
    if threads is None:
        return None
    return as_int(threads, name, 1, max_threads(),
                  f"(at most {THREADS_PER_CORE} x the {logical_cores()} logical cores)")


def check_count(value, name: str, hi: int, lo: int = 1) -> int:
    """A count within [lo, hi] (hi: one of the MAX_* ceilings above)."""
    return as_int(value, name, lo, hi)


# --- memory -------------------------------------------------------------------------------


def _cgroup_available() -> int | None:
    """What the cgroup (v2) memory limit leaves, where there is one."""
    try:
        limit = open("/sys/fs/cgroup/memory.max").read().strip()
        if limit == "max":
            return None
        used = int(open("/sys/fs/cgroup/memory.current").read().strip())
        return max(0, int(limit) - used)
    except (OSError, ValueError):
        return None


def available_memory_bytes() -> int | None:
    """Memory available to this process now [bytes]: psutil's or /proc/meminfo's
    MemAvailable, capped by a cgroup limit; ``None`` where neither can be read."""
    avail = None
    try:
        import psutil

        avail = int(psutil.virtual_memory().available)
    except Exception:  # psutil is optional
        try:
            with open("/proc/meminfo") as f:
                for line in f:
                    if line.startswith("MemAvailable:"):
                        avail = int(line.split()[1]) * 1024
                        break
        except (OSError, ValueError, IndexError):
            avail = None
    cg = _cgroup_available()
    if cg is not None:
        avail = cg if avail is None else min(avail, cg)
    return avail


def format_bytes(n: float) -> str:
    """``8653291520`` -> ``'8.65 GB'``."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} bytes"


def check_memory(need_bytes: float, what: str) -> None:
    """Refuse a request whose estimated memory ``need_bytes`` exceeds MEMORY_FRACTION of
    the memory available; ``what`` names the fields that set the size."""
    avail = available_memory_bytes()
    if avail is None or not math.isfinite(need_bytes):
        if math.isfinite(need_bytes):
            return
        raise ValueError(f"{what}: the memory needed cannot be computed (too large)")
    if need_bytes > MEMORY_FRACTION * avail:
        raise ValueError(
            f"{what}: would need about {format_bytes(need_bytes)} of memory, but "
            f"{format_bytes(avail)} is available (at most {MEMORY_FRACTION:.0%} of it may "
            "be used); ask for less")


# --- sizes of the commands ------------------------------------------------------------------


def slab_memory_bytes(n_photons: int, radial_bins: int = 0, angle_bins: int = 0) -> float:
    """The slab's profiles: the core keeps one tally of 2 x (radial + angle) float64 bins
    per batch (up to 64 batches and at least 256 photons each) until it merges them;
    Python holds them as lists of floats (32 bytes each) and numpy copies."""
    bins = 2 * (radial_bins + angle_bins)
    batches = min(max(1, math.ceil(n_photons / 256)), 65)
    return bins * (8.0 * (batches + 1) + 32.0 + 16.0)


def check_slab(n_photons, threads=None, radial_bins: int | None = None,
               angle_bins: int | None = None, prefix: str = "", seed=None, band=None) -> int:
    """Photons, threads, seed, band and profile bins of a slab run, with its memory;
    ``prefix`` is ``'--'`` for the command line's option names. Returns the photon count."""
    p = (lambda k: f"{prefix}{k.replace('_', '-')}") if prefix else (lambda k: k)
    n = check_count(n_photons, p("photons") if prefix else "n_photons", MAX_SLAB_PHOTONS)
    check_threads(threads, p("threads"))
    if seed is not None:
        as_int(seed, p("seed"), 0, 2**64 - 1)
    if band is not None:
        as_int(band, p("band"), 0, 2**32 - 1)
    rb = 0 if radial_bins is None else check_count(radial_bins, p("radial_bins"),
                                                   MAX_RADIAL_BINS)
    ab = 0 if angle_bins is None else check_count(angle_bins, p("angle_bins"),
                                                  MAX_ANGLE_BINS)
    if rb or ab:
        check_memory(slab_memory_bytes(n, rb, ab),
                     f"{p('radial_bins')} = {rb}, {p('angle_bins')} = {ab}")
    return n


def shared_bands(settings: dict, bands: int) -> tuple[bool, bool]:
    """Whether a render of ``bands`` bands with ``settings`` traces one spectral photon pass
    for all of them, and whether it holds every band at once (a spectral pass, or hero camera
    paths over every band's maps)."""
    spectral = bool(settings.get("spectral_photons")) and bands > 1
    return spectral, spectral or (bool(settings.get("hero_camera")) and bands > 1)


def render_memory_bytes(width: int, height: int, bands: int, settings: dict,
                        texels: int = 0) -> float:
    """A render's largest allocations: the film and radiance cube per pixel and band, the
    colour images per pixel, and the photon maps: at least one stored photon per photon
    emitted (the volume maps hold ``volume_stored`` where that budget is set), for one band
    at a time, or for every band at once with ``spectral_photons`` (their maps are built
    together from the shared photons, which carry a power per band until then) or
    ``hero_camera`` (one camera pass over every band's maps). Either also holds every band's
    copy of the scene's ``texels`` image-texture pixels (a band-by-band render holds one,
    which :func:`check_texture` counted at load)."""
    pixels = float(width) * float(height)
    need = pixels * (bands * PIXEL_BAND_BYTES + PIXEL_COLOUR_BYTES)
    integrator = settings.get("integrator")
    spectral, together = shared_bands(settings, bands)
    if integrator not in ("path", "volpath", "volpath-nee"):
        photons = float(settings.get("photons") or 0)
        if integrator in VOLUME_INTEGRATORS:
            stored = settings.get("volume_stored") or settings.get("volume_photons") or 0
            photons += float(stored)
        maps = 1.0
        if spectral:
            # every band's map, and the shared photons with their B powers while they build
            maps = bands + 1 + bands * 4.0 / PHOTON_BYTES
        elif together:
            maps = float(bands)
        need += photons * PHOTON_BYTES * 1.05 * maps
    if together:
        need += float(texels) * TEXEL_BYTES * bands
    return need


def check_render(settings: dict, width: int, height: int, bands: int, texels: int = 0) -> None:
    """Ceilings on a render's counts and its memory, before the core starts (``settings``
    as validated by :func:`dentalux.scene.schema.validate_settings`; ``texels``: the
    scene's image-texture pixels)."""
    check_threads(settings.get("threads"))
    for key in ("photons", "volume_photons", "volume_stored"):
        if settings.get(key) is not None:
            check_count(settings[key], key, MAX_RENDER_PHOTONS, lo=0)
    if settings.get("spp") is not None:
        check_count(settings["spp"], "spp", MAX_SPP)
    if width * height > MAX_PIXELS:
        raise ValueError(f"resolution = {width}x{height}: {width * height:,} pixels is out of "
                         f"range: allowed at most {MAX_PIXELS:,} pixels")
    textures = f", {texels:,} texture pixels" if texels else ""
    check_memory(render_memory_bytes(width, height, bands, settings, texels),
                 f"resolution = {width}x{height}, {bands} band(s), photons = "
                 f"{settings.get('photons')}, volume_photons = {settings.get('volume_photons')}"
                 f", volume_stored = {settings.get('volume_stored')}{textures}")


def format_seconds(t: float) -> str:
    """``5400`` -> ``'1.5 h'``."""
    if t >= 3600:
        return f"{t / 3600:.3g} h"
    if t >= 60:
        return f"{t / 60:.3g} min"
    return f"{t:.2g} s"


def check_grid(shape, spacing: float, name: str = "resolution") -> None:
    """A procedural tooth's signed-distance grid of ``shape`` nodes at ``spacing`` mm: at
    most MAX_TOOTH_NODES (its time, estimated in the refusal) and the memory it needs."""
    nodes = float(shape[0]) * float(shape[1]) * float(shape[2])
    check_memory(nodes * TOOTH_NODE_BYTES,
                 f"{name} = {spacing:g} mm ({int(nodes):,} grid nodes)")
    if nodes > MAX_TOOTH_NODES:
        raise ValueError(
            f"{name} = {spacing:g} mm needs {int(nodes):,} grid nodes, about "
            f"{format_seconds(nodes * TOOTH_NODE_SECONDS)} on 2 cores: allowed at most "
            f"{MAX_TOOTH_NODES:,} nodes (about "
            f"{format_seconds(MAX_TOOTH_NODES * TOOTH_NODE_SECONDS)}); give a coarser "
            f"{name}")


def check_texture(width: int, height: int, path: str) -> None:
    """An image texture's size, read from its header before its pixels are decoded."""
    if width * height > MAX_TEXTURE_PIXELS:
        raise ValueError(f"{path}: a {width}x{height} image is out of range: allowed at most "
                         f"{MAX_TEXTURE_PIXELS:,} pixels (e.g. 4096x4096)")
    check_memory(float(width) * height * TEXEL_BYTES, f"{path} ({width}x{height} pixels)")


def check_bands_in(bands, lo: float, hi: float, what: str, name: str = "bands",
                   extrapolate: bool = False) -> list[float]:
    """One band rule for every command: each band lies in the colour range
    (:data:`BAND_RANGE_NM`) and, unless the material allows extrapolation, in its data
    range [lo, hi] nm (``what`` names the material)."""
    out = []
    c_lo, c_hi = BAND_RANGE_NM
    for i, b in enumerate(bands):
        if isinstance(b, bool) or not isinstance(b, Real) or not math.isfinite(float(b)):
            raise ValueError(f"{name}[{i}] = {b!r}: must be a finite wavelength in nm")
        x = float(b)
        if not c_lo <= x <= c_hi:
            raise ValueError(f"{name}[{i}] = {x:g} nm is out of range: allowed "
                             f"[{c_lo:g}, {c_hi:g}] nm (the colour-matching range)")
        if not extrapolate and not lo <= x <= hi:
            raise ValueError(f"{name}[{i}] = {x:g} nm is out of range for {what}: its data "
                             f"cover [{lo:g}, {hi:g}] nm and it allows no extrapolation (give "
                             "bands inside its data, or set extrapolate = true in its TOML to "
                             "use the extrapolation rules of docs/materials.md)")
        out.append(x)
    return out


# --- the slab's Python API (called by dentalux.slab) ----------------------------------------


def check_layers(layers, name: str = "layers") -> list:
    """A non-empty sequence of layers (``None``, a string or a scalar is a TypeError that
    names the argument)."""
    if layers is None or isinstance(layers, str | bytes) or not hasattr(layers, "__iter__"):
        raise TypeError(f"{name} = {layers!r}: must be a list of dentalux.Layer, got "
                        f"{type(layers).__name__}")
    out = list(layers)
    if not out:
        raise ValueError(f"{name} = []: give at least one dentalux.Layer")
    return out


def check_lobes(lobes, name: str = "lobes") -> list[tuple[float, float]] | None:
    """``None`` or a non-empty sequence of (weight, g) pairs of finite numbers, weights > 0,
    g in (-1, 1)."""
    if lobes is None:
        return None
    if isinstance(lobes, str | bytes) or not hasattr(lobes, "__iter__"):
        raise TypeError(f"{name} = {lobes!r}: must be a list of (weight, g) pairs")
    out = []
    for i, lobe in enumerate(lobes):
        if isinstance(lobe, str | bytes) or not hasattr(lobe, "__len__") or len(lobe) != 2:
            raise TypeError(f"{name}[{i}] = {lobe!r}: must be a (weight, g) pair of numbers")
        w, g = lobe
        for part, v in (("weight", w), ("g", g)):
            if isinstance(v, bool) or not isinstance(v, Real) or not math.isfinite(float(v)):
                raise TypeError(f"{name}[{i}].{part} = {v!r}: must be a finite number")
        if not float(w) > 0:
            raise ValueError(f"{name}[{i}].weight = {w!r} is out of range: allowed > 0")
        if not -1 < float(g) < 1:
            raise ValueError(f"{name}[{i}].g = {g!r} is out of range: allowed (-1, 1)")
        out.append((float(w), float(g)))
    if not out:
        raise ValueError(f"{name} = []: give at least one (weight, g) pair, or None")
    return out


# --- readings (dentalux.dental, design, shade, report) ---------------------------------------


def check_band_count(n: int, name: str = "--bands") -> None:
    """At most MAX_READING_BANDS bands in one reading, refused before they are built."""
    if n > MAX_READING_BANDS:
        raise ValueError(f"{name}: {n:,} bands is out of range: allowed at most "
                         f"{MAX_READING_BANDS:,} (380-780 nm every 0.1 nm); each band is two "
                         "or three Monte Carlo runs")


def check_reading_args(photons, seed=None, reconstruction=None, threads=None,
                       bands=None, contact=None) -> int:
    """The counts and names of a reading's Python API (dentalux.dental.read, design):
    ``photons`` an integer 1 ... MAX_SLAB_PHOTONS (``True`` and 500.7 refused, never read as
    1 or truncated), ``seed`` an integer, ``reconstruction`` one of spectra.BASES (named as
    the argument, not as the internal ``basis``). Returns the photon count."""
    from dentalux import inputs, spectra

    n = inputs.integer(photons, "photons", 1, MAX_SLAB_PHOTONS)
    if seed is not None:
        inputs.integer(seed, "seed", 0, 2**64 - 1)
    if reconstruction is not None and reconstruction not in spectra.BASES:
        raise ValueError(f"reconstruction = {reconstruction!r}: allowed "
                         f"{', '.join(spectra.BASES)}")
    if threads is not None:
        inputs.integer(threads, "threads", 1, max_threads())
    if contact is not None:  # a coupling fluid's index, as an instrument file's contact_index
        from dentalux.instrument import CONTACT_INDEX_MAX

        inputs.number(contact, "contact", 1.0, CONTACT_INDEX_MAX)
    if bands is not None:  # the whole reading: one walk of `photons` per band at least
        nb = len(spectra.resolve_bands(bands))
        total = float(n) * nb
        if total > MAX_READING_PHOTONS:
            raise ValueError(
                f"photons = {n:,} per band x {nb} band(s): the reading would trace at least "
                f"{total:.3g} photons, about {format_seconds(total / PHOTON_RATE)} at "
                f"{PHOTON_RATE / 1e6:g} M photons/s: allowed at most "
                f"{MAX_READING_PHOTONS:.3g}; give fewer photons or bands")
    return n


def check_design_work(nodes: int, layers: int, bands: int, photons: int, runs: int,
                      name: str = "nodes") -> None:
    """The fast model of ``dentalux design`` traces nodes^layers x bands x runs x photons
    photons before the search starts: at most MAX_DESIGN_PHOTONS (estimated time in the
    refusal)."""
    total = float(nodes) ** layers * bands * runs * photons
    if total > MAX_DESIGN_PHOTONS:
        raise ValueError(
            f"{name} = {nodes} per layer, {layers} layer(s), {bands} band(s), photons = "
            f"{photons:,}: the fast model would trace {total:.3g} photons, about "
            f"{format_seconds(total / PHOTON_RATE)} at {PHOTON_RATE / 1e6:g} M photons/s: "
            f"allowed at most {MAX_DESIGN_PHOTONS:.3g}; give fewer nodes, bands or photons")
