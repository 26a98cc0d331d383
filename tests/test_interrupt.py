"""Ctrl-C stops long native runs promptly: the CLI exits with 130 (the shell's code for
SIGINT), no traceback, no hang."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

DENTALUX = str(Path(sys.executable).with_name("dentalux"))
SCENES = Path(__file__).resolve().parents[1] / "scenes"

LONG_RUNS = {
    "slab": [DENTALUX, "slab", "--mua", "0.04", "--mus", "26", "--g", "0.9", "--n", "1.54",
             "--thickness", "2", "--photons", "1000000000"],
    "render": [DENTALUX, "render", str(SCENES / "discs.toml"), "--out", "{tmp}",
               "--integrator", "volpath", "--spp", "100000", "--resolution", "64x48"],
    "render-bre": [DENTALUX, "render", str(SCENES / "discs.toml"), "--out", "{tmp}",
                   "--integrator", "bre", "--spp", "100000", "--resolution", "64x48",
                   "--volume-photons", "200000"],
    "render-hero-camera": [DENTALUX, "render", str(SCENES / "discs.toml"), "--out", "{tmp}",
                           "--integrator", "vpm", "--hero-camera", "--bands", "450,540,605",
                           "--spp", "100000", "--resolution", "64x48",
                           "--volume-photons", "200000"],
    # the layered solver's threads (41 bands of a two-layer stack, many seconds of solve)
    "shade-layered": [DENTALUX, "shade", "--layer", "enamel:0.6", "--layer", "dentin:0.9",
                      "--substrate", "none", "--bands", "full:2", "--solver", "layered"],
}


@pytest.mark.parametrize("name", sorted(LONG_RUNS))
def test_ctrl_c_stops_promptly(name, tmp_path):
    cmd = [c.replace("{tmp}", str(tmp_path / "out")) for c in LONG_RUNS[name]]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(3.0)  # past start-up: the native loop is running
    assert proc.poll() is None, proc.communicate()
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("did not stop within 10 s of SIGINT")
    assert time.monotonic() - t0 < 5.0
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "panic" not in err
