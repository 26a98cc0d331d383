"""Instrument classes and their published natural-tooth readings (``instruments validate``).

Every preset names its class (:data:`dentalux.instrument.CLASSES`). A class whose instruments
have read natural teeth in a published study carries that study's mean and SD
(data/instrument_classes.toml names rows of data/natural_teeth.csv). :func:`validate` reads the
natural incisor's labial middle third (:data:`dentalux.design.render.NATURAL_STACK`, substrate
none, colour over the preset's white backing) through every preset of such a class and says
whether it lies inside mean ± 2 SD (:data:`dentalux.natural_teeth.SPREAD`) in L*, a*, b*.
A failure is a finding about the preset's geometry or the tissues, not a bug to hide.
"""

from __future__ import annotations

from pathlib import Path

from dentalux import inputs, instrument, natural_teeth
from dentalux.reading import DEFAULT_SOLVER

DATA = Path(__file__).parent / "data" / "instrument_classes.toml"
#: quick defaults of the command (the reading's s.e. is well below the SDs, about 1 L*)
PHOTONS = 4000
BANDS = (450.0, 500.0, 550.0, 600.0, 650.0)


def classes() -> dict:
    """{class: {'description', 'published' (dict or None), 'no_readings' (str or None)}}."""
    doc = inputs.read_toml(DATA, "instrument class file")
    tables = doc.get("classes", {})
    rows = {r["id"]: r for r in natural_teeth.rows()}
    out = {}
    for name in instrument.CLASSES:
        t = tables.get(name, {})
        pub = None
        if "natural_incisor" in t:
            ni = t["natural_incisor"]
            mean, sd = rows[ni["mean_row"]], rows[ni["sd_row"]]
            pub = {"mean": [mean[c] for c in "Lab"], "sd": [sd[c] for c in "Lab"],
                   "sources": [ni["mean_row"], ni["sd_row"]], "sd_status": ni["sd_status"]}
        out[name] = {"description": t.get("description", ""), "published": pub,
                     "no_readings": t.get("no_readings")}
    return out


def natural_incisor():
    """The natural incisor's labial middle third as a specimen [(material, mm)]."""
    from dentalux.design.render import NATURAL_STACK
    from dentalux.design.targets import parse_stack

    return parse_stack(NATURAL_STACK)


def natural_incisor_text() -> str:
    from dentalux.design.render import NATURAL_STACK

    return NATURAL_STACK


def check(lab, published: dict) -> list[bool]:
    """Per coordinate: inside mean ± SPREAD·sd."""
    k = natural_teeth.SPREAD
    return [abs(float(x) - m) <= k * s
            for x, m, s in zip(lab, published["mean"], published["sd"], strict=True)]


def validate(photons: int = PHOTONS, bands=BANDS, seed: int = 1, threads=None,
             presets=None, solver: str = DEFAULT_SOLVER) -> dict:
    """``{"presets": [{name, class, reading: {lab}, published: {mean, sd, sources}, inside}]}``
    for every preset whose class has published natural-tooth readings. ``presets`` (names)
    restricts the list (None: every preset); ``solver`` as :func:`dentalux.dental.read`'s
    (a fibre probe is read by the layered solver whatever it says)."""
    from dentalux import dental

    cls = classes()
    specimen = natural_incisor()
    out = []
    for name, inst in instrument.presets().items():
        pub = cls[inst.instrument_class]["published"]
        if pub is None or (presets is not None and name not in presets):
            continue
        # the walk cannot follow a fibre probe's separate fibres: the layered solver reads it
        how = "layered" if inst.fibres is not None and solver == "monte-carlo" else solver
        m = dental.read(specimen, instrument=inst, photons=photons, bands=list(bands),
                        seed=seed, threads=threads, solver=how)
        lab = [float(x) for x in m.lab_white]
        out.append({"name": name, "class": inst.instrument_class, "reading": {"lab": lab},
                    "published": {k: pub[k] for k in ("mean", "sd", "sources")},
                    "inside": all(check(lab, pub))})
    return {"presets": out}
