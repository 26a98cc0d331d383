"""``dentalux materials list|show NAME|plot NAME``: browse the material library."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import typer

from dentalux import materials as lib
from dentalux.strict_json import dumps_checked

if TYPE_CHECKING:
    from rich.table import Table

materials_app = typer.Typer(
    no_args_is_help=True,
    help="The material library: list, show or plot spectral coefficients (1/mm, nm).",
)


@materials_app.command("list")
def list_command(
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """List every material name with its class, provenance kind and wavelength range."""
    rows = []
    for name in lib.names():
        m = lib.get(name)
        rows.append({
            "name": name,
            "resolves_to": m.name,
            "kind": m.provenance.get("kind"),
            "class": m.material_class,
            "wavelength_nm": [float(m.wavelength_nm[0]), float(m.wavelength_nm[-1])],
            "points": int(m.wavelength_nm.size),
            "description": m.description,
        })
    if as_json:
        print(dumps_checked({"materials": rows}, "materials list"))
        return
    from rich.console import Console

    console = Console()
    console.print(list_table(rows, console.width))


def list_table(rows: list[dict], width: int = 80) -> Table:
    """The library as one line per name, readable at 80 columns: names are never cut, a
    default name (``dentin``) says which variant it stands for, and the description is cut
    to the line (``materials show NAME`` prints it whole, with every value's source; ``--json``
    also gives the number of known wavelengths)."""
    from rich import box
    from rich.table import Table

    table = Table(title="materials", box=box.SIMPLE_HEAD, pad_edge=False, show_edge=False,
                  caption="whole descriptions and sources: dentalux materials show NAME")
    cells = []
    for r in rows:
        lo, hi = r["wavelength_nm"]
        span = f"{lo:g}–{hi:g}" if lo != hi else f"{lo:g}"
        if r["name"] != r["resolves_to"]:
            cells.append((r["name"], "default", span, f"= {r['resolves_to']}"))
        else:
            cells.append((r["name"], r["kind"], span, r["description"]))
    # the short columns keep their full width; the description takes the rest of the line
    heads = ("name", "kind", "nm")
    widths = [max([len(head), *(len(c[i]) for c in cells)]) for i, head in enumerate(heads)]
    for head, w in zip(heads, widths, strict=True):
        table.add_column(head, no_wrap=True, width=w)
    rest = max(width - sum(widths) - 10, 12)  # 3 separators, 6 cells of padding, 1 spare
    table.add_column("description", no_wrap=True, width=rest)
    for c in cells:
        desc = c[3] if len(c[3]) <= rest else c[3][: rest - 1] + "…"
        table.add_row(*c[:3], desc)
    return table


@materials_app.command("show")
def show_command(
    name: str = typer.Argument(..., help="material name, name@variant or a TOML path"),
    wavelength: list[float] = typer.Option(
        None, "--wavelength", "-w", help="also evaluate at these wavelengths [nm] (repeatable)"
    ),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """Show a material's known values, the provenance of each, and optional evaluations."""
    m = lib.get(name)
    d = m.to_dict()
    if wavelength:
        opt = m.at(np.asarray(wavelength, dtype=float))
        d["evaluated"] = {"wavelength_nm": list(wavelength),
                          **{q: getattr(opt, q).tolist() for q in lib.QUANTITIES}}
    if as_json:
        print(dumps_checked(d, "materials show"))
        return
    from rich.console import Console
    from rich.table import Table

    console = Console()
    console.print(f"[bold]{m.name}[/bold]: {m.description}")
    table = Table(title="known values (mua, mus in 1/mm)")
    for col in ("λ [nm]",) + lib.QUANTITIES:
        table.add_column(col, justify="right")
    for i, lam in enumerate(m.wavelength_nm):
        table.add_row(f"{lam:g}", *(f"{getattr(m, q)[i]:.4g}" for q in lib.QUANTITIES))
    console.print(table)
    if wavelength:
        ev = Table(title="evaluated (power law for mua, mus; linear for g, fd, n)")
        for col in ("λ [nm]",) + lib.QUANTITIES:
            ev.add_column(col, justify="right")
        for i, lam in enumerate(wavelength):
            ev.add_row(f"{lam:g}", *(f"{d['evaluated'][q][i]:.4g}" for q in lib.QUANTITIES))
        console.print(ev)
    prov = m.provenance
    console.print(f"class: {m.material_class}\nkind: {prov.get('kind')}\n"
                  f"source: {prov.get('source')}")
    if prov.get("notes"):
        console.print(f"notes: {prov['notes']}")
    for q, entry in prov.get("values", {}).items():
        entries = entry if isinstance(entry, list) else [entry]
        for i, e in enumerate(entries):
            at = f" @ {m.wavelength_nm[i]:g} nm" if isinstance(entry, list) else ""
            console.print(f"  {q}{at}: {e}")
    for s in prov.get("scaling", []):
        console.print(f"  SCALED: {s}")


def plot_material(m: lib.Material, out: Path, lo: float = 380.0, hi: float = 780.0) -> Path:
    """Plot μa, μs (log axis) and g over [lo, hi] nm with the known points marked; write a
    PNG to ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not (0 < lo < hi):
        raise ValueError(f"wavelength range [{lo}, {hi}] nm: need 0 < from < to")
    lam = np.linspace(lo, hi, 201)
    opt = m.at(lam)
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), constrained_layout=True)
    for ax, q, label in zip(axes, ("mua", "mus", "g"),
                            ("μa [1/mm]", "μs [1/mm]", "g"), strict=True):
        curve = getattr(opt, q)
        ax.plot(lam, curve, color="C0")
        ax.plot(m.wavelength_nm, getattr(m, q), "o", color="C3", label="known values")
        inside = (m.wavelength_nm[0] <= lam) & (lam <= m.wavelength_nm[-1])
        ax.axvspan(lo, m.wavelength_nm[0], color="0.92")
        ax.axvspan(m.wavelength_nm[-1], hi, color="0.92")
        if q in ("mua", "mus") and np.all(curve[inside] > 0):
            ax.set_yscale("log")
        ax.set_xlabel("wavelength [nm]")
        ax.set_ylabel(label)
        ax.set_xlim(lo, hi)
    axes[0].legend(loc="best", fontsize=8)
    title = f"{m.name} ({m.provenance.get('kind')}); shaded: extrapolated"
    if m.is_scaled:
        title += "; SCALED"
    fig.suptitle(title)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


@materials_app.command("plot")
def plot_command(
    name: str = typer.Argument(..., help="material name, name@variant or a TOML path"),
    out: str = typer.Option(
        None, "--out", "-o", help="image file, .png, .svg or .pdf (default: NAME.png; "
                                  "replaced if it exists)"),
    lo: float = typer.Option(380.0, "--from", help="first wavelength [nm]"),
    hi: float = typer.Option(780.0, "--to", help="last wavelength [nm]"),
) -> None:
    """Plot μa, μs and g over wavelength to a PNG."""
    from dentalux.output_paths import atomic_file, check_out_file

    m = lib.get(name)
    if out is None:
        out = m.name.replace("@", "_").replace("/", "_") + ".png"
    out = check_out_file(out, "--out", (".png", ".svg", ".pdf"))
    with atomic_file(out, "--out") as tmp:
        plot_material(m, tmp, lo, hi)
    print(out)


def register(app: typer.Typer) -> None:
    app.add_typer(materials_app, name="materials")
