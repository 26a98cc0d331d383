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
