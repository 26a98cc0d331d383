"""Minimal end-to-end check of the slab binding (the full suite is test_slab.py)."""

import dentalux
import pytest
from dentalux.slab import simulate


def test_energy_ledger_closes():
    r = simulate([dentalux.Layer(mua=1, mus=9, g=0.75, n=1.0, thickness=0.2)], n_photons=20000)
    assert abs(r.total_reflectance + r.total_transmittance + r.absorbed - 1) < 1e-9


def test_negative_mua_is_a_value_error_naming_the_field():
    with pytest.raises(ValueError, match=r"layers\[0\]\.mua"):
        simulate([dentalux.Layer(mua=-1, mus=9, g=0.75, n=1.0, thickness=0.2)], n_photons=10)


def test_a_rust_panic_is_a_python_error_not_a_crash():
    from dentalux import _core

    with pytest.raises(RuntimeError, match="internal error in dentalux core: deliberate"):
        _core.panic_in_worker()
    # the interpreter and the native module still work afterwards
    r = simulate([dentalux.Layer(mua=1, mus=9, g=0.75, n=1.0, thickness=0.2)], n_photons=100)
    assert r.photons == 100
