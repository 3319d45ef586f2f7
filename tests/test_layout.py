"""The package's import structure: no import cycle (lazy imports inside functions included) and
every import points down the order of wings below.

``LAYERS`` is the one place the allowed order is written (docs/architecture.md draws it). A
module of a wing may import its own wing and any wing of a lower layer; wings that share a layer
(the three tasks) may not import each other. The graph is read from the source with ``ast``, so
it sees every import statement wherever it stands, not only the ones that ran.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = "meshrepair"
SRC = Path(__file__).resolve().parents[1] / "src" / PKG

# Lowest first. A wing is a subpackage or a top-level module of ``meshrepair``.
LAYERS: list[tuple[str, ...]] = [
    ("errors",),
    ("options", "atomic"),
    ("_kernels",),
    ("mesh",),
    ("io",),
    ("metrics", "synthetic", "baselines"),
    ("model",),
    ("holes",),
    ("denoise", "fill", "complete"),  # the tasks: none imports another
    ("render",),
    ("viewer",),
    ("report",),
    ("batch",),
    ("commands",),
    ("cli", "__init__"),
    ("__main__",),  # python -m meshrepair: the cli
]
RANK = {wing: i for i, layer in enumerate(LAYERS) for wing in layer}


def _modules() -> dict[str, tuple[Path, bool]]:
    mods = {}
    for p in SRC.rglob("*.py"):
        rel = p.relative_to(SRC.parent).with_suffix("")
        name = ".".join(rel.parts)
        is_pkg = p.name == "__init__.py"
        if is_pkg:
            name = name[: -len(".__init__")]
        mods[name] = (p, is_pkg)
    return mods


def _resolve(cur: str, is_pkg: bool, level: int, module: str | None) -> str:
    if level == 0:
        return module or ""
    base = cur.split(".") if is_pkg else cur.split(".")[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([module] if module else []))


def import_graph() -> dict[str, set[str]]:
    """``{module: modules it imports}`` within the package (every ``import`` / ``from ...
    import`` statement of the file, at any depth; ``from pkg import name`` counts ``pkg`` and,
    when ``name`` is a module, ``pkg.name``)."""
    mods = _modules()
    edges: dict[str, set[str]] = {m: set() for m in mods}
    for m, (p, is_pkg) in mods.items():
        tree = ast.parse(p.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(m, is_pkg, node.level, node.module)
                targets = [base] + [f"{base}.{a.name}" for a in node.names]
            else:
                continue
            for t in targets:
                while t and t not in mods:
                    t = t.rpartition(".")[0]
                if t and t != m and t != PKG and t.startswith(PKG + "."):
                    edges[m].add(t)
    return edges


def wing(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on: set[str] = set()
    stack: list[str] = []
    out: list[list[str]] = []
    counter = 0
    for root in edges:
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return out


def upward_imports(edges: dict[str, set[str]]) -> list[str]:
    bad = []
    for m, targets in edges.items():
        a = wing(m)
        for t in sorted(targets):
            b = wing(t)
            if a == b:
                continue
            if RANK[b] >= RANK[a]:
                bad.append(f"{m} -> {t} ({a!r} may not import {b!r})")
    return bad


def test_every_wing_has_a_layer():
    wings = {wing(m) for m in _modules()}
    assert wings <= set(RANK), f"wings without a layer in LAYERS: {sorted(wings - set(RANK))}"


def test_no_import_cycle():
    assert cycles(import_graph()) == []


def test_imports_point_down():
    assert upward_imports(import_graph()) == []


def test_top_level_is_small():
    top = sorted(p.stem for p in SRC.glob("*.py") if p.name != "__init__.py")
    assert len(top) <= 12, top


def test_the_checker_sees_a_cycle_and_an_upward_import():
    """The checks above can fail: a made-up graph with a lazy cycle and an upward arrow."""
    g = {"meshrepair.mesh.a": {"meshrepair.model.b"}, "meshrepair.model.b": {"meshrepair.mesh.a"}}
    assert cycles(g) == [["meshrepair.mesh.a", "meshrepair.model.b"]]
    assert upward_imports(g) == [
        "meshrepair.mesh.a -> meshrepair.model.b ('mesh' may not import 'model')"]


@pytest.mark.parametrize("name", ["penalties", "inner", "linear", "operators", "solver"])
def test_documented_old_paths_still_import(name, recwarn):
    """Names the README documented before the layout keep working for one release, with a
    DeprecationWarning that names the new path."""
    import importlib
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        old = importlib.import_module(f"{PKG}.{name}")
    new = {"operators": "mesh.operators"}.get(name, f"model.{name}")
    assert old is importlib.import_module(f"{PKG}.{new}")
    assert any(issubclass(w.category, DeprecationWarning) and new in str(w.message)
               for w in caught)
