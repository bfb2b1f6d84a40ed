"""The editor's host policy: which names the server answers to, spelt one way.

A browser sends the name it was asked to open in the Host header, and its page's origin in the
Origin header; the editor answers only its own names (DNS rebinding: a page of another domain
that resolves its name to this machine is refused) and takes changes only from its own page.
This module decides what those names are and how two spellings compare; the ASGI guard that
applies it is :class:`partscale.serve.app.HostGuard`, the server that binds them
:func:`partscale.serve.serve`.
"""

from __future__ import annotations

import ipaddress
import socket
from urllib.parse import urlsplit

#: Host header values every editor answers, whatever it is bound to.
LOOPBACK_HOSTS = ["127.0.0.1", "localhost", "[::1]"]


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

    Always :data:`LOOPBACK_HOSTS` plus the host the server was started with, as the printed
    URL spells it (``127.0.0.2``, ``[::1]``, ``192.168.1.5``, ``myhost``); for a wildcard bind
    (``0.0.0.0``, ``::``) this machine's name and addresses instead. Never any name: a page on
    another domain that rebinds it here is refused.

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
    names = list(LOOPBACK_HOSTS)
    extra = _this_machine() if is_wildcard(host) else [url_host(host)]
    names += [n for n in extra if n not in names]
    return names


def split_host(raw: str) -> tuple[str, int | None]:
    """``(canonical host, port or None)`` of a Host header value (``[::1]:8000`` read whole).

    Anything after the name but a port makes the host ``""``, which no host list holds.

    Examples
    --------
    >>> from partscale.serve.hosts import split_host
    >>> split_host("LOCALHOST:8000"), split_host("[0::1]"), split_host("127.1:80x")
    (('localhost', 8000), ('[::1]', None), ('', None))
    """
    raw = raw.strip()
    if raw.startswith("["):
        end = raw.find("]") + 1
        name, rest = raw[:end], raw[end:]
    else:
        name, _, rest = raw.partition(":")
        rest = ":" + rest if rest else ""
    port = None
    if rest.startswith(":") and rest[1:].isdigit():
        port = int(rest[1:])
    elif rest:
        return "", None  # junk after the name: matches no host
    return canonical_host(name), port


def same_origin(origin: str, host: str, port: int | None) -> bool:
    """Whether an Origin header value is ``http://host:port`` (the port 80 when absent).

    ``host`` and ``port`` as :func:`split_host` reads the Host header; a path, a query, a
    fragment or another scheme in the origin never matches.

    Examples
    --------
    >>> from partscale.serve.hosts import same_origin
    >>> same_origin("http://127.0.0.1:8000", "127.0.0.1", 8000)
    True
    >>> same_origin("http://evil.example:8000", "127.0.0.1", 8000)
    False
    """
    parts = urlsplit(origin)
    if parts.scheme != "http" or parts.path not in ("", "/") or parts.query or parts.fragment:
        return False
    o_host, o_port = split_host(parts.netloc)
    return o_host == host and (o_port or 80) == (port or 80)
