"""The material library: spectral optical coefficients with provenance.

A :class:`Material` holds μa(λ), μs(λ) [1/mm], the HG asymmetry g(λ), the isotropic fraction
f_d(λ) of the paper's eq. 10 and the refractive index n(λ) at a few known wavelengths [nm],
plus where every value came from. :meth:`Material.at` evaluates them at any wavelength:

- between known points, μa and μs follow a power law (linear in log μ versus log λ); where a
  neighbouring value is 0 the power law is undefined and linear interpolation is used instead;
  g, f_d and n are interpolated linearly;
- outside the known range, μs follows the power law through the two nearest known points
  (constant when there is only one point or one of the two is 0); μa, g, f_d and n are held at
  the nearest known value.

Materials come from TOML files (format in ``docs/materials.md``): every ``*.toml`` in
``dentalux/data`` that has ``[materials.*]`` tables is part of the library. A plain name such
as ``enamel`` resolves through the ``[defaults]`` table to a named variant
(``enamel@zoller2018-kienle``); :func:`get` also takes ``"enamel"`` with ``variant=...`` or
a path to a TOML file.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dentalux import inputs

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

QUANTITIES = ("mua", "mus", "g", "fd", "n")
"""Spectral quantities of a material, in file order."""

KINDS = ("measured", "transcribed", "derived", "fitted")
"""Allowed ``provenance.kind`` of a material entry."""

VALUE_KINDS = KINDS + ("assumed", "borrowed")
"""Allowed first word of a per-value provenance string (``"transcribed: ..."``)."""

CLASSES = ("tissue", "resin-composite", "zirconia", "lithium-disilicate", "feldspathic-ceramic",
           "veneering-ceramic", "glass-ceramic", "restorative", "reference")
"""Allowed ``class`` of a material entry (``materials list --json`` gives it): ``tissue``
for enamel and dentin, the restorative classes, ``restorative`` for a restorative material
of unnamed composition (the paper's disc), ``reference`` for idealised media such as air.
Every library entry has one; a user's file may leave it out (``None``)."""

#: the largest absorption or scattering coefficient [1/mm]: a mean free path of 1 nm, far
#: beyond any dental material (enamel and dentin: 1e-3 ... 1e2); 1e300 read "cr": null
MAX_COEFFICIENT = 1e6
#: the largest refractive index (dental materials 1.3-2.2; nothing optical exceeds about 4)
MAX_INDEX = 10.0

DATA_DIR = Path(__file__).parent / "data"
"""Directory whose ``*.toml`` files with ``[materials.*]`` tables form the library."""


@dataclass(frozen=True)
class Optics:
    """Optical properties at one or more wavelengths.

    mua, mus: absorption and scattering coefficients [1/mm]; g: HG asymmetry in (-1, 1);
    fd: isotropic fraction (eq. 10) in [0, 1]; n: refractive index (>= 1). Floats for a
    scalar wavelength, numpy arrays for an array of wavelengths.
    """

    mua: float | np.ndarray
    mus: float | np.ndarray
    g: float | np.ndarray
    fd: float | np.ndarray
    n: float | np.ndarray

    @property
    def mus_reduced(self):
        """Reduced scattering coefficient μs' = μs (1 - g_eff), g_eff = (1 - fd) g [1/mm]."""
        return self.mus * (1.0 - (1.0 - self.fd) * self.g)


@dataclass(frozen=True, eq=False)
class Material:
    """A medium with spectral coefficients at known wavelengths and their provenance.

    ``wavelength_nm`` [nm] is strictly increasing; ``mua``, ``mus`` [1/mm], ``g``, ``fd``,
    ``n`` are arrays of the same length. ``provenance`` is a dict with ``kind``, ``source``,
    ``notes``, ``values`` (one string, or one string per wavelength, for each quantity) and,
    for scaled materials, ``scaling`` (a list of the scalings applied, oldest first).
    """

    name: str
    wavelength_nm: np.ndarray
    mua: np.ndarray
    mus: np.ndarray
    g: np.ndarray
    fd: np.ndarray
    n: np.ndarray
    provenance: dict = field(default_factory=dict)
    description: str = ""
    ci: dict = field(default_factory=dict)
    extrapolate: bool = False
    material_class: str | None = None
    """The TOML's ``class`` (one of :data:`CLASSES`), or None where the file has none."""
    """Whether bands outside ``wavelength_nm`` may be used (by the extrapolation rules of the
    module doc): the TOML's ``extrapolate = true``; every library entry says so, a user's file
    must say so itself (dentalux.limits.check_bands_in)."""
    """Optional confidence intervals of fitted values: ``{"mua": (N, 2) array, ...}`` from the
    file's ``mua_ci``/``mus_ci``/... keys (same units as the quantity)."""

    def __post_init__(self) -> None:
        _validate(self)

    # -- evaluation ---------------------------------------------------------------------

    def at(self, wavelength_nm) -> Optics:
        """Evaluate all quantities at ``wavelength_nm`` [nm] (scalar or array); see the
        module docstring for the interpolation and extrapolation rules."""
        lam = np.asarray(wavelength_nm, dtype=float)
        if not np.all(np.isfinite(lam)) or np.any(lam <= 0):
            raise ValueError(
                f"wavelength_nm = {wavelength_nm!r}: must be finite and > 0 [nm]"
            )
        scalar = lam.ndim == 0
        lam1 = np.atleast_1d(lam)
        out = {
            "mua": _power_interp(lam1, self.wavelength_nm, self.mua, extrapolate=False),
            "mus": _power_interp(lam1, self.wavelength_nm, self.mus, extrapolate=True),
        }
        for q in ("g", "fd", "n"):
            out[q] = np.interp(lam1, self.wavelength_nm, getattr(self, q))
        for q in ("mua", "mus"):  # a steep power law can leave the range far from its data
            bad = ~(np.isfinite(out[q]) & (out[q] <= MAX_COEFFICIENT))
            if np.any(bad):
                at = float(lam1[np.argmax(bad)])
                raise ValueError(
                    f"material {self.name!r}: {q} at {at:g} nm = {out[q][np.argmax(bad)]:.3g}, "
                    f"extrapolated from its data ({self.wavelength_nm[0]:g}-"
                    f"{self.wavelength_nm[-1]:g} nm), is beyond the allowed {MAX_COEFFICIENT:g} "
                    "1/mm: give data that reach these bands, or ask for bands inside them")
        if scalar:
            out = {k: float(v[0]) for k, v in out.items()}
        else:
            out = {k: v.reshape(lam.shape) for k, v in out.items()}
        return Optics(**out)

    def value_provenance(self, quantity: str, wavelength_nm: float | None = None) -> str:
        """The provenance string of ``quantity`` (at the known wavelength nearest to
        ``wavelength_nm`` when the entry gives one string per wavelength)."""
        if quantity not in QUANTITIES + ("wavelength_nm",):
            raise ValueError(f"quantity = {quantity!r}: allowed {', '.join(QUANTITIES)}")
        entry = self.provenance.get("values", {}).get(quantity, "")
        if isinstance(entry, list):
            i = 0 if wavelength_nm is None else int(
                np.argmin(np.abs(self.wavelength_nm - float(wavelength_nm)))
            )
            return entry[i]
        return entry

    # -- derived materials --------------------------------------------------------------

    def scaled(
        self,
        mus_factor: float = 1.0,
        mua_factor: float = 1.0,
        g: float | None = None,
        note: str = "",
    ) -> Material:
        """A copy with μs × ``mus_factor``, μa × ``mua_factor`` and, if given, g set to ``g``
        at every wavelength (the paper scaled coefficients and anisotropy "to permit
        rendering with a limited number of photons"). The scaling is appended to
        ``provenance["scaling"]`` and noted in the affected per-value strings; the name
        gains a ``+scaled`` suffix so that no output can present it as the original."""
        for key, value in (("mus_factor", mus_factor), ("mua_factor", mua_factor)):
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ValueError(f"{key} = {value!r} is out of range: allowed a number >= 0")
        if g is not None and not (isinstance(g, int | float) and -1.0 < g < 1.0):
            raise ValueError(f"g = {g!r} is out of range: allowed (-1, 1)")
        record = {"mus_factor": float(mus_factor), "mua_factor": float(mua_factor),
                  "g": None if g is None else float(g), "note": str(note)}
        prov = copy.deepcopy(self.provenance)
        prov.setdefault("scaling", []).append({k: v for k, v in record.items()
                                               if v is not None})
        values = prov.setdefault("values", {})
        text = f" [scaled: {note}]" if note else " [scaled]"
        changes = {"mus": f" x {float(mus_factor):g}" if mus_factor != 1.0 else None,
                   "mua": f" x {float(mua_factor):g}" if mua_factor != 1.0 else None,
                   "g": f" set to {g:g}" if g is not None else None}
        for q, change in changes.items():
            if change is not None:
                suffix = change + text
                entry = values.get(q, "")
                values[q] = ([e + suffix for e in entry] if isinstance(entry, list)
                             else entry + suffix)
        name = self.name if self.name.endswith("+scaled") else self.name + "+scaled"
        return Material(
            name=name,
            wavelength_nm=self.wavelength_nm.copy(),
            mua=self.mua * float(mua_factor),
            mus=self.mus * float(mus_factor),
            g=self.g.copy() if g is None else np.full_like(self.g, float(g)),
            fd=self.fd.copy(),
            n=self.n.copy(),
            provenance=prov,
            description=self.description,
            extrapolate=self.extrapolate, material_class=self.material_class,
            ci={q: v * (float(mus_factor) if q == "mus" else float(mua_factor) if q == "mua"
                        else 1.0)
                for q, v in self.ci.items() if not (q == "g" and g is not None)},
        )

    def similar(self, g: float, note: str = "") -> Material:
        """A copy with the anisotropy lowered to ``g`` by the similarity relation: wherever
        g_λ > g, μs becomes μs (1 − g_λ)/(1 − g), so the reduced scattering coefficient
        μs' = μs (1 − g) is kept and light that has scattered many times is nearly unchanged
        (docs/materials.md gives the measured error). Wavelengths with g_λ ≤ g keep their
        values. The paper lowered its teeth's anisotropy for the same reason: a strongly
        forward phase function weights few photons of a density estimate, which shows as
        grain. Recorded like :meth:`scaled` (``+scaled`` name, ``provenance["scaling"]``)."""
        if not (isinstance(g, int | float) and -1.0 < g < 1.0):
            raise ValueError(f"g = {g!r} is out of range: allowed (-1, 1)")
        lower = self.g > g
        factor = np.where(lower, (1.0 - self.g) / (1.0 - g), 1.0)
        why = f"similarity relation to g = {g:g}, mus x (1 - g_lambda)/(1 - {g:g})"
        out = self.scaled(note=f"{why}; {note}" if note else why)
        prov = out.provenance
        prov["scaling"][-1].pop("mus_factor")
        prov["scaling"][-1].update({"similarity_g": float(g),
                                    "mus_factors": [round(float(f), 6) for f in factor]})
        for q in ("mus", "g"):
            entry = prov.setdefault("values", {}).get(q, "")
            suffix = f" [similarity relation to g = {g:g}]"
            prov["values"][q] = ([e + suffix for e in entry] if isinstance(entry, list)
                                 else entry + suffix)
        return Material(
            name=out.name, wavelength_nm=out.wavelength_nm, mua=out.mua,
            mus=self.mus * factor, g=np.where(lower, float(g), self.g), fd=out.fd, n=out.n,
            provenance=prov, description=out.description, extrapolate=out.extrapolate,
            material_class=out.material_class,
            ci={q: v * (factor[:, None] if q == "mus" else 1.0)
                for q, v in out.ci.items() if q != "g"},
        )

    @property
    def is_scaled(self) -> bool:
        """True when :meth:`scaled` produced this material (see ``provenance['scaling']``)."""
        return bool(self.provenance.get("scaling"))

    def to_dict(self) -> dict:
        """Plain-data form (lists, not arrays), as in the TOML file, plus the name."""
        d = {"name": self.name, "description": self.description,
             "wavelength_nm": self.wavelength_nm.tolist(), "extrapolate": self.extrapolate}
        if self.material_class is not None:
            d["class"] = self.material_class
        for q in QUANTITIES:
            d[q] = getattr(self, q).tolist()
        for q, v in self.ci.items():
            d[f"{q}_ci"] = np.asarray(v).tolist()
        d["provenance"] = copy.deepcopy(self.provenance)
        return d


# ----------------------------------------------------------------------------------------
# interpolation
# ----------------------------------------------------------------------------------------


def _power_interp(lam: np.ndarray, xs: np.ndarray, ys: np.ndarray,
                  extrapolate: bool) -> np.ndarray:
    """Log-log linear interpolation of ``ys(xs)`` at ``lam``; linear where a neighbour is 0.
    Outside [xs[0], xs[-1]]: the power law through the two nearest points when
    ``extrapolate`` (and both are > 0), else the nearest value."""
    if len(xs) == 1:
        return np.full(lam.shape, ys[0], dtype=float)
    out = np.interp(lam, xs, ys)  # linear: the fallback, and the value at known points
    # segment index k with xs[k] <= lam <= xs[k+1], clipped to the end segments
    k = np.clip(np.searchsorted(xs, lam, side="right") - 1, 0, len(xs) - 2)
    x0, x1, y0, y1 = xs[k], xs[k + 1], ys[k], ys[k + 1]
    positive = (y0 > 0) & (y1 > 0)
    inside = (lam >= xs[0]) & (lam <= xs[-1])
    use = positive & (inside | extrapolate)
    if np.any(use):
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            b = np.log(y1 / y0) / np.log(x1 / x0)
            power = y0 * (lam / x0) ** b
        out = np.where(use, power, out)
    return out


# ----------------------------------------------------------------------------------------
# validation and loading
# ----------------------------------------------------------------------------------------


def _validate(m: Material) -> None:
    where = f"material {m.name!r}"
    lam = m.wavelength_nm
    if lam.ndim != 1 or lam.size == 0:
        raise ValueError(f"{where}: wavelength_nm must be a non-empty list [nm]")
    if not np.all(np.isfinite(lam)) or np.any(lam <= 0) or np.any(np.diff(lam) <= 0):
        raise ValueError(f"{where}: wavelength_nm must be positive and strictly increasing [nm]")
    hi, n_hi = MAX_COEFFICIENT, MAX_INDEX
    ranges = {
        "mua": (f"[0, {hi:g}] [1/mm]", lambda v: (v >= 0) & (v <= hi)),
        "mus": (f"[0, {hi:g}] [1/mm]", lambda v: (v >= 0) & (v <= hi)),
        "g": ("(-1, 1)", lambda v: (v > -1) & (v < 1)),
        "fd": ("[0, 1]", lambda v: (v >= 0) & (v <= 1)),
        "n": (f"[1, {n_hi:g}]", lambda v: (v >= 1) & (v <= n_hi)),
    }
    for q, (allowed, ok) in ranges.items():
        v = getattr(m, q)
        if v.shape != lam.shape:
            raise ValueError(
                f"{where}: {q} has {v.size} values but wavelength_nm has {lam.size}"
            )
        bad = ~(np.isfinite(v) & ok(v))
        if np.any(bad):
            i = int(np.argmax(bad))
            raise ValueError(
                f"{where}: {q}[{i}] = {float(v[i])!r} at {lam[i]:g} nm is out of range: "
                f"allowed {allowed}"
            )
    for q, v in m.ci.items():
        if q not in QUANTITIES:
            raise ValueError(f"{where}: {q}_ci: unknown quantity, allowed {', '.join(QUANTITIES)}")
        if np.shape(v) != (lam.size, 2):
            raise ValueError(f"{where}: {q}_ci must hold one [low, high] pair per wavelength")
        v = np.asarray(v, dtype=float)
        bad = ~np.isfinite(v).all(axis=1) | (v[:, 0] > v[:, 1])
        if np.any(bad):
            i = int(np.argmax(bad))
            raise ValueError(f"{where}: {q}_ci[{i}] = {v[i].tolist()} at {lam[i]:g} nm: "
                             "allowed a [low, high] pair of finite numbers, low <= high")
    prov = m.provenance
    if not isinstance(prov, dict):
        raise ValueError(f"{where}: provenance must be a table")
    kind = prov.get("kind")
    if kind not in KINDS:
        raise ValueError(f"{where}: provenance.kind = {kind!r}: allowed {', '.join(KINDS)}")
    for key in ("source",):
        if not isinstance(prov.get(key), str) or not prov[key]:
            raise ValueError(f"{where}: provenance.{key} must be a non-empty string")
    values = prov.get("values", {})
    if not isinstance(values, dict):
        raise ValueError(f"{where}: provenance.values must be a table")
    for q, entry in values.items():
        if q not in QUANTITIES + ("wavelength_nm",):
            raise ValueError(
                f"{where}: provenance.values.{q}: unknown quantity, allowed "
                f"wavelength_nm, {', '.join(QUANTITIES)}"
            )
        entries = entry if isinstance(entry, list) else [entry]
        if isinstance(entry, list) and len(entry) != lam.size:
            raise ValueError(
                f"{where}: provenance.values.{q} has {len(entry)} strings; "
                f"give one string or one per wavelength ({lam.size})"
            )
        for e in entries:
            first = e.split(":", 1)[0].split(" ", 1)[0] if isinstance(e, str) else None
            if first not in VALUE_KINDS:
                raise ValueError(
                    f"{where}: provenance.values.{q} = {e!r} must start with one of "
                    f"{', '.join(VALUE_KINDS)}"
                )


def _from_table(name: str, table: dict, origin: str) -> Material:
    where = f"{origin}: materials.{name}"
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table")
    missing = [k for k in ("wavelength_nm",) + QUANTITIES if k not in table]
    if missing:
        raise ValueError(f"{where}: missing key(s) {', '.join(missing)}")
    known = {"description", "wavelength_nm", "provenance", "extrapolate", "class", *QUANTITIES,
             *(f"{q}_ci" for q in QUANTITIES)}
    unknown = sorted(set(table) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}")
    # strict types (dentalux.inputs): no true for a number, no "1.0"; the ranges of each
    # quantity are _validate's
    arrays = {"wavelength_nm": np.asarray(inputs.wavelengths(table["wavelength_nm"],
                                                             f"{where}.wavelength_nm"))}
    for k in QUANTITIES:
        arrays[k] = np.asarray(inputs.numbers(table[k], f"{where}.{k}"), dtype=float)
    ci = {}
    for q in QUANTITIES:
        if f"{q}_ci" in table:
            key = f"{where}.{q}_ci"
            pairs = table[f"{q}_ci"]
            if not isinstance(pairs, list):
                raise ValueError(f"{key} must be a list of [low, high] pairs")
            rows = []
            for i, pair in enumerate(pairs):
                if not isinstance(pair, list) or len(pair) != 2:
                    raise ValueError(f"{key}[{i}] = {pair!r}: must be a [low, high] pair")
                low, high = inputs.numbers(pair, f"{key}[{i}]")
                if low > high:
                    raise ValueError(f"{key}[{i}] = [{low:g}, {high:g}]: low must not exceed "
                                     "high")
                rows.append((low, high))
            ci[q] = np.asarray(rows, dtype=float).reshape(-1, 2)
    for k in ("description",):
        if k in table:
            inputs.text(table[k], f"{where}.{k}")
    prov = copy.deepcopy(inputs.table(table.get("provenance", {}), f"{where}.provenance"))
    values = prov.setdefault("values", {})
    # Quantities without their own string inherit the entry's kind and source (documented).
    for q in ("wavelength_nm",) + QUANTITIES:
        if q not in values and prov.get("kind") in KINDS:
            values[q] = f"{prov['kind']}: {prov.get('source', '')} (entry-level provenance)"
    prov["file"] = origin
    material_class = table.get("class")
    if material_class is not None and material_class not in CLASSES:
        raise ValueError(f"{where}.class = {material_class!r}: allowed {', '.join(CLASSES)}")
    try:
        extrapolate = table.get("extrapolate", False)
        if not isinstance(extrapolate, bool):
            raise ValueError(f"{where}.extrapolate = {extrapolate!r}: allowed true or false")
        return Material(name=name, description=str(table.get("description", "")),
                        provenance=prov, ci=ci, extrapolate=extrapolate,
                        material_class=material_class, **arrays)
    except ValueError as exc:
        raise ValueError(f"{origin}: {exc}") from None


def load(path) -> dict[str, Material]:
    """Read every ``[materials.NAME]`` table of a TOML file into ``{name: Material}``.
    A ``[defaults]`` table (plain name -> variant) adds the plain names as aliases."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"material file {str(path)!r} not found")
    doc = inputs.read_toml(path, "material file")
    inputs.known_keys(doc, ("materials", "defaults"), f"material file {path}")
    tables = doc.get("materials", {})
    if not isinstance(tables, dict):
        raise ValueError(f"{path}: [materials] must be a table of tables")
    out = {name: _from_table(name, t, str(path)) for name, t in tables.items()}
    defaults = inputs.table(doc.get("defaults", {}), f"{path}: defaults")
    for alias, target in defaults.items():
        if not isinstance(target, str) or target not in out:
            raise ValueError(f"{path}: defaults.{alias} = {target!r} is not a material here")
        out[alias] = out[target]
    return out


_LIBRARY: dict[str, Material] | None = None
_LIBRARY_KEY: tuple | None = None


def _library() -> dict[str, Material]:
    """The merged library of every data/*.toml with [materials.*] tables (cached until a
    file changes)."""
    global _LIBRARY, _LIBRARY_KEY
    files = sorted(DATA_DIR.glob("*.toml"))
    key = tuple((str(f), f.stat().st_mtime_ns) for f in files)
    if _LIBRARY is not None and key == _LIBRARY_KEY:
        return _LIBRARY
    lib: dict[str, Material] = {}
    origin: dict[str, str] = {}
    for f in files:
        doc = tomllib.loads(f.read_text(encoding="utf-8"))
        if "materials" not in doc:
            continue
        for name, m in load(f).items():
            if name in lib and lib[name] is not m:
                raise ValueError(
                    f"material {name!r} is defined twice: in {origin[name]} and {f.name}"
                )
            lib[name] = m
            origin[name] = f.name
    _LIBRARY, _LIBRARY_KEY = lib, key
    return lib


def names() -> list[str]:
    """All names :func:`get` accepts: plain default names and ``base@variant`` names."""
    return sorted(_library())


def variants(base: str) -> list[str]:
    """The ``base@variant`` names of a base material (e.g. ``enamel``)."""
    return sorted(n for n in _library() if n.startswith(base + "@"))


def get(name: str, variant: str | None = None) -> Material:
    """A material by name (``enamel``, ``enamel@fried1995-transcribed``), by name and
    ``variant`` (``get("enamel", "zijp1995")``), or from a TOML file path (``variant`` then
    picks the entry when the file has several)."""
    if not isinstance(name, str | Path):
        raise ValueError(f"material name must be a string, got {type(name).__name__}")
    text = str(name)
    if text.endswith(".toml") or "/" in text or "\\" in text:
        mats = load(text)
        real = {k: m for k, m in mats.items() if k == m.name}
        if variant is not None:
            if variant not in mats:
                raise ValueError(
                    f"material {variant!r} not in {text}: allowed {', '.join(sorted(mats))}"
                )
            return mats[variant]
        if len(real) != 1:
            raise ValueError(
                f"{text} holds {len(real)} materials ({', '.join(sorted(real))}): "
                "pass variant=NAME to choose one"
            )
        return next(iter(real.values()))
    lib = _library()
    key = text if variant is None else f"{text}@{variant}"
    if key not in lib:
        allowed = variants(text) if variant is not None else names()
        raise ValueError(f"unknown material {key!r}: allowed {', '.join(allowed)}")
    return lib[key]
