"""The ``partscale`` command: thin typer commands over the library's public functions.

Each subcommand lives in its own module and is registered here. Errors a user can cause
(:class:`partscale.errors.InputError`, and the operating system refusing a file or memory)
print one line and exit with code 2; ``-v`` shows the traceback. Warnings print as one line
each. SIGTERM stops a command like Ctrl-C: every temporary file is removed (exit 143).
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
import warnings
from collections.abc import Iterator
from typing import Annotated

import typer

from .. import _interrupt
from ..errors import InputError, PartscaleWarning, one_line
from . import _common, _help
from .batch import batch, optional_values
from .complete import complete
from .editor import editor
from .eval import eval_suite
from .export import export
from .fit import fit
from .import_ import import_
from .info import info
from .render import render
from .scale import scale
from .segment import segment
from .suggest import suggest

app = typer.Typer(
    name="partscale",
    help="Part-aware resizing of completed 3D objects as coloured signed distance fields.",
    cls=_help.Group,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
    epilog='Try it: partscale import "$(python -m partscale.data table)" -o table.csdf.npz '
    "(the table shipped with partscale); each command's --help ends with examples.",
)


def _version(value: bool) -> None:
    if value:
        from .. import __version__

        typer.echo(f"partscale {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    verbose: Annotated[
        bool, typer.Option("-v", "--verbose", help="Show tracebacks on errors.")
    ] = False,
    version: Annotated[
        bool,
        typer.Option(
            "--version", help="Print the version and exit.", callback=_version, is_eager=True
        ),
    ] = False,
) -> None:
    _common.state["verbose"] = verbose


# In pipeline order, which is the order `partscale --help` lists them.
_help.command(app, "import", import_)
_help.command(app, "complete", complete)
_help.command(app, "info", info)
_help.command(app, "segment", segment)
_help.command(app, "suggest", suggest)
_help.command(app, "scale", scale)
_help.command(app, "fit", fit)
_help.command(app, "export", export)
_help.command(app, "render", render)
_help.command(app, "editor", editor)
# the editor's first name, kept working; hidden since `edit` reads as the resizing stage
app.command("edit", hidden=True, cls=_help.Command, epilog=_help.epilog("editor"))(editor)
_help.command(app, "eval", eval_suite)
_help.command(app, "batch", batch)


def _click_modules() -> list:
    """click's exception modules: typer may vendor its own copy (``typer._click``) or use click."""
    import importlib

    mods = []
    for name in ("typer._click.exceptions", "click.exceptions"):
        try:
            mods.append(importlib.import_module(name))
        except ImportError:
            pass
    return mods


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is so that ``with`` blocks clean up (as for Ctrl-C)."""


@contextlib.contextmanager
def _terminate_cleanly() -> Iterator[dict]:
    """Turn SIGTERM into :class:`Terminated` and Ctrl-C into KeyboardInterrupt while a command
    runs (main thread only), each also noted (:mod:`partscale._interrupt`) so that a library
    that swallows the exception cannot make the command go on to write or exit 0.
    """
    seen = {"term": False}
    _interrupt.clear()
    if threading.current_thread() is not threading.main_thread():
        yield seen
        return

    def on_term(signum, frame):
        seen["term"] = True
        _interrupt.note(signum)
        raise Terminated()

    def on_int(signum, frame):
        _interrupt.note(signum)
        raise KeyboardInterrupt()

    previous = signal.signal(signal.SIGTERM, on_term)
    previous_int = signal.signal(signal.SIGINT, on_int)
    try:
        yield seen
    finally:
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)
        _interrupt.clear()  # the command has ended: its signals are not the caller's


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    kind = "note" if issubclass(category, PartscaleWarning) else "warning"
    _common.error_line(str(message), kind=kind)


@contextlib.contextmanager
def _one_line_warnings(verbose: bool = False) -> Iterator[None]:
    """Warnings print as one line each; partscale's own notes always show.

    numpy's floating-point warnings ("invalid value encountered in cast") say nothing a user
    can act on: inputs are validated before arithmetic and outputs checked for finiteness, so
    at this boundary they are silenced (with -v they show).
    """
    import numpy as np

    with warnings.catch_warnings(), np.errstate(all="warn" if verbose else "ignore"):
        warnings.filterwarnings("always", category=PartscaleWarning)
        warnings.showwarning = _show_warning
        yield


def main(argv: list[str] | None = None) -> None:
    """Entry point of the console script: one line and exit 2 for every user error."""
    from .. import reuse_freed_memory

    # every edit allocates whole new grids: at 256 and beyond, reusing the pages of the last
    # one instead of faulting in fresh ones halves the time (see reuse_freed_memory)
    reuse_freed_memory()
    words = list(sys.argv[1:] if argv is None else argv)
    _announce_first_compile(words)
    verbose = any(w in ("-v", "--verbose") for w in words)
    try:
        with _terminate_cleanly() as seen, _one_line_warnings(verbose):
            _main(argv, seen)
    finally:
        if argv is None:
            # the console script's process ends next: its exit need not walk every object the
            # libraries made (their teardown took 0.3-0.45 CPU seconds after an import at 256,
            # 0.05 with the objects frozen)
            import gc

            gc.freeze()


def _announce_first_compile(argv: list[str]) -> None:
    """On a terminal (as the progress bars), one line when a first compile starts."""
    if not _common.stderr.is_terminal:
        return
    from .. import _jit

    words = [a for a in argv if not a.startswith("-")]
    note = _jit.first_compile_note(words[0] if words else None)
    _jit.on_first_compile(
        lambda: _common.stderr.print(f"partscale: note: {note}", highlight=False, soft_wrap=True)
    )


def _main(argv: list[str] | None, seen: dict) -> None:
    mods = _click_modules()
    usage_errors = tuple(m.ClickException for m in mods)
    exits = tuple(m.Exit for m in mods if hasattr(m, "Exit"))
    aborts = tuple(m.Abort for m in mods if hasattr(m, "Abort"))
    args = _help.accept_deprecated(list(sys.argv[1:] if argv is None else argv))
    args = optional_values(args)
    try:
        # Outside standalone mode click returns a command's exit code instead of exiting.
        code = app(args=args, standalone_mode=False)
        _interrupt.raise_if_interrupted()  # a signal a library swallowed still ends it so
    except InputError as exc:
        if _common.is_verbose():
            raise
        _common.error_line(_help.in_cli_terms(exc, args))
        sys.exit(2)
    except OSError as exc:  # the system refused a file the command did not guard itself
        if _common.is_verbose():
            raise
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        _common.error_line(f"{where}{exc.strerror or one_line(exc)}")
        sys.exit(2)
    except MemoryError:
        if _common.is_verbose():
            raise
        _common.error_line("out of memory (the memory guard's estimate was too low)")
        sys.exit(2)
    except typer.Exit as exc:  # typer turns Ctrl-C (and so SIGTERM) into Exit(130)
        _exit_if_terminated(seen)
        sys.exit(exc.exit_code)
    except usage_errors as exc:
        if _common.is_verbose():
            raise
        if not exc.format_message().strip():  # bare command: click already printed the help
            sys.exit(exc.exit_code)
        ctx = getattr(exc, "ctx", None)
        where = f" ({ctx.command_path} --help for usage)" if ctx is not None else ""
        _common.error_line(f"{exc.format_message()}{where}")
        sys.exit(2)
    except exits as exc:
        _exit_if_terminated(seen)
        sys.exit(getattr(exc, "exit_code", 0))
    except (typer.Abort, *aborts, KeyboardInterrupt):
        _exit_if_terminated(seen)
        _common.error_line("aborted")
        sys.exit(130)
    if isinstance(code, int) and code:
        _exit_if_terminated(seen)  # click returns Ctrl-C's 130 outside standalone mode
        sys.exit(code)


def _exit_if_terminated(seen: dict) -> None:
    if seen["term"]:
        _common.error_line("terminated (SIGTERM); nothing half-written was left")
        sys.exit(143)
