"""Running the editor: bind (loopback unless told otherwise), print the URL, open a browser."""

from __future__ import annotations

import ipaddress
import socket
import sys
import webbrowser
from collections.abc import Callable
from pathlib import Path

from .._options import keyword_options
from ..errors import InputError


def is_loopback(host: str) -> bool:
    """True for ``localhost`` and loopback addresses (127.0.0.0/8, ::1)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def url_host(host: str) -> str:
    """The host as the printed URL names it: a wildcard as 127.0.0.1, IPv6 in brackets."""
    shown = "127.0.0.1" if host in ("0.0.0.0", "::", "[::]") else host
    return f"[{shown}]" if ":" in shown and not shown.startswith("[") else shown


def allowed_hosts(host: str) -> list[str]:
    """Host headers the app accepts when bound to ``host``: loopback names and the URL's host.

    Any for a non-loopback ``host`` (the caller asked to expose the editor). For loopback,
    :data:`~partscale.serve.app.LOOPBACK_HOSTS` plus the host as the printed URL spells it
    (``127.0.0.2``, ``[0:0:0:0:0:0:0:1]``), so the URL shown always answers.
    """
    from .app import LOOPBACK_HOSTS

    if not is_loopback(host):
        return ["*"]
    shown = url_host(host).lower()
    return LOOPBACK_HOSTS + ([shown] if shown not in LOOPBACK_HOSTS else [])


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
) -> None:
    """Serve the editor for ``path`` until interrupted (Ctrl-C).

    Parameters
    ----------
    path : path
        The ``.csdf.npz`` to edit.
    host : str
        Interface to bind; loopback by default. Any other address exposes the editor (and
        save/export) to the network, so the caller must have asked for it explicitly.
    port : int
        0 picks a free port.
    open_browser : bool
        Open the page in the default browser (else only print the URL).
    announce : callable(str), optional
        Where the URL and warnings go (default: stderr).
    """
    import uvicorn

    from .app import create_app

    say = announce or (lambda m: print(m, file=sys.stderr, flush=True))
    if not (0 <= port <= 65535):
        raise InputError(f"--port: expected 0..65535, got {port}")
    loopback = is_loopback(host)
    app = create_app(path, allowed_hosts=allowed_hosts(host))
    try:
        port = _free_port(host) if port == 0 else _check_port(host, port)
    except OSError as exc:
        what = (
            "--host: expected an address of this machine"
            if port == 0
            else "--port: expected a free port"
        )
        raise InputError(f"{what}, got {host}:{port} ({exc.strerror or exc})") from None
    if not loopback:
        say(
            f"warning: serving on {host}, not loopback: anyone who can reach this machine can "
            "view, edit and save this object"
        )
    url = f"http://{url_host(host)}:{port}/"
    say(f"partscale editor for {Path(path).name}: {url}  (Ctrl-C to stop)")
    config = uvicorn.Config(app, host=host.strip("[]"), port=port, log_level="warning")
    server = uvicorn.Server(config)
    if open_browser:
        original_startup = server.startup

        async def startup(sockets=None):
            await original_startup(sockets=sockets)
            webbrowser.open(url)

        server.startup = startup  # type: ignore[method-assign]  # open the page once listening
    server.run()
