"""python/dentalux/_core.pyi against the compiled module: every public function and constant
of ``dentalux._core`` has a stub, no stub names something the module lacks, and a function's
parameters (names, order, which have defaults) are those of its native signature
(``__text_signature__``, which PyO3 writes from ``#[pyo3(signature = ...)]``). A function
added to the core without a stub, or an argument added to one, fails here."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pytest
from dentalux import _core

STUB = Path(__file__).resolve().parents[1] / "python" / "dentalux" / "_core.pyi"
# stub-only names: type aliases that describe arguments and have no runtime object
ALIASES = {"LayerTuple", "WindowTuple"}


def _stub() -> tuple[dict[str, ast.FunctionDef], set[str]]:
    tree = ast.parse(STUB.read_text())
    functions, values = {}, set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            functions[node.name] = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            values.add(node.target.id)
        elif isinstance(node, ast.Assign):
            values.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return functions, values


def _public() -> dict[str, object]:
    return {name: getattr(_core, name) for name in dir(_core)
            if not name.startswith("_") or name == "__version__"}


def test_every_public_name_has_a_stub():
    functions, values = _stub()
    missing = [n for n in _public() if n not in functions and n not in values]
    assert not missing, f"in dentalux._core but not in _core.pyi: {missing}"


def test_no_stub_without_its_object():
    functions, values = _stub()
    public = _public()
    stale = [n for n in (*functions, *values) if n not in public and n not in ALIASES]
    assert not stale, f"in _core.pyi but not in dentalux._core: {stale}"


def test_functions_and_constants_are_stubbed_as_such():
    functions, values = _stub()
    for name, obj in _public().items():
        if callable(obj):
            assert name in functions, f"{name} is a function; _core.pyi declares a value"
        else:
            assert name in values, f"{name} is a value; _core.pyi declares a function"


def _native_parameters(fn) -> list[tuple[str, bool]] | None:
    native = inspect.unwrap(fn)  # dentalux._guard wraps the native functions
    if not getattr(native, "__text_signature__", None):
        return None
    return [(p.name, p.default is not inspect.Parameter.empty)
            for p in inspect.signature(native).parameters.values()]


def _stub_parameters(node: ast.FunctionDef) -> list[tuple[str, bool]]:
    args = node.args.posonlyargs + node.args.args
    first_default = len(args) - len(node.args.defaults)
    out = [(a.arg, i >= first_default) for i, a in enumerate(args)]
    defaults = node.args.kw_defaults
    out += [(a.arg, d is not None) for a, d in zip(node.args.kwonlyargs, defaults, strict=True)]
    return out


@pytest.mark.parametrize("name", sorted(n for n, o in _public().items() if callable(o)))
def test_parameters_match_the_native_signature(name):
    functions, _ = _stub()
    if name not in functions:
        pytest.fail(f"{name}: no stub in _core.pyi")
    native = _native_parameters(getattr(_core, name))
    if native is None:
        pytest.skip(f"{name}: the native function carries no text signature")
    assert _stub_parameters(functions[name]) == native, (
        f"{name}: _core.pyi's parameters (name, has default) differ from the module's")
