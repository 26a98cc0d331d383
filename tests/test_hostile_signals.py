"""Issue 18, part 3, item 13 and the documented limits: SIGTERM ends a render at once with
nothing written (docs/limits.md, beside Ctrl-C's exit 130), and docs/limits.md quotes the
numbers of dentalux.limits."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from dentalux import limits

ROOT = Path(__file__).resolve().parents[1]
DENTALUX = str(Path(sys.executable).with_name("dentalux"))


def test_sigterm_ends_a_render_with_nothing_written(tmp_path):
    out = tmp_path / "out"
    cmd = [DENTALUX, "render", str(ROOT / "scenes" / "discs.toml"), "--out", str(out),
           "--integrator", "volpath", "--spp", "100000", "--resolution", "64x48"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(3.0)
    assert proc.poll() is None, proc.communicate()
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    try:
        proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("did not stop within 10 s of SIGTERM")
    assert time.monotonic() - t0 < 2.0
    assert proc.returncode == -signal.SIGTERM
    assert list(tmp_path.iterdir()) == []


def test_limits_page_quotes_the_constants():
    text = (ROOT / "docs" / "limits.md").read_text()
    for value in (limits.MAX_SLAB_PHOTONS, limits.MAX_FIT_PHOTONS, limits.MAX_RENDER_PHOTONS,
                  limits.MAX_SPP, limits.MAX_PIXELS, limits.MAX_RADIAL_BINS,
                  limits.MAX_ANGLE_BINS, limits.MAX_TEXTURE_PIXELS):
        assert f"{value:,}" in text, value
    for name, value in (("THREADS_PER_CORE", limits.THREADS_PER_CORE),
                        ("WORKERS_PER_CORE", limits.WORKERS_PER_CORE)):
        assert f"{name} = {value}" in text
    assert f"{100 * limits.MEMORY_FRACTION:.0f} %" in text
    assert f"{limits.PHOTON_BYTES} bytes" in text
    assert f"{limits.TOOTH_NODE_BYTES} bytes" in text
    assert f"{limits.TEXEL_BYTES} bytes" in text
    assert "docs/limits.md" in (ROOT / "README.md").read_text()


def test_help_reads_the_constants(capsys):
    from dentalux.cli import main

    with pytest.raises(SystemExit):
        main(["slab", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert f"{limits.MAX_RADIAL_BINS:,}" in help_text
