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
from .edit import edit
from .export import export
from .import_ import import_
from .info import info
from .render import render
from .scale import scale

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


app.command("info")(info)
app.command("scale")(scale)
app.command("export")(export)
app.command("render")(render)
app.command("import")(import_)
app.command("edit")(edit)


def main(argv: list[str] | None = None) -> None:
    """Entry point of the console script."""
    try:
        app(args=argv, standalone_mode=False)
    except InputError as exc:
        if _common.is_verbose():
            raise
        _common.error_line(str(exc))
        sys.exit(2)
    except typer.Exit as exc:
        sys.exit(exc.exit_code)
    except typer.Abort:
        _common.stderr.print("partscale: aborted", highlight=False)
        sys.exit(130)
    except Exception as exc:  # click usage errors come through here in non-standalone mode
        import click

        if isinstance(exc, click.exceptions.ClickException):
            exc.show(file=sys.stderr)
            sys.exit(2)
        if isinstance(exc, click.exceptions.Exit):
            sys.exit(exc.exit_code)
        raise
