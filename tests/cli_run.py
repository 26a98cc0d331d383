"""Running the installed `dentalux` command from tests: its path, the packaged scenes and a
subprocess call with a timeout (shared by the command-line tests)."""

import subprocess
import sys
from pathlib import Path

DENTALUX = str(Path(sys.executable).with_name("dentalux"))
SCENES = Path(__file__).resolve().parents[1] / "scenes"


def cli(*args, timeout: float = 120):
    """Run ``dentalux ARGS...``; the CompletedProcess with its text output."""
    return subprocess.run([DENTALUX, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def run_main(capsys, *args) -> tuple[int, str, str]:
    """The command line in process: (exit code, stdout, stderr); 0 when it returns."""
    from dentalux.cli import main

    try:
        main([str(a) for a in args])
        code = 0
    except SystemExit as exc:
        code = exc.code or 0
    out = capsys.readouterr()
    return code, out.out, out.err
