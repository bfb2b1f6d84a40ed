"""Running the editor: bind (loopback unless told otherwise), print the URL, open a browser."""

from __future__ import annotations

import socket
import sys
import webbrowser
from collections.abc import Callable
from pathlib import Path

from .._options import keyword_options
from ..errors import InputError
from .hosts import allowed_hosts, canonical_host, is_loopback, is_wildcard, url_host


def _free_port(host: str) -> int:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.bind((host.strip("[]"), 0))
        return int(s.getsockname()[1])


def _check_port(host: str, port: int) -> int:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        # as uvicorn binds: a port left in TIME_WAIT by a previous run is free to reuse
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind((host.strip("[]"), port))
    return port


@keyword_options
def serve(
    path: str | Path,
    *,
    host: str = "127.0.0.1",
    port: int = 0,
    open_browser: bool = True,
    announce: Callable[[str], None] | None = None,
    expose: bool = False,
) -> None:
    """Serve the editor for ``path`` until interrupted (Ctrl-C).

    Parameters
    ----------
    path : path
        The ``.csdf.npz`` to edit.
    host : str
        Interface to bind; loopback by default. Any other address (``""`` and ``0.0.0.0``:
        every interface) exposes the editor (and save/export) to the network, and is refused
        unless ``expose`` says the caller means it. Whatever it is, requests are answered only
        for the names in :func:`allowed_hosts`.
    port : int
        0 picks a free port.
    open_browser : bool
        Open the page in the default browser (else only print the URL).
    announce : callable(str), optional
        Where the URL and warnings go (default: stderr).
    expose : bool
        Allow a ``host`` beyond loopback (reachable from other machines).

    Returns
    -------
    None
        Once the server has stopped.

    Raises
    ------
    InputError
        A file that is not a CSDF, a port out of range or taken, or a host that is not an
        address of this machine.

    Examples
    --------
    >>> from partscale import save, shapes
    >>> from partscale.serve import serve
    >>> path = save(shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1), "box.csdf.npz")
    >>> serve("box.csdf.npz", port=8000)  # doctest: +SKIP
    partscale editor for box.csdf.npz: http://127.0.0.1:8000/  (Ctrl-C to stop)
    >>> serve("box.csdf.npz", port=70000)
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: port: expected 0..65535, got 70000
    """
    import uvicorn

    from .app import create_app

    say = announce or (lambda m: print(m, file=sys.stderr, flush=True))
    if not (0 <= port <= 65535):
        raise InputError(f"port: expected 0..65535, got {port}")
    if not isinstance(host, str):
        raise InputError(f"host: expected an address or a name, got {type(host).__name__}")
    given, host = host, host.strip() or "0.0.0.0"  # what a socket binds for "": everywhere
    loopback = is_loopback(host)
    if not loopback and expose is not True:
        raise InputError(
            f"host: expected a loopback address (127.0.0.1, localhost, ::1) unless exposing the "
            f"editor, got {given!r}, {_reach(host)}: add expose to mean it",
            params=("expose",),
        )
    hosts = allowed_hosts(host)
    app = create_app(path, allowed_hosts=hosts)
    bind = canonical_host(host)  # 127.000.000.001 is 127.0.0.1 to a browser: bind that
    try:
        port = _free_port(bind) if port == 0 else _check_port(bind, port)
    except OSError as exc:
        what = (
            "host: expected an address of this machine"
            if port == 0
            else "port: expected a free port"
        )
        raise InputError(f"{what}, got {host}:{port} ({exc.strerror or exc})") from None
    if not loopback:
        say(
            f"warning: serving on {host}, not loopback: {_reach(host)} (Host names answered: "
            f"{', '.join(hosts)})"
        )
    url = f"http://{url_host(host)}:{port}/"
    say(f"partscale editor for {Path(path).name}: {url}  (Ctrl-C to stop)")
    config = uvicorn.Config(app, host=bind.strip("[]"), port=port, log_level="warning")
    server = uvicorn.Server(config)
    if open_browser:
        original_startup = server.startup

        async def startup(sockets=None):
            await original_startup(sockets=sockets)
            webbrowser.open(url)

        server.startup = startup  # type: ignore[method-assign]  # open the page once listening
    server.run()


def _reach(host: str) -> str:
    """What binding ``host`` (not loopback) exposes, for the refusal and the warning."""
    where = "every interface of this machine" if is_wildcard(host) else f"the interface {host}"
    return (
        f"which binds {where}: anyone who can reach it, and any web page opened on a machine "
        "that can, can reach this editor and view, edit and save this object"
    )
