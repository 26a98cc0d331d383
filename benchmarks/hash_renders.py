"""Bit-identity check for behaviour-preserving changes: render every integrator on the
built-in discs and Cornell box, and the crown figure's teeth (triangle meshes), with aimed
photons too (48x36, one band at 540 nm, fixed seed) with the core's
`examples/hash_render` binary and print a hash of each image's bits. Run it with the binary
built before and after a change (e.g. from a `git worktree` of the old commit) and compare
the two lists; they must be equal line for line.

    cargo build --release -p dentalux-core --example hash_render
    .venv/bin/python benchmarks/hash_renders.py [--bin target/release/examples/hash_render]
        [--inputs DIR]

`--inputs` keeps the scene and settings JSON files there (default: a temporary folder).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
from pathlib import Path

from dentalux.scene import builtin, load_scene
from dentalux.scene.builtin import scene_file
from dentalux.scene.load import scene_from_dict

BASE = {"spp": 2, "photons": 20000, "volume_photons": 100000, "volume_stored": 0, "aim": 0.0,
        "k": 64, "seed": 5, "max_depth": 64, "passes": 1, "alpha": 0.7,
        "final_gather": False, "kernel_layer": 0.3, "kernel_clip": True,
        "volume_estimator": "points", "band": 540}
# (scene, name, settings changes)
CASES = [
    ("cornell", "path", {"integrator": "path"}),
    ("cornell", "pm", {"integrator": "pm"}),
    ("cornell", "ppm", {"integrator": "ppm", "passes": 2}),
    ("cornell", "volpath", {"integrator": "volpath"}),
    ("cornell", "vpm", {"integrator": "vpm"}),
    ("discs", "bre", {"integrator": "bre"}),
    ("discs", "bre-noclip-r0.5", {"integrator": "bre", "kernel_clip": False, "radius": 0.5}),
    ("discs", "ppm", {"integrator": "ppm", "passes": 2}),
    ("discs", "ppm-beam", {"integrator": "ppm", "passes": 2, "volume_estimator": "beam"}),
    ("discs", "ppm-beam-r0.6", {"integrator": "ppm", "passes": 2, "volume_estimator": "beam",
                                "radius": 0.6}),
    ("discs", "volpath-nee", {"integrator": "volpath-nee"}),
    ("discs", "volpath", {"integrator": "volpath"}),
    ("discs", "vpm-full", {"integrator": "vpm-full"}),
    ("discs", "vpm", {"integrator": "vpm"}),
    ("discs", "vpm-full-beam", {"integrator": "vpm-full", "volume_estimator": "beam"}),
    ("discs", "vpm-aim", {"integrator": "vpm", "aim": 0.5, "volume_stored": 100000}),
    ("crown", "vpm-aim", {"integrator": "vpm", "aim": 0.5, "volume_stored": 100000}),
    ("crown", "volpath-nee", {"integrator": "volpath-nee"}),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default="target/release/examples/hash_render")
    ap.add_argument("--inputs", default=None)
    a = ap.parse_args()
    folder = Path(a.inputs or tempfile.mkdtemp(prefix="dentalux-hash-"))
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("discs", "cornell"):
        text = load_scene(scene_file(name)).to_json(540.0, (48, 36))
        (folder / f"{name}.json").write_text(text)
    # the crown figure's scene with coarse teeth meshes (1 mm triangles)
    crown = scene_from_dict(builtin.crown((48, 36), 1.0)[0]).to_json(540.0, (48, 36))
    (folder / "crown.json").write_text(crown)
    for scene, name, change in CASES:
        settings = folder / f"{scene}_{name}.settings.json"
        settings.write_text(json.dumps({**BASE, **change}))
        out = subprocess.run([a.bin, str(folder / f"{scene}.json"), str(settings)],
                             capture_output=True, text=True, check=True).stdout.split()
        print(f"{scene:8s} {name:16s} {out[-1]}")


if __name__ == "__main__":
    main()
