#!/usr/bin/env bash
# Wheel smoke test (`make wheel-test`, part of `make test`): install a built wheel into a
# throwaway virtual environment with nothing but its declared dependencies (pip's cache is
# reused), then use it from an empty folder outside the checkout:
#   dentalux --version (must be pyproject.toml's version), every data file, scene and
#   template of python/dentalux present in the install, a slab, `dentalux demo`, Fig. 2 of
#   `dentalux figures`, a tiny render of the packaged discs scene, `dentalux shade --json`
#   and a small `dentalux report`.
# Usage: [PIP=.venv/bin/pip] tests/wheel_smoke.sh dist/dentalux-VERSION-*.whl
set -euo pipefail

wheel=$(realpath "${1:?usage: tests/wheel_smoke.sh WHEEL}")
src=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/dentalux-wheel.XXXXXX")
trap 'rm -rf "$work"' EXIT
step() { printf 'wheel smoke [%3ds]: %s\n' "$SECONDS" "$*"; }

step "installing $(basename "$wheel") into a fresh venv"
# The venv gets no pip of its own when PIP names one (pip >= 22.3 installs into it with
# --python): nothing in it but the wheel and its dependencies, and no ensurepip to wait for.
if [[ -n "${PIP:-}" ]]; then
    python3 -m venv --without-pip "$work/venv"
    pip_in=("$PIP" --python "$work/venv/bin/python")
else
    python3 -m venv "$work/venv"
    pip_in=("$work/venv/bin/pip")
fi
# --no-compile: pip would byte-compile all of scipy, matplotlib and friends (most of the
# install time); the runs below compile only what they import, once (bytecode is written
# even where the caller sets PYTHONDONTWRITEBYTECODE: the venv is thrown away).
"${pip_in[@]}" install --quiet --disable-pip-version-check --no-compile "$wheel"
unset PYTHONDONTWRITEBYTECODE
py="$work/venv/bin/python"
dx="$work/venv/bin/dentalux"
mkdir "$work/run" && cd "$work/run"

version=$(sed -n 's/^version = "\(.*\)"$/\1/p' "$src/pyproject.toml" | head -n 1)
got=$("$dx" --version)
step "$got"
[[ "$got" == "dentalux $version" ]] || { echo "expected 'dentalux $version'" >&2; exit 1; }

step "package files (data, scenes, templates) in the install"
"$py" - "$src/python/dentalux" <<'EOF'
import sys
from pathlib import Path

import dentalux

src, inst = Path(sys.argv[1]), Path(dentalux.__file__).parent
if inst.resolve() == src.resolve():
    sys.exit("dentalux was imported from the checkout, not from the wheel")
wanted = [p.relative_to(src) for p in src.rglob("*") if p.is_file()
          and "__pycache__" not in p.parts and p.suffix not in (".pyc", ".so")]
missing = [str(p) for p in wanted if not (inst / p).is_file()]
if missing:
    sys.exit(f"the wheel lacks {len(missing)} file(s) of python/dentalux: {', '.join(missing)}")
for sub in ("data", "scenes", "report/templates"):
    if not any((inst / sub).iterdir()):
        sys.exit(f"the wheel has no {sub}/ files")
print(f"  {len(wanted)} files, all installed")
EOF

step "slab"
"$dx" slab --mua 0.1 --mus 5 --g 0.8 --n 1.5 --thickness 1 --photons 20000 --json \
    | "$py" -c 'import json, sys; d = json.load(sys.stdin); print("  R", d["total_reflectance"])'

step "demo (the Table 1 slab) and figures --only fig2 (data files read by the figures)"
"$dx" demo --photons 20000 > demo.log
"$dx" figures --quality preview --only fig2 --out figures > figures.log
test -s figures/fig2_spd.png

step "tiny render of the packaged discs scene"
scene=$("$py" -c 'from dentalux.scene.builtin import scene_file; print(scene_file("discs"))')
"$dx" render "$scene" --out render --resolution 16x12 --spp 1 --photons 2000 \
    --volume-photons 5000 --threads 2 > render.log
test -s render/radiance.npy && test -s render/render.json && test -s render/image.png

step "shade"
"$dx" shade enamel --against dentin --bands paper --photons 2000 --json > shade.json
"$py" -c 'import json; d = json.load(open("shade.json")); print("  TP00", d["tp00"], d["verdict"])'

step "report"
"$dx" report enamel --against dentin --thickness 1 --bands paper --photons 1000 \
    --tp-thicknesses 0.5 --render render --out report.html > /dev/null
grep -q 'data-key="tp00"' report.html
step "passed"
