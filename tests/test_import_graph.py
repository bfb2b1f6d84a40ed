"""The package's import graph, read from the source with ``ast``: no module takes part in an
import circle (every import counts: module-level, type-only and deferred inside a function),
and no module imports a private name (``_x``: a private module or a private name in a module)
owned by another package.

A private name belongs to the package it lives in; modules of that package and of its
subpackages may import it (``partscale._files`` serves every stage; ``partscale.edit``'s
modules share ``partscale.edit._warp_kernels``), other packages may not.
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

import partscale

SRC = Path(partscale.__file__).parent

#: Known exceptions: circles, each a sorted tuple of its modules. Each is to be removed (and
#: then removed here); the test fails on any other.
KNOWN_CIRCLES: set[tuple[str, ...]] = set()
#: Known exceptions: (importing module, imported private name). Each is to be removed (and
#: then removed here); the test fails on any other.
KNOWN_PRIVATE: set[tuple[str, str]] = set()


def _modules() -> dict[str, Path]:
    """Dotted name -> file of every module of the package (packages as their ``__init__``)."""
    out = {}
    for path in SRC.rglob("*.py"):
        parts = path.relative_to(SRC.parent).with_suffix("").parts
        if "static" in parts:
            continue
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


MODULES = _modules()


def _is_package(name: str) -> bool:
    return MODULES.get(name, Path()).name == "__init__.py"


def _package_of(name: str) -> str:
    return name if _is_package(name) else name.rpartition(".")[0]


def _targets(name: str, node: ast.Import | ast.ImportFrom) -> list[str]:
    """The dotted names ``node`` in module ``name`` imports (``module.attr`` for names)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if node.level:
        base = _package_of(name).split(".")
        base = base[: len(base) - (node.level - 1)]
        module = ".".join(base + ([node.module] if node.module else []))
    else:
        module = node.module or ""
    return [f"{module}.{a.name}" for a in node.names]


def _imports() -> dict[str, list[str]]:
    """Module -> the dotted names it imports, anywhere in it."""
    return {
        name: [
            t
            for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.Import | ast.ImportFrom)
            for t in _targets(name, node)
        ]
        for name, path in MODULES.items()
    }


IMPORTS = _imports()


def _module_of(target: str) -> str | None:
    """The package's module that ``target`` (a module or ``module.attr``) is or lives in."""
    while target and target not in MODULES:
        target = target.rpartition(".")[0]
    return target or None


def test_the_import_graph_has_no_new_circle():
    """No module imports one that imports it back, directly or not."""
    graph = nx.DiGraph()
    for name, targets in IMPORTS.items():
        for t in targets:
            m = _module_of(t)
            if m is not None and m != name and not name.startswith(m + "."):
                # a submodule importing its own package's __init__ runs after it: not an arrow
                graph.add_edge(name, m)
    circles = {tuple(sorted(c)) for c in nx.strongly_connected_components(graph) if len(c) > 1}
    assert circles - KNOWN_CIRCLES == set(), f"import circles: {sorted(circles - KNOWN_CIRCLES)}"


def _private_owner(target: str) -> str | None:
    """The package owning the first private part of ``target``, or None if none is private."""
    parts = target.split(".")
    for k, part in enumerate(parts):
        if part.startswith("_") and not part.startswith("__"):
            return _package_of(_module_of(".".join(parts[:k])) or ".".join(parts[:k]))
    return None


def test_no_module_imports_a_private_name_of_another_package():
    """``from ..other._x import y`` and ``from ..other.mod import _y`` only inside ``other``."""
    found = set()
    for name, targets in IMPORTS.items():
        for t in targets:
            owner = _private_owner(t)
            if owner is not None and not (name == owner or name.startswith(owner + ".")):
                found.add((name, t))
    assert found - KNOWN_PRIVATE == set(), (
        f"private names borrowed: {sorted(found - KNOWN_PRIVATE)}"
    )


def test_the_graph_is_read():
    """The reader sees the pipeline's arrows (the test above cannot pass on an empty graph)."""
    assert "partscale.csdf.CSDF" in IMPORTS["partscale.segment.api"]
    assert "partscale._files.atomic_path" in IMPORTS["partscale.csdf"]
    assert len(MODULES) > 100
