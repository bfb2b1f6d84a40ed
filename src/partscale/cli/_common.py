"""What every subcommand shares: the error boundary, verbosity and the progress bar."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from .._options import MAX_RES, MIN_RES
from ..progress import ProgressCallback

stderr = Console(stderr=True)
state = {"verbose": False}

#: ``--res`` of the commands that import (``import``, ``complete``, ``batch``, ``eval``): one
#: declaration, one help text.
RES_HELP = f"Voxels along the object's longest side, {MIN_RES} to {MAX_RES}."
Res = Annotated[int, typer.Option("--res", metavar="N", help=RES_HELP)]

#: ``--allow-deform`` of the commands that fit (``fit``, ``batch``): one help text.
ALLOW_DEFORM_HELP = (
    "Where no zone reaches the size part-aware, stretch thin slabs or scale globally instead "
    "of refusing"
)

#: ``--size`` of ``fit`` and ``batch``: the target extents.
SIZE_HELP = (
    "Target extents along x, y and z: = (unchanged), 2.1 (object units), 210cm / 2100mm / 80in, "
    "+20cm / -5cm (change), or 120% (of the current extent)."
)


def spaced(name: str, form: str, parse: Callable[[tuple], Any] | None = None) -> Callable:
    """A callback for an option of several values (``name``, e.g. ``--zone``; ``form``, e.g.
    ``START END``), checked as it is read. Typed with commas (``--zone 40%,60% --to 120%``) the
    option takes the next words for its other values (``--to``), and the command is refused for
    a stray argument or a missing ``-o``, which says nothing of the option. ``parse``: checks
    and converts the values once they are known to be spaced.

    >>> spaced("--zone", "START END")(("40%", "60%"))
    ('40%', '60%')
    >>> spaced("--zone", "START END")(("40%,60%", "--to"))
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: --zone: expected START END separated by spaces, got '40%,60%' '--to'
    """

    def check(value: tuple | None) -> Any:
        from ..errors import InputError

        if value is None:
            return None
        text = [str(v) for v in value]
        if any("," in v or (v.startswith("-") and v[1:2].isalpha()) for v in text):
            got = " ".join(repr(v) for v in text)
            raise InputError(f"{name}: expected {form} separated by spaces, got {got}")
        return value if parse is None else parse(value)

    return check


def _size_form(value: tuple[str, str, str]) -> tuple[str, str, str]:
    """The form of each extent of ``--size`` (the extent and the object's units are known once
    it is read)."""
    from ..edit import parse_size

    for axis, v in zip("xyz", value, strict=True):
        parse_size(v, extent=1e6, units="m", what=f"size {axis}")
    return value


#: ``--size``'s callback (``fit``, ``batch``).
check_size = spaced("--size", "three extents X Y Z (each =, 2.1, 210cm, +20cm or 120%)", _size_form)


#: ``--square`` of ``import``, ``scale``, ``fit`` and ``batch``: what it means (each adds how).
SQUARE_HELP = "Turn the mesh about up so its walls run along x and z"

#: The CSDF a command reads (``info``, ``segment``, ``export``, ``render``, ``editor``).
CsdfIn = Annotated[Path, typer.Argument(metavar="IN", help="A .csdf.npz file.")]

#: ``-o`` of the commands that write a CSDF (``import``, ``complete``, ``segment``).
CsdfOut = Annotated[
    Path, typer.Option("-o", "--output", metavar="OUT", help="Where to write: a .csdf.npz file.")
]


@contextlib.contextmanager
def progress_bar(description: str) -> Iterator[ProgressCallback]:
    """A rich progress bar on stderr, driven by the core's ``progress(fraction, message)``.

    Hidden when stderr is not a terminal, so pipes and CI logs stay clean.
    """
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TextColumn("{task.fields[stage]}"),
        TimeElapsedColumn(),
        console=stderr,
        transient=True,
        disable=not stderr.is_terminal,
    ) as bar:
        task = bar.add_task(description, total=1.0, stage="")

        def callback(fraction: float, message: str) -> None:
            bar.update(task, completed=fraction, stage=message)

        yield callback


def csdf_or_mesh(path: Path, res: int | None = None):
    """The CSDF a command reads: ``path`` itself, or a mesh imported at ``res`` (default: the
    import's, as ``fit`` finds a mesh's zones) with a progress bar, as ``partscale import``
    would."""
    from ..csdf import SUFFIX, load

    if path.name.lower().endswith(SUFFIX):
        return load(path)
    from ..errors import InputError
    from ..ingest import MESH_SUFFIXES
    from ..ingest import load as import_file

    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputError(
            f"{path}: expected a {SUFFIX} file or a mesh ({', '.join(MESH_SUFFIXES)}), got "
            f"{path.suffix or 'no suffix'}"
        )
    with progress_bar(f"import {path.name}") as bar:
        if res is None:
            return import_file(path, progress=bar)
        return import_file(path, res=res, progress=bar)


def done(message: str) -> None:
    """One line on stderr saying what was written."""
    stderr.print(message, highlight=False)


def check_output(path: Path, *, suffixes: tuple[str, ...], what: str) -> Path:
    """Validate an output path up front, before any work is done: its suffix, and that a file
    can be written there (an existing folder that accepts files, no directory in the way)."""
    from .._files import check_writable
    from ..errors import InputError

    name = path.name.lower()
    if not any(name.endswith(s) for s in suffixes):
        raise InputError(
            f"{path}: expected {what} ending in {' or '.join(suffixes)}, got {path.suffix or 'no suffix'}"
        )
    return check_writable(path)


MAX_LINE = 1000
"""Longest message line printed (a hostile value echoed in a message is cut, not dumped)."""


def error_line(message: str, *, kind: str = "error") -> None:
    """Print one unwrapped line on stderr (rich would wrap it at the terminal width)."""
    first = " ".join(str(message).split())
    if len(first) > MAX_LINE:
        first = first[: MAX_LINE - 3] + "..."
    sys.stderr.write(f"partscale: {kind}: {first}\n")
    sys.stderr.flush()


def is_verbose() -> bool:
    return state["verbose"] or "-v" in sys.argv or "--verbose" in sys.argv
