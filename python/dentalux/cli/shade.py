"""``dentalux shade``: the colour numbers a dental lab reads off a disc of a material."""

from __future__ import annotations

import typer

from dentalux import dental, instrument, shade_guides
from dentalux.cli import measure_options as mo
from dentalux.cli.measure_options import DEFAULTS
from dentalux.strict_json import check_finite, dumps_strict


def shade_command(
    material: str = typer.Argument(None, help="material name in the library, or a TOML file "
                                   "(omit when --layer gives a layered specimen)"),
    thickness: float = typer.Option(1.0, help="disc thickness [mm]"),
    against: str = typer.Option(None, help="reference material (name or TOML) for ΔE00/ΔTP00"),
    instrument_name: str = typer.Option(
        instrument.DEFAULT, "--instrument",
        help="instrument preset (`dentalux instruments list`), a TOML file, or 'infinite' "
             "(a laterally infinite disc over infinite areas)"),
    illuminated_diameter: float = typer.Option(None, help="override: lit spot diameter [mm]"),
    viewed_diameter: float = typer.Option(None, help="override: viewed window diameter [mm]"),
    geometry: str = typer.Option(None, help="override: " + "|".join(instrument.GEOMETRIES)),
    bands: mo.Bands = DEFAULTS["bands"],
    backing_black: mo.BackingBlack = None,
    backing_white: mo.BackingWhite = None,
    contact: mo.Contact = None,
    match: str = typer.Option(None, help="report the nearest tabs of a shade guide: "
                              "bioform | vita-classical | vita-3d-master | an imported "
                              "guide (`dentalux guides list`) | a guide FILE.csv"),
    layer: list[str] = typer.Option(None, help="MATERIAL:THICKNESS, repeated top to bottom: "
                                    "a layered specimen instead of MATERIAL"),
    substrate: str = typer.Option(None, help="substrate under the --layer stack "
                                  "(see `dentalux design --help`)"),
    photons: mo.Photons = DEFAULTS["photons"],
    precision: mo.Precision = None,
    solver: mo.Solver = DEFAULTS["solver"],
    seed: mo.Seed = DEFAULTS["seed"],
    estimator: mo.Estimator = DEFAULTS["estimator"],
    observer: mo.Observer = DEFAULTS["observer"],
    illuminant: mo.Illuminant = DEFAULTS["illuminant"],
    threads: mo.Threads = None,
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
    readings_out: str = typer.Option(
        None, "--readings-out", help="write the reading over black and white as a readings "
        "file (CSV) for `dentalux fit --readings`; an existing readings file gains the rows"),
) -> None:
    """CIELAB over black/white and in transmission, TP, TP00, CR, OP as an instrument reads
    them (and ΔE00 vs --against, the nearest shade tabs with --match)."""
    if readings_out:
        from dentalux import readings

        readings.check_out(readings_out)
    inst = instrument.get(instrument_name).override(
        illuminated_diameter_mm=illuminated_diameter, viewed_diameter_mm=viewed_diameter,
        geometry=geometry)
    specimen = None
    if layer:
        if material is not None:
            raise ValueError("give either MATERIAL or --layer, not both")
        from dentalux import design

        specimen = design.parse_fixed_layers(layer)
        if substrate is not None:
            specimen = design.specimen(specimen, substrate)
            core = design.backings(substrate)  # an opaque core replaces both backings
            backing_black = core.get("backing_black", backing_black)
            backing_white = core.get("backing_white", backing_white)
    elif material is None:
        raise ValueError("MATERIAL: missing (or give --layer MATERIAL:THICKNESS)")
    elif substrate is not None:
        raise ValueError("--substrate goes with --layer")
    kw = dict(bands=mo.bands(bands), backing_black=backing_black, backing_white=backing_white,
              contact=contact, photons=photons, seed=seed, estimator=estimator,
              observer=observer, illuminant=illuminant, threads=threads,
              progress=False if as_json else None, precision=precision, solver=solver)
    out = dental.shade(material, thickness, against=against, instrument=inst, match=match,
                       specimen=specimen, **kw)
    check_finite(out, "shade")  # a NaN or inf reading is an error, never printed
    if match:
        out.update(shade_guides.instrument_note(match, inst, illuminant=illuminant,
                                                observer=observer))
    if readings_out:
        total = sum(t for _, t in specimen) if specimen else thickness
        readings.write(readings_out, out, total, comment=readings.comment_from_shade(
            out, material if specimen is None else out.get("layers"), photons, seed))
    if as_json:
        print(dumps_strict(out))
        return
    m = out
    se = m["stderr"]
    ins = m["instrument"]
    def mm(d):  # the infinite disc's areas are unbounded (None in the JSON)
        return "unbounded" if d is None else f"{d} mm"

    where = (f"{ins['name']}: {ins['geometry']}, lit {mm(ins['illuminated_diameter_mm'])}, "
             f"viewed {mm(ins['viewed_diameter_mm'])}, specular {ins['specular']}")
    title = (" / ".join(f"{n} {t:g} mm" for n, t in specimen) if specimen
             else f"{material}, {thickness:g} mm")
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"{title}, {illuminant}, {observer} deg, read by {where}")
    table.add_column("quantity")
    table.add_column("value ± standard error", justify="right")
    for key, label in (("lab_black", "L*a*b* over black"), ("lab_white", "L*a*b* over white"),
                       ("lab_transmitted", "L*a*b* transmitted")):
        table.add_row(label, "  ".join(f"{x:.2f} ± {e:.2f}" for x, e in zip(m[key], se[key],
                                                                              strict=True)))
    for key, label in (("tp", "TP (ΔE*ab)"), ("tp00", "TP00 (ΔE00)"), ("cr", "CR = Yb/Yw"),
                       ("op", "OP")):
        digits = 4 if key == "cr" else 2
        table.add_row(label, f"{m[key]:.{digits}f} ± {se[key]:.{digits}f}")
    table.add_row("edge loss over black / white",
                  f"{m['edge_loss']['black']:.4f} / {m['edge_loss']['white']:.4f}")
    if against:
        table.add_row(f"ΔE00 vs {against} (over white)",
                      f"{m['delta_e00']:.3f} ± {m['delta_e00_stderr']:.3f}")
        table.add_row("  verdict", f"{m['verdict']} (PT {dental.PT}, AT {dental.AT}; "
                      f"classes within ±{dental.VERDICT_SIGMAS:g} s.e.)")
        table.add_row("ΔTP00", f"{m['delta_tp00']:.3f}")
    for row in m.get("shade_match", [])[:3]:
        table.add_row(f"{match} {row['tab']}", f"ΔE00 {row['delta_e00']:.2f}")
    if m.get("shade_match_instrument", {}).get("note"):
        table.add_row("  guide instrument", m["shade_match_instrument"]["note"])
    # the JSON's photons are the run's total; the table says it per band too
    per_band = (f"{m['photons'] // max(len(m['wavelength_nm']), 1)} photons per band "
                f"({m['photons']} in all)")
    if m["method"] != "layered":
        how = per_band
    elif m["photons"]:
        how = f"layered solver, its rim walk's budget {per_band}"
    else:
        how = "layered solver alone (no rim, no Monte Carlo)"
    photons_line = f"{how}, {m['cpu_seconds']:.1f} CPU-s"
    if "precision" in m:
        p = m["precision"]
        photons_line += (f"; precision asked {p['requested']:g}: the reading has no Monte "
                         "Carlo noise" if p["noise_free"] else
                         f"; precision asked {p['requested']:g}, reached {p['achieved']:.3f} "
                         f"ΔE00 ({p['photons_per_band']} photons per band)")
    if "rim_bound" in m:  # the standard error of these bands is the zero count's bound
        rb = m["rim_bound"]
        seen = {nm for bands in rb["bands_nm"].values() for nm in bands}
        photons_line += (f"\nno photon of the rim walk ({rb['launched_per_band']} per band) "
                         f"reached the window from past the rim in {len(seen)} of "
                         f"{len(m['wavelength_nm'])} bands: their standard error is the "
                         "bound from that zero count")
    table.caption = photons_line
    Console().print(table)


def register(app: typer.Typer) -> None:
    app.command("shade")(shade_command)
