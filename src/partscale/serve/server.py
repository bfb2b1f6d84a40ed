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


def canonical_host(name: str) -> str:
    """``name`` as a browser puts it in a Host header: how two spellings are compared.

    Lower case without a trailing dot; IPv4 in any form browsers accept (``127.000.000.001``,
    ``127.1``, ``0x7f.0.0.1``) as a dotted quad; IPv6 compressed, in brackets.

    Parameters
    ----------
    name : str
        A host name or address, as typed or as a Host header holds it (without a port).

    Returns
    -------
    str
        The one spelling of it that :func:`allowed_hosts` and the Host guard compare.

    Examples
    --------
    >>> from partscale.serve import canonical_host
    >>> canonical_host("127.1"), canonical_host("0x7f.0.0.1"), canonical_host("LOCALHOST.")
    ('127.0.0.1', '127.0.0.1', 'localhost')
    >>> canonical_host("[0:0::1]")
    '[::1]'
    """
    n = name.strip().lower().rstrip(".")
    inner = n[1:-1] if n.startswith("[") and n.endswith("]") else n
    if ":" in inner:
        try:
            return f"[{ipaddress.IPv6Address(inner).compressed}]"
        except ValueError:
            return n
    if inner and all(c in "0123456789abcdefx." for c in inner) and inner[0].isdigit():
        try:  # the WHATWG URL parser reads IPv4 as inet_aton does (octal, hex, short forms)
            return socket.inet_ntoa(socket.inet_aton(inner))
        except OSError:
            return n
    return n


def is_loopback(host: str) -> bool:
    """True for ``localhost`` and loopback addresses (127.0.0.0/8, ::1), in any spelling.

    Parameters
    ----------
    host : str
        A host name or address (:func:`canonical_host` reads its spelling).

    Returns
    -------
    bool
        Whether only this machine reaches it.

    Examples
    --------
    >>> from partscale.serve import is_loopback
    >>> is_loopback("127.0.0.2"), is_loopback("[::1]"), is_loopback("192.168.1.5")
    (True, True, False)
    """
    c = canonical_host(host)
    if c == "localhost":
        return True
    try:
        return ipaddress.ip_address(c.strip("[]")).is_loopback
    except ValueError:
        return False


def is_wildcard(host: str) -> bool:
    """True for an address that binds every interface (``0.0.0.0``, ``::``)."""
    return canonical_host(host) in ("0.0.0.0", "[::]")


def url_host(host: str) -> str:
    """The host as the printed URL names it: a wildcard as 127.0.0.1, IPv6 in brackets."""
    return "127.0.0.1" if is_wildcard(host) else canonical_host(host)


def _this_machine() -> list[str]:
    # what a wildcard bind is reached by from elsewhere: this machine's name and its addresses
    names = {socket.gethostname(), socket.getfqdn()}
    try:
        infos = socket.getaddrinfo(socket.gethostname(), None, proto=socket.IPPROTO_TCP)
    except OSError:
        infos = []
    names |= {str(info[4][0]) for info in infos}
    return sorted(canonical_host(n) for n in names if n)


def allowed_hosts(host: str) -> list[str]:
    """Host header values the app answers when bound to ``host`` (the DNS-rebinding guard).

    Always :data:`~partscale.serve.app.LOOPBACK_HOSTS` plus the host the server was started
    with, as the printed URL spells it (``127.0.0.2``, ``[::1]``, ``192.168.1.5``,
    ``myhost``); for a wildcard bind (``0.0.0.0``, ``::``) this machine's name and addresses
    instead. Never any name: a page on another domain that rebinds it here is refused.

    Parameters
    ----------
    host : str
        The interface the server binds (``serve``'s ``host``).

    Returns
    -------
    list of str
        Host names in :func:`canonical_host`'s spelling, the loopback ones first.

    Examples
    --------
    >>> from partscale.serve import allowed_hosts
    >>> allowed_hosts("127.0.0.1")
    ['127.0.0.1', 'localhost', '[::1]']
    >>> allowed_hosts("192.168.1.5")
    ['127.0.0.1', 'localhost', '[::1]', '192.168.1.5']
    """
    from .app import LOOPBACK_HOSTS

    names = list(LOOPBACK_HOSTS)
    extra = _this_machine() if is_wildcard(host) else [url_host(host)]
    names += [n for n in extra if n not in names]
    return names


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
