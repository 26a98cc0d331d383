"""The library's restorative materials (issue 41, part 4): every entry has a class and a
source for every value, and each fitted restorative reproduces the published readings it was
fitted to (python/dentalux/data/fit_restoratives.py) within 4 Monte Carlo standard errors
plus the fit's stated residual."""

from __future__ import annotations

import json

import numpy as np
import pytest
from dentalux import materials as M
from dentalux.data import fit_restoratives as F

RESTORATIVE_CLASSES = ("resin-composite", "zirconia", "lithium-disilicate",
                       "feldspathic-ceramic", "veneering-ceramic", "glass-ceramic")


def test_every_library_material_has_a_class_and_a_source_for_every_value():
    for name in M.names():
        m = M.get(name)
        assert m.material_class in M.CLASSES, (name, m.material_class)
        if name.startswith(("enamel", "dentin")):
            assert m.material_class == "tissue"
        assert m.provenance["kind"] in M.KINDS and m.provenance["source"].strip()
        values = m.provenance["values"]
        for q in ("wavelength_nm",) + M.QUANTITIES:
            assert q in values, (name, q)
            for lam in m.wavelength_nm:
                text = m.value_provenance(q, lam)
                first = text.split(":")[0].split(" ")[0]
                assert first in M.VALUE_KINDS, (name, q, text)
                # a value is never bare: after its status word it says where it comes from
                assert len(text.split(":", 1)[-1].strip()) > 10, (name, q, text)


def test_library_holds_six_restoratives_in_three_classes():
    rest = [n for n in M.names() if "@" in n and M.get(n).material_class in RESTORATIVE_CLASSES]
    classes = {M.get(n).material_class for n in rest}
    assert len(rest) >= 6 and len(classes) >= 3, (rest, classes)
    # every fitted restorative is the one fit_restoratives.py derives, and says so
    assert set(F.READINGS) <= set(rest)
    for name, spec in F.READINGS.items():
        m = M.get(name)
        assert m.material_class == spec["class"]
        assert m.provenance["kind"] == "fitted"
        assert "fit_restoratives.py" in m.provenance["notes"]
        for q in ("mus", "mua"):
            text = m.value_provenance(q)
            assert text.startswith(("fitted", "borrowed")), (name, q, text)
            if text.startswith("fitted"):
                assert spec["instrument"] in text, (name, q, text)
        for q in ("g", "n"):
            assert m.value_provenance(q).startswith("assumed")
            assert getattr(m, q)[0] == pytest.approx(F.CLASS_OPTICS[spec["class"]][q])
    # restoratives have no plain default name: which composite is 'the' composite is the
    # user's choice (and `materials list` keeps each name whole at 80 columns)
    for plain in ("resin-composite", "lithium-disilicate", "zirconia", "veneering-ceramic"):
        assert plain not in M.names()


def test_materials_list_json_gives_every_entry_a_class(capsys):
    from dentalux.cli import main

    try:
        main(["materials", "list", "--json"])
    except SystemExit as exc:
        assert not exc.code
    rows = json.loads(capsys.readouterr().out)["materials"]
    assert {r["name"] for r in rows} == set(M.names())
    for r in rows:
        # the keys the listing had before are kept
        assert {"name", "resolves_to", "kind", "class", "wavelength_nm", "points",
                "description"} <= set(r)
        assert r["class"] == M.get(r["name"]).material_class
    by_name = {r["name"]: r for r in rows}
    assert by_name["enamel"]["class"] == "tissue" and by_name["air"]["class"] == "reference"
    assert by_name["zirconia@zeno-iadr2010"]["class"] == "zirconia"


def test_class_key_is_checked_and_optional(tmp_path):
    body = """
[materials.x]
{cls}
wavelength_nm = [550.0]
mua = [0.1]
mus = [1.0]
g = [0.5]
fd = [0.0]
n = [1.5]
[materials.x.provenance]
kind = "fitted"
source = "test"
"""
    path = tmp_path / "m.toml"
    path.write_text(body.format(cls=""))
    assert M.get(str(path)).material_class is None
    path.write_text(body.format(cls='class = "zirconia"'))
    m = M.get(str(path))
    assert m.material_class == "zirconia" and m.to_dict()["class"] == "zirconia"
    assert m.scaled(mus_factor=2.0).material_class == "zirconia"
    path.write_text(body.format(cls='class = "zirkonia"'))
    with pytest.raises(ValueError, match="class"):
        M.get(str(path))


@pytest.mark.parametrize("name", sorted(F.READINGS))
def test_fitted_restorative_reproduces_the_published_readings(name):
    """The library entry, read as its study read it (one band: the spectra are flat; an
    independent seed), lies within 4 standard errors plus the fit's stated residual of each
    published number it was fitted to."""
    spec = F.READINGS[name]
    m = M.get(name)
    assert np.ptp(m.mus) == 0 and np.ptp(m.mua) == 0  # flat: one band reads every band
    sim = F.simulate(m, spec, photons=10_000, seed=2)
    for (thickness, quantity, value, _scale), (got, se) in zip(spec["readings"], sim,
                                                               strict=True):
        slack = 4.0 * se + F.STATED_RESIDUAL[name][quantity]
        assert abs(got - value) <= slack, (name, thickness, quantity, value, got, se)
