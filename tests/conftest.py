"""Shared pytest fixtures: a seeded numpy generator (tests must be reproducible)."""

import json
import types

import numpy as np
import pytest


@pytest.fixture
def np_rng():
    return np.random.default_rng(12345)


# --- every JSON a test reads is standard JSON (issue 43) ----------------------------------
# A test module that parses `dentalux ... --json` output, render.json or colour.json with
# `json.loads` / `json.load` gets a strict parser instead: NaN, Infinity and -Infinity (which
# Python's json reads and writes by default) fail the test, so every --json command and JSON
# file the suite exercises is checked against RFC 8259.


def _refuse_constant(name):
    raise AssertionError(f"non-standard JSON constant {name} (RFC 8259 has no NaN or Infinity)")


class _StrictJson(types.ModuleType):
    """The json module with strict ``loads``/``load``; everything else passes through."""

    def __getattr__(self, name):
        return getattr(json, name)

    @staticmethod
    def loads(s, **kw):
        kw.setdefault("parse_constant", _refuse_constant)
        return json.loads(s, **kw)

    @staticmethod
    def load(fp, **kw):
        kw.setdefault("parse_constant", _refuse_constant)
        return json.load(fp, **kw)


STRICT_JSON = _StrictJson("json")


@pytest.fixture(autouse=True)
def _strict_json_in_tests(request):
    module = getattr(request, "module", None)
    if module is None or getattr(module, "json", None) is not json:
        yield
        return
    module.json = STRICT_JSON
    try:
        yield
    finally:
        module.json = json
