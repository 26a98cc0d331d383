"""``dentalux shade``: the colour numbers a dental lab reads off a disc of a material."""

from __future__ import annotations

import json

import typer
from rich.console import Console
from rich.table import Table

from dentalux import dental
from dentalux.spectra import full_bands


def _bands(spec: str):
    if spec in ("full", "paper"):
        return spec
    if spec.startswith("full:"):  # full:STEP, a 380-780 nm sweep every STEP nm
        try:
            return full_bands(step=float(spec[5:]))
        except ValueError:
            raise ValueError(f"--bands = {spec!r}: full:STEP needs a step > 0 [nm]") from None
    try:
        return [float(x) for x in spec.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"--bands = {spec!r}: 'full', 'paper' or comma-separated nm") from None


def shade_command(
    material: str = typer.Argument(..., help="material name in the library, or a TOML file"),
    thickness: float = typer.Option(1.0, help="disc thickness [mm]"),
    against: str = typer.Option(None, help="reference material (name or TOML) for ΔE00/ΔTP00"),
    bands: str = typer.Option("full", help="'full' (380-780 nm/10 nm), 'full:STEP', 'paper' "
                              "or a comma-separated nm list"),
    backing_black: float = typer.Option(0.0, help="black backing reflectance, in [0, 1]"),
    backing_white: float = typer.Option(0.9, help="white backing reflectance, in [0, 1]"),
    contact: float = typer.Option(None, help="optical contact: coupling medium index (>= 1); "
                                  "default an air gap"),
    photons: int = typer.Option(dental.DEFAULT_PHOTONS, help="photons per band and run"),
    seed: int = typer.Option(1, help="random seed"),
    estimator: str = typer.Option("weighted", help="weighted | analog"),
    observer: str = typer.Option("2", help="'2' (CIE 1931) or '10' (CIE 1964)"),
    illuminant: str = typer.Option("D65", help="illuminant (colour-science name)"),
    threads: int = typer.Option(None, help="worker threads (default: all cores)"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """CIELAB over black/white and in transmission, TP, TP00, CR, OP (and ΔE00 vs --against)."""
    kw = dict(bands=_bands(bands), backing_black=backing_black, backing_white=backing_white,
              contact=contact, photons=photons, seed=seed, estimator=estimator,
              observer=observer, illuminant=illuminant, threads=threads,
              progress=False if as_json else None)
    m = dental.metrics(material, thickness, **kw)
    ref = dental.metrics(against, thickness, **kw) if against else None
    cmp = dental.compare(m, ref) if ref else None
    if as_json:
        out = m.to_json()
        if cmp:
            out.update({k: cmp[k] for k in ("delta_e00", "delta_tp00", "verdict")})
        print(json.dumps(out))
        return
    table = Table(title=f"{m.material}, {m.thickness:g} mm, {illuminant}, {observer} deg")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("MC std. error", justify="right")
    for key, label in (("lab_black", "L*a*b* over black"), ("lab_white", "L*a*b* over white"),
                       ("lab_transmitted", "L*a*b* transmitted")):
        v = getattr(m, key)
        e = [m.stderr[f"{key}.{c}"] for c in "Lab"]
        table.add_row(label, " ".join(f"{x:7.2f}" for x in v), " ".join(f"{x:.2f}" for x in e))
    for key, label in (("tp", "TP (ΔE*ab)"), ("tp00", "TP00 (ΔE00)"), ("cr", "CR = Yb/Yw"),
                       ("op", "OP")):
        table.add_row(label, f"{getattr(m, key):.4f}", f"{m.stderr[key]:.4f}")
    if cmp:
        table.add_row(f"ΔE00 vs {ref.material} (over white)", f"{cmp['delta_e00']:.3f}",
                      f"{cmp['delta_e00_stderr']:.3f}")
        table.add_row("  verdict", cmp["verdict"], f"PT {dental.PT}, AT {dental.AT}")
        table.add_row("ΔTP00", f"{cmp['delta_tp00']:.3f}", f"{cmp['delta_tp00_stderr']:.3f}")
        table.add_row("  translucency verdict", cmp["translucency_verdict"],
                      f"TPT {dental.TPT}, TAT {dental.TAT}")
    Console().print(table)
    Console().print(f"{m.photons} photons in {m.seconds:.1f} s")


def register(app: typer.Typer) -> None:
    app.command("shade")(shade_command)
