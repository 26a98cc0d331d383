"""``dentalux fit``: measured TT and TR of a disc -> absorption and scattering coefficients."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from dentalux import limits
from dentalux.inverse import fit, fit_table, write_spectrum_toml
from dentalux.inverse.table import check_spectrum_rows, read_table
from dentalux.output_paths import atomic_file, check_out_file
from dentalux.strict_json import dumps_checked


def _print_results(results) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"inversion ({results[0].model})")
    for col in ("λ [nm]", "μa [1/mm]", "μa interval", "μs [1/mm]", "μs interval",
                "μs' [1/mm]", "residual"):
        table.add_column(col, justify="right")
    for r in results:
        mua = f"{r.mua:.4g}" if r.mua_resolved else f"≤ {r.mua_upper_bound:.3g}"
        table.add_row(
            "" if r.wavelength_nm is None else f"{r.wavelength_nm:g}", mua,
            f"[{r.mua_ci[0]:.3g}, {r.mua_ci[1]:.3g}]", f"{r.mus:.4g}",
            f"[{r.mus_ci[0]:.3g}, {r.mus_ci[1]:.3g}]", f"{r.musp:.4g}", f"{r.residual:.1e}",
        )
    Console().print(table)
    for r in results:
        for note in r.notes:
            Console(stderr=True).print(f"note: {note}")


def write_checked_spectrum(results, out: Path, name: str, **kw) -> None:
    """Write the spectrum TOML atomically, and only if the material library reads it back
    (what ``shade`` and ``render`` will do with it)."""
    from dentalux import materials

    with atomic_file(out, "--out") as tmp:
        write_spectrum_toml(results, tmp, name, **kw)
        try:
            materials.load(tmp)
        except ValueError as exc:
            msg = str(exc).replace(str(tmp), str(out))
            raise ValueError(f"--out = '{out}': the fitted spectrum would not load as a "
                             f"material ({msg}); nothing was written") from None


def _fit_readings(readings_path: Path, instrument_name, g, n, model, photons, seed, out, name,
                  as_json: bool, solver: str | None, smooth: float | None) -> None:
    """``fit --readings``: a material from instrument readings (dentalux.inverse.readings_fit)."""
    from dentalux import instrument, materials, readings
    from dentalux.inverse import readings_fit

    if model not in readings_fit.MODELS:
        raise ValueError(f"--model = {model!r}: with --readings allowed "
                         f"{', '.join(readings_fit.MODELS)}")
    solver = readings_fit.DEFAULT_SOLVER if solver is None else solver
    if solver not in readings_fit.SOLVERS:
        raise ValueError(f"--solver = {solver!r}: allowed {', '.join(readings_fit.SOLVERS)}")
    if instrument_name is None:
        raise ValueError("--readings needs --instrument NAME|FILE.toml (the instrument that "
                         "read them; `dentalux instruments list`)")
    if out is None:
        raise ValueError("--readings needs --out MATERIAL.toml")
    out = check_out_file(out, "--out", (".toml",))
    if photons is not None:
        limits.check_count(photons, "--photons", limits.MAX_FIT_PHOTONS, lo=1000)
    inst = instrument.get(instrument_name)
    data = readings.load(readings_path)
    name = name or out.stem
    res = readings_fit.fit(data, inst, g=g, n=n, model=model,
                           photons=photons or readings_fit.DEFAULT_PHOTONS, seed=seed,
                           solver=solver, smooth=0.0 if smooth is None else smooth)
    doc = readings_fit.material_doc(res, data, inst, name)
    import tomli_w

    with atomic_file(out, "--out") as tmp:
        tmp.write_bytes(tomli_w.dumps(doc).encode())
        try:
            materials.load(tmp)
        except ValueError as exc:
            msg = str(exc).replace(str(tmp), str(out))
            raise ValueError(f"--out = '{out}': the fitted material would not load ({msg}); "
                             "nothing was written") from None
    for w in res.warnings:  # plain lines: a warning is never wrapped mid-word
        print(f"warning: {w}", file=sys.stderr)
    if as_json:
        print(dumps_checked({
            "material": name, "file": str(out),
            "residuals": [{k: r[k] for k in ("thickness_mm", "backing", "delta_e00")}
                          for r in res.residuals],
            "identifiable": res.identifiable, "model": res.model}, "fit"))
        return
    from rich.console import Console
    from rich.table import Table

    how = f"{res.model} ({res.solver})" if res.solver else res.model
    table = Table(title=f"{name}: {how} fit to {readings_path} read with {inst.name} "
                        f"(g {res.g:g}, n {res.n:g}; {res.seconds:.1f} s)")
    for col in ("line", "thickness [mm]", "backing", "measured L*a*b*", "predicted L*a*b*",
                "ΔE00", "model s.e. ΔE00"):
        table.add_column(col, justify="right")
    for r in res.residuals:
        table.add_row(str(r["line"]), f"{r['thickness_mm']:g}", str(r["backing"]),
                      " ".join(f"{x:.2f}" for x in r["measured_lab"]),
                      " ".join(f"{x:.2f}" for x in r["predicted_lab"]),
                      f"{r['delta_e00']:.3f}", f"{r['mc_stderr_de00']:.3f}")
    table.caption = (f"identifiable: {res.identifiable} ({res.identifiability}); "
                     + "; ".join(f"{k} {v}" for k, v in res.assumed.items()))
    Console().print(table)
    Console().print(f"wrote {out}")


def fit_command(
    tt: float = typer.Option(None, help="total transmittance (fraction)"),
    tr: float = typer.Option(None, help="total reflectance (fraction, specular included)"),
    n: float = typer.Option(None, help="refractive index of the sample (>= 1)"),
    g: float = typer.Option(None, help="HG anisotropy, in (-1, 1)"),
    thickness: float = typer.Option(None, help="sample thickness [mm]"),
    model: str = typer.Option("mc", help="forward model: mc | ad | telegrapher | km (with "
                              "--readings: mc, through the instrument, or km, Kubelka-Munk "
                              "with the Saunderson correction)"),
    readings_path: Path = typer.Option(
        None, "--readings", help="CSV of instrument readings: thickness_mm, backing "
        "(black|white|reflectance|FILE.csv spectrum), L,a,b or r400...r700 [, sd_*] "
        "(docs/fitting.md)"),
    instrument_name: str = typer.Option(
        None, "--instrument", help="with --readings: the instrument that read them (preset "
        "name or TOML file)"),
    fd: float = typer.Option(0.0, help="isotropic fraction of eq. 10, in [0, 1]"),
    n_outside: float = typer.Option(1.0, "--n-outside", help="refractive index around it"),
    tr_diffuse_only: bool = typer.Option(
        False, "--tr-diffuse-only", help="TR excludes the front-face specular reflection"),
    tt_err: float = typer.Option(0.005, help="absolute uncertainty of TT"),
    tr_err: float = typer.Option(0.005, help="absolute uncertainty of TR"),
    tol: float = typer.Option(None, help="fit tolerance on TT/TR (default 0.001 for mc)"),
    photons: int = typer.Option(
        None, help=f"photons per Monte Carlo evaluation (mc; 1000 ... "
                   f"{limits.MAX_FIT_PHOTONS:.0e}; default 400 000, with --readings 20 000 "
                   "per band, for the layered solver's rim correction where it reads)"),
    seed: int = typer.Option(1, help="random seed of the Monte Carlo evaluations (mc)"),
    table: Path = typer.Option(None, help="CSV: wavelength_nm,tt,tr,n,g,thickness_mm[,fd,...]"),
    out: str = typer.Option(
        None, help="material TOML to write (with --table or --readings; replaced if it "
                   "exists)"),
    name: str = typer.Option(None, help="material name in the TOML (default: file stem)"),
    description: str = typer.Option("", help="material description in the TOML"),
    as_json: bool = typer.Option(False, "--json", help="print JSON"),
    solver: str = typer.Option(
        None, help="with --readings --model mc: how the instrument's readings are computed: "
        "auto (default: the layered solver where the beam is normal, else Monte Carlo) | "
        "layered | monte-carlo"),
    smooth: float = typer.Option(
        None, help="with --readings (spectral): weight >= 0 of a second-difference penalty "
        "on log μa and log μs across the bands (default 0: each band on its own)"),
) -> None:
    """Find μa and μs [1/mm] from total transmittance and reflectance of a disc, or
    (--readings) a material from an instrument's readings over black and white."""
    if readings_path is not None:
        given = [k for k, v in (("tt", tt), ("tr", tr), ("thickness", thickness),
                                ("table", table)) if v is not None]
        if given:
            raise ValueError(f"--readings reads thickness and backing per row; drop --"
                             f"{', --'.join(given)}")
        _fit_readings(readings_path, instrument_name, g, n, model, photons, seed, out, name,
                      as_json, solver, smooth)
        return
    if instrument_name is not None:
        raise ValueError("--instrument goes with --readings")
    for flag, value in (("--solver", solver), ("--smooth", smooth)):
        if value is not None:
            raise ValueError(f"{flag} goes with --readings")
    photons = 400_000 if photons is None else photons
    if model == "mc":
        limits.check_count(photons, "--photons", limits.MAX_FIT_PHOTONS, lo=1000)
    if out is not None:
        if table is None:
            raise ValueError("--out needs --table (a spectral batch)")
        out = check_out_file(out, "--out", (".toml",))
    opts = dict(model=model, fd=fd, n_outside=n_outside, tr_diffuse_only=tr_diffuse_only,
                tt_err=tt_err, tr_err=tr_err, tol=tol, photons=photons, seed=seed)
    if table is not None:
        given = [k for k, v in (("tt", tt), ("tr", tr), ("n", n), ("g", g),
                                ("thickness", thickness)) if v is not None]
        if given:
            raise ValueError(f"--table reads tt, tr, n, g, thickness per row; drop --"
                             f"{', --'.join(given)}")
        opts.pop("fd")
        if out is not None:
            check_spectrum_rows(read_table(table), str(table))
        results = fit_table(table, progress=None if not as_json else False, fd=fd, **{
            k: v for k, v in opts.items() if k != "model"}, model=model)
        if out is not None:
            write_checked_spectrum(results, out, name or out.stem, source=table.name,
                                   description=description)
        if as_json:
            print(dumps_checked([dict(r.to_json(), wavelength_nm=r.wavelength_nm)
                                 for r in results], "fit --table"))
        else:
            _print_results(results)
            if out is not None:
                from rich.console import Console

                Console().print(f"wrote {out}")
        return
    missing = [k for k, v in (("tt", tt), ("tr", tr), ("n", n), ("g", g),
                              ("thickness", thickness)) if v is None]
    if missing:
        raise ValueError(f"missing --{', --'.join(missing)} (or give --table)")
    result = fit(tt=tt, tr=tr, n=n, g=g, thickness=thickness, **opts)
    if as_json:
        print(dumps_checked(result.to_json(), "fit"))
    else:
        _print_results([result])


def register(app: typer.Typer) -> None:
    app.command("fit")(fit_command)
