"""A shade report a lab can send and a clinician can read: one self-contained HTML file
(``dentalux report``).

The page opens with a summary in plain words (:func:`_summary_material`,
:func:`_summary_design`): the material, its thickness, ΔE00 to the target with its standard
error and the verdict against 0.8 / 1.8 (:func:`dentalux.dental.verdict`, every class the
±2 s.e. interval reaches, with :func:`dentalux.dental.verdict_probabilities`), TP00 against
the target's, and colour swatches of target and prediction side by side (display sRGB,
:func:`dentalux.color.lab_to_display_srgb`). The instrument is stated once. Every number the
page shows carries its ± (the shade JSON's ``stderr`` object holds the standard errors under
the same keys as the values). The scientist's detail follows: the tables, the charts, the
inputs and the provenance.

Two sources: materials at a thickness (:func:`build`, as ``dentalux shade``), or a design
result (:func:`build_design`, the object ``dentalux design --json`` prints:
``dentalux report --design design.json``).

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
COMPARE_SHOWN = COMPARE_SHOWN + ("verdict_probability",)
#: shown once for the whole report, not for each material
INSTRUMENT_KEY = "instrument"
SECTION_KEYS = ("edge_loss", "shade_match")
#: shade JSON keys not shown as cells: the spectra (drawn in the charts instead)
SPECTRUM_KEYS = ("wavelength_nm", "reflectance_black", "reflectance_white",
                 "reflectance_black_stderr", "reflectance_white_stderr")
#: shade JSON keys shown beside the values they qualify (``stderr.lab_white.L`` beside
#: ``lab_white.L``), not as rows of their own
PAIRED_KEYS = ("stderr",)
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


def _percent(key: str, p: float) -> dict:
    """A probability's cell, shown in per cent (< 1 % and > 99 % where rounding would say
    0 or 100 of an open-ended tail)."""
    cell = _cell(key, p)
    pc = 100.0 * float(p)
    cell["text"] = "< 1 %" if 0 < pc < 0.5 else "> 99 %" if 99.5 <= pc < 100 else f"{pc:.0f} %"
    return cell


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
    if not (math.isfinite(thickness) and thickness > 0):
        raise ValueError(f"thickness = {thickness!r}: must be a finite number > 0 [mm]")
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


def _pm(key: str, value, err, digits: int | None) -> dict:
    """A value and its standard error, each a :func:`_cell` (the error's key is
    ``stderr.KEY`` as in the shade JSON; None where no error is known)."""
    return {"v": _cell(key, value, digits),
            "e": None if err is None else _cell(f"stderr.{key}", err, digits)}


def _page(spec: str, name: str, out: dict, ref=None) -> dict:
    """One material's tables: every leaf of its shade JSON in a data-key cell, each value
    beside its standard error (``stderr``); ``ref``: the reference's DentalMetrics (for the
    error of ΔTP00, which the shade JSON does not carry)."""
    se = out.get("stderr", {})
    lab = [{"label": label,
            "cells": [_pm(f"{key}.{c}", x, (se.get(key) or [None] * 3)[i], DIGITS[key])
                      for i, (c, x) in enumerate(zip("Lab", out[key], strict=True))]}
           for key, label in LAB_ROWS if key in out]
    scalars = [{"label": label, **_pm(key, out[key], se.get(key), DIGITS[key])}
               for key, label in SCALAR_ROWS if key in out]
    compare = None
    if "delta_e00" in out:
        dtp = out.get("delta_tp00")
        dtp_err = None
        if ref is not None and "tp00" in se:
            dtp_err = float(math.hypot(se["tp00"], ref.stderr["tp00"]))
        probs = out.get("verdict_probability") or {}
        compare = {"delta_e00": _cell("delta_e00", out["delta_e00"], DIGITS["delta_e00"]),
                   "verdict": _cell("verdict", out.get("verdict")),
                   "verdict_class": _verdict_class(out.get("verdict")),
                   "delta_tp00": _cell("delta_tp00", dtp, DIGITS["delta_tp00"]),
                   "delta_tp00_stderr": None if dtp_err is None else
                   {"key": "derived.delta_tp00_stderr", "text": f"{dtp_err:.2f}"},
                   "translucency_verdict": dental.translucency_verdict(dtp)
                   if isinstance(dtp, float) else "—",
                   "probabilities": [_percent(f"verdict_probability.{k}", v)
                                     for k, v in probs.items()],
                   "stderr": _cell("delta_e00_stderr", out["delta_e00_stderr"],
                                   DIGITS["delta_e00_stderr"])
                   if "delta_e00_stderr" in out else None}
    shown = {k for k, _ in LAB_ROWS + SCALAR_ROWS} | set(COMPARE_SHOWN) | set(SECTION_KEYS) \
        | {INSTRUMENT_KEY}
    return {"spec": spec, "name": name, "lab": lab, "scalars": scalars, "compare": compare,
            "sections": [{"key": k, "rows": _generic_rows(out[k], k)}
                         for k in SECTION_KEYS if k in out],
            "other": [r for k in out if k not in shown and k not in SPECTRUM_KEYS
                      and k not in PAIRED_KEYS for r in _generic_rows(out[k], k)],
            "json_text": json.dumps(out, indent=1)}


def _verdict_class(verdict) -> str:
    """The CSS class of a verdict: its worst class (``imperceptible or acceptable`` is
    coloured as acceptable)."""
    if not isinstance(verdict, str):
        return "none"
    return verdict.rsplit(" or ", 1)[-1]


#: what each verdict class means at the chair (Paravina et al. 2015's 50:50 % thresholds)
MEANING = {"imperceptible": "half of observers would not see the difference (ΔE00 < 0.8)",
           "acceptable": "a difference that can be seen but that half of observers would "
                         "accept (0.8 ≤ ΔE00 ≤ 1.8)",
           "unacceptable": "a difference more than half of observers would not accept "
                           "(ΔE00 > 1.8)"}


def _probabilities_text(probs: dict) -> str:
    return ", ".join(f"{k} {_percent(k, v)['text']}" for k, v in probs.items())


def _verdict_words(verdict: str) -> str:
    """A verdict in plain words: its meaning, or for a verdict that spans classes, that the
    estimate's precision cannot decide between them."""
    classes = verdict.split(" or ")
    if len(classes) == 1:
        return MEANING.get(verdict, verdict)
    reach = ", ".join(classes[:-1]) + " and " + classes[-1]
    return (f"the estimate's ±2 s.e. interval reaches {reach}: the precision cannot decide "
            "between them (more photons narrow it)")


def _swatch(label: str, lab, lab_err, illuminant: str, observer: str, key: str) -> dict:
    """A colour swatch: the CIELAB (± s.e.) as display sRGB (:mod:`dentalux.color`)."""
    from dentalux.color import lab_to_display_srgb

    srgb = lab_to_display_srgb(lab, illuminant, str(observer))
    err = list(lab_err) if lab_err is not None else [None] * 3
    parts = []
    for c, x, e in zip(("L*", "a*", "b*"), lab, err, strict=True):
        parts.append(f"{c} {x:.1f}" + (f" ± {e:.1f}" if e else ""))
    return {"label": label, "key": key, "lab": [float(x) for x in lab], "text": ", ".join(parts),
            "rgb": ",".join(str(v) for v in srgb["rgb"]), "hex": srgb["hex"],
            "clipped": srgb["clipped"]}


def _tp_sentence(name: str, tp, tp_err, ref_name, ref_tp, ref_err) -> str:
    """TP00 of the restoration against the target's (the natural tooth's), in words."""
    if tp is None:
        return "Translucency was not read."
    text = f"Translucency TP00 {tp:.1f} ± {tp_err:.1f}"
    if ref_tp is None:
        return text + (f"; {ref_name} gives no translucency to compare with" if ref_name
                       else "") + "."
    dtp = abs(tp - ref_tp)
    dtp_err = math.hypot(tp_err or 0.0, ref_err or 0.0)
    tv = dental.translucency_verdict(dtp)
    more = "more" if tp > ref_tp else "less"
    return (f"{text} against {ref_name}'s {ref_tp:.1f} ± {ref_err:.1f}: {name} is {more} "
            f"translucent by ΔTP00 {dtp:.1f} ± {dtp_err:.1f}, {tv} (perceptible from "
            f"{dental.TPT}, acceptable up to {dental.TAT}).")


def _summary_material(name: str, thickness: float, out: dict, where: str, against_name,
                      ref, illuminant: str, observer: str) -> dict:
    """The plain-words summary of one material (module doc)."""
    se = out["stderr"]
    sentences = [f"{name}, {thickness:g} mm thick, as read by {where} over a white backing."]
    swatches = [_swatch(f"{name} (prediction)", out["lab_white"], se["lab_white"], illuminant,
                        observer, "lab_white")]
    verdict = None
    if "delta_e00" in out:
        verdict = out["verdict"]
        sentences.append(
            f"ΔE00 to {against_name}: {out['delta_e00']:.2f} ± "
            f"{out['delta_e00_stderr']:.2f}, {verdict}: {_verdict_words(verdict)}.")
        probs = out.get("verdict_probability")
        if probs:
            sentences.append(f"Probability of each verdict: {_probabilities_text(probs)}.")
        swatches.insert(0, _swatch(f"{against_name} (target)", ref.lab_white,
                                   [ref.stderr[f"lab_white.{c}"] for c in "Lab"],
                                   illuminant, observer, "target.lab_white"))
        sentences.append(_tp_sentence(name, out["tp00"], se["tp00"], against_name,
                                      ref.tp00, ref.stderr["tp00"]))
    else:
        swatches.append(_swatch(f"{name} over black", out["lab_black"], se["lab_black"],
                                illuminant, observer, "lab_black"))
        sentences.append("No target given (--against): no ΔE00. "
                         + _tp_sentence(name, out["tp00"], se["tp00"], None, None, None))
    return {"name": name, "sentences": sentences, "swatches": swatches,
            "verdict": verdict, "verdict_class": _verdict_class(verdict)}


def _instrument_section(ins) -> dict:
    """The instrument, stated once: its JSON leaves as data-key rows and a sentence."""
    if not isinstance(ins, dict) or not ins:
        return {"rows": [], "geometry": _geometry({})}
    return {"rows": _generic_rows(ins, INSTRUMENT_KEY), "geometry": _geometry({"instrument":
                                                                               ins})}


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

    pages = [_page(s["spec"], mats[s["spec"]].name, s["json"], ref_metrics) for s in sections]
    illuminant, observer = kw.get("illuminant", "D65"), kw.get("observer", "2")
    against_name = mats[str(against)].name if against else None
    summary = [_summary_material(mats[s["spec"]].name, float(thickness), s["json"],
                                 _geometry(s["json"])["short"], against_name, ref_metrics,
                                 illuminant, observer) for s in sections]
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
        "mode": "materials", "summary": summary, "design": None,
        "instrument": _instrument_section(sections[0]["json"].get(INSTRUMENT_KEY)),
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


# -- a design result (dentalux report --design design.json) -----------------------------------

DESIGN_REQUIRED = ("thickness_mm", "materials", "lab", "delta_e00", "delta_e00_stderr",
                   "verdict")


def _designs_key(doc) -> str:
    """Where a result keeps its designs: ``designs`` (a search), or ``evaluated`` (the
    ranked candidates of ``design --evaluate --json``, which carry the same keys)."""
    if isinstance(doc, dict) and "designs" not in doc and "evaluated" in doc:
        return "evaluated"
    return "designs"


def read_design(path) -> dict:
    """The object ``dentalux design --json`` printed, read from ``path`` and checked for what
    the report needs (a ValueError naming the file and the key otherwise)."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"--design: file not found: {path}")
    doc = inputs.read_json(p, "--design: design file")
    where = f"--design = {str(path)!r}"
    if not isinstance(doc, dict) or not isinstance(doc.get(_designs_key(doc)), list) \
            or not doc[_designs_key(doc)]:
        raise ValueError(f"{where}: not what `dentalux design --json` prints (no 'designs' "
                         "list, nor the 'evaluated' one of --evaluate)")
    tgt = doc.get("target")
    if not isinstance(tgt, dict) or not isinstance(tgt.get("lab"), list) \
            or len(tgt["lab"]) != 3:
        raise ValueError(f"{where}: 'target' has no 'lab' triple")
    for i, d in enumerate(doc[_designs_key(doc)]):
        missing = [k for k in DESIGN_REQUIRED if not isinstance(d, dict) or k not in d]
        if missing:
            raise ValueError(f"{where}: {_designs_key(doc)}[{i}] lacks {', '.join(missing)}")
        if len(d["lab"]) != 3 or len(d["thickness_mm"]) != len(d["materials"]):
            raise ValueError(f"{where}: {_designs_key(doc)}[{i}]: 'lab' or 'thickness_mm' "
                             "malformed")
    if not isinstance(doc.get("instrument"), dict):
        raise ValueError(f"{where}: no 'instrument' object")
    return doc


def _target_label(target: dict) -> str:
    src = target.get("source") or {}
    if src.get("kind") == "shade-guide":
        return f"shade tab {src.get('guide')}:{src.get('tab')}"
    if src.get("kind") == "stack" and isinstance(src.get("stack"), list):
        return "the tooth region " + "/".join(f"{x.get('material')} {x.get('thickness_mm')} mm"
                                              for x in src["stack"] if isinstance(x, dict))
    return "L*a*b* " + " ".join(f"{x:.1f}" for x in target["lab"])


def _target_tp(target: dict) -> tuple[float | None, float | None]:
    """The target's TP00 and its error: the TP target, or a stack target's reading."""
    if target.get("tp00") is not None:
        return float(target["tp00"]), float(target.get("tp00_stderr", 0.0))
    src = target.get("source") or {}
    if src.get("tp00_read") is not None:
        return float(src["tp00_read"]), float(src.get("tp00_read_stderr", 0.0))
    return None, None


def _layers_text(d: dict, cement, substrate) -> str:
    errs = d.get("thickness_stderr_mm") or [None] * len(d["thickness_mm"])
    parts = [f"{m} {t:.2f}" + (f" ± {e:.2f}" if e else "") + " mm"
             for m, t, e in zip(d["materials"], d["thickness_mm"], errs, strict=True)]
    text = " over ".join(parts)
    if cement:
        text += f", cement {cement['material']} {cement['thickness_mm']:g} mm"
    if substrate == "none":
        text += ", with nothing behind it (on the instrument's backings)"
    elif substrate:
        text += f", on {substrate}"
    return text


def _design_rows(designs: list[dict], key: str = "designs") -> list[dict]:
    """The designs table: every number with its error, as data-key cells (``key``: the
    JSON key of the list)."""
    rows = []
    for i, d in enumerate(designs):
        k = f"{key}.{i}"
        te = d.get("thickness_stderr_mm") or [None] * len(d["thickness_mm"])
        le = d.get("lab_stderr") or [None] * 3
        row = {"rank": i + 1,
               "thickness": [{"v": _cell(f"{k}.thickness_mm.{j}", t, 2),
                              "e": None if e is None else
                              _cell(f"{k}.thickness_stderr_mm.{j}", e, 2)}
                             for j, (t, e) in enumerate(zip(d["thickness_mm"], te,
                                                            strict=True))],
               "materials": " / ".join(d["materials"]),
               "lab": [{"v": _cell(f"{k}.lab.{j}", x, 1),
                        "e": None if e is None else _cell(f"{k}.lab_stderr.{j}", e, 1)}
                       for j, (x, e) in enumerate(zip(d["lab"], le, strict=True))],
               "de": {"v": _cell(f"{k}.delta_e00", d["delta_e00"], 2),
                      "e": _cell(f"{k}.delta_e00_stderr", d["delta_e00_stderr"], 2)},
               "verdict": _cell(f"{k}.verdict", d["verdict"]),
               "verdict_class": _verdict_class(d["verdict"]),
               "probabilities": [_percent(f"{k}.verdict_probability.{c}", v)
                                 for c, v in (d.get("verdict_probability") or {}).items()],
               "sensitivity": [_cell(f"{k}.sensitivity.{j}", x, 2)
                               for j, x in enumerate(d.get("sensitivity") or [])],
               "verified": {**_cell(f"{k}.verified", d.get("verified")),
                            "text": {True: "yes", False: "NO"}.get(d.get("verified"), "—")},
               "note": (d.get("verification") or {}).get("note", ""),
               "tp": None}
        if "tp00" in d:
            row["tp"] = {"v": _cell(f"{k}.tp00", d["tp00"], 2),
                         "e": _cell(f"{k}.tp00_stderr", d.get("tp00_stderr"), 2)}
        rows.append(row)
    return rows


def _specs(doc: dict, d: dict) -> list[str]:
    """A design's materials as given to ``design`` (the file's ``layers[].spec``: a library
    name or ``FILE.toml:NAME``), else their names."""
    layers = doc.get("layers") or []
    specs = [lay.get("spec") if isinstance(lay, dict) else None for lay in layers]
    if len(specs) == len(d["materials"]) and all(isinstance(x, str) for x in specs):
        return specs
    return list(d["materials"])


def _read_design(doc: dict, kw: dict):
    """The best design's specimen read through its instrument (spectra, TP00), or the reason
    it cannot be: (DentalMetrics or None, note)."""
    from dentalux import design as design_api

    substrate = doc.get("substrate")
    if substrate is None:
        return None, ("the design file does not name its substrate (written before "
                      "`design --json` gave 'substrate'): spectra and TP00 not read")
    best = doc[_designs_key(doc)][0]
    cement = doc.get("cement")
    try:
        m = design_api.read(list(zip(_specs(doc, best), best["thickness_mm"], strict=True)),
                            substrate, None if not cement else (
                                cement.get("spec") or cement["material"],
                                cement["thickness_mm"]),
                            instrument=doc["instrument"].get("name"), **kw)
    except (ValueError, FileNotFoundError, KeyError) as exc:
        return None, f"spectra and TP00 not read: {exc}"
    return m, None


def build_design(design, figure=None, render=None, command: str | None = None,
                 read: bool = True, **kw) -> dict:
    """Everything the report of a design result shows (module doc): ``design`` is the path of
    a ``dentalux design --json`` file; ``read``: read the best design's specimen (its spectra
    and TP00) with ``kw`` (the keyword arguments of :func:`dentalux.dental.read`: bands,
    photons, seed, ...; the file's bands when it names them)."""
    from dentalux import __version__
    from dentalux.report import charts

    doc = read_design(design)
    kw = {k: v for k, v in kw.items() if v is not None}
    kw["progress"] = False
    if doc.get("bands_nm"):  # the design's own bands: its numbers were read at them
        kw["bands"] = doc["bands_nm"]
    figure = _figure(figure) if figure is not None else None
    render = _render(render) if render is not None else None
    illuminant, observer = kw.get("illuminant", "D65"), kw.get("observer", "2")
    key = _designs_key(doc)
    target, designs = doc["target"], doc[key]
    best = designs[0]
    label = _target_label(target)
    m, note = _read_design(doc, kw) if read else (None, "not read (read=False)")
    ins = _instrument_section(doc["instrument"])
    where = ins["geometry"]["short"]
    layers = _layers_text(best, doc.get("cement"), doc.get("substrate"))
    best_of = "Best of the thicknesses evaluated" if key == "evaluated" else "Best design"
    sentences = [f"{best_of} for {label}: {layers} (top to bottom), as read by {where} "
                 "over a white backing."]
    sentences.append(f"ΔE00 to the target: {best['delta_e00']:.2f} ± "
                     f"{best['delta_e00_stderr']:.2f}, {best['verdict']}: "
                     f"{_verdict_words(best['verdict'])}.")
    if best.get("verdict_probability"):
        sentences.append("Probability of each verdict: "
                         f"{_probabilities_text(best['verdict_probability'])}.")
    tp, tp_err = (best["tp00"], best.get("tp00_stderr", 0.0)) if "tp00" in best else \
        ((m.tp00, m.stderr["tp00"]) if m is not None else (None, None))
    ref_tp, ref_err = _target_tp(target)
    if tp is None:
        sentences.append(f"Translucency was not read ({note}).")
    else:
        sentences.append(_tp_sentence("the restoration", tp, tp_err,
                                      "the target" if ref_tp is not None else label,
                                      ref_tp, ref_err))
    if "verified" in best:
        v = (best.get("verification") or {}).get("note")
        if best["verified"]:
            sentences.append(f"Checked by the full Monte Carlo: {v or 'verified'}.")
        else:
            sentences.append(v + "." if v and v.startswith("NOT VERIFIED") else
                             f"Not verified by the full Monte Carlo{': ' + v if v else ''}.")
    if len(designs) > 1:
        what = "candidate(s)" if key == "evaluated" else "design(s)"
        sentences.append(f"{len(designs) - 1} more {what} follow in the table below.")
    swatches = [_swatch(f"target ({label})", target["lab"], target.get("lab_stderr"),
                        illuminant, observer, "target.lab")]
    for i, d in enumerate(designs):
        swatches.append(_swatch(f"design {i + 1}: " + "/".join(f"{t:.2f}" for t in
                                                              d["thickness_mm"]) + " mm",
                                d["lab"], d.get("lab_stderr"), illuminant, observer,
                                f"{key}.{i}.lab"))
    chart_list = []
    provenance = []
    if m is not None:
        chart_list.append(charts.spectra([("design 1", m)], where))
        mats = {}
        cement = doc.get("cement")
        for name in _specs(doc, best) + ([cement.get("spec") or cement["material"]]
                                         if cement else []):
            try:
                mats[name] = dental._resolve_material(name)
            except (ValueError, FileNotFoundError, KeyError):
                continue
        if mats:
            chart_list.append(charts.optics([(k, v) for k, v in mats.items()]))
            provenance = [{"spec": k, **_provenance(v)} for k, v in mats.items()]
    inputs_ = {"design file": str(design), "substrate": doc.get("substrate", "—"),
               "layers": ", ".join(f"{lay['material']} {lay.get('range_mm')}"
                                   for lay in doc.get("layers", [])) or "—",
               **{k: _input_text(k, v) for k, v in kw.items() if k != "progress"},
               "spectra of design 1": note or "read with the settings above"}
    return {
        "mode": "design",
        "summary": [{"name": "design 1", "sentences": sentences, "swatches": swatches,
                     "verdict": best["verdict"],
                     "verdict_class": _verdict_class(best["verdict"])}],
        "design": {"rows": _design_rows(designs, key), "target": label,
                   "target_cells": [{"v": _cell(f"target.lab.{j}", x, 1),
                                     "e": None if not target.get("lab_stderr") else
                                     _cell(f"target.lab_stderr.{j}",
                                           target["lab_stderr"][j], 1)}
                                    for j, x in enumerate(target["lab"])],
                   "json_text": json.dumps(doc, indent=1)},
        "instrument": ins,
        "title": f"dentalux design report: {label}",
        "version": __version__,
        "generated": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "python": platform.python_version(), "command": command,
        "seed": kw.get("seed", "default"), "thickness": float(sum(best["thickness_mm"])),
        "against": label, "geometry": [ins["geometry"]],
        "pt": dental.PT, "at": dental.AT, "tpt": dental.TPT, "tat": dental.TAT,
        "inputs": inputs_, "pages": [], "charts": chart_list, "provenance": provenance,
        "figure": figure, "render": render,
    }


def write_design(out, design, **kw) -> Path:
    """Build the report of a design result and write it to ``out`` (as :func:`write`)."""
    from dentalux.output_paths import atomic_file

    p = check_out(out)
    html = render_html(build_design(design, **kw))
    with atomic_file(p, "--out") as tmp:
        tmp.write_text(html, encoding="utf-8")
    return p
