"""The ``partscale`` command: thin typer commands over the library's public functions.

Each subcommand lives in its own module and is registered here. Errors a user can cause
(:class:`partscale.errors.InputError`) print one line and exit with code 2; ``-v`` shows the
traceback.
"""

from __future__ import annotations

import sys
from typing import Annotated

import typer

from ..errors import InputError
from . import _common
from .batch import batch, optional_values
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
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


@app.callback()
def _root(
    verbose: Annotated[
        bool, typer.Option("-v", "--verbose", help="Show tracebacks on errors.")
    ] = False,
) -> None:
    _common.state["verbose"] = verbose


# In pipeline order, which is the order `partscale --help` lists them.
app.command("import")(import_)
app.command("info")(info)
app.command("segment")(segment)
app.command("suggest")(suggest)
app.command("scale")(scale)
app.command("fit")(fit)
app.command("export")(export)
app.command("render")(render)
app.command("editor")(editor)
# the editor's first name, kept working; hidden since `edit` reads as the resizing stage
app.command("edit", hidden=True)(editor)
app.command("eval")(eval_suite)
app.command("batch")(batch)


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


def main(argv: list[str] | None = None) -> None:
    """Entry point of the console script: one line and exit 2 for every user error."""
    mods = _click_modules()
    usage_errors = tuple(m.ClickException for m in mods)
    exits = tuple(m.Exit for m in mods if hasattr(m, "Exit"))
    aborts = tuple(m.Abort for m in mods if hasattr(m, "Abort"))
    try:
        # Outside standalone mode click returns a command's exit code instead of exiting.
        args = optional_values(list(sys.argv[1:] if argv is None else argv))
        code = app(args=args, standalone_mode=False)
    except InputError as exc:
        if _common.is_verbose():
            raise
        _common.error_line(str(exc))
        sys.exit(2)
    except typer.Exit as exc:
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
        sys.exit(getattr(exc, "exit_code", 0))
    except (typer.Abort, *aborts):
        _common.error_line("aborted")
        sys.exit(130)
    if isinstance(code, int) and code:
        sys.exit(code)
