"""The core's settings schema, read once: the settings' keys with their defaults and ranges,
the integrator names and what each traces, and the pass bound live in the Rust core
(integrators/settings.rs, contract/mod.rs; docs/render-contract.md). ``limits`` and
``scene.schema`` read them from here."""

from __future__ import annotations

import json

from dentalux import _core

SETTINGS_SCHEMA: dict = json.loads(_core.settings_schema())
# the integrators in the core's order, each {"name", "traces_photons", ...}
INTEGRATOR_INFO: tuple[dict, ...] = tuple(SETTINGS_SCHEMA["integrators"])
