"""The layering has no circles (issue 17): Python's module-level imports inside
``python/dentalux`` and the core's module references (``crate::``, ``super::`` outside
comments) inside ``crates/dentalux-core/src`` form graphs without cycles. Imports inside
functions are lazy and do not count; parent modules do not depend on their children."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def py_graph(root: Path):
    """Module -> the package modules it imports at module level."""
    mods = {}
    for f in root.rglob("*.py"):
        rel = f.relative_to(root.parent).with_suffix("")
        name = ".".join(rel.parts)
        if name.endswith(".__init__"):
            name = name[: -len(".__init__")]
        mods[name] = f
    for f in root.glob("*.pyi"):  # native modules (the core) are leaves
        mods.setdefault(f"dentalux.{f.stem}", None)
    g = {m: set() for m in mods}
    for m, f in mods.items():
        if f is None:
            continue
        tree = ast.parse(f.read_text())
        pkg = m if f.name == "__init__.py" else m.rpartition(".")[0]
        for node in tree.body:  # module level only: imports inside functions are lazy
            stmts = [node]
            if isinstance(node, ast.If):
                stmts = node.body
            for st in stmts:
                if isinstance(st, ast.Import):
                    targets = [a.name for a in st.names]
                elif isinstance(st, ast.ImportFrom):
                    base = st.module or ""
                    if st.level:
                        parts = pkg.split(".")
                        parts = parts[: len(parts) - st.level + 1]
                        base = ".".join(parts + ([base] if base else []))
                    targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base
                               for a in st.names]
                else:
                    continue
                for t in targets:
                    if t in mods and t != m:
                        g[m].add(t)
    return g

def cycles(g):
    """Every circle a depth-first walk meets, as [a, b, ..., a]."""
    seen, stack, out = {}, [], []

    def visit(v):
        seen[v] = 1
        stack.append(v)
        for w in sorted(g[v]):
            if seen.get(w) == 1:
                out.append(stack[stack.index(w):] + [w])
            elif w not in seen:
                visit(w)
        stack.pop()
        seen[v] = 2
    for v in sorted(g):
        if v not in seen:
            visit(v)
    return out

def rust_graph(src: Path):
    """Core module -> the modules its code names (outside comments), parents excluded."""
    mods = {}
    for f in src.rglob("*.rs"):
        rel = f.relative_to(src).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] in ("mod", "lib"):
            parts = parts[:-1]
        mods["::".join(parts)] = f
    g = {m: set() for m in mods}
    for m, f in mods.items():
        text = "\n".join(line.split("//")[0] for line in f.read_text().splitlines())
        here = m.split("::") if m else []
        for path in re.findall(r"\b((?:crate|super|self)(?:::\w+)+)", text):
            parts = path.split("::")
            if parts[0] == "crate":
                parts = parts[1:]
            else:
                # `self` is this module (a file's or a folder's), `super` its parent
                base = here
                while parts and parts[0] in ("super", "self"):
                    if parts[0] == "super":
                        base = base[:-1]
                    parts = parts[1:]
                parts = base + parts
            # longest module prefix
            for k in range(len(parts), 0, -1):
                cand = "::".join(parts[:k])
                if cand in mods:
                    break
            else:
                continue
            if cand != m and not m.startswith(cand + "::") and not cand.startswith(m + "::") :
                g[m].add(cand)
    return g


def test_python_imports_have_no_circle():
    g = py_graph(ROOT / "python" / "dentalux")
    assert "dentalux.scene.schema" in g and "dentalux._core" in g
    assert cycles(g) == []


def test_core_modules_have_no_circle():
    g = rust_graph(ROOT / "crates" / "dentalux-core" / "src")
    assert "integrators::render" in g and "scene" in g["integrators::render"]
    assert cycles(g) == []


def test_a_circle_is_found(tmp_path):
    """The checks can fail: a two-module circle in each language is reported."""
    pkg = tmp_path / "dentalux"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from dentalux import b\n")
    (pkg / "b.py").write_text("import dentalux.a\n\ndef f():\n    from dentalux import a\n")
    assert cycles(py_graph(pkg)) == [["dentalux.a", "dentalux.b", "dentalux.a"]]
    src = tmp_path / "src"
    (src / "x").mkdir(parents=True)
    (src / "lib.rs").write_text("mod x;\nmod y;\n")
    (src / "x" / "mod.rs").write_text("// crate::y in a comment is no use\npub mod z;\n")
    (src / "x" / "z.rs").write_text("use crate::y::Y;\n")
    (src / "y.rs").write_text("use crate::x::z::f;\n")
    assert cycles(rust_graph(src)) == [["x::z", "y", "x::z"]]
    # `super::` from a file module names a sibling: x::z and x::w use each other
    (src / "y.rs").write_text("")
    (src / "x" / "mod.rs").write_text("pub mod w;\npub mod z;\n")
    (src / "x" / "z.rs").write_text("use super::w::W;\n")
    (src / "x" / "w.rs").write_text("use super::z::Z;\n")
    assert cycles(rust_graph(src)) == [["x::w", "x::z", "x::w"]]
