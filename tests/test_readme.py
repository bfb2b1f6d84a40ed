"""The README as a user reads it: every command block runs, every picture and link exists, and
the text speaks to users (no development log).

Blocks run in order in one folder (a later block may use a file an earlier one made, as a reader
following the guide would), with the installed ``partscale`` and ``python`` first on PATH. A
block preceded by ``<!-- test: skip (REASON) -->`` is reported as skipped with its reason.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from conftest import ROOT

README = ROOT / "README.md"
BLOCK_TIMEOUT_S = 600

_BLOCK = re.compile(
    r"(?:<!-- test: skip \((?P<why>[^)]*)\) -->\n)?^```(?P<lang>bash|python)\n(?P<code>.*?)^```",
    re.MULTILINE | re.DOTALL,
)


@dataclass(frozen=True)
class Block:
    line: int
    lang: str
    code: str
    skip: str | None


def blocks(text: str) -> list[Block]:
    """The README's ```bash and ```python blocks, in order, each with its skip reason or None."""
    return [
        Block(text.count("\n", 0, m.start("code")) + 1, m["lang"], m["code"], m["why"])
        for m in _BLOCK.finditer(text)
    ]


BLOCKS = blocks(README.read_text())


def skip_reason(block: Block) -> str | None:
    """Why ``block`` does not run here: its marker's reason, or an optional extra missing."""
    if block.skip:
        return block.skip
    if re.search(r"\.usd[acz]?\b", block.code) and importlib.util.find_spec("pxr") is None:
        return "writes USD: usd-core (the optional partscale[usd]) is not installed"
    return None


def test_the_readme_has_command_blocks_and_few_skips():
    """The guide shows commands, and nearly all of them run here."""
    assert len(BLOCKS) >= 12, f"expected a command block per task, got {len(BLOCKS)}"
    skipped = [b for b in BLOCKS if b.skip]
    assert len(skipped) <= 4, f"expected at most 4 skipped blocks, got {len(skipped)}"
    fences = re.findall(r"^```(\w*)$", README.read_text(), re.MULTILINE)
    others = {f for f in fences[::2] if f not in ("bash", "python", "json")}
    assert not others, f"a block this test does not run: {others}"


class Workspace:
    """One folder the blocks run in, in order; a block runs the ones before it first."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.done = 0
        bin_dir = str(Path(sys.executable).parent)
        self.env = {**os.environ, "PATH": bin_dir + os.pathsep + os.environ.get("PATH", "")}
        self.env.pop("PARTSCALE_DEMO_OBJECT", None)

    def run_through(self, index: int) -> None:
        while self.done <= index:
            block = BLOCKS[self.done]
            self.done += 1
            if not skip_reason(block):
                self._run(block)

    def _run(self, block: Block) -> None:
        if block.lang == "bash":
            cmd = ["bash", "-euo", "pipefail", "-c", block.code]
        else:
            script = self.path / f"readme_block_{block.line}.py"
            script.write_text(block.code)
            cmd = [sys.executable, str(script)]
        r = subprocess.run(
            cmd,
            cwd=self.path,
            env=self.env,
            capture_output=True,
            text=True,
            timeout=BLOCK_TIMEOUT_S,
            stdin=subprocess.DEVNULL,
        )
        assert r.returncode == 0, (
            f"README.md line {block.line}: the {block.lang} block exited {r.returncode}\n"
            f"--- block\n{block.code}--- stdout\n{r.stdout[-3000:]}--- stderr\n{r.stderr[-3000:]}"
        )


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Workspace:
    return Workspace(tmp_path_factory.mktemp("readme"))


@pytest.mark.parametrize("index", range(len(BLOCKS)), ids=[f"line{b.line}" for b in BLOCKS])
def test_readme_block_runs(index, workspace):
    """Each block exits 0 when run, after the blocks before it, as a reader would run them."""
    block = BLOCKS[index]
    if why := skip_reason(block):
        pytest.skip(f"README.md line {block.line}: {why}")
    workspace.run_through(index)


def test_readme_python_api_block_makes_what_it_says(workspace):
    """The Python API's lines, on the top level, write the fitted table, its mesh and its
    picture."""
    api = next(i for i, b in enumerate(BLOCKS) if b.lang == "python" and "partscale.fit(" in b.code)
    workspace.run_through(api)
    from partscale import load

    c = load(workspace.path / "table_3m.csdf.npz")
    sb = c.surface_bounds()
    assert abs((sb[1, 0] - sb[0, 0]) - 3.0) <= c.voxel_size, "x: expected 3 m within a voxel"
    assert (workspace.path / "table_3m.png").stat().st_size > 1000
    import trimesh

    mesh = trimesh.load(workspace.path / "table_3m.glb", force="mesh")
    assert abs(mesh.extents[0] - 3.0) <= 2 * c.voxel_size, (
        f"mesh x: expected 3 m, got {mesh.extents}"
    )


_LINK = re.compile(r"!?\[[^\]]*\]\((?P<target>[^)#\s]+)(?:#[^)]*)?\)")


def test_every_picture_and_link_in_the_readme_exists():
    missing = [
        m["target"]
        for m in _LINK.finditer(README.read_text())
        if "://" not in m["target"] and not (ROOT / m["target"]).exists()
    ]
    assert not missing, f"README links to files that do not exist: {missing}"


#: What a development log says and a user's guide does not.
_NOT_FOR_USERS = {
    "a path outside the repository": re.compile(r"\.\./shared"),
    "an issue number": re.compile(r"\bissues? \d+", re.IGNORECASE),
    "a session": re.compile(r"\bsessions?\b", re.IGNORECASE),
    "a dated run": re.compile(r"\b20\d\d-\d\d-\d\d\b"),
    "a load average": re.compile(r"load average|\bload:? ~?\d+(?:\.\d+)?[–,)]", re.IGNORECASE),
    "tried and not kept": re.compile(r"not kept", re.IGNORECASE),
    "a private name": re.compile(r"`[\w.]*\._(?!_)\w+"),
    "a round of work": re.compile(r"\b(?:this|eighth|seventh|ninth|last|next) round\b"),
}


def test_the_readme_speaks_to_users():
    """No development log in the guide: paths outside the repository, issue or session numbers,
    dated runs, load averages, what was tried and dropped, private names; no table cell longer
    than a short paragraph."""
    text = README.read_text()
    found = [
        f"{what}: {m[0]!r} (line {text.count(chr(10), 0, m.start()) + 1})"
        for what, rx in _NOT_FOR_USERS.items()
        for m in rx.finditer(text)
    ]
    cells = [c for line in text.splitlines() if line.startswith("|") for c in line.split("|")]
    found += [f"a table cell of {len(c)} characters" for c in cells if len(c) > 200]
    assert not found, "\n".join(found)


def test_the_checks_catch_a_development_log():
    """The rules above, on lines the README used to hold: each is caught."""
    old = [
        "partscale batch ../shared/data -o out/all",
        "### Completing partial scans (issue 17)",
        "2026-12-04 12:45–12:52 (nineteenth session, load 0.6–1.9, three runs)",
        "quiet: load 0.4–1.9",
        "Tried and not kept: refining up by the rotation axis",
        "**The legs themselves say the fold** (`symmetry._Arms`)",
    ]
    for line in old:
        assert any(rx.search(line) for rx in _NOT_FOR_USERS.values()), line
