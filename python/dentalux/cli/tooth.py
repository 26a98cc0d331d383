"""``dentalux tooth incisor|molar --out DIR``: write a procedural tooth as OBJ meshes."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from dentalux import teeth

tooth_app = typer.Typer(
    no_args_is_help=True,
    help="Procedural teeth: enamel.obj (air | enamel) and dentin.obj (enamel | dentin), mm.",
)


def _run(kind: str, out: Path, resolution: float, as_json: bool) -> None:
    build = {"incisor": teeth.incisor, "molar": teeth.molar}[kind]
    tooth = build(resolution=resolution)
    doc = tooth.write(out)
    doc["out"] = str(out)
    if as_json:
        print(json.dumps(doc))
        return
    d, tgt = doc["dimensions"], doc["targets"]
    print(f"{kind}: {doc['enamel']['triangles']} + {doc['dentin']['triangles']} triangles, "
          f"closed and oriented, dentin inside enamel (no crossings)")
    for key in ("crown_width_mm", "crown_length_mm", "crown_thickness_mm", "root_length_mm"):
        print(f"  {key:20s} {d[key]:6.2f}  (target {tgt[key][0]:g}: {tgt[key][1]})")
    t = doc["enamel_thickness_mm"]
    print(f"  enamel thickness over the crown {t['crown_min']:.2f}-{t['crown_max']:.2f} mm")
    print(f"wrote {out / 'enamel.obj'}, {out / 'dentin.obj'}, {out / 'tooth.json'}")


@tooth_app.command("incisor")
def incisor_command(
    out: Path = typer.Option(Path("incisor"), "--out", "-o", help="output directory"),
    resolution: float = typer.Option(0.2, help="marching-cubes grid spacing [mm]"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """A maxillary central incisor (crown 8.7 x 10.2 mm)."""
    _run("incisor", out, resolution, as_json)


@tooth_app.command("molar")
def molar_command(
    out: Path = typer.Option(Path("molar"), "--out", "-o", help="output directory"),
    resolution: float = typer.Option(0.2, help="marching-cubes grid spacing [mm]"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """A maxillary first molar (crown 10.0 x 11.0 x 7.5 mm, three roots)."""
    _run("molar", out, resolution, as_json)


def register(app: typer.Typer) -> None:
    app.add_typer(tooth_app, name="tooth")
