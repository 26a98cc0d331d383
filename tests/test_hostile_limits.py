"""Issue 18, part 3, items 3-6, 8, 9 and 12: sizes and counts refused up front with the memory
they would need, threads and Dask workers bounded, one band rule, a fit that round-trips,
and the Python API's errors (numpy integers, overflows, panics, progress callbacks).

Nothing here allocates more than a few MB: the machine's available memory is replaced by a
fixed figure where a test needs one, and the core is replaced by a stand-in for renders."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest
from dentalux import _core, _guard, limits
from dentalux.cli import main
from dentalux.testing import bands_from_band

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell.toml"
DISCS = ROOT / "scenes" / "discs.toml"
TABLE1 = ROOT / "python" / "dentalux" / "data" / "table1.csv"
SLAB = ["slab", "--mua", "1", "--mus", "9", "--g", "0.75", "--thickness", "0.2"]
GB = 1_000_000_000


class FakeCore:
    def __init__(self):
        self.calls = 0

    def __call__(self, scene_json, settings_json, progress=None):
        self.calls += 1
        scene = json.loads(scene_json)
        if progress is not None:
            progress(1)
        h, w = scene["camera"]["height"], scene["camera"]["width"]
        return np.ones((h, w), dtype=np.float32), {"photons_emitted": 1}


@pytest.fixture
def core(monkeypatch):
    fake = FakeCore()
    monkeypatch.setattr(_core, "render_bands", bands_from_band(fake), raising=False)
    return fake


@pytest.fixture
def eight_gb(monkeypatch):
    """A machine with 8 GB available, whatever this one has."""
    monkeypatch.setattr(limits, "available_memory_bytes", lambda: 8 * GB)


@pytest.fixture
def no_slab(monkeypatch):
    """Fail if the slab simulation starts: a refusal must come first."""
    import dentalux.cli.slab as slab_cli

    def never(*a, **k):
        raise AssertionError("the simulation started before the input was refused")

    monkeypatch.setattr(slab_cli, "simulate", never)


def run(capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert "Traceback" not in err and "panicked" not in err
    return exc.value.code, out, err


# ---------------------------------------------------------------------------------------
# 3. Sizes that cannot fit


def test_render_photon_maps_refused_with_their_memory(core, eight_gb, capsys, tmp_path):
    code, _, err = run(capsys, ["render", DISCS, "--out", tmp_path / "o", "--integrator",
                                "vpm", "--volume-photons", "5000000000", "--aim", "0.9",
                                "--resolution", "4x3", "--bands", "540"])
    assert code == 2 and "volume_photons = 5000000000" in err and "105 GB" in err, err
    assert "8 GB is available" in err and core.calls == 0
    assert not (tmp_path / "o").exists()


def test_render_volume_stored_sets_the_estimate(core, eight_gb):
    from dentalux.scene.load import load_scene

    sc = load_scene(DISCS)
    settings = {"integrator": "vpm", "photons": 1000, "volume_photons": 10**9,
                "volume_stored": 10**6}
    need = limits.render_memory_bytes(4, 3, 1, settings)
    assert need < 0.1 * GB  # the budget, not the emitted count, sizes the maps
    from dentalux import render

    with pytest.raises(ValueError, match="would need about"):
        render(sc, integrator="vpm", volume_photons=10**9, bands=[540], resolution=(4, 3),
               progress=False)
    render(sc, integrator="vpm", volume_photons=10**9, volume_stored=10**6, bands=[540],
           resolution=(4, 3), progress=False)
    assert core.calls == 1


def test_render_pixels_have_a_ceiling(core, capsys, tmp_path):
    code, _, err = run(capsys, ["render", CORNELL, "--out", tmp_path / "o", "--resolution",
                                "100000x100000", "--bands", "540"])
    assert code == 2 and "pixels is out of range" in err and core.calls == 0


@pytest.mark.parametrize("bins", ["2000000000", "4611686018427387904", "100000000"])
def test_slab_radial_bins_ceiling(no_slab, capsys, tmp_path, bins):
    code, _, err = run(capsys, [*SLAB, "--profiles", tmp_path / "p.npz", "--radial-bins",
                                bins])
    assert code == 2 and "--radial-bins" in err and f"{limits.MAX_RADIAL_BINS:,}" in err, err
    assert list(tmp_path.iterdir()) == []


def test_slab_profile_memory_checked(no_slab, monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(limits, "available_memory_bytes", lambda: 100_000_000)
    code, _, err = run(capsys, [*SLAB, "--profiles", tmp_path / "p.npz", "--radial-bins",
                                "1000000", "--photons", "10000000"])
    assert code == 2 and "would need about" in err and "--radial-bins = 1000000" in err, err


def test_texture_size_read_from_the_header(tmp_path):
    """An 8000 x 8000 PNG is a few kB on disk; it is refused before its pixels are decoded."""
    from dentalux.scene.load import read_toml, scene_from_dict
    from PIL import Image

    Image.new("1", (8000, 8000)).save(tmp_path / "big.png")
    assert (tmp_path / "big.png").stat().st_size < 200_000
    d = read_toml(CORNELL)
    d["surfaces"]["tex"] = {"type": "image", "file": "big.png"}
    with pytest.raises(ValueError, match=r"surfaces\.tex\.file = 'big\.png'.*8000x8000.*at "
                                         r"most 16,777,216 pixels"):
        scene_from_dict(d, base_dir=tmp_path)


def test_tooth_grid_refused_before_it_is_built(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(limits, "available_memory_bytes", lambda: 2 * GB)
    t0 = time.perf_counter()
    code, _, err = run(capsys, ["tooth", "incisor", "--resolution", "0.02", "--out",
                                tmp_path / "t"])
    assert code == 2 and "resolution = 0.02 mm" in err and "would need about" in err, err
    assert time.perf_counter() - t0 < 5 and not (tmp_path / "t").exists()


def test_memory_estimate_reads_the_machine():
    avail = limits.available_memory_bytes()
    assert avail is None or avail > 0
    assert limits.format_bytes(8653291520) == "8.65 GB"


# ---------------------------------------------------------------------------------------
# 4. Counts with a ceiling


def test_slab_photons_ceiling(no_slab, capsys):
    code, _, err = run(capsys, [*SLAB, "--photons", "1000000000000000"])
    assert code == 2 and "--photons" in err and f"{limits.MAX_SLAB_PHOTONS:,}" in err, err


@pytest.mark.parametrize("photons,message", [("100000000000", "100,000,000"),
                                             ("0", "out of range")])
def test_fit_mc_photons(monkeypatch, capsys, photons, message):
    import dentalux.cli.fit as fit_cli

    monkeypatch.setattr(fit_cli, "fit", lambda **k: pytest.fail("fitted"))
    code, _, err = run(capsys, ["fit", "--tt", "0.5", "--tr", "0.3", "--n", "1.5", "--g",
                                "0.7", "--thickness", "1", "--model", "mc", "--photons",
                                photons])
    assert code == 2 and "--photons" in err and message in err, err


def test_fit_api_photons_zero_refused():
    from dentalux.inverse import fit

    with pytest.raises(ValueError, match="photons = 0"):
        fit(tt=0.5, tr=0.3, n=1.5, g=0.7, thickness=1.0, model="mc", photons=0)


@pytest.mark.parametrize("args,field", [
    (["--photons", "1000000000000000"], "photons"),
    (["--volume-photons", "1000000000000000"], "volume_photons"),
    (["--spp", "1000000000"], "spp"),
])
def test_render_counts_ceiling(core, capsys, tmp_path, args, field):
    code, _, err = run(capsys, ["render", CORNELL, "--out", tmp_path / "o", "--bands", "540",
                                "--resolution", "4x3", *args])
    assert code == 2 and f"{field} = " in err and "out of range" in err, err
    assert core.calls == 0


# ---------------------------------------------------------------------------------------
# 5. Threads


@pytest.mark.parametrize("threads", ["10000", "100000", "-1", "0"])
def test_threads_bounded_on_the_command_line(no_slab, core, capsys, tmp_path, threads):
    code, _, err = run(capsys, [*SLAB, "--threads", threads])
    assert code == 2 and "threads" in err and "OverflowError" not in err, err
    code, _, err = run(capsys, ["render", CORNELL, "--out", tmp_path / "o", "--bands", "540",
                                "--resolution", "4x3", "--threads", threads])
    assert code == 2 and "threads" in err and core.calls == 0, err


def test_threads_bounded_in_python(core):
    from dentalux import render

    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=r"threads = 1099511627776 is out of range: allowed "
                                         r"1 \.\.\. " + f"{limits.max_threads()}"):
        render(CORNELL, threads=2**40, bands=[540], resolution=(4, 3), progress=False)
    assert time.perf_counter() - t0 < 5 and core.calls == 0
    assert limits.check_threads(limits.max_threads()) == limits.max_threads()
    assert limits.check_threads(np.int64(1)) == 1
    for bad in (-1, 0, 2**70, limits.max_threads() + 1):
        with pytest.raises(ValueError, match="threads"):
            limits.check_threads(bad)
    with pytest.raises(TypeError, match="threads"):
        limits.check_threads(1.5)


# ---------------------------------------------------------------------------------------
# 6. Dask


def test_cluster_unreachable_address_is_named(core, capsys, tmp_path):
    pytest.importorskip("dask.distributed")
    t0 = time.perf_counter()
    code, _, err = run(capsys, ["render", DISCS, "--out", tmp_path / "o", "--resolution",
                                "4x3", "--bands", "540", "--cluster", "tcp://127.0.0.1:1"])
    assert code == 2 and "tcp://127.0.0.1:1" in err and "no Dask scheduler" in err, err
    assert time.perf_counter() - t0 < 10 and not (tmp_path / "o").exists()


@pytest.mark.parametrize("address", ["tcp://", "tcp://host", "tcp://h:notaport"])
def test_cluster_bad_tcp_address(address):
    from dentalux.distributed import check_reachable

    with pytest.raises(ValueError, match="expected tcp://HOST:PORT|no Dask scheduler"):
        check_reachable(address)


def test_cluster_workers_capped(monkeypatch):
    pytest.importorskip("dask.distributed")
    import dask.distributed as dd
    from dentalux.distributed import DaskExecutor

    monkeypatch.setattr(dd, "LocalCluster", lambda **k: pytest.fail("started a cluster"))
    n = max(64, limits.max_workers() + 1)
    with pytest.raises(ValueError, match=rf"local:{n}.*allowed 1 \.\.\. {limits.max_workers()}"):
        DaskExecutor(f"local:{n}")


def test_cluster_start_failure_cleans_up(monkeypatch):
    pytest.importorskip("dask.distributed")
    import dask.distributed as dd
    from dentalux.distributed import DaskExecutor

    closed = []

    class Cluster:
        def __init__(self, **k):
            pass

        def close(self):
            closed.append(True)

    def client(*a, **k):
        raise OSError("boom")

    monkeypatch.setattr(dd, "LocalCluster", Cluster)
    monkeypatch.setattr(dd, "Client", client)
    with pytest.raises(OSError):
        DaskExecutor("local:1")
    assert closed == [True]


# ---------------------------------------------------------------------------------------
# 8. One band rule


def test_band_rule():
    assert limits.check_bands_in([450, 540.0], 400, 700, "m") == [450.0, 540.0]
    with pytest.raises(ValueError, match=r"bands\[0\] = 100 nm is out of range: allowed "
                                         r"\[360, 830\] nm"):
        limits.check_bands_in([100], 300, 900, "m")
    with pytest.raises(ValueError, match=r"bands\[0\] = 2000 nm"):
        limits.check_bands_in([2000], 300, 3000, "m", extrapolate=True)
    with pytest.raises(ValueError, match=r"bands\[1\] = 800 nm is out of range for m: its "
                                         r"data cover \[450, 600\] nm"):
        limits.check_bands_in([500, 800], 450, 600, "m")
    assert limits.check_bands_in([800], 450, 600, "m", extrapolate=True) == [800.0]
    with pytest.raises(ValueError, match="finite"):
        limits.check_bands_in([float("nan")], 450, 600, "m")


def test_render_applies_the_colour_range(core, capsys, tmp_path):
    code, _, err = run(capsys, ["render", CORNELL, "--out", tmp_path / "o", "--bands", "300",
                                "--resolution", "4x3"])
    assert code == 2 and "360" in err and core.calls == 0, err


# ---------------------------------------------------------------------------------------
# 9. A fitted spectrum that round-trips


def test_fit_table_duplicate_wavelengths_refused_before_fitting(monkeypatch, capsys,
                                                                tmp_path):
    import dentalux.cli.fit as fit_cli

    monkeypatch.setattr(fit_cli, "fit_table", lambda *a, **k: pytest.fail("fitted"))
    table = tmp_path / "t.csv"
    table.write_text("wavelength_nm,tt,tr,n,g,thickness_mm\n"
                     "540,0.5,0.3,1.5,0.7,1\n540,0.52,0.31,1.5,0.7,1\n")
    code, _, err = run(capsys, ["fit", "--table", table, "--model", "telegrapher", "--out",
                                tmp_path / "m.toml"])
    assert code == 2 and "rows 1 and 2" in err and "540" in err, err
    assert not (tmp_path / "m.toml").exists()


def test_fit_spectrum_must_load_back(monkeypatch, capsys, tmp_path):
    from dentalux import materials

    def refuse(path):
        raise ValueError(f"{path}: mua must be positive")

    monkeypatch.setattr(materials, "load", refuse)
    out = tmp_path / "m.toml"
    code, _, err = run(capsys, ["fit", "--table", TABLE1, "--model", "telegrapher", "--out",
                                out])
    assert code == 2 and "would not load" in err and str(out) in err, err
    assert list(tmp_path.iterdir()) == []


def test_fitted_spectrum_loads(capsys, tmp_path):
    from dentalux import materials

    out = tmp_path / "m.toml"
    code, text, _ = run(capsys, ["fit", "--table", TABLE1, "--model", "telegrapher", "--out",
                                 out, "--name", "disc"])
    assert code == 0 and f"wrote {out}" in text
    assert "disc" in materials.load(out)


# ---------------------------------------------------------------------------------------
# 12. Python API


def test_numpy_integers_accepted(core):
    from dentalux import render

    res = render(CORNELL, spp=np.int64(1), photons=np.int32(10), seed=np.uint8(3),
                 threads=np.int64(1), bands=[np.float32(540)],
                 resolution=(np.int64(4), np.int16(3)), progress=False)
    assert res.radiance.shape == (3, 4, 1)
    assert limits.as_int(np.int64(32), "width", 1) == 32


def test_progress_callback_is_called_and_its_error_propagates(core):
    from dentalux import render

    seen = []
    render(CORNELL, bands=[450, 540], resolution=(4, 3), progress=lambda d, t: seen.append(
        (d, t)))
    assert seen and seen[-1][0] == seen[-1][1]

    def boom(done, total):
        raise ZeroDivisionError("callback")

    with pytest.raises(ZeroDivisionError, match="callback"):
        render(CORNELL, bands=[540], resolution=(4, 3), progress=boom)


def test_native_progress_callback_error_propagates():
    layer = (0.1, 10.0, 0.9, 1.4, 1.0, 0.0, None)  # mua, mus, g, n, thickness, fd, lobes

    def boom(done):
        raise ZeroDivisionError("stop")

    with pytest.raises(ZeroDivisionError, match="stop"):
        _core.slab_simulate([layer], 50_000_000, 1, progress=boom)


def test_panics_become_runtime_error(capfd):
    with pytest.raises(RuntimeError, match="deliberate test panic"):
        _core.panic_in_worker()
    assert "panicked" not in capfd.readouterr().err

    class PanicException(BaseException):  # PyO3's, by name
        pass

    def panics():
        raise PanicException("capacity overflow")

    def overflows():
        raise OverflowError("can't convert negative int to unsigned")

    with pytest.raises(RuntimeError, match="internal error in dentalux core .*capacity"):
        _guard.guarded(panics, "slab_simulate")()
    with pytest.raises(ValueError, match="slab_simulate: an integer argument is out of range"):
        _guard.guarded(overflows, "slab_simulate")()
    assert getattr(_core.slab_simulate, "__dentalux_guarded__", False)


def test_native_overflow_is_value_error():
    layer = (0.1, 10.0, 0.9, 1.4, 1.0, 0.0, None)  # mua, mus, g, n, thickness, fd, lobes
    for kw in ({"threads": -1}, {"band": -5}):
        with pytest.raises(ValueError):
            _core.slab_simulate([layer], 1000, 1, **kw)
    with pytest.raises(ValueError):
        _core.slab_simulate([layer], 2**70, 1)


def test_slab_argument_checks():
    """The checks dentalux.slab calls (issue 18 item 12)."""
    with pytest.raises(ValueError, match=r"n_photons = 1180591620717411303424"):
        limits.check_slab(2**70)
    with pytest.raises(ValueError, match="threads = -1"):
        limits.check_slab(1000, threads=-1)
    with pytest.raises(ValueError, match="band = -5"):
        limits.check_slab(1000, band=-5)
    assert limits.check_slab(np.int64(1000), threads=np.int64(1), band=np.int64(540)) == 1000
    with pytest.raises(TypeError, match="layers = None: must be a list"):
        limits.check_layers(None)
    with pytest.raises(TypeError, match=r"lobes = 'ab': must be a list of \(weight, g\)"):
        limits.check_lobes("ab")
    with pytest.raises(TypeError, match=r"lobes\[0\]"):
        limits.check_lobes([("a", 0.5)])
    with pytest.raises(ValueError, match=r"lobes\[0\]\.g = 1"):
        limits.check_lobes([(1.0, 1)])
    assert limits.check_lobes([(0.5, 0.9), (0.5, np.float64(-0.2))]) == [(0.5, 0.9),
                                                                         (0.5, -0.2)]


@pytest.mark.parametrize("bands", ["100", "2000", "300,800"])
def test_shade_applies_the_colour_range(capsys, bands):
    code, _, err = run(capsys, ["shade", "enamel", "--thickness", "1", "--bands", bands])
    assert code == 2 and "out of range: allowed [360, 830] nm" in err, err


def test_spectra_bands_colour_range():
    from dentalux import spectra

    assert list(spectra.resolve_bands([360, 830])) == [360, 830]
    with pytest.raises(ValueError, match=r"bands\[0\] = 359 nm"):
        spectra.resolve_bands([359, 400])


def test_stages_name_what_runs_when_a_person_watches(capsys):
    """Long runs whose total is not known in units (a tooth's meshes) show a spinner with the
    stage and the elapsed time; nothing when no one watches."""
    import io

    from dentalux import progress
    from rich.console import Console

    with progress.stages("molar at 0.05 mm", enabled=False) as step:
        step("building the meshes")
    assert capsys.readouterr().err == ""
    shown = io.StringIO()
    console = Console(file=shown, force_terminal=True, width=80)
    with progress.stages("molar at 0.05 mm", enabled=True, console=console) as step:
        step("building the meshes")
    assert "molar at 0.05 mm: building the meshes" in shown.getvalue()
