"""``dentalux tooth incisor|molar --out DIR``: write a procedural tooth as OBJ meshes."""

from __future__ import annotations

import typer

from dentalux.output_paths import check_out_dir, rebase, staged_dir
from dentalux.outputs import dumps_strict
from dentalux.progress import stages

tooth_app = typer.Typer(
    no_args_is_help=True,
    help="Procedural teeth: enamel.obj (air | enamel) and dentin.obj (enamel | dentin), mm.",
)


def _run(kind: str, out: str, resolution: float, as_json: bool,
         overwrite: bool = False) -> None:
    from dentalux import teeth  # scipy's interpolation: imported when a tooth is built

    out = check_out_dir(out, "--out", overwrite=overwrite)
    build = {"incisor": teeth.incisor, "molar": teeth.molar}[kind]
    # a fine grid takes minutes (docs/limits.md): a person watching sees it running
    with stages(f"{kind} at {resolution:g} mm", enabled=False if as_json else None) as step:
        step("building the meshes")
        tooth = build(resolution=resolution)
        step("checking and writing")
        with staged_dir(out, "--out") as stage:
            doc = rebase(tooth.write(stage), stage, out)
    doc["out"] = str(out)
    if as_json:
        print(dumps_strict(doc))
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
    out: str = typer.Option("incisor", "--out", "-o",
                            help="output folder: new or empty (see --overwrite)"),
    resolution: float = typer.Option(0.2, help="marching-cubes grid spacing [mm]"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
    overwrite: bool = typer.Option(False, "--overwrite",
                                   help="write into a non-empty --out folder"),
) -> None:
    """A maxillary central incisor (crown 8.7 x 10.2 mm)."""
    _run("incisor", out, resolution, as_json, overwrite)


@tooth_app.command("molar")
def molar_command(
    out: str = typer.Option("molar", "--out", "-o",
                            help="output folder: new or empty (see --overwrite)"),
    resolution: float = typer.Option(0.2, help="marching-cubes grid spacing [mm]"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
    overwrite: bool = typer.Option(False, "--overwrite",
                                   help="write into a non-empty --out folder"),
) -> None:
    """A maxillary first molar (crown 10.0 x 11.0 x 7.5 mm, three roots)."""
    _run("molar", out, resolution, as_json, overwrite)


def register(app: typer.Typer) -> None:
    app.add_typer(tooth_app, name="tooth")
