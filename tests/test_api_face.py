"""The top level as users meet it: ``import partscale`` is light, its names load on first use,
the type stub and the runtime offer the same names, and every package's ``__all__`` holds what
its docstring names.
"""

from __future__ import annotations

import ast
import importlib
import json
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import partscale

SRC = Path(partscale.__file__).parent
HEAVY = ("numba", "trimesh", "scipy", "skimage")


def _loaded_after(code: str) -> list[str]:
    """The heavy libraries in ``sys.modules`` after running ``code`` in a fresh interpreter."""
    probe = (
        f"{code}\nimport json, sys\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    )
    out = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=300
    )
    return json.loads(out.stdout.splitlines()[-1])


def test_import_partscale_loads_no_heavy_library():
    """``import partscale`` imports none of numba, trimesh, scipy, scikit-image."""
    assert _loaded_after("import partscale") == []


def test_a_name_loads_its_stage_on_first_use():
    """Reading ``partscale.fit`` imports the zones stage (and numba with it), nothing before."""
    assert "numba" in _loaded_after("import partscale\npartscale.fit")


def _stub() -> tuple[dict[str, tuple[str, str | None]], list[str]]:
    """The stub's names -> (module, attribute or None for the module), and its ``__all__``."""
    names: dict[str, tuple[str, str | None]] = {}
    listed: list[str] = []
    for node in ast.parse((SRC / "__init__.pyi").read_text()).body:
        if isinstance(node, ast.ImportFrom):
            for a in node.names:
                names[a.asname or a.name] = (node.module, a.name) if node.module else (a.name, None)
        elif isinstance(node, ast.Assign) and node.targets[0].id == "__all__":  # type: ignore[attr-defined]
            listed = ast.literal_eval(node.value)
    return names, listed


def test_the_stub_and_the_runtime_offer_the_same_names():
    """``__init__.pyi`` (what type checkers see) lists every name ``partscale`` offers, its
    ``__all__`` is sorted and complete, and each name is the object the stub says."""
    names, listed = _stub()
    assert listed == sorted(names), f"stub __all__ {listed} vs its imports {sorted(names)}"
    assert partscale.__all__ == listed
    for name, (module, attr) in names.items():
        expected = importlib.import_module(f"partscale.{module}")
        if attr is not None:
            expected = getattr(expected, attr)
        assert getattr(partscale, name) is expected, name
    with pytest.raises(AttributeError, match="no attribute 'fitt'"):
        partscale.fitt  # noqa: B018


def test_the_pipeline_runs_from_the_top_level(tmp_path):
    """The main functions chain as the README's Python block shows (an analytic box)."""
    from partscale import shapes

    box = shapes.grid(
        lambda p: shapes.boxes_sdf(p, [((0, 0, 0), (1.0, 0.5, 0.4))]),
        [(0, 0, 0), (1.0, 0.5, 0.4)],
        voxel_size=0.02,
    )
    recipe, _ = partscale.fit(box, ["1.5", "=", "="])
    longer = partscale.apply_recipe(box, recipe)
    lo, hi = longer.surface_bounds()
    assert abs((hi - lo)[0] - 1.5) <= 0.02, f"expected 1.5 long within a voxel, got {hi - lo}"
    back = partscale.load(partscale.save(longer, tmp_path / "longer.csdf.npz"))
    assert np.array_equal(back.sdf, longer.sdf) and back.meta == longer.meta


_ROLE = re.compile(r":(?:func|class|data|obj|exc|meth|attr|mod):`~?([A-Za-z_][\w.]*)`")
#: packages without a library ``__all__``: the typer app (``app``, ``main``), not a library face
NO_ALL = {"partscale.cli"}


def _packages() -> list[str]:
    subpackages = (p.parent.relative_to(SRC).parts for p in SRC.rglob("__init__.py"))
    return ["partscale", *sorted("partscale." + ".".join(p) for p in subpackages if p)]


def _resolves(dotted: str) -> bool:
    """Whether ``partscale.a.b.c`` names a module or an attribute of one."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for p in parts[cut:]:
            if not hasattr(obj, p):
                return False
            obj = getattr(obj, p)
        return True
    return False


@pytest.mark.parametrize("name", _packages())
def test_every_package_all_and_docstring_agree(name):
    """Each package has ``__all__``; every name in it exists; every bare name its docstring
    refers to (``:func:`x```) is in it (or is one of its modules); every ``partscale.``
    reference resolves."""
    if name in NO_ALL:
        pytest.skip(f"{name} is the command line, not a library face")
    module = importlib.import_module(name)
    listed = getattr(module, "__all__", None)
    assert listed is not None, f"{name} has no __all__"
    assert [n for n in listed if not hasattr(module, n)] == [], f"{name}.__all__ names missing"
    refs = _ROLE.findall(module.__doc__ or "")
    modules = {m.name for m in pkgutil.iter_modules(module.__path__)}
    bare = sorted({r for r in refs if "." not in r} - set(listed) - modules)
    assert bare == [], f"{name}'s docstring names {bare}, not in its __all__"
    broken = sorted({r for r in refs if r.startswith("partscale.") and not _resolves(r)})
    assert broken == [], f"{name}'s docstring refers to {broken}, which do not exist"
