"""A shade report a lab can send: one self-contained HTML file (``dentalux report``).

:func:`build` gathers, for each material (a library name or a TOML file, as for ``dentalux
shade``), the object ``dentalux shade --json`` prints for the same arguments (through
:func:`shade_json`, the one place that asks :mod:`dentalux.dental`), the disc's spectra, its
optical coefficients, TP against thickness and its provenance; :func:`write` renders them with
the jinja2 template ``templates/report.html.j2`` (package data) into one HTML file with the
charts embedded as base64 PNG (:mod:`dentalux.report.charts`), so it opens with no network.

Every leaf of the shade JSON (``lab_white.L``, ``tp00``, ``verdict``, and whatever
``instrument``, ``edge_loss`` or ``shade_match`` keys the installed dentalux gives) appears in
the page in a cell marked ``data-key`` (the JSON path) and ``data-value`` (the value as JSON
prints it); the text shown is that value rounded (:data:`DIGITS`).
"""

from __future__ import annotations

import base64
import datetime as _dt
import json
import math
import platform
from pathlib import Path

import numpy as np

from dentalux import dental, inputs

#: decimals shown for each JSON key (the full value is in the cell's data-value)
DIGITS = {"lab_black": 2, "lab_white": 2, "lab_transmitted": 2, "tp": 2, "tp00": 2,
          "cr": 4, "op": 2, "delta_e00": 2, "delta_tp00": 2, "delta_e00_stderr": 2}
LAB_ROWS = (("lab_black", "over black"), ("lab_white", "over white"),
            ("lab_transmitted", "transmitted"))
SCALAR_ROWS = (("tp", "TP (ΔE*ab, black against white)"),
               ("tp00", "TP00 (ΔE00, black against white)"),
               ("cr", "CR = Y over black / Y over white"),
               ("op", "OP (Δa*b*, transmitted against over black)"))
COMPARE_KEYS = ("delta_e00", "delta_tp00", "verdict")
COMPARE_SHOWN = COMPARE_KEYS + ("delta_e00_stderr",)
SECTION_KEYS = ("instrument", "edge_loss", "shade_match")
#: shade JSON keys not shown as cells: the spectra (drawn in the charts instead)
SPECTRUM_KEYS = ("wavelength_nm", "reflectance_black", "reflectance_white",
                 "reflectance_black_stderr", "reflectance_white_stderr")
#: shade JSON keys that describe a run's cost: two runs of the same seed differ in them
RUN_COST_KEYS = ("cpu_seconds",)
#: thickness factors of the TP-vs-thickness chart when none are given (times --thickness)
TP_FACTORS = (0.25, 0.5, 1.0, 1.5, 2.0)
#: the largest image ``--figure`` (or a ``--render`` folder's image) embeds [bytes]: the HTML
#: holds it as base64 (4/3 larger) and a browser must load it whole
MAX_FIGURE_BYTES = 64 * 1024 * 1024
FIGURE_SUFFIXES = {".png": (b"\x89PNG\r\n\x1a\n", "image/png"),
                   ".jpg": (b"\xff\xd8\xff", "image/jpeg"), ".jpeg": (b"\xff\xd8\xff",
                                                                   "image/jpeg")}


INFINITE_NOTE = ("infinite geometry: a laterally infinite disc on an ideal Lambertian "
                 "backing, normal illumination, all reflected light collected (SCI); no "
                 "instrument aperture and no edge loss")


def shade_json(material, thickness: float, against=None, instrument=None, match=None,
               **kw) -> dict:
    """The object ``dentalux shade --json`` prints for these arguments (:func:`dental.shade`).

    ``kw``: the keyword arguments of :func:`dentalux.dental.read` (bands, backings, contact,
    photons, seed, estimator, observer, illuminant, threads)."""
    from dentalux.strict_json import check_finite

    kw.setdefault("progress", False)
    out = dental.shade(material, thickness, against=against, instrument=instrument,
                       match=match, **kw)
    # as `dentalux shade`: a NaN or inf reading is an error, never a number in the report
    check_finite(out, f"report: {material} at {thickness:g} mm")
    return out


def _leaves(obj, prefix: str = "") -> list[tuple[str, object]]:
    """(JSON path, value) of every number/string/bool/null under ``obj``; Lab triples get
    the component names (``lab_white.L``), other lists their index."""
    if isinstance(obj, dict):
        out = []
        for k, v in obj.items():
            out += _leaves(v, f"{prefix}.{k}" if prefix else str(k))
        return out
    if isinstance(obj, list | tuple):
        names = "Lab" if len(obj) == 3 and prefix.rsplit(".", 1)[-1].startswith("lab") else None
        out = []
        for i, v in enumerate(obj):
            out += _leaves(v, f"{prefix}.{names[i] if names else i}")
        return out
    return [(prefix, obj)]


def _cell(key: str, value, digits: int | None = None) -> dict:
    """One table cell: the JSON path, the value as JSON writes it, and the text shown."""
    raw = json.dumps(value)
    if isinstance(value, float):
        text = f"{value:.{digits}f}" if digits is not None else f"{value:.4g}"
    elif value is None:
        text = "—"
    else:
        text = str(value)
    return {"key": key, "value": raw if not isinstance(value, str) else value, "text": text}


def _generic_rows(obj, prefix: str) -> list[dict]:
    """Key/value rows of a JSON section of unknown shape (instrument, edge loss, ...)."""
    rows = []
    for path, value in _leaves(obj, prefix):
        label = path[len(prefix) + 1:] if path.startswith(prefix + ".") else path
        rows.append({"label": label or prefix, "cell": _cell(path, value)})
    return rows


def _spectra(material, thickness: float, instrument, kw: dict):
    """The disc's spectra (``DentalMetrics``), read through the instrument ``shade`` uses."""
    from dentalux import instrument as instruments

    return dental.metrics(material, thickness, instrument=instruments.DEFAULT
                          if instrument is None else instrument, **kw)


def _geometry(out: dict) -> dict:
    """How the numbers were read, from the JSON's ``instrument`` object (none: the infinite
    geometry: a laterally infinite disc on ideal backings)."""
    ins = out.get("instrument")
    if not isinstance(ins, dict) or not ins or ins.get("name") == "infinite":
        text = INFINITE_NOTE + (" (instrument 'infinite')" if isinstance(ins, dict) and ins
                                else "")
        return {"text": text, "infinite": True, "short": "infinite geometry"}
    parts = [f"As read by instrument {ins.get('name')}"]
    for key, label, unit in (("geometry", "geometry", ""), ("illuminated_diameter_mm",
                             "lit spot", " mm"), ("viewed_diameter_mm", "viewed window", " mm"),
                             ("specular", "specular component", "")):
        if ins.get(key) is not None:
            parts.append(f"{label} {ins[key]}{unit}")
    return {"text": ", ".join(parts), "infinite": False,
            "short": f"instrument {ins.get('name')}"}


def _provenance(mat) -> dict:
    """What the page says about where a material's values came from."""
    prov = dict(getattr(mat, "provenance", {}) or {})
    values = prov.pop("values", {}) or {}
    scaling = prov.pop("scaling", []) or []
    rows = []
    for q in ("wavelength_nm", "mua", "mus", "g", "fd", "n"):
        entry = values.get(q)
        if entry is None:
            continue
        if isinstance(entry, list):
            for lam, text in zip(mat.wavelength_nm, entry, strict=False):
                rows.append({"quantity": f"{q} at {lam:g} nm", "text": text})
        else:
            rows.append({"quantity": q, "text": entry})
    data = None
    if hasattr(mat, "wavelength_nm"):
        data = [{"wavelength_nm": f"{lam:g}", **{q: f"{getattr(mat, q)[i]:.6g}"
                                                 for q in ("mua", "mus", "g", "fd", "n")}}
                for i, lam in enumerate(mat.wavelength_nm)]
    return {"name": getattr(mat, "name", "material"),
            "description": getattr(mat, "description", ""),
            "fields": [{"key": k, "text": v if isinstance(v, str) else json.dumps(v)}
                       for k, v in prov.items()],
            "value_rows": rows, "scaling": [json.dumps(s) for s in scaling], "data": data}


def _tp_thicknesses(thickness: float, given) -> list[float]:
    ts = [thickness * f for f in TP_FACTORS] if given is None else [float(t) for t in given]
    if not ts or not all(math.isfinite(t) and t > 0 for t in ts):
        raise ValueError(f"--tp-thicknesses = {given!r}: need thicknesses > 0 [mm]")
    return sorted(set(ts) | {float(thickness)})


def _input_text(key: str, value) -> str:
    """An option's value as the inputs table shows it."""
    if key == "contact" and value is None:
        return "— (the instrument's)"
    if isinstance(value, list | tuple | np.ndarray):
        return ", ".join(f"{x:g}" for x in value)
    return str(value)


def _figure(path, option: str = "--figure") -> dict:
    """A rendered image to embed (``--figure``; ``option`` names the option in errors, e.g.
    ``--render`` for a render folder's image): PNG or JPEG, checked by its magic bytes and
    its size (at most MAX_FIGURE_BYTES, before it is read)."""
    p = Path(path)
    kind = FIGURE_SUFFIXES.get(p.suffix.lower())
    if kind is None:
        raise ValueError(f"{option} = {str(path)!r}: allowed a .png or .jpg file")
    if not p.is_file():
        raise FileNotFoundError(f"{option}: file not found: {path}")
    size = p.stat().st_size
    if size > MAX_FIGURE_BYTES:
        raise ValueError(f"{option} = {str(path)!r}: {size:,} bytes is too large to embed: "
                         f"allowed at most {MAX_FIGURE_BYTES:,} bytes (the report would hold "
                         f"{size * 4 // 3:,} bytes of base64)")
    blob = p.read_bytes()
    if not blob.startswith(kind[0]):
        raise ValueError(f"{option} = {str(path)!r}: not a {p.suffix.lower()[1:]} image")
    return {"name": p.name, "src": f"data:{kind[1]};base64,{base64.b64encode(blob).decode()}"}


def _page(spec: str, name: str, out: dict) -> dict:
    """One material's tables: every leaf of its shade JSON in a data-key cell."""
    lab = [{"label": label, "cells": [_cell(f"{key}.{c}", x, DIGITS[key])
                                      for c, x in zip("Lab", out[key], strict=True)]}
           for key, label in LAB_ROWS if key in out]
    scalars = [{"label": label, "cell": _cell(key, out[key], DIGITS[key])}
               for key, label in SCALAR_ROWS if key in out]
    compare = None
    if "delta_e00" in out:
        dtp = out.get("delta_tp00")
        compare = {"delta_e00": _cell("delta_e00", out["delta_e00"], DIGITS["delta_e00"]),
                   "verdict": _cell("verdict", out.get("verdict")),
                   "delta_tp00": _cell("delta_tp00", dtp, DIGITS["delta_tp00"]),
                   "translucency_verdict": dental.translucency_verdict(dtp)
                   if isinstance(dtp, float) else "—",
                   "stderr": _cell("delta_e00_stderr", out["delta_e00_stderr"],
                                   DIGITS["delta_e00_stderr"])
                   if "delta_e00_stderr" in out else None}
    shown = {k for k, _ in LAB_ROWS + SCALAR_ROWS} | set(COMPARE_SHOWN) | set(SECTION_KEYS)
    return {"spec": spec, "name": name, "lab": lab, "scalars": scalars, "compare": compare,
            "sections": [{"key": k, "rows": _generic_rows(out[k], k)}
                         for k in SECTION_KEYS if k in out],
            "other": [r for k in out if k not in shown and k not in SPECTRUM_KEYS
                      for r in _generic_rows(out[k], k)],
            "json_text": json.dumps(out, indent=1)}


def _render(folder) -> dict:
    """A ``dentalux render --out`` folder to embed (``--render``): its colour image and the
    CIELAB of its named regions (colour.json), with the scene's name (render.json)."""
    d = Path(folder)
    colour = d / "colour.json"
    if not d.is_dir() or not colour.is_file():
        raise ValueError(f"--render = {str(folder)!r}: not a `dentalux render --out` folder "
                         "with a colour image (no colour.json in it)")
    # standard JSON, UTF-8, depth and size bounded (dentalux.inputs): errors name the file
    c = inputs.read_json(colour, "--render: colour file")
    meta = inputs.read_json(d / "render.json", "--render: render file") \
        if (d / "render.json").is_file() else {}
    try:
        regions = [{"name": str(n), "rect": ", ".join(str(int(v)) for v in r["rect"]),
                    "lab": [f"{float(x):.2f}" for x in r["lab"]]}
                   for n, r in (c.get("regions") or {}).items()]
    except (ValueError, KeyError, TypeError, AttributeError):
        raise ValueError(f"--render = {str(folder)!r}: colour.json or render.json is not "
                         "what `dentalux render` writes") from None
    if not (d / "image.png").is_file():
        raise ValueError(f"--render = {str(folder)!r}: no image.png in it (was the render "
                         "written with --out to this folder?)")
    image = _figure(d / "image.png", "--render")
    return {**image, "name": f"{meta.get('scene_name') or d.name} ({d.name}/image.png)",
            "regions": regions, "illuminant": c.get("illuminant"),
            "observer": c.get("observer")}


def build(materials, thickness: float, against=None, instrument=None, match=None,
          tp_thicknesses=None, figure=None, render=None, command: str | None = None,
          **kw) -> dict:
    """Everything the report shows, as plain data for the template (see module doc)."""
    from dentalux import __version__
    from dentalux import instrument as instruments
    from dentalux.report import charts

    if isinstance(materials, str | Path) or not materials:
        materials = [materials] if materials else []
    if not materials:
        raise ValueError("materials: give at least one material (a name or a TOML file)")
    kw = {k: v for k, v in kw.items() if v is not None or k == "contact"}
    kw["progress"] = False
    ts = _tp_thicknesses(float(thickness), tp_thicknesses)
    figure = _figure(figure) if figure is not None else None
    render = _render(render) if render is not None else None
    specs = list(materials) + ([against] if against else [])
    mats = {str(s): dental._resolve_material(s) for s in specs}
    sections = []
    for spec in materials:
        out = shade_json(spec, thickness, against=against, instrument=instrument, match=match,
                         **kw)
        m = _spectra(spec, thickness, instrument, kw)
        tp = []
        for t in ts:
            j = out if t == float(thickness) else shade_json(spec, t, instrument=instrument,
                                                              **kw)
            tp.append((t, j["tp"], j["tp00"]))
        sections.append({"spec": str(spec), "json": out, "metrics": m, "tp": tp})
    ref_metrics = _spectra(against, thickness, instrument, kw) if against else None
    geometry = []
    for s in sections:
        g = _geometry(s["json"])
        if g not in geometry:
            geometry.append(g)
    where = " / ".join(g["short"] for g in geometry)

    pages = [_page(s["spec"], mats[s["spec"]].name, s["json"]) for s in sections]
    inputs = {"materials": ", ".join(map(str, materials)), "thickness [mm]": f"{thickness:g}",
              "against": against or "—",
              "instrument": instrument or f"{instruments.DEFAULT} (the default of shade)",
              "match": match or "—",
              **{k: _input_text(k, v) for k, v in kw.items() if k != "progress"},
              "TP chart thicknesses [mm]": ", ".join(f"{t:g}" for t in ts)}
    labelled = [(mats[s["spec"]].name, s["metrics"]) for s in sections]
    if ref_metrics is not None:
        labelled.append((f"{mats[str(against)].name} (reference)", ref_metrics))
    return {
        "title": "dentalux shade report: " + ", ".join(mats[str(m)].name for m in materials),
        "version": __version__,
        "generated": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "python": platform.python_version(),
        "command": command,
        "seed": kw.get("seed", "default"),
        "thickness": float(thickness), "against": against,
        "geometry": geometry,
        "pt": dental.PT, "at": dental.AT, "tpt": dental.TPT, "tat": dental.TAT,
        "inputs": inputs, "pages": pages,
        "charts": [charts.spectra(labelled, where),
                   charts.optics([(m.name, m) for m in mats.values()]),
                   charts.tp_thickness([(mats[s["spec"]].name, s["tp"]) for s in sections],
                                       float(thickness), where)],
        "provenance": [{"spec": k, **_provenance(m)} for k, m in mats.items()],
        "figure": figure, "render": render,
    }


def render_html(context: dict) -> str:
    """The page for :func:`build`'s context (template ``templates/report.html.j2``)."""
    import jinja2

    env = jinja2.Environment(loader=jinja2.PackageLoader("dentalux.report", "templates"),
                             autoescape=jinja2.select_autoescape(["html", "j2"]),
                             undefined=jinja2.StrictUndefined, trim_blocks=True,
                             lstrip_blocks=True)
    return env.get_template("report.html.j2").render(**context)


def check_out(out) -> Path:
    """The report's path: an ``.html`` file (the rules of :mod:`dentalux.output_paths`)."""
    from dentalux.output_paths import check_out_file

    return check_out_file(out, "--out", (".html", ".htm"))


def write(out, materials, thickness: float, **kw) -> Path:
    """Build the report and write it to ``out`` (an .html file, replaced if it exists),
    atomically: a temporary file in the same folder, renamed when complete."""
    from dentalux.output_paths import atomic_file

    p = check_out(out)
    html = render_html(build(materials, thickness, **kw))
    with atomic_file(p, "--out") as tmp:
        tmp.write_text(html, encoding="utf-8")
    return p
