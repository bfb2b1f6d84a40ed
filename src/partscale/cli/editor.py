"""``partscale editor``: the browser editor for one CSDF file (``partscale edit``, its old name,
still works)."""

from __future__ import annotations

from typing import Annotated

import typer

from . import _common


def editor(
    path: _common.CsdfIn,
    port: Annotated[
        int, typer.Option("--port", metavar="N", help="Port to serve on (0: any free one).")
    ] = 0,
    no_browser: Annotated[
        bool, typer.Option("--no-browser", help="Only print the URL; do not open a browser.")
    ] = False,
    host: Annotated[
        str,
        typer.Option(
            "--host",
            metavar="HOST",
            help="Interface to bind: loopback unless --expose.",
        ),
    ] = "127.0.0.1",
    expose: Annotated[
        bool,
        typer.Option(
            "--expose",
            help="Allow a --host beyond loopback (0.0.0.0: every interface): anyone who can "
            "reach this machine can then view, edit and save the object.",
        ),
    ] = False,
) -> None:
    """Open the object in the browser editor: drag zone planes, preview, apply, undo, save.

    Edits are written only when you press Save: to NAME.edited.csdf.npz, or over the input when
    you tick overwrite.
    """
    from ..serve import serve

    serve(path, host=host, port=port, open_browser=not no_browser, expose=expose)
