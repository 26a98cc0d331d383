"""A probe of separate fibres (dentalux.fibres): its reading by the layered solver against a
brute-force photon walk (tests/fibre_walk.py), its exact reduction to today's concentric
discs, reciprocity of the areas, a white tile, and every bad layout refused with its field
named (ValueError in Python, exit 2 from the command line, nothing written)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from cli_run import run_main
from dentalux import dental, instrument
from dentalux.reading import engine
from dentalux.reading.layered.stack import ACCURACY
from dentalux.slab import Layer
from fibre_walk import walk

SIGMAS = 4.0


def _probe(sources, receivers, acceptance=None, tip=3.5, **kw) -> instrument.Instrument:
    fib = [{"x_mm": x, "y_mm": y, "diameter_mm": d, "role": "source"} for x, y, d in sources]
    for x, y, d in receivers:
        row = {"x_mm": x, "y_mm": y, "diameter_mm": d, "role": "receiver"}
        if acceptance is not None:
            row["acceptance_deg"] = acceptance
        fib.append(row)
    kw = {"geometry": "0-d", "backing_black": 0.0, "backing_white": 0.0, **kw}
    return instrument.Instrument(name="probe", fibres={"tip_diameter_mm": tip, "fibres": fib},
                                 **kw)


def _over_black(inst, layer: Layer) -> float:
    out = engine.measure([[layer]], [550.0], inst, np.zeros(1), np.zeros(1), 1000, 1,
                         solver="layered")
    return float(out.values[0, 0])


# two sources of unequal size and three receivers at unequal distances: every term of the
# layout (weights by area, J0 per distance, the acceptance cone) is exercised
SOURCES = [(0.0, 0.0, 0.8), (-1.2, 0.0, 0.5)]
RECEIVERS = [(0.9, 0.0, 0.6), (0.0, 0.9, 0.6), (0.0, -1.0, 0.8)]


@pytest.mark.parametrize("mua, mus, g, acceptance, photons", [
    (0.05, 6.0, 0.6, 40.0, 150_000),   # weakly absorbing: light spreads past the receivers
    (0.3, 5.0, 0.8, 30.0, 250_000),    # forward scattering, a narrower cone
])
def test_a_fibre_layout_agrees_with_a_brute_force_walk(mua, mus, g, acceptance, photons):
    layer = Layer(mua=mua, mus=mus, g=g, n=1.5, thickness=1.5, fd=0.0)
    solved = _over_black(_probe(SOURCES, RECEIVERS, acceptance), layer)
    mc, se = walk(mua, mus, g, 1.5, 1.5, SOURCES, RECEIVERS, acceptance, photons)
    assert abs(solved - mc) <= SIGMAS * se + ACCURACY * solved, (solved, mc, se)
    assert se < 0.05 * mc  # the walk resolves the reading to a few per cent


def test_concentric_regions_as_one_pair_are_todays_window_bit_for_bit():
    """The window's order sums with the concentric lit disc and window given as one pair
    (lit, view, 0, 1) are the arrays of today's call, exactly (same responses)."""
    from dentalux.reading import layered

    bs = [[Layer(mua=0.1, mus=4.0, g=0.7, n=1.5, thickness=1.0, fd=0.0)]]
    res = layered.responses(bs, 1.0, 1.0, (37.0, 53.0))
    local = layered.local_parts(bs, 1.0, 1.0)
    keys = engine.WINDOW_KEYS
    today = layered.order_sums(res, local, 0.04, (0.0, 1.5), (0.0, 2.0), 8, keys)
    pair = layered.order_sums(res, local, 0.04, None, None, 8, keys,
                              pairs=(((0.0, 1.5), (0.0, 2.0), 0.0, 1.0),))
    assert np.array_equal(today, pair)


def test_one_fibre_that_lights_and_reads_is_todays_disc():
    """A 3 mm fibre with role 'both' at the centre, read through the preset's geometry (no
    acceptance given), is contact-probe-3mm on a laterally infinite specimen: equal within
    1e-12, the layered solver's own run-to-run scatter (two solves of one specimen differ
    at 1e-17 in a reflectance; the window's arithmetic is the same, test above)."""
    disc = dataclasses.replace(instrument.get("contact-probe-3mm"), specimen_diameter_mm=None)
    fibre = instrument.Instrument(
        name="one-fibre", geometry=disc.geometry, backing_black=disc.backing_black,
        backing_white=disc.backing_white,
        fibres={"tip_diameter_mm": 3.0,
                "fibres": [{"x_mm": 0.0, "y_mm": 0.0, "diameter_mm": 3.0, "role": "both"}]})
    specimen = [("enamel", 0.6), ("dentin", 0.9)]
    a = dental.read(specimen, instrument=disc, bands=[450.0, 550.0, 650.0])
    b = dental.read(specimen, instrument=fibre, bands=[450.0, 550.0, 650.0])
    for key in ("over_black", "over_white", "transmitted"):
        np.testing.assert_allclose(b.spectra[key], a.spectra[key], rtol=1e-12, atol=0)
    np.testing.assert_allclose(b.lab_white, a.lab_white, rtol=1e-12)
    assert fibre.white_fraction() == disc.white_fraction() == 1.0


def test_swapping_source_and_receiver_is_reciprocal_in_the_areas():
    """Power read per unit irradiance is symmetric: reading x source area is unchanged when
    a 0.5 mm source and a 1.0 mm receiver swap roles (same acceptance)."""
    layer = Layer(mua=0.1, mus=4.0, g=0.7, n=1.5, thickness=2.0, fd=0.0)
    ab = _over_black(_probe([(0.0, 0.0, 0.5)], [(1.2, 0.0, 1.0)], 30.0), layer)
    ba = _over_black(_probe([(1.2, 0.0, 1.0)], [(0.0, 0.0, 0.5)], 30.0), layer)
    assert ab * 0.5**2 == pytest.approx(ba * 1.0**2, rel=1e-9)
    assert ab > 0.0


def test_a_fibre_probe_with_a_tile_is_white_normalised_and_reads_its_tile_as_certified():
    tile = {"mua_per_mm": 0.3, "mus_per_mm": 5.0, "g": 0.8, "n": 1.5, "thickness_mm": 1.5,
            "reflectance": 0.9, "backing": 0.0}
    inst = _probe(SOURCES, RECEIVERS, 20.0, white_reference=tile)
    assert inst.white_normalised and not _probe(SOURCES, RECEIVERS, 20.0).white_normalised
    same = [[Layer(mua=0.3, mus=5.0, g=0.8, n=1.5, thickness=1.5, fd=0.0)]]
    out = engine.measure(same, [550.0], inst, np.zeros(1), np.zeros(1), 1000, 1)
    assert out.values[0, 0] == pytest.approx(0.9, rel=1e-12)


def test_the_monte_carlo_walk_and_a_rim_are_refused_with_reasons():
    inst = _probe(SOURCES, RECEIVERS, 20.0)
    with pytest.raises(ValueError, match="fibre probe.*layered"):
        dental.read([("enamel", 1.0)], instrument=inst, solver="monte-carlo", bands=[550.0])
    with pytest.raises(ValueError, match="walks = 'shared'"):
        engine.measure([[Layer(mua=0.1, mus=4.0, g=0.7, n=1.5, thickness=1.0, fd=0.0)]],
                       [550.0], inst, np.zeros(1), np.zeros(1), 100, 1, walks="shared")
    with pytest.raises(ValueError, match="specimen_diameter_mm.*laterally infinite"):
        _probe(SOURCES, RECEIVERS, 20.0, specimen_diameter_mm=10.0)
    with pytest.raises(ValueError, match="geometry.*normal"):
        _probe(SOURCES, RECEIVERS, 20.0, geometry="d8-sci")


def test_the_preset_reads_the_natural_incisor():
    inst = instrument.get("fibre-probe")
    assert inst.fibres is not None and inst.white_normalised
    assert inst.instrument_class == "clinical-contact-probe"
    for key in ("tip_diameter_mm", "fibres", "white_reference"):
        assert key in inst.provenance
    m = dental.read([("enamel", 0.9), ("dentin", 2.9), ("enamel", 0.6)], instrument=inst,
                    bands=[450.0, 550.0, 650.0])
    assert all(math.isfinite(x) for x in m.lab_white)
    assert m.to_json()["instrument"]["fibres"]


HEAD = ('[instruments.bad]\ngeometry = "0-d"\ntip_diameter_mm = 3.0\n'
        'backing_black = 0.0\nbacking_white = 0.9\n')


def _fibre(x=0.0, y=0.0, d=0.5, role="source", extra=""):
    return (f'[[instruments.bad.fibres]]\nx_mm = {x}\ny_mm = {y}\ndiameter_mm = {d}\n'
            f'role = "{role}"\n{extra}')


GOOD = _fibre() + _fibre(x=1.0, role="receiver", extra="acceptance_deg = 25.0\n")


@pytest.mark.parametrize("text, named", [
    (HEAD + _fibre() + _fibre(x=0.3, role="receiver"), r"fibres\[1\] overlaps.*fibres\[0\]"),
    (HEAD + _fibre() + _fibre(x=1.4, role="receiver"), r"fibres\[1\].*outside tip"),
    (HEAD + _fibre(d=0.0) + _fibre(x=1.0, role="receiver"), r"fibres\[0\]\.diameter_mm"),
    (HEAD + _fibre(d=-0.5) + _fibre(x=1.0, role="receiver"), r"fibres\[0\]\.diameter_mm"),
    (HEAD.replace("3.0", "0.0") + GOOD, r"tip_diameter_mm"),
    (HEAD + _fibre() + _fibre(x=1.0, role="receiver", extra="acceptance_deg = 90.0\n"),
     r"fibres\[1\]\.acceptance_deg"),
    (HEAD + _fibre() + _fibre(x=1.0, role="receiver", extra="acceptance_deg = 0.0\n"),
     r"fibres\[1\]\.acceptance_deg"),
    (HEAD + _fibre() + _fibre(x=1.0, role="receiver", extra="numerical_aperture = 1.2\n"),
     r"fibres\[1\]\.numerical_aperture"),
    (HEAD + _fibre(extra="acceptance_deg = 20.0\n") + _fibre(x=1.0, role="receiver"),
     r"fibres\[0\].*source fibre's emission cone"),
    (HEAD + GOOD + _fibre(x=-1.0, role="receiver", extra="acceptance_deg = 30.0\n"),
     r"fibres\[2\]\.acceptance_deg.*share one acceptance"),
    (HEAD + _fibre() + _fibre(x=1.0, role="lamp"), r"fibres\[1\]\.role"),
    (HEAD + _fibre() + _fibre(x=1.0), r"one fibre that lights.*one that receives"),
    (HEAD + "specimen_diameter_mm = 10.0\n" + GOOD, r"specimen_diameter_mm"),
    (HEAD + "viewed_diameter_mm = 3.0\n" + GOOD, r"viewed_diameter_mm"),
    (HEAD.replace('"0-d"', '"d8-sci"') + GOOD, r"geometry"),
])
def test_bad_layouts_exit_2_with_the_field_named_and_nothing_written(tmp_path, capsys, text,
                                                                     named):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=named) as exc:
        instrument.get(str(path))
    assert "bad.toml" in str(exc.value) and "instruments.bad" in str(exc.value)
    out = tmp_path / "readings.csv"
    code, _, err = run_main(capsys, "shade", "enamel", "--thickness", "1", "--instrument",
                            path, "--readings-out", out)
    assert code == 2 and "instruments.bad" in err
    assert not out.exists()


def test_a_good_layout_reads_from_the_command_line_and_monte_carlo_exits_2(tmp_path, capsys):
    path = tmp_path / "good.toml"
    path.write_text(HEAD.replace("[instruments.bad]", "[instruments.good]")
                    + GOOD.replace("instruments.bad", "instruments.good"))
    code, out, _ = run_main(capsys, "shade", "enamel", "--thickness", "1", "--instrument",
                            path, "--bands", "550", "--json")
    assert code == 0 and '"fibres"' in out
    code, _, err = run_main(capsys, "shade", "enamel", "--thickness", "1", "--instrument",
                            path, "--bands", "550", "--solver", "monte-carlo")
    assert code == 2 and "fibre probe" in err
