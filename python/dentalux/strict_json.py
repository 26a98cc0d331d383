"""Standard JSON (RFC 8259) out of dentalux's results: numpy values become Python numbers
and lists, non-finite floats ``null``. Every JSON file dentalux writes goes through
:func:`dumps_strict`."""

from __future__ import annotations

import json
import math

import numpy as np


def json_safe(x):
    """Copy of ``x`` with every non-finite float (inf, NaN) replaced by ``None`` and numpy
    scalars and arrays turned into Python numbers and lists."""
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, np.ndarray):
        x = x.tolist()
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [json_safe(v) for v in x]
    return x


def dumps_strict(obj, **kw) -> str:
    """Standard JSON (RFC 8259): non-finite numbers become ``null``, never ``Infinity`` or
    ``NaN``."""
    return json.dumps(json_safe(obj), allow_nan=False, **kw)


def check_finite(obj, what: str, path: str = "") -> None:
    """Refuse a result that holds NaN or an infinity where a number belongs: a ``ValueError``
    naming ``what`` (the command or function) and the key path, so that a reading is an
    error (exit code 2), never a ``null`` or ``NaN`` with exit code 0. ``None`` (a value
    that does not apply, e.g. ``contact_index`` of an air gap) is left alone."""
    stack = [(obj, path)]
    while stack:
        x, key = stack.pop()
        if isinstance(x, np.ndarray):
            x = x.tolist()
        elif isinstance(x, np.generic):
            x = x.item()
        if isinstance(x, float):
            if not math.isfinite(x):
                raise ValueError(
                    f"{what}: the result's {key or 'value'} = {x!r} is not a finite number: "
                    "the input lies outside what the model can compute (a coefficient, "
                    "diameter or thickness at an extreme?); nothing was printed")
        elif isinstance(x, dict):
            stack.extend((v, f"{key}.{k}" if key else str(k)) for k, v in x.items())
        elif isinstance(x, list | tuple):
            stack.extend((v, f"{key}[{i}]") for i, v in enumerate(x))


def dumps_checked(obj, what: str, **kw) -> str:
    """Standard JSON of a result whose every number is finite (:func:`check_finite`)."""
    check_finite(obj, what)
    return dumps_strict(obj, **kw)
