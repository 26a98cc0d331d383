"""The instrument that reads a specimen: lit spot, viewed window, geometry, backings, contact.

A dental number is always "as read by" an instrument. An :class:`Instrument` names the
diameter of the lit spot and of the viewed window at the specimen, the measuring geometry,
the black and white backings, an air gap or an optical-contact fluid between specimen and
backing, and optionally the specimen's own diameter. The slab simulator in the core runs
with that geometry inside the walk (:mod:`dentalux_core::instrument`): photons enter
uniformly over the lit disc, the backing lies under the specimen, and light is read only
where it leaves inside the window. Light that leaves elsewhere is the edge loss. The lit
region and the window may be rings (``illuminated_inner_diameter_mm``,
``viewed_inner_diameter_mm``): a fibre-optic probe's illuminating ring around a central
receiving bundle, or the reverse (docs/instruments.md, "A fibre-optic probe"). A probe of
separate fibres names them instead (``fibres`` and ``tip_diameter_mm``, :mod:`dentalux.fibres`):
such a probe is read by the layered solver alone, on a laterally infinite specimen. An optional
``white_reference`` names the instrument's calibration tile, read through the same window, by
which readings are divided instead of an ideal white (:mod:`dentalux.white_reference`).

Geometries, each simulated in its reciprocal form (same reading for a reciprocal specimen,
far fewer photons for a narrow detector):

- ``d8-sci`` / ``d8-sce``: diffuse illumination, viewing 8 deg off the normal, specular
  component included or excluded; simulated as an 8 deg beam collected over the hemisphere
  (SCE drops the first-surface specular reflection inside the window).
- ``45-0`` and ``0-45``: an annular 45 deg ring and a normal view; simulated as a normal
  beam collected over the ring 45 +- 8 deg (the CIE 15 tolerance of every ray within 8 deg
  of its beam axis, instruments.toml), normalised by the ring's Lambertian fraction.
- ``noncontact``: a small view inside wide light (a telespectroradiometer in a booth),
  read like ``45-0``; the view must not exceed the lit spot.
- ``0-d``: a normal beam, the whole hemisphere collected, specular included: the geometry
  of the ``infinite`` instrument, which is dentalux's laterally infinite disc on ideal
  backings (the adding formula of :mod:`dentalux.dental`).

Presets live in ``data/instruments.toml`` with a provenance entry for every number; a
user's own instrument is a TOML file with the same keys (docs/instruments.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from numbers import Real
from pathlib import Path

from dentalux import fibres as fibre_layout
from dentalux import inputs
from dentalux import white_reference as tiles

DATA = Path(__file__).parent / "data" / "instruments.toml"
INFINITE = "infinite"
# every reading, from the command line or the API, is through this preset unless told
# otherwise: the only preset whose reading of the natural incisor falls inside its class's
# published range (`dentalux instruments validate`; docs/instruments.md, "The default")
DEFAULT = "45-0"
# half-width of the 45 deg ring [deg]: CIE 15 keeps every ray within 8 deg of its beam axis
RING_HALF_WIDTH = 8.0
#: diameters an instrument may name [mm]: squares and overlap areas of discs stay well inside
#: float range (a 1e-300 mm spot squares to 0 and reads 0/0); ``infinite`` alone has inf
DIAMETER_RANGE_MM = (1e-9, 1e9)
#: the largest refractive index of a coupling fluid (glycerin 1.47, immersion oils 1.52;
#: nothing a lab couples with exceeds 3)
CONTACT_INDEX_MAX = 3.0


@dataclass(frozen=True)
class Geometry:
    """How a geometry is simulated: the beam's incidence, the detector cone (None: the
    hemisphere), whether the first-surface specular reflection counts, and whether the view
    may be larger than the lit spot."""

    incidence: str
    cone_deg: tuple[float, float] | None
    specular: str
    view_may_exceed_light: bool


_RING = (45.0 - RING_HALF_WIDTH, 45.0 + RING_HALF_WIDTH)
GEOMETRIES = {
    "d8-sci": Geometry("angle:8", None, "included", False),
    "d8-sce": Geometry("angle:8", None, "excluded", False),
    "45-0": Geometry("normal", _RING, "excluded", True),
    "0-45": Geometry("normal", _RING, "excluded", True),
    "noncontact": Geometry("normal", _RING, "excluded", False),
    "0-d": Geometry("normal", None, "included", True),
}
#: instrument classes (``class`` in a TOML table; docs/instruments.md): the kind of instrument
#: whose published natural-tooth readings a preset is checked against
#: (:mod:`dentalux.instrument_classes`). A user's file without ``class`` is ``custom``; the
#: built-in laterally infinite disc is ``idealised``.
CLASSES = ("clinical-contact-probe", "benchtop-d8", "noncontact-45-0", "imaging", "custom",
           "idealised")
KEYS = ("geometry", "illuminated_diameter_mm", "viewed_diameter_mm", "backing_black",
        "backing_white", "contact_index", "specimen_diameter_mm",
        "illuminated_inner_diameter_mm", "viewed_inner_diameter_mm", "white_reference",
        "fibres")
#: the inner diameters that make the lit region or the window a ring (annulus): 0 is a disc
INNER_KEYS = ("illuminated_inner_diameter_mm", "viewed_inner_diameter_mm")


def _number(name: str, value, lo: float, lo_open: bool, hi: float = math.inf,
            allow_inf: bool = False) -> float:
    """``value`` as a float inside [lo, hi] (lo open where asked), or a ValueError naming it:
    strictly a number (no bool, no string: ``"4.0"`` is refused, not compared as text)."""
    if allow_inf and isinstance(value, Real) and not isinstance(value, bool) \
            and math.isinf(float(value)) and float(value) > 0:
        return math.inf
    return inputs.number(value, name, lo, None if math.isinf(hi) else hi, lo_open=lo_open)


def _diameter(name: str, value, allow_inf: bool = False) -> float:
    """A diameter [mm] inside DIAMETER_RANGE_MM (inf only for the infinite geometry)."""
    lo, hi = DIAMETER_RANGE_MM
    if allow_inf and isinstance(value, Real) and not isinstance(value, bool) \
            and math.isinf(float(value)) and float(value) > 0:
        return math.inf
    return inputs.number(value, name, lo, hi, unit="mm")


def _backing(name: str, value):
    """A backing reflectance: a number in [0, 1], {wavelength_nm = [...], reflectance = [...]}
    or the (wavelengths, reflectances) pair this returns for such a table. A table's
    wavelengths are strictly increasing (sorted, each once) and finite, inside
    dentalux.inputs.WAVELENGTH_RANGE_NM; no other key is allowed."""
    if isinstance(value, tuple) and len(value) == 2:
        value = {"wavelength_nm": value[0], "reflectance": value[1]}
    if isinstance(value, dict):
        inputs.known_keys(value, ("wavelength_nm", "reflectance"), name)
        for key in ("wavelength_nm", "reflectance"):
            if key not in value:
                raise ValueError(f"{name}: a spectrum needs wavelength_nm = [...] and "
                                 f"reflectance = [...] of numbers (missing {key})")
        wl = inputs.wavelengths(value["wavelength_nm"], f"{name}.wavelength_nm")
        r = inputs.numbers(value["reflectance"], f"{name}.reflectance", 0.0, 1.0)
        if len(wl) != len(r):
            raise ValueError(f"{name}: wavelength_nm has {len(wl)} values and reflectance "
                             f"{len(r)}: they must have the same length")
        return (tuple(wl), tuple(r))
    return _number(name, value, 0.0, False, 1.0)


def _inner(name: str, value, outer: float, outer_name: str) -> float:
    """An inner diameter [mm]: 0 (a disc) or a finite number in [0, outer) (a ring whose outer
    diameter is ``outer``, the field ``outer_name``); a ValueError naming it otherwise."""
    if math.isinf(outer):
        hi_text = "0 (the 'infinite' geometry has no rings)"
        if isinstance(value, Real) and not isinstance(value, bool) and float(value) == 0.0:
            return 0.0
        raise ValueError(f"{name} = {value!r} is out of range: allowed {hi_text}")
    x = inputs.number(value, name, 0.0, None, unit="mm")
    if not x < outer:
        raise ValueError(f"{name} = {x:g} mm is out of range: allowed [0, {outer:g}) mm, "
                         f"smaller than {outer_name} = {outer:g} mm (0 for a disc)")
    return x


@dataclass(frozen=True)
class Instrument:
    """One instrument's measuring geometry (diameters in mm at the specimen).

    The lit region and the window are concentric discs, or rings where an inner diameter is
    given (``illuminated_inner_diameter_mm``, ``viewed_inner_diameter_mm``; 0 is a disc): a
    fibre-optic contact probe lights a ring of fibres and reads a central bundle, or the
    reverse.
    """

    name: str
    geometry: str = "0-45"
    illuminated_diameter_mm: float = 3.0
    viewed_diameter_mm: float = 3.0
    backing_black: float | tuple = 0.0
    backing_white: float | tuple = 0.9
    contact_index: float | None = None
    specimen_diameter_mm: float | None = None
    description: str = ""
    provenance: dict = field(default_factory=dict, compare=False)
    instrument_class: str = "custom"
    illuminated_inner_diameter_mm: float = 0.0
    viewed_inner_diameter_mm: float = 0.0
    #: the calibration tile (:class:`dentalux.white_reference.WhiteReference` or its table);
    #: None divides by an ideal, non-penetrating white as before
    white_reference: object = None
    #: a probe of separate fibres (:class:`dentalux.fibres.Layout`, or its table
    #: {tip_diameter_mm, fibres}); None: the concentric lit region and window above
    fibres: object = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name = {self.name!r}: must be a non-empty string")
        if not isinstance(self.geometry, str) or self.geometry not in GEOMETRIES:
            raise ValueError(f"geometry = {self.geometry!r}: allowed {', '.join(GEOMETRIES)}")
        if not isinstance(self.instrument_class, str) or self.instrument_class not in CLASSES:
            raise ValueError(f"class = {self.instrument_class!r}: allowed {', '.join(CLASSES)}")
        if self.fibres is not None:
            self._check_fibres()
        # only the built-in idealisation may have infinite areas (see is_infinite)
        infinite = self.name == INFINITE and self.geometry == "0-d"
        ill = _diameter("illuminated_diameter_mm", self.illuminated_diameter_mm, infinite)
        view = _diameter("viewed_diameter_mm", self.viewed_diameter_mm, infinite)
        if math.isinf(ill) != math.isinf(view):
            raise ValueError(f"illuminated_diameter_mm = {ill:g}, viewed_diameter_mm = "
                             f"{view:g}: both infinite (the 'infinite' geometry) or both finite")
        if view > ill and not GEOMETRIES[self.geometry].view_may_exceed_light:
            raise ValueError(
                f"viewed_diameter_mm = {view:g} is larger than illuminated_diameter_mm = "
                f"{ill:g}: geometry {self.geometry} views inside the lit area (allowed "
                f"viewed_diameter_mm <= {ill:g})")
        fields = {"illuminated_diameter_mm": ill, "viewed_diameter_mm": view,
                  "backing_black": _backing("backing_black", self.backing_black),
                  "backing_white": _backing("backing_white", self.backing_white)}
        if self.contact_index is not None:
            fields["contact_index"] = _number("contact_index", self.contact_index, 1.0, False,
                                              CONTACT_INDEX_MAX)
        if self.specimen_diameter_mm is not None:
            spec = _diameter("specimen_diameter_mm", self.specimen_diameter_mm)
            if view > spec:
                raise ValueError(
                    f"viewed_diameter_mm = {view:g} is larger than specimen_diameter_mm = "
                    f"{spec:g}: the window would look past the specimen (allowed "
                    f"viewed_diameter_mm <= {spec:g})")
            fields["specimen_diameter_mm"] = spec
        lit_outer = ill if self.specimen_diameter_mm is None else min(
            ill, fields["specimen_diameter_mm"])
        for key, outer, what in (
                ("illuminated_inner_diameter_mm", lit_outer,
                 "illuminated_diameter_mm" if lit_outer == ill else "specimen_diameter_mm"),
                ("viewed_inner_diameter_mm", view, "viewed_diameter_mm")):
            fields[key] = _inner(key, getattr(self, key), outer, what)
        if not isinstance(self.description, str):
            raise ValueError(f"description = {self.description!r}: must be a string")
        if not isinstance(self.provenance, dict):
            raise ValueError(f"provenance = {self.provenance!r}: must be a table of strings")
        if self.white_reference is not None:
            if infinite:
                raise ValueError("white_reference: the 'infinite' instrument divides by an "
                                 "ideal white; name a preset or a TOML file to give a tile")
            fields["white_reference"] = tiles.parse(self.white_reference,
                                                              "white_reference")
        for key, value in fields.items():  # store what was checked (floats, not "4.0")
            object.__setattr__(self, key, value)
        if self.white_reference is not None and self.white_reference.diameter_mm is not None:
            tiles.instrument_for(self)  # a tile narrower than the window is refused here

    def _check_fibres(self) -> None:
        """Parse the layout; a fibre probe lights along the normal, has no rings and no rim
        (the rim's correction is a slab walk, which cannot follow separate fibres); its
        diameters are the tip's."""
        layout = fibre_layout.parse(self.fibres, "fibres")
        if GEOMETRIES[self.geometry].incidence != "normal":
            allowed = [g for g, v in GEOMETRIES.items() if v.incidence == "normal"]
            raise ValueError(f"geometry = {self.geometry!r}: a fibre probe lights along the "
                             f"normal through its source fibres: allowed {', '.join(allowed)}")
        if self.specimen_diameter_mm is not None:
            raise ValueError(
                f"specimen_diameter_mm = {self.specimen_diameter_mm!r}: a fibre probe is read "
                "by the layered solver on a laterally infinite specimen (a rim's correction "
                "is a slab walk, which cannot follow separate fibres): leave it out")
        for key in INNER_KEYS:
            if getattr(self, key) != 0.0:
                raise ValueError(f"{key} = {getattr(self, key)!r}: a fibre probe's regions "
                                 "are its fibres: leave it out (0)")
        for key in ("illuminated_diameter_mm", "viewed_diameter_mm"):
            object.__setattr__(self, key, layout.tip_diameter_mm)
        object.__setattr__(self, "fibres", layout)

    @property
    def is_infinite(self) -> bool:
        """The laterally infinite disc read over infinite areas (the adding formula): the
        built-in ``infinite`` instrument, whose areas are infinite. A user's file cannot
        take the name (:func:`_from_table`), and a finite instrument is never this one."""
        return self.name == INFINITE and math.isinf(self.illuminated_diameter_mm)

    @property
    def spec(self) -> Geometry:
        """The geometry; a fibre probe's receivers read into their acceptance cone."""
        geometry = GEOMETRIES[self.geometry]
        if self.fibres is not None and self.fibres.acceptance_deg is not None:
            return replace(geometry, cone_deg=(0.0, self.fibres.acceptance_deg))
        return geometry

    @property
    def lit_diameter_mm(self) -> float:
        """The lit part of the specimen: light falling beyond its rim never enters it, and
        the reading's normalisation (an ideal white lit alike) is the same per unit area."""
        if self.specimen_diameter_mm is None:
            return self.illuminated_diameter_mm
        return min(self.illuminated_diameter_mm, self.specimen_diameter_mm)

    @property
    def is_discs(self) -> bool:
        """Whether the lit region and the window are both discs (no inner diameter)."""
        return self.illuminated_inner_diameter_mm == 0.0 and self.viewed_inner_diameter_mm == 0.0

    def window(self, backing: float, brute_force: bool = False) -> tuple:
        """The core's window tuple for one run with a backing of reflectance ``backing``:
        (lit inner radius, lit radius, viewed inner radius, viewed radius, specimen radius,
        backing, cone).

        For two discs the normalised reading is symmetric in the two diameters (reciprocity,
        and the rotational symmetry of a normal beam read over a ring or a hemisphere), so the
        run lights the smaller disc and reads the larger: every photon then counts towards
        the reading, instead of (b/a)^2 of them for a small view in wide light.
        ``brute_force`` lights the lit disc and reads the window as the instrument does (for
        checks). Rings are lit and read as the instrument does (no swap): the normalisation
        by an ideal white is not symmetric for them. A fibre probe has no such tuple (the
        walk cannot follow its fibres): a ValueError.
        """
        if self.fibres is not None:
            raise ValueError(f"instrument {self.name!r} is a fibre probe: the slab walk "
                             "cannot follow separate fibres; it is read by the layered "
                             "solver (solver = 'layered' or 'auto')")
        spec = math.inf if self.specimen_diameter_mm is None else self.specimen_diameter_mm / 2
        a, b = self.lit_diameter_mm / 2, self.viewed_diameter_mm / 2
        if self.is_discs:
            if not brute_force:
                a, b = min(a, b), max(a, b)
            return (0.0, a, 0.0, b, spec, float(backing), self.spec.cone_deg)
        a0 = self.illuminated_inner_diameter_mm / 2
        b0 = self.viewed_inner_diameter_mm / 2
        return (a0, a, b0, b, spec, float(backing), self.spec.cone_deg)

    @property
    def white_normalised(self) -> bool:
        """Whether an ideal Lambertian white lit like the specimen sends light through the
        window, so that the reading is a reflectance factor, or whether a white reference tile
        is given (the reading is then specimen / tile × the tile's reflectance). A probe whose
        lit ring and read centre do not overlap has neither without a tile: its reading is
        then the fraction of the incident power leaving inside the window."""
        return self.white_reference is not None or self._white_overlap() > 0.0

    def _white_overlap(self) -> float:
        """Lit area inside the window over the lit area (rings concentric at the centre; a
        fibre probe's sources' power falling on its receivers)."""
        if self.fibres is not None:
            from dentalux.reading.layered.window import pairs_overlap

            return pairs_overlap(self.fibres.pairs())
        a, b = self.lit_diameter_mm, self.viewed_diameter_mm
        a0, b0 = self.illuminated_inner_diameter_mm, self.viewed_inner_diameter_mm
        lo, hi = max(a0, b0), min(a, b)
        return 0.0 if hi <= lo else (hi**2 - lo**2) / (a**2 - a0**2)

    def white_fraction(self, brute_force: bool = False) -> float:
        """Power an ideal Lambertian white sends through the run's window, the reading's
        normaliser: for discs min(a, b)^2 / a^2 (1 when the run lights the smaller disc); for
        rings the lit area inside the window over the lit area, or 1 where they do not
        overlap (the fraction of the incident power; see :attr:`white_normalised`); for
        fibres the like over every source and receiver."""
        a, b = self.lit_diameter_mm, self.viewed_diameter_mm
        if self.is_discs and self.fibres is None:
            return 1.0 if a <= b or not brute_force else (b / a) ** 2
        f = self._white_overlap()
        return f if f > 0.0 else 1.0

    def reading(self, window: dict, stderr: dict, brute_force: bool = False
                ) -> tuple[float, float]:
        """Reflectance factor (and its standard error) from one run's window tallies."""
        key = "viewed_cone_reflectance" if self.spec.cone_deg else "viewed_reflectance"
        value, var = window[key], stderr[key] ** 2
        if self.spec.cone_deg is None and self.spec.specular == "excluded":
            value -= window["viewed_specular"]
            var += stderr["viewed_specular"] ** 2  # conservative: the two are correlated
        f = self.white_fraction(brute_force)
        return value / f, math.sqrt(var) / f

    def to_json(self) -> dict:
        """The ``instrument`` object of ``dentalux shade --json``."""
        def backing(v):
            return {"wavelength_nm": list(v[0]), "reflectance": list(v[1])} if isinstance(
                v, tuple) else v

        def finite(x):
            return None if x is None or math.isinf(x) else x

        return {
            "name": self.name,
            "class": self.instrument_class,
            "geometry": self.geometry,
            "illuminated_diameter_mm": finite(self.illuminated_diameter_mm),
            "viewed_diameter_mm": finite(self.viewed_diameter_mm),
            "specular": self.spec.specular,
            "contact_index": self.contact_index,
            "backing_black": backing(self.backing_black),
            "backing_white": backing(self.backing_white),
            "specimen_diameter_mm": self.specimen_diameter_mm,
            # rings only: a disc instrument's object is as it was before rings existed
            **({} if self.is_discs else {
                "illuminated_inner_diameter_mm": self.illuminated_inner_diameter_mm,
                "viewed_inner_diameter_mm": self.viewed_inner_diameter_mm,
                "white_normalised": self.white_normalised}),
            # only for fibres: every other instrument's object is as before
            **({} if self.fibres is None else {
                **self.fibres.to_json(), "acceptance_deg": self.fibres.acceptance_deg,
                "white_normalised": self.white_normalised}),
            # only with a tile: an instrument without one prints as before
            **({} if self.white_reference is None else {
                "white_reference": self.white_reference.to_json(),
                "white_normalised": True}),
        }

    def override(self, **changes) -> Instrument:
        """A copy with the given fields changed (None leaves a field as it is); the name
        gains a ``+custom`` mark so a reading never claims to be the plain preset."""
        changes = {k: v for k, v in changes.items() if v is not None}
        if not changes:
            return self
        bad = sorted(set(changes) - set(KEYS))
        if bad:
            raise ValueError(f"unknown instrument field {bad[0]!r}: allowed {', '.join(KEYS)}")
        geometric = sorted(set(changes) - {"backing_black", "backing_white", "contact_index",
                                           "white_reference"})
        regions = sorted(set(changes) - {"backing_black", "backing_white", "contact_index",
                                         "white_reference", "fibres", "geometry"})
        if self.fibres is not None and regions:
            raise ValueError(f"{regions[0]}: instrument {self.name!r} is a fibre probe; its "
                             "lit and read regions are its fibres: change fibres instead")
        if self.is_infinite and geometric:
            raise ValueError(f"{geometric[0]}: the 'infinite' instrument has no lit spot, window "
                             "or geometry to change; name a preset (dentalux instruments list) "
                             "or a TOML file")
        name = self.name if self.name.endswith("+custom") else f"{self.name}+custom"
        if self.is_infinite:
            name = INFINITE  # the backings and contact are today's infinite-geometry options
        return replace(self, name=name, **changes)


def overlap_area(rho, a: float, b: float):
    """Area [mm²] shared by two discs of radii ``a`` and ``b`` [mm] whose centres are
    ``rho`` [mm] apart (array-valued in ``rho``)."""
    import numpy as np

    rho = np.asarray(rho, dtype=float)
    small, big = min(a, b), max(a, b)
    out = np.where(rho <= big - small, np.pi * small**2, 0.0)
    lens = (rho > big - small) & (rho < a + b)
    r = np.where(lens, rho, 1.0)
    ca = np.clip((r**2 + a**2 - b**2) / (2 * r * a), -1, 1)
    cb = np.clip((r**2 + b**2 - a**2) / (2 * r * b), -1, 1)
    k = (-r + a + b) * (r + a - b) * (r - a + b) * (r + a + b)
    area = a**2 * np.arccos(ca) + b**2 * np.arccos(cb) - 0.5 * np.sqrt(np.clip(k, 0, None))
    return np.where(lens, area, out)


def reading_from_profile(radial_reflectance, r_max: float, a: float, b: float) -> float:
    """The reading of a lit disc of radius ``a`` and a window of radius ``b`` [mm] from a
    pencil beam's exit profile R(r) [1/mm²] (bins over [0, r_max]): by superposition the
    power from the lit disc that leaves inside the window is ∫ R(ρ) A(ρ) 2πρ dρ / (π a²),
    A the discs' overlap, and an ideal white reads π min(a, b)² / (π a²) of it."""
    import numpy as np

    prof = np.asarray(radial_reflectance, dtype=float)
    edges = np.linspace(0.0, r_max, prof.size + 1)
    # each bin's ring area times the overlap at its (area-weighted) mean radius
    ring = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    mid = (2.0 / 3.0) * (edges[1:] ** 3 - edges[:-1] ** 3) / (edges[1:] ** 2 - edges[:-1] ** 2)
    return float(np.sum(prof * ring * overlap_area(mid, a, b)) / (np.pi * min(a, b) ** 2))


def _infinite() -> Instrument:
    return Instrument(
        name=INFINITE, geometry="0-d", illuminated_diameter_mm=math.inf,
        viewed_diameter_mm=math.inf, backing_black=0.0, backing_white=0.9,
        description="Laterally infinite disc lit and viewed over infinite areas, on ideal "
                    "Lambertian backings (no edge loss): the adding formula.",
        provenance={"geometry": "assumed: the idealisation of dentalux.dental's adding formula"},
        instrument_class="idealised")


def _from_table(name: str, table: dict, where: str, builtin: bool = False,
                base: Path | None = None) -> Instrument:
    key = f"{where}: instruments.{name}"
    if not isinstance(table, dict):
        raise ValueError(f"{key} must be a table of keys")
    if not builtin and name == INFINITE:
        raise ValueError(f"{key}: the name {INFINITE!r} is reserved for the built-in "
                         "laterally infinite geometry (the adding formula); give your "
                         "instrument another name")
    known = set(KEYS) | {"description", "provenance", "class", "tip_diameter_mm"}
    inputs.known_keys(table, known, key)
    layout = None
    if "fibres" in table or "tip_diameter_mm" in table:
        for k in ("illuminated_diameter_mm", "viewed_diameter_mm", *INNER_KEYS):
            if k in table:
                raise ValueError(f"{key}.{k}: a fibre probe's lit and read regions are its "
                                 "fibres (fibres, tip_diameter_mm): leave it out")
        if "fibres" not in table:
            raise ValueError(f"{key}.tip_diameter_mm: give the fibres too "
                             f"([[instruments.{name}.fibres]])")
        layout = fibre_layout.parse({"tip_diameter_mm": table.get("tip_diameter_mm"),
                                     "fibres": table["fibres"]}, f"{key}.fibres")
    for k in ("geometry",) + (() if layout else ("illuminated_diameter_mm",
                                                 "viewed_diameter_mm")):
        if k not in table:
            raise ValueError(f"{key} needs {k!r}")
    geometry = inputs.text(table["geometry"], f"{key}.geometry")
    if geometry not in GEOMETRIES:
        raise ValueError(f"{key}.geometry = {geometry!r}: allowed {', '.join(GEOMETRIES)}")
    klass = inputs.text(table.get("class", "custom"), f"{key}.class")
    if klass not in CLASSES or (klass == "idealised" and not builtin):
        allowed = [c for c in CLASSES if builtin or c != "idealised"]
        raise ValueError(f"{key}.class = {klass!r}: allowed {', '.join(allowed)}"
                         + ("" if builtin else " ('idealised' is the built-in infinite disc)"))
    contact = _number(f"{key}.contact_index", table.get("contact_index", 1.0), 1.0, False,
                      CONTACT_INDEX_MAX)
    provenance = inputs.table(table.get("provenance", {}), f"{key}.provenance")
    for k, v in provenance.items():
        inputs.text(v, f"{key}.provenance.{k}")
    spec = table.get("specimen_diameter_mm")
    tile = None if "white_reference" not in table else tiles.parse(
        table["white_reference"], f"{key}.white_reference", base)
    try:
        return Instrument(
            name=name,
            geometry=geometry,
            illuminated_diameter_mm=layout.tip_diameter_mm if layout else _diameter(
                f"{key}.illuminated_diameter_mm", table["illuminated_diameter_mm"]),
            viewed_diameter_mm=layout.tip_diameter_mm if layout else _diameter(
                f"{key}.viewed_diameter_mm", table["viewed_diameter_mm"]),
            backing_black=_backing(f"{key}.backing_black", table.get("backing_black", 0.0)),
            backing_white=_backing(f"{key}.backing_white", table.get("backing_white", 0.9)),
            contact_index=None if contact == 1.0 else contact,
            specimen_diameter_mm=None if spec is None else _diameter(
                f"{key}.specimen_diameter_mm", spec),
            description=inputs.text(table.get("description", ""), f"{key}.description"),
            provenance=dict(provenance),
            instrument_class=klass,
            illuminated_inner_diameter_mm=_number(
                f"{key}.illuminated_inner_diameter_mm",
                table.get("illuminated_inner_diameter_mm", 0.0), 0.0, False),
            viewed_inner_diameter_mm=_number(
                f"{key}.viewed_inner_diameter_mm",
                table.get("viewed_inner_diameter_mm", 0.0), 0.0, False),
            white_reference=tile,
            fibres=layout,
        )
    except ValueError as exc:
        msg = str(exc)
        raise ValueError(msg if msg.startswith(where) else f"{key}: {msg}") from None


def _load(path: Path, builtin: bool = False) -> dict[str, Instrument]:
    doc = inputs.read_toml(path, "instrument file")
    where = f"instrument file {path}"
    inputs.known_keys(doc, ("instruments",), where)
    tables = doc.get("instruments")
    if not isinstance(tables, dict) or not tables:
        raise ValueError(f"{where}: needs [instruments.NAME] tables")
    return {name: _from_table(name, t, where, builtin, path.parent)
            for name, t in tables.items()}


def presets() -> dict[str, Instrument]:
    """Every named instrument: ``infinite`` and the presets of data/instruments.toml."""
    return {INFINITE: _infinite(), **_load(DATA, builtin=True)}


def get(instrument) -> Instrument:
    """An Instrument, a preset name, or a TOML file with one ``[instruments.NAME]`` table;
    None is :data:`DEFAULT`, the instrument of ``dentalux shade`` and ``dental.read``."""
    if isinstance(instrument, Instrument):
        return instrument
    if instrument is None:  # the one default of the command line and the API
        instrument = DEFAULT
    if not isinstance(instrument, (str, Path)):
        raise ValueError(f"instrument = {instrument!r}: expected a name or a TOML file")
    text = str(instrument)
    if text.endswith(".toml"):
        path = Path(text)
        if not path.is_file():
            raise ValueError(f"instrument file {path.name!r} not found")
        found = _load(path)
        if len(found) != 1:
            raise ValueError(f"instrument file {path.name} holds {len(found)} instruments "
                             f"({', '.join(found)}): give one")
        return next(iter(found.values()))
    known = presets()
    if text not in known:
        import difflib

        near = difflib.get_close_matches(text, known, n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise ValueError(f"instrument = {text!r} is unknown{hint}: allowed "
                         f"{', '.join(known)} or a TOML file")
    return known[text]
