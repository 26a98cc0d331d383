"""The fast forward model that drives a design search: a Monte Carlo response surface.

For a restoration of k layers (1 to 3) with thickness ranges, the full specimen (layers,
cement, substrate; :mod:`dentalux.design.substrates`) is read by the reading engine
(:mod:`dentalux.reading`: the instrument's lit spot, window and backing inside the walk, so
the edge loss is in every number) at the nodes of a regular grid in thickness space,
``nodes`` per layer, for every band: the reading over the white backing and, when a
translucency target is given, over the black one (the same walk). Every node runs with the same seed
(common random numbers; measured, they correlate the nodes' noise only weakly).

The nodes are evenly spaced in log thickness (densest at the thin end, where a reading
changes fastest), and between them each band's reading is interpolated by a tensor-product
cubic spline in log thickness (quadratic with 3 nodes, linear with 2); since the spline is
linear in the data, its weights are computed once per axis and a dense thickness grid costs
a matrix product. Colour follows from the interpolated spectra exactly as
:func:`dentalux.dental.read` computes it (the same illuminant, observer and reconstruction),
so the fast model is the Monte Carlo itself, interpolated: its error is the nodes' Monte
Carlo error (carried through the spline weights as sqrt(sum w_i^2 sigma_i^2): common random
numbers hardly correlate the nodes, whose photon histories part as soon as a layer boundary
moves) plus the interpolation error, which the verification (:mod:`dentalux.design.verify`)
measures.
"""

from __future__ import annotations

import numpy as np

from dentalux import reading
from dentalux.color import delta_e00
from dentalux.reading.layered import interpolate
from dentalux.slab import Layer

DEFAULT_NODES = {1: 6, 2: 4, 3: 3}
DATA_MARGIN_NM = 25.0


def check_data(material, wl: np.ndarray, name: str) -> None:
    """A ValueError when more than half the bands lie over ``DATA_MARGIN_NM`` outside the
    wavelengths where ``material`` has data (beyond them its coefficients are held or
    extrapolated, materials.py)."""
    known = np.asarray(getattr(material, "wavelength_nm", []), dtype=float)
    if known.size == 0:
        return
    lo, hi = float(known.min()), float(known.max())
    outside = (wl < lo - DATA_MARGIN_NM) | (wl > hi + DATA_MARGIN_NM)
    if outside.sum() * 2 > wl.size:
        raise ValueError(
            f"{name} = {getattr(material, 'name', material)!r} has no data over the bands "
            f"asked for: its data cover {lo:g}-{hi:g} nm, and {int(outside.sum())} of the "
            f"{wl.size} bands ({wl.min():g}-{wl.max():g} nm) lie more than "
            f"{DATA_MARGIN_NM:g} nm outside (allowed: at most half)")


def axis_weights(nodes: np.ndarray, t) -> np.ndarray:
    """Spline weights (len(t), len(nodes)): the interpolant at ``t`` is weights @ values.
    The spline runs in log thickness, where the nodes are evenly spaced (see Surface)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    n = len(nodes)
    if n == 1:
        return np.ones((t.size, 1))
    # the not-a-knot cubic spline (the parabola through 3 nodes, the line through 2), as
    # the instrument window's spline in spatial frequency
    return interpolate.cubic_spline(np.log(nodes), np.log(np.clip(t, nodes[0], nodes[-1])))


class ColourMap:
    """Band readings (..., bands) -> CIELAB, as dental.read computes colour."""

    def __init__(self, wl: np.ndarray, illuminant="D65", observer="2",
                 reconstruction="hold"):
        from dentalux.color import system
        from dentalux.spectra import Reconstruction

        self.cs = system(illuminant, str(observer))
        rec = Reconstruction(wl, grid=self.cs.wavelengths, basis=reconstruction)
        self.matrix = (self.cs.weights @ rec.matrix).T  # (bands, 3)

    def lab(self, readings) -> np.ndarray:
        return self.cs.XYZ_to_Lab(np.asarray(readings) @ self.matrix)


class Surface:
    """Readings of the specimen over the thickness grid, interpolated (module doc).

    ``parts``: the restoration's materials (resolved), top to bottom; ``ranges``: (lo, hi)
    per layer [mm]; ``tail``: [(material, mm)] below the restoration (cement, substrate);
    ``rb``: backing reflectance per band for each channel read ("white", and "black" when
    ``black``)."""

    def __init__(self, parts, ranges, tail, inst, wl, rb_white, rb_black, colour: ColourMap,
                 photons: int, seed: int, black: bool, nodes: int | None = None,
                 estimator: str = "weighted", threads: int | None = None, progress=None,
                 solver: str = reading.DEFAULT_SOLVER):
        k = len(parts)
        n = int(nodes or DEFAULT_NODES[k])
        if n < 2:
            raise ValueError(f"nodes = {nodes!r}: allowed an integer >= 2 per layer")
        self.k, self.wl, self.colour, self.black = k, wl, colour, black
        self.ranges = [(float(lo), float(hi)) for lo, hi in ranges]
        # nodes evenly spaced in log thickness: a layer's reading saturates roughly as
        # exp(-t / tau), with tau as short as 0.2 mm for an absorbing, scattering shade, so it
        # changes fastest at the thin end, where the nodes are densest
        self.nodes = [np.geomspace(lo, hi, n) for lo, hi in self.ranges]
        channels = ["white"] + (["black"] if black else [])
        shape = tuple(len(x) for x in self.nodes)
        self.values = np.zeros(shape + (len(channels), len(wl)))
        self.errors = np.zeros_like(self.values)
        optics = [m.at(wl) for m in parts] + [m.at(wl) for m, _ in tail]
        tail_t = [float(t) for _, t in tail]
        index = list(np.ndindex(*shape))
        self.photons = 0
        self.cpu_seconds = 0.0

        # every node is one reading of the engine (dentalux.reading): both backings from
        # the same walk, every node with the same seed
        pick = [reading.CHANNELS.index(f"over_{c}") for c in channels]

        def stacks_at(idx):
            thick = [self.nodes[d][i] for d, i in enumerate(idx)] + tail_t
            return [[Layer(mua=float(o.mua[b]), mus=float(o.mus[b]), g=float(o.g[b]),
                           n=float(o.n[b]), thickness=t, fd=float(o.fd[b]))
                     for o, t in zip(optics, thick, strict=True)]
                    for b in range(len(wl))]

        # the layered solver solves every node together, each layer and thickness once
        got_all = reading.engine.measure_many([stacks_at(idx) for idx in index], wl, inst,
                                              rb_black, rb_white, photons, seed, estimator,
                                              threads, progress, solver=solver)
        for idx, got in zip(index, got_all, strict=True):
            self.values[idx] = got.values[pick]
            self.errors[idx] = got.stderr[pick]
            self.photons += got.photons
            self.cpu_seconds += got.cpu_seconds

    # -- interpolation -----------------------------------------------------------------

    def _weights(self, points: np.ndarray) -> np.ndarray:
        """Combined tensor-product weights (m, nodes) at ``points`` (m, k)."""
        w = axis_weights(self.nodes[0], points[:, 0])
        for d in range(1, self.k):
            wd = axis_weights(self.nodes[d], points[:, d])
            w = (w[:, :, None] * wd[:, None, :]).reshape(len(points), -1)
        return w

    def readings(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Interpolated readings and their standard errors, (m, channels, bands) each."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        w = self._weights(p)
        flat_v = self.values.reshape(w.shape[1], -1)
        flat_e = self.errors.reshape(w.shape[1], -1)
        shape = (len(p),) + self.values.shape[self.k:]
        # nodes taken as independent: one seed, but their histories part as soon as a layer
        # boundary moves (a same-seed read between nodes differs from the spline as much as
        # an independent one, benchmarks/design.py), so the root sum of squares
        return (w @ flat_v).reshape(shape), np.sqrt((w**2) @ flat_e**2).reshape(shape)

    def grid(self, axes) -> np.ndarray:
        """Interpolated readings over the tensor grid ``axes`` (one array per layer):
        shape (len(a0), ..., channels, bands)."""
        x = self.values
        for d in range(self.k):
            x = np.tensordot(x, axis_weights(self.nodes[d], axes[d]), axes=([0], [1]))
        # x is now (channels, bands, f_0, ..., f_k-1)
        return np.moveaxis(x, (0, 1), (-2, -1))

    # -- colour ------------------------------------------------------------------------

    def metrics(self, readings: np.ndarray) -> dict:
        """lab_white (..., 3) and, with the black channel, lab_black and tp00 (...)."""
        out = {"lab_white": self.colour.lab(readings[..., 0, :])}
        if self.black:
            out["lab_black"] = self.colour.lab(readings[..., 1, :])
            out["tp00"] = np.asarray(delta_e00(out["lab_black"], out["lab_white"]))
        return out

    def at(self, point, target_lab=None) -> dict:
        """Fast-model numbers at one design point with first-order standard errors (each
        band's interpolated error, bands independent): lab_white, tp00 and, given
        ``target_lab``, delta_e00 to it."""
        vals, errs = self.readings(np.asarray(point, dtype=float)[None, :])
        vals, errs = vals[0], errs[0]
        n_in = vals.size
        h = 1e-6
        batch = np.broadcast_to(vals, (1 + n_in,) + vals.shape).copy()
        batch.reshape(1 + n_in, -1)[1 + np.arange(n_in), np.arange(n_in)] += h
        m = self.metrics(batch)
        sig = errs.ravel()
        out, stderr = {}, {}
        if target_lab is not None:
            m["delta_e00"] = np.asarray(delta_e00(m["lab_white"], np.asarray(target_lab)))
        for key, value in m.items():
            d = (value[1:] - value[0]) / h
            out[key] = value[0]
            if d.ndim == 1:
                stderr[key] = float(np.sqrt(np.sum((d * sig) ** 2)))
            else:
                stderr[key] = [float(np.sqrt(np.sum((d[:, j] * sig) ** 2))) for j in range(3)]
        out = {k: (v.tolist() if np.ndim(v) else float(v)) for k, v in out.items()}
        return {"values": out, "stderr": stderr}
