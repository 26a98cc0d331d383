"""The forward models of ``dentalux fit --readings``: every reading's spectrum from μa, μs.

- ``km``: Kubelka–Munk with the Saunderson correction (:func:`km_reflectance`).
- ``mc``: the reading engine (:func:`dentalux.dental.read`) through the instrument, with one
  of its solvers: the Monte Carlo walks, or the layered solver (noise-free but for the small
  Monte Carlo correction for the specimen's rim) wherever the beam is normal.
- ``table``: the ``mc`` model tabulated over a (log μa, log μs) grid, one reading whose
  "bands" are the grid's nodes (a reading depends on the band only through the material), for
  each backing level read; a smoothing spline whose misfit is the nodes' noise. A backing
  spectrum is tabulated at its lowest and highest reflectance and interpolated linearly
  between them, band by band; the fit's defect correction takes up what that misses.

The model's error beside each value is its standard error between replicates (Monte Carlo,
or the rim correction's; not the bound that stands for it where the rim walk saw no event,
:func:`replicate_stderr`) and, with the layered solver, its stated accuracy
(:data:`ACCURACY`, relative).
"""

from __future__ import annotations

import numpy as np

from dentalux.color import system
from dentalux.inverse.models.boundary import moments, specular
from dentalux.reading import engine
from dentalux.reading.layered.stack import ACCURACY
from dentalux.readings import BackingFile, Readings
from dentalux.spectra import Reconstruction

#: the table's photons per node, as a fraction of the fit's photons: the defect correction
#: reads the fit itself with all of them, so the table needs to be right in slope only
TABLE_PHOTON_FRACTION = 0.5
SLOTS = ("black", "white")


def km_reflectance(mua, mus, g: float, n: float, thickness, rg, diffuse_only: bool):
    """Kubelka–Munk + Saunderson reflectance of a disc on a backing (readings_fit's module
    doc); ``diffuse_only``: the instrument excludes the specular reflection k1, though the
    light still enters through the face (1 - k1), as in :mod:`dentalux.inverse.models.km`;
    arrays broadcast."""
    k = 2.0 * np.asarray(mua, dtype=float)
    s = np.maximum(0.75 * np.asarray(mus, dtype=float) * (1.0 - g), 1e-12)
    a = 1.0 + k / s
    b = np.sqrt(np.maximum(a * a - 1.0, 0.0))
    bsx = np.maximum(b * s * thickness, 1e-12)
    # b coth(bSX), with its limit 1/(SX) as b -> 0 (no absorption)
    bcoth = np.where(b * s * thickness < 1e-8, 1.0 / (s * thickness),
                     b / np.tanh(np.minimum(bsx, 300.0)))
    r = (1.0 - rg * (a - bcoth)) / (a - rg + bcoth)
    k1, k2 = specular(n, 1.0), moments(n, 1.0)[0]
    return (0.0 if diffuse_only else k1) + (1.0 - k1) * (1.0 - k2) * r / (1.0 - k2 * r)


def replicate_stderr(m, name: str) -> list[float]:
    """The model's noise in reading ``name`` of ``m`` (a DentalMetrics): its standard error
    between replicates. Where the rim walk saw no event the reading's standard error is a
    bound from that zero count instead (engine.rim_bound), far above what the term turns
    out to be; the fit weighs residuals and smooths its table by noise, not by that bound."""
    return m.spectra.get(f"{name}_replicate_stderr", m.spectra[f"{name}_stderr"])


class Problem:
    """The readings, the instrument and one forward model: spectra of every reading."""

    def __init__(self, readings: Readings, inst, g, n, model, photons, seed, bands,
                 solver: str = "monte-carlo"):
        self.r, self.inst, self.g, self.n = readings, inst, g, n
        self.model, self.photons, self.seed, self.solver = model, photons, seed, solver
        self.bands = np.asarray(bands, dtype=float)
        self.cs = system(readings.illuminant, str(readings.observer))
        self.rec = Reconstruction(self.bands, grid=self.cs.wavelengths, basis="hold")
        self.diffuse_only = inst.spec.specular == "excluded"
        self.layered = model == "mc" and engine.use_layered(inst, solver)
        self.accuracy = ACCURACY if self.layered else 0.0
        self.evaluations = 0
        self.mc_calls = 0
        self.cpu_seconds = 0.0
        self.defect = 0.0
        # each reading -> (thickness, the pair of backings read together, slot 0|1)
        self.calls: dict = {}
        self.slot = []
        for t in sorted({row.thickness_mm for row in readings.rows}):
            backs = []
            for row in readings.rows:
                if row.thickness_mm == t and row.backing not in backs:
                    backs.append(row.backing)
            for i in range(0, len(backs), 2):
                self.calls[(t, i // 2)] = backs[i:i + 2]
        for row in readings.rows:
            for key, pair in self.calls.items():
                if key[0] == row.thickness_mm and row.backing in pair:
                    self.slot.append((key, pair.index(row.backing)))
                    break
        # every reading's backing reflectance at the bands
        self.slot_rg = np.array([self.rg(row.backing) for row in readings.rows])

    def backing_value(self, backing):
        """What dental.read takes for a readings file's backing: the instrument's named one,
        a number, or a spectrum (wavelengths, reflectances)."""
        if isinstance(backing, str):
            return getattr(self.inst, f"backing_{backing}")
        if isinstance(backing, BackingFile):
            return backing.spectrum
        return backing

    def rg(self, backing) -> np.ndarray:
        from dentalux.dental import backing_spectrum

        return backing_spectrum(self.backing_value(backing), self.bands, "backing")

    def material(self, bands, mua, mus):
        from dentalux.materials import Material

        bands = np.asarray(bands, float)
        return Material(name="fit", wavelength_nm=bands, mua=np.asarray(mua, float),
                        mus=np.asarray(mus, float), g=np.full(bands.size, self.g),
                        fd=np.zeros(bands.size), n=np.full(bands.size, self.n),
                        provenance={"kind": "fitted", "source": "dentalux fit --readings"})

    def read(self, bands, mua, mus, backings=None) -> dict:
        """One reading per (thickness, pair of backings) call at ``bands``; ``backings``
        maps a call to the values read in its slots (default: the readings' own)."""
        from dentalux import dental

        mat = self.material(bands, mua, mus)
        got = {}
        for key, pair in self.calls.items():
            values = (backings[key] if backings else
                      [self.backing_value(b) for b in pair])
            over = {f"backing_{SLOTS[j]}": v for j, v in enumerate(values)}
            got[key] = dental.read([(mat, key[0])], bands=np.asarray(bands).tolist(),
                                   instrument=self.inst, photons=self.photons, seed=self.seed,
                                   progress=False, illuminant=self.r.illuminant,
                                   observer=self.r.observer, solver=self.solver, **over)
            self.cpu_seconds += got[key].cpu_seconds
        return got

    def model_err(self, values, stderr):
        """The model's error of each value: its standard error and, with the layered solver,
        its stated accuracy."""
        return np.hypot(stderr, self.accuracy * np.asarray(values))

    def spectra(self, mua, mus):
        """(readings, bands) reflectances and the model's errors (plus the defect correction
        of the table model)."""
        self.evaluations += 1
        if self.model == "km":
            out = np.array([km_reflectance(mua, mus, self.g, self.n, row.thickness_mm,
                                           rg, self.diffuse_only)
                            for row, rg in zip(self.r.rows, self.slot_rg, strict=True)])
            return out, np.zeros_like(out)
        if self.model == "table":
            pts = np.column_stack([np.log(mua), np.log(mus)])
            pts = np.clip(pts, self.table_lo, self.table_hi)
            vals, errs = [], []
            for (key, j), rg in zip(self.slot, self.slot_rg, strict=True):
                levels = self.tables[(key, j)]
                at = [(lv, tab.ev(pts[:, 0], pts[:, 1]), err.ev(pts[:, 0], pts[:, 1]))
                      for lv, tab, err in levels]
                if len(at) == 1:
                    vals.append(at[0][1])
                    errs.append(at[0][2])
                else:  # linear in the backing's reflectance between its two levels
                    (l0, v0, e0), (l1, v1, e1) = at
                    w = (rg - l0) / (l1 - l0)
                    vals.append(v0 + w * (v1 - v0))
                    errs.append(np.maximum(np.abs(e0), np.abs(e1)))
            vals = np.asarray(vals) + self.defect
            return vals, self.model_err(vals, np.abs(np.asarray(errs)))
        self.mc_calls += 1
        got = self.read(self.bands, mua, mus)
        vals, errs = [], []
        for key, j in self.slot:
            name = f"over_{SLOTS[j]}"
            vals.append(got[key].spectra[name])
            errs.append(replicate_stderr(got[key], name))
        return np.asarray(vals), self.model_err(vals, np.asarray(errs))

    def _levels(self, key) -> list[list[float]]:
        """The constant backing reflectances a call's table is read at: per slot, one level
        (a constant backing) or its spectrum's lowest and highest."""
        out = []
        for b in self.calls[key]:
            r = self.rg(b)
            out.append([float(r[0])] if np.ptp(r) < 1e-9 else [float(r.min()), float(r.max())])
        return out

    def build_table(self, log_mua_range, log_mus_range, nodes):
        """The table model (module doc): every (thickness, backing pair) read over a grid of
        (log μa, log μs) nodes at each backing level; cubic between nodes."""
        from scipy.interpolate import RectBivariateSpline

        la = np.linspace(*log_mua_range, nodes[0])
        ls = np.linspace(*log_mus_range, nodes[1])
        a, s = np.meshgrid(la, ls, indexing="ij")
        fake = 380.0 + 0.1 * np.arange(a.size)  # node k is read as band 380 + 0.1 k nm
        levels = {key: self._levels(key) for key in self.calls}
        self.tables = {(key, j): [] for key in self.calls for j in range(len(self.calls[key]))}
        full, self.photons = self.photons, max(1000, int(self.photons * TABLE_PHOTON_FRACTION))
        try:
            for k in range(max(len(lv) for slots in levels.values() for lv in slots)):
                # the layered solver keeps each specimen's solve, so a second level re-reads
                # only the rim correction
                at = {key: [lv[min(k, len(lv) - 1)] for lv in slots]
                      for key, slots in levels.items()}
                got = self.read(fake, np.exp(a.ravel()), np.exp(s.ravel()), at)
                for key, slots in levels.items():
                    for j, lv in enumerate(slots):
                        if k >= len(lv):
                            continue
                        name = f"over_{SLOTS[j]}"
                        v = np.asarray(got[key].spectra[name]).reshape(a.shape)
                        e = np.asarray(replicate_stderr(got[key], name)).reshape(a.shape)
                        # a smoothing spline: its squared misfit at the nodes is about their
                        # summed noise variance, so it follows the surface, not the noise
                        self.tables[(key, j)].append((
                            lv[k], RectBivariateSpline(la, ls, v, kx=3, ky=3,
                                                       s=float(np.sum(e * e))),
                            RectBivariateSpline(la, ls, e, kx=1, ky=1)))
        finally:
            self.photons = full
        self.table_lo = np.array([la[0], ls[0]])
        self.table_hi = np.array([la[-1], ls[-1]])
        self.defect = 0.0
        self.model = "table"

    def lab(self, spectra):
        return self.cs.XYZ_to_Lab(self.cs.grid_to_XYZ(self.rec(np.asarray(spectra))))
