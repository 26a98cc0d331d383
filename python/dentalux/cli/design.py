"""``dentalux design``: which thickness of each material matches a target tooth (issue 19),
or how given thicknesses rank (``--evaluate``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import typer

from dentalux import instrument as instruments
from dentalux.cli import measure_options
from dentalux.strict_json import dumps_checked

if TYPE_CHECKING:
    from rich.table import Table


def design_command(
    target: str = typer.Option(..., help="lab:L,a,b | GUIDE:TAB (e.g. vita-classical:A2, or "
                               "a guide from `dentalux guides import`) | FILE.csv:TAB | "
                               "stack:MATERIAL:MM/MATERIAL:MM/..."),
    layer: list[str] = typer.Option(..., help="MATERIAL:MIN-MAX [mm], top to bottom; "
                                    "repeat for 1 to 3 layers (with --evaluate the range "
                                    "may be left out)"),
    total: str = typer.Option(None, help="total restoration thickness MIN-MAX [mm] "
                              "(veneer 0.3-0.8, crown 1.0-2.0)"),
    substrate: str = typer.Option("dentin", help="none | dentin | stump | zirconia | metal | "
                                  "reflectance:R | reflectance:FILE.csv"),
    cement: str = typer.Option(None, help="cement layer MATERIAL:MM between restoration "
                               "and substrate"),
    instrument: str = typer.Option(instruments.DEFAULT, help="instrument preset or TOML file"),
    target_instrument: str = typer.Option(None, help="instrument that read the target "
                                          "(preset or TOML file; default: --instrument)"),
    target_tp: float = typer.Option(None, help="translucency target TP00"),
    bands: measure_options.Bands = measure_options.DEFAULTS["bands"],
    photons: int = typer.Option(
        None, help="photons per band and run (default: dentalux.design.search's)"),
    verify_photons: int = typer.Option(None, help="photons for the verification (default "
                                       "--photons)"),
    precision: measure_options.Precision = None,
    solver: measure_options.Solver = measure_options.DEFAULTS["solver"],
    designs: int = typer.Option(3, help="how many designs to report"),
    nodes: int = typer.Option(None, help="fast-model nodes per layer (default 6/4/3)"),
    seed: int = typer.Option(1, help="random seed"),
    threads: int = typer.Option(None, help="worker threads (default: all cores)"),
    evaluate: str = typer.Option(None, help="no search: read these thicknesses T1/T2/... "
                                 "[mm] (one per layer, top to bottom; candidates separated "
                                 "by ',', e.g. 0.5/0.9,0.6/0.8) and rank them by ΔE00"),
    plot: str = typer.Option(None, help="write the ΔE00 curve (one layer) or plane (two "
                             "layers) of the design (PNG)"),
    render: str = typer.Option(None, help="render the best design's crown beside a natural "
                               "incisor into folder DIR (its files are replaced) and print the "
                               "rendered ΔE00 beside the predicted one"),
    render_quality: str = typer.Option("draft", help="with --render: draft | preview | paper"),
    render_repeats: int = typer.Option(1, help="with --render: independent renders averaged "
                                       "(from 2 on their spread is the error)"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """Rank layer thicknesses by ΔE00 to a target, verified by the full Monte Carlo."""
    # the design package pulls in scipy's interpolation: imported here, not at start-up
    from dentalux.design import optimise, search
    from dentalux.design import targets as design_targets

    t_inst, d_inst = design_targets.resolve_instrument(target_instrument, instrument)
    photons = search.DEFAULT_PHOTONS if photons is None else photons
    if evaluate is not None:
        _evaluate(target, layer, evaluate, total, substrate, cement, instrument, target_tp,
                  bands, photons, precision, seed, threads, plot, render, as_json, solver)
        return
    if render is not None:  # refuse a bad folder or substrate before the search
        from dentalux.design import render as design_render

        design_render.check(render, substrate, render_quality, render_repeats)
    if plot is not None:
        from dentalux.design.plot import check_path

        check_path(plot, len(layer))
    if t_inst != d_inst:  # read a stack target through its own instrument
        target = design_targets.parse(target, read=design_targets.read_through(
            target_instrument, bands=measure_options.bands(bands), photons=verify_photons
            or photons, seed=seed + 2, threads=threads, solver=solver), instrument=t_inst)
    res = optimise(target, layer, total=total, substrate=substrate, cement=cement,
                   instrument=instrument, bands=measure_options.bands(bands), target_tp=target_tp,
                   photons=photons, verify_photons=verify_photons, seed=seed,
                   designs=designs, nodes=nodes, threads=threads,
                   progress=False if as_json else None, precision=precision, solver=solver)
    res.target = design_targets.parse(res.target, instrument=t_inst)
    note = design_targets.differs_note(res.target, d_inst)
    if plot is not None:
        from dentalux.design.plot import plane

        plane(res, plot, total)
    rendered = None
    if render is not None:
        rendered = design_render.render_design(res, render, quality=render_quality,
                                               repeats=render_repeats, seed=seed,
                                               threads=threads,
                                               progress=False if as_json else None)
    guide_note = _guide_instrument(res)
    if as_json:
        out = {**res.to_json(), **_setup_json(res, layer, cement)}
        out.update(guide_note)
        if rendered is not None:
            out["render"] = _render_json(rendered)
        print(dumps_checked(out, "design"))
        return
    from rich.console import Console

    console = Console()
    console.print(design_table(res.target, res.designs, res.substrate,
                               res.instrument["name"]))
    if note:
        console.print(f"note: {note}")
    elif guide_note and guide_note["target_instrument"]["note"]:
        console.print(f"note: {guide_note['target_instrument']['note']}")
    console.print(f"search {res.search_seconds:.1f} s, verification {res.verify_seconds:.1f} s")
    if plot:
        console.print(f"plot: {plot}")
    if rendered is not None:
        r, p = rendered["rendered"], rendered["predicted"]
        # the two ΔE00 answer different questions: the render's is crown against the rendered
        # natural incisor, the slab's is the design against its target
        console.print(f"design 1: rendered ΔE00 crown vs natural incisor {r['delta_e00']:.2f} ± "
                      f"{r['delta_e00_stderr']:.2f}; slab ΔE00 design vs target "
                      f"{p['delta_e00']:.2f} ± {p['delta_e00_stderr']:.2f} (rendered L*a*b* crown "
                      + " ".join(f"{x:.1f}" for x in r["lab"]["crown"]) + ", natural "
                      + " ".join(f"{x:.1f}" for x in r["lab"]["natural"])
                      + f"; {rendered['seconds']:.0f} s)")
        console.print(f"render: {rendered['files']['annotated_png']}, "
                      f"{rendered['files']['render_json']}")


#: the widest single word of a verdict: the verdict column never cuts a word
VERDICT_WIDTH = max(len(v) for v in ("imperceptible", "acceptable", "unacceptable"))


def design_table(target, designs: list[dict], substrate: str, instrument: str,
                 evaluated: bool = False) -> Table:
    """The designs (or ``--evaluate``'s candidates) as a table readable at 80 columns: short
    headers, no outer padding, the title and the verdicts wrapped at spaces, never cut."""
    from rich import box
    from rich.table import Table

    t = target
    what = "candidates ranked" if evaluated else "designs"
    table = Table(title=f"{what} for L*a*b* {t.lab[0]:.1f} {t.lab[1]:.1f} {t.lab[2]:.1f}"
                  + (f", TP00 {t.tp00:.1f}" if t.tp00 is not None else "")
                  + f" on {substrate}, read by {instrument}", box=box.SIMPLE_HEAD,
                  pad_edge=False, padding=(0, 1), title_justify="left")
    table.add_column("mm, top\nto bottom", no_wrap=True)
    table.add_column("L* a* b*", justify="right", overflow="fold")
    table.add_column("ΔE00\n± s.e.", justify="right", no_wrap=True)
    table.add_column("verdict", min_width=VERDICT_WIDTH, overflow="fold")
    if evaluated:
        table.add_column("in\nranges", overflow="fold")
    else:
        table.add_column("ΔE00 per\n0.1 mm", justify="right", overflow="fold")
        table.add_column("veri-\nfied", overflow="fold")
    for d in designs:
        row = ["/".join(f"{x:.2f}" for x in d["thickness_mm"]),
               " ".join(f"{x:.1f}" for x in d["lab"]),
               f"{d['delta_e00']:.2f}±{d['delta_e00_stderr']:.2f}", d["verdict"]]
        if evaluated:
            row.append("yes" if d["within_ranges"] else "NO")
        else:
            row += [" ".join(f"{x:.2f}" for x in d["sensitivity"]),
                    "yes" if d["verified"] else "NO"]
        table.add_row(*row)
    return table


def _setup_json(res, layer_specs=(), cement_spec=None) -> dict:
    """What the design was made for, beside ``DesignResult.to_json`` (new keys, for
    ``dentalux report --design``): the substrate, the layers (name, range and ``spec``: the
    material as given, a library name or ``FILE.toml:NAME``, so it can be read again), the
    cement, the bands."""
    from dentalux.design import constraints

    specs = [constraints.parse_layer(t, i)[0] for i, t in enumerate(layer_specs)]
    layers = [{**lay, **({"spec": specs[i]} if i < len(specs) else {})}
              for i, lay in enumerate(res.layers)]
    cement = None
    if res.cement is not None:
        cement = {"material": str(getattr(res.cement[0], "name", "material")),
                  "thickness_mm": float(res.cement[1])}
        if cement_spec:
            cement["spec"] = str(cement_spec).rpartition(":")[0]
    return {"substrate": res.substrate, "layers": layers, "cement": cement,
            "bands_nm": res.bands}


def _evaluate(target, layer, evaluate, total, substrate, cement, instrument, target_tp, bands,
              photons, precision, seed, threads, plot, render, as_json, solver) -> None:
    """``--evaluate``: read the given thicknesses and rank them (dentalux.design.evaluate)."""
    from dentalux.design.evaluate import evaluate as run

    for name, value in (("--plot", plot), ("--render", render)):
        if value is not None:
            raise ValueError(f"{name} with --evaluate: the plot and the render belong to a "
                             "search; drop --evaluate to search")
    res = run(target, layer, evaluate, total=total, substrate=substrate, cement=cement,
              instrument=instrument, bands=measure_options.bands(bands), target_tp=target_tp,
              photons=photons, seed=seed, precision=precision, threads=threads,
              progress=False if as_json else None, solver=solver)
    if as_json:
        print(dumps_checked(res.to_json(), "design --evaluate"))
        return
    from rich.console import Console

    console = Console()
    console.print(design_table(res.target, res.evaluated, res.substrate,
                               res.instrument["name"], evaluated=True))
    console.print(f"{len(res.evaluated)} read in {res.seconds:.1f} s, "
                  f"{res.photons_per_band} photons per band")


def _guide_instrument(res) -> dict:
    """``target_instrument``: a guide target's instrument against the design's (a note
    when they differ); empty for other targets."""
    from inspect import signature

    from dentalux import shade_guides
    from dentalux.design import search

    src = res.target.source or {}
    if src.get("kind") != "shade-guide":
        return {}
    # the command line reads designs under optimise's own illuminant and observer
    params = signature(search.optimise).parameters
    return shade_guides.instrument_note(src["guide"], res.instrument["name"],
                                        key="target_instrument",
                                        illuminant=params["illuminant"].default,
                                        observer=params["observer"].default)


def _render_json(report: dict) -> dict:
    """The ``render`` key of ``--json``: the comparison and the files (render.json in DIR
    holds the rest: settings, regions, white tile, timings)."""
    keys = ("rendered", "predicted", "rendered_minus_predicted", "crown", "files", "seconds")
    return {k: report[k] for k in keys}


def register(app: typer.Typer) -> None:
    app.command("design")(design_command)
