"""The API's docstrings: every example in them runs, and every public name of every public package
has a numpydoc docstring with Parameters, Returns and an Example.

Examples run as doctests (ELLIPSIS and NORMALIZE_WHITESPACE on) in a temporary folder, on the
table shipped with partscale (``partscale.data.table()``) or on ``partscale.shapes``.
"""

from __future__ import annotations

import doctest
import fnmatch
import importlib
import importlib.util
import inspect
import math
import pkgutil
import re
import tomllib
from pathlib import Path
from types import ModuleType

import pytest

import partscale

#: Public packages and modules that are not held to the rule, and why: the command line's
#: docstrings are typer's help texts (its reference is docs/cli.md, checked by tests/test_cli*).
NOT_API = {"partscale.cli"}


def public_packages() -> list[str]:
    """``partscale`` and each module or package directly under it whose name has no leading ``_``.

    Found from the source tree, not listed: a public package added later is held to the rule
    without anyone remembering to add it here.
    """
    found = [
        f"partscale.{m.name}"
        for m in pkgutil.iter_modules(partscale.__path__)
        if not m.name.startswith("_")
    ]
    return ["partscale", *sorted(n for n in found if n not in NOT_API)]


#: Packages whose public names must each have Parameters, Returns and an Example: every one.
COVERED = public_packages()


def public_names(module: ModuleType) -> list[str]:
    """A package's ``__all__``; for a module without one, what it defines without a leading ``_``."""
    if hasattr(module, "__all__"):
        return list(module.__all__)
    return [
        n
        for n, obj in vars(module).items()
        if not n.startswith("_")
        and (inspect.isfunction(obj) or inspect.isclass(obj))
        and obj.__module__ == module.__name__
    ]


def public_callables(package: str) -> list[tuple[str, object]]:
    module = importlib.import_module(package)
    out = []
    for name in public_names(module):
        obj = getattr(module, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            out.append((f"{package}.{name}", obj))
    return out


def _doctests() -> list[doctest.DocTest]:
    finder = doctest.DocTestFinder(exclude_empty=True)
    seen: set[str] = set()
    tests = []
    for package in COVERED:
        module = importlib.import_module(package)
        objects = [(package, module), *public_callables(package)]
        for name, obj in objects:
            for t in finder.find(obj, name, module=False, globs={}):
                # the same docstring reached twice (a name re-exported by another package) runs
                # once; not keyed by file and line: with module=False the file is None, and a
                # decorated function's line is its wrapper's, shared with every other one
                key = t.docstring or ""
                if t.examples and key not in seen:
                    seen.add(key)
                    tests.append(t)
    return tests


DOCTESTS = _doctests()


@pytest.mark.parametrize("test", DOCTESTS, ids=[t.name for t in DOCTESTS])
def test_docstring_example_runs(test, tmp_path, monkeypatch):
    """Each docstring example gives the output it shows (run in a folder of its own)."""
    if "usd" in test.name.rsplit(".", 1)[-1] and importlib.util.find_spec("pxr") is None:
        pytest.skip("usd-core not installed (the optional partscale[usd]): USD examples skipped")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PARTSCALE_CACHE", str(tmp_path / "cache"))
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    runner = doctest.DocTestRunner(optionflags=flags)
    out: list[str] = []
    test.globs = {}
    result = runner.run(test, out=out.append)
    assert result.failed == 0, "".join(out)


def _params(obj) -> list[str]:
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return []
    return [
        p.name
        for p in sig.parameters.values()
        if p.name not in ("self", "cls") and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
    ]


def _returns_something(obj) -> bool:
    if inspect.isclass(obj):
        return False
    ann = inspect.signature(obj).return_annotation
    return ann not in (None, "None", inspect.Signature.empty) or ann is inspect.Signature.empty


def _section(doc: str, name: str) -> bool:
    return re.search(rf"^\s*{name}\n\s*-{{3,}}\s*$", doc, re.MULTILINE) is not None


def missing_sections(obj) -> list[str]:
    """What the numpydoc rule asks of ``obj``'s docstring and it lacks."""
    doc = inspect.getdoc(obj) or ""
    if not doc:
        return ["a docstring"]
    missing = []
    if "\n" in doc.split("\n\n", 1)[0]:
        missing.append("one-line summary")
    if _params(obj) and not (_section(doc, "Parameters") or _section(doc, "Attributes")):
        missing.append("Parameters")
    if _returns_something(obj) and not (_section(doc, "Returns") or _section(doc, "Yields")):
        missing.append("Returns")
    if not (_section(doc, "Examples") and ">>>" in doc):
        missing.append("Examples with >>>")
    return missing


def test_every_public_package_is_held_to_the_rule():
    """The packages found are the ones a user imports (a discovery that found few would leave
    the rest unchecked)."""
    expected = {
        "partscale",
        "partscale.batch",
        "partscale.complete",
        "partscale.csdf",
        "partscale.data",
        "partscale.edit",
        "partscale.errors",
        "partscale.evaluate",
        "partscale.export",
        "partscale.ingest",
        "partscale.meshedit",
        "partscale.render",
        "partscale.segment",
        "partscale.serve",
        "partscale.shapes",
        "partscale.zones",
    }
    assert expected <= set(COVERED), sorted(expected - set(COVERED))
    assert not any(p.split(".")[-1].startswith("_") for p in COVERED), COVERED


def _braces(pattern: str) -> list[str]:
    """A glob's ``{a,b}`` alternatives spelled out (ruff's globs have them, fnmatch has not)."""
    m = re.search(r"\{([^{}]*)\}", pattern)
    if m is None:
        return [pattern]
    return [
        x
        for alt in m.group(1).split(",")
        for x in _braces(pattern[: m.start()] + alt + pattern[m.end() :])
    ]


def test_ruff_holds_every_public_package_to_the_docstring_rules():
    """ruff's pydocstyle rules (D, numpy convention) are selected and no per-file ignore lifts
    them from a public module: a file under a public package, or a public module, whose path
    has no part with a leading ``_`` (``__init__.py`` included)."""
    root = Path(__file__).resolve().parents[1]
    lint = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["ruff"]["lint"]
    assert "D" in lint["select"] and lint["pydocstyle"]["convention"] == "numpy"
    lifted = [
        glob
        for pattern, rules in lint.get("per-file-ignores", {}).items()
        if any(r == "D" or r.startswith("D1") for r in rules)
        for glob in _braces(pattern)
    ]
    files = []
    for package in COVERED[1:]:
        name = package.split(".")[1]
        folder = root / "src" / "partscale" / name
        files += sorted(folder.rglob("*.py")) if folder.is_dir() else [folder.with_suffix(".py")]
    files.append(root / "src" / "partscale" / "__init__.py")
    public = [
        f.relative_to(root).as_posix()
        for f in files
        if f.name == "__init__.py" or not any(p.startswith("_") for p in f.relative_to(root).parts)
    ]
    assert len(public) >= 50, public
    exempt = [f for f in public if any(fnmatch.fnmatch(f, g) for g in lifted)]
    assert not exempt, exempt


@pytest.mark.parametrize("package", COVERED)
def test_public_names_have_parameters_returns_and_an_example(package):
    """Every public function and class of every public package says what it is in one line, then
    documents its parameters, what it returns and how to call it (a class's Parameters may be
    its Attributes)."""
    problems = [
        f"{name}: no {', '.join(miss)}"
        for name, obj in public_callables(package)
        if (miss := missing_sections(obj))
    ]
    assert not problems, "\n".join(problems)


def test_the_rule_catches_a_bare_docstring():
    """The check above, on a function documented the way most were: caught."""

    def resize(csdf, factor: float) -> object:
        """The object scaled by ``factor``,
        about its centre."""

    assert missing_sections(resize) == [
        "one-line summary",
        "Parameters",
        "Returns",
        "Examples with >>>",
    ]


def test_doctests_were_found():
    """The examples are collected (a finder that finds nothing would pass every run)."""
    assert len(DOCTESTS) >= 100, len(DOCTESTS)
    assert all(t.name.startswith("partscale") and t.examples for t in DOCTESTS)


def test_a_radial_edit_grows_a_centred_slab_alike_on_both_sides():
    """A square slab centred on the axis grows alike on both sides (within half a voxel), round
    (its sides by the shift) or as a square (by the shift times cos 45 degrees)."""
    from partscale import shapes
    from partscale.edit import RadialZone, apply_radial

    slab = shapes.box((-0.5, 0, -0.5), (0.5, 0.1, 0.5), voxel_size=0.04)
    (lo0, hi0) = slab.surface_bounds()
    for sides, grow in ((0, 0.1), (4, 0.1 * math.cos(math.pi / 4))):
        out = apply_radial(slab, RadialZone("y", (0.0, 0.0), 0.1, 0.4, 0.5, sides=sides))
        lo, hi = out.surface_bounds()
        for ax in (0, 2):
            assert abs((hi[ax] - hi0[ax]) - grow) <= 0.5 * slab.voxel_size, (sides, hi, hi0)
            assert abs((lo0[ax] - lo[ax]) - grow) <= 0.5 * slab.voxel_size, (sides, lo, lo0)


def test_find_radial_finds_a_centred_sphere_about_its_centre():
    from partscale import shapes, zones

    ball = shapes.sphere((0, 0, 0), 0.5, voxel_size=0.025)
    frame = zones.find_radial(ball)
    assert max(abs(c) for c in frame.center) <= 0.25 * ball.voxel_size
