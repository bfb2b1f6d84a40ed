"""The CLI's vocabulary and help: what every ``--help`` shows, its examples, old spellings."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
import typer
from conftest import ROOT, assert_bad_input

TYPE_METAVAR = re.compile(r"<[A-Za-z_]+(\[[^\]]*\])?>")
"""A Python type as typer shows it in place of a metavar: ``<int>``, ``<list[Path]>``."""

PROSE_DEFAULT = re.compile(r"\bdefaults?\b", re.IGNORECASE)
"""A default written into the help's prose: the one way is typer's ``[default: X]``."""


def _commands():
    from partscale.cli import app

    group = typer.main.get_command(app)
    return group, {n: c for n, c in group.commands.items() if not c.hidden}


def _help_text(*args: str) -> str:
    from typer.testing import CliRunner

    from partscale.cli import app

    result = CliRunner().invoke(app, [*args, "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return result.output


def _meaning(help_text: str) -> str:
    """What an option is, as its help says first: the text before the first '.', ':' or ';'
    (the rest may add what it does in that command)."""
    return re.split(r"[.:;]", help_text, maxsplit=1)[0].strip()


def test_every_help_has_an_example_readable_metavars_one_meaning_per_name_and_no_prose_defaults():
    """Walk ``partscale --help`` and every subcommand's: no Python type shown as a metavar (and
    none on a flag), an example that runs the command, each option name meaning one thing in
    every command that has it (the same first clause of its help), no default in prose."""
    group, commands = _commands()
    problems: list[str] = []
    meanings: dict[str, dict[str, str]] = {}
    for name, cmd in [("", group), *commands.items()]:
        where = f"partscale {name}".strip()
        text = _help_text(*([name] if name else []))
        for m in TYPE_METAVAR.finditer(text):
            problems.append(f"{where} --help: Python type {m[0]} as a metavar")
        if name and not re.search(rf"^\s*partscale {re.escape(name)} \S", text, re.MULTILINE):
            problems.append(f"{where} --help: no example")
        for p in cmd.params:
            if getattr(p, "hidden", False):
                continue
            help_text = getattr(p, "help", None) or ""
            if PROSE_DEFAULT.search(help_text):
                problems.append(f"{where} {p.opts[0]}: default in prose: {help_text!r}")
            if p.param_type_name != "option":
                continue
            if not getattr(p, "is_flag", False) and not p.metavar:
                problems.append(f"{where} {p.opts[0]}: no metavar")
            for opt in p.opts:
                meanings.setdefault(opt, {})[where] = _meaning(help_text)
    for opt, by_command in meanings.items():
        if len(set(by_command.values())) > 1:
            problems.append(f"{opt} means different things: {by_command}")
    assert not problems, "\n".join(problems)


def test_the_meaning_check_catches_the_old_size():
    """The rule the walk applies, on what ``--size`` said before: three meanings, caught."""
    old = {
        "fit": "X Y Z target extents: = (unchanged), 2.1 / 210cm / 2100mm, +20cm / -5cm, or 120%.",
        "export": "Resize the grid first to this many voxels along the longest side: 32, 64.",
        "render": "Image width and height in pixels.",
    }
    assert len({_meaning(h) for h in old.values()}) == 3
    assert PROSE_DEFAULT.search("Or decimate (default 0.1; 0 keeps full resolution).")
    assert TYPE_METAVAR.search("--texture <list[Path]> 3D texture") and TYPE_METAVAR.search(
        "--square <bool>"
    )


def test_version_is_the_installed_one(cli):
    from importlib.metadata import version

    proc = cli("--version", check=True)
    assert proc.stdout.strip() == f"partscale {version('partscale')}"


def test_old_spellings_still_work_with_one_note_each(cli, tmp_path):
    from partscale import save, shapes
    from partscale.cli._help import DEPRECATED, accept_deprecated

    src = tmp_path / "box.csdf.npz"
    save(shapes.box((0, 0, 0), (0.4, 0.2, 0.3), voxel_size=0.02), src)
    proc = cli("render", src, "-o", tmp_path / "a.png", "--size", "64", check=True)
    notes = [ln for ln in proc.stderr.splitlines() if "note:" in ln]
    assert len(notes) == 1 and "render --size is now --pixels" in notes[0], proc.stderr
    from PIL import Image

    with Image.open(tmp_path / "a.png") as im:
        assert im.size == (64, 64)
    proc = cli("export", src, "--mesh", tmp_path / "a.glb", "--size=32", check=True)
    assert "export --size is now --grid" in proc.stderr and "(32 x" in proc.stderr, proc.stderr
    # every old spelling maps to an option its command has; values equal to one are not touched
    _group, commands = _commands()
    for command, table in DEPRECATED.items():
        opts = {o for p in commands[command].params for o in p.opts}
        assert set(table.values()) <= opts, (command, table)
        assert set(table) & opts == set(), (command, "old spelling still declared")
    argv = ["-v", "fit", "x.csdf.npz", "-o", "y.csdf.npz", "--size", "2", "=", "="]
    assert accept_deprecated(argv) == argv  # fit's --size is the new name


def test_lengths_take_every_unit_the_importer_takes(cli, tmp_path):
    from partscale.edit import SUFFIXES, parse_length, parse_size

    assert parse_length("80in", units="m") == pytest.approx(80 * 0.0254)
    assert parse_size("+10in", extent=1.0, units="m") == pytest.approx(1.254)
    src = tmp_path / "box.csdf.npz"
    from partscale import load, save, shapes

    save(shapes.box((0, 0, 0), (0.4, 0.2, 0.3), voxel_size=0.01), src)
    out = tmp_path / "long.csdf.npz"
    cli("scale", src, "-o", out, "--axis", "x", "--zone", "40%", "60%", "--by", "4in", check=True)
    ext = [c.surface_bounds()[1][0] - c.surface_bounds()[0][0] for c in (load(src), load(out))]
    # the length grows by 4 inches within a voxel (DEST - END snaps to whole voxels)
    assert abs(ext[1] - ext[0] - 4 * 0.0254) <= 0.01, ext
    # the importer's --units are the same table
    from partscale import data

    proc = cli("import", data.table(), "-o", tmp_path / "x.csdf.npz", "--units", "ft")
    assert_bad_input(proc, "units", ", ".join(SUFFIXES))


def test_library_errors_name_parameters_not_cli_options():
    from partscale import InputError, data, ingest

    for kwargs in ({"res": 8}, {"pad": 1}, {"up": "w"}, {"units": "ft"}, {"scale": -1.0}):
        with pytest.raises(InputError) as e:
            ingest.load(data.table(), **kwargs)
        assert "--" not in str(e.value) and next(iter(kwargs)) in str(e.value), str(e.value)


@pytest.mark.slow
def test_the_help_examples_run_in_order_on_the_shipped_table(tmp_path):
    """Every example of every ``--help``, in :data:`EXAMPLES` order in one folder, as a user
    would paste them (bash, the installed ``partscale``); the editor's is started and stopped
    once it serves its page."""
    from partscale.cli._help import EXAMPLES

    bindir = Path(sys.executable).parent
    env = dict(os.environ)
    env["PATH"] = f"{bindir}{os.pathsep}{env.get('PATH', '')}"
    env["PARTSCALE_CACHE"] = str(tmp_path / "cache")
    assert (bindir / "partscale").exists() or pytest.skip("no partscale script beside python")
    for command, lines in EXAMPLES.items():
        for line in lines:
            if command == "editor":
                _serve_then_stop(line + " --no-browser", env, tmp_path)
                continue
            proc = subprocess.run(
                ["bash", "-c", line], cwd=tmp_path, env=env, capture_output=True, text=True
            )
            assert proc.returncode == 0, (line, proc.stderr[-2000:])
    for name in ("table_longer.glb", "table_longer_mesh.png", "table_completed.csdf.npz"):
        assert (tmp_path / name).stat().st_size > 0, name


def _serve_then_stop(line: str, env: dict, cwd: Path) -> None:
    proc = subprocess.Popen(
        ["bash", "-c", f"exec {line}"],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        deadline = time.monotonic() + 120
        seen = []
        assert proc.stdout is not None
        while time.monotonic() < deadline:
            out = proc.stdout.readline()
            if not out:
                break
            seen.append(out)
            if "http://" in out:
                return
        raise AssertionError(f"{line}: no URL printed: {''.join(seen)[-2000:]}")
    finally:
        proc.terminate()
        proc.communicate(timeout=30)


def test_root_help_names_the_demo_object():
    text = _help_text()
    assert "python -m partscale.data table" in text
    assert (ROOT / "src" / "partscale" / "data" / "table.glb").is_file()
