"""What every route of the editor's API shares: JSON errors, the JSON body, library calls run in
the thread pool with their errors mapped to HTTP statuses, and the download header.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable
from typing import Any, TypeVar
from urllib.parse import quote

from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import JSONResponse, Response

from .._files import parse_json
from ..errors import InputError, MemoryLimitError

T = TypeVar("T")

#: Every API answer is about the object as it is now: never cached.
NO_STORE = {"Cache-Control": "no-store"}


class HTTPError(Exception):
    """Ends a request with a JSON ``{"error": message}`` and ``status`` (see :func:`http_error`).

    Examples
    --------
    >>> from partscale.serve.handling import HTTPError
    >>> HTTPError(409, "undo: expected an edit to undo, got none").status
    409
    """

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


def error(message: str, status: int = 400) -> JSONResponse:
    """The JSON answer ``{"error": message}`` with ``status``, never cached."""
    return JSONResponse({"error": message}, status_code=status, headers=NO_STORE)


async def http_error(request: Request, exc: HTTPError) -> Response:
    """The app's handler of :class:`HTTPError`: its message and status as :func:`error`."""
    return error(str(exc), exc.status)


def content_disposition(name: str) -> str:
    r"""``attachment`` header for ``name`` (RFC 6266): an ASCII fallback and the UTF-8 name.

    Headers are Latin-1 on the wire, and a ``"`` or ``\`` would end or escape the quoted
    string: the fallback replaces those and anything outside printable ASCII with ``_``;
    ``filename*`` (RFC 5987) carries the exact name percent-encoded.

    Examples
    --------
    >>> from partscale.serve.handling import content_disposition
    >>> content_disposition('tä"ble.glb')
    'attachment; filename="t__ble.glb"; filename*=UTF-8\'\'t%C3%A4%22ble.glb'
    """
    fallback = "".join(c if " " <= c <= "~" and c not in '"\\' else "_" for c in name)
    return f"attachment; filename=\"{fallback}\"; filename*=UTF-8''{quote(name, safe='')}"


async def json_body(request: Request) -> Any:
    """The request's JSON body (``{}`` when empty); the app's body limit bounds its size.

    Raises
    ------
    HTTPError
        415 unless the Content-Type is ``application/json``; 400 for a body that is no JSON
        or is beyond the reader's depth, size or number limits.
    """
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if ctype != "application/json":
        raise HTTPError(415, f"request: expected Content-Type application/json, got {ctype!r}")
    body = await request.body()
    if not body:
        return {}
    try:  # the one hardened reader: depth, size and number limits, no NaN/Infinity
        return parse_json(body, what="request body")
    except InputError as exc:
        raise HTTPError(400, str(exc)) from None


def checked(check: Callable[..., T], *args: Any) -> T:
    """``check(*args)``, one of the shared option checks (:mod:`partscale._options`), its
    InputError the request's fault.

    Raises
    ------
    HTTPError
        400 with the check's one line (the option, what was expected, what came).

    Examples
    --------
    >>> from partscale._options import yes_no
    >>> from partscale.serve.handling import checked
    >>> checked(yes_no, True, "save.overwrite")
    True
    >>> checked(yes_no, "yes", "save.overwrite")
    Traceback (most recent call last):
    ...
    partscale.serve.handling.HTTPError: save.overwrite: expected true or false, got 'yes'
    """
    try:
        return check(*args)
    except InputError as exc:
        raise HTTPError(400, str(exc)) from None


def _quiet(fn: Callable[..., T], *args: Any) -> T:
    """``fn(*args)`` without numpy's floating-point warnings on the server's stderr (inputs
    are validated first; a request never learns of them).
    """
    import numpy as np

    with np.errstate(all="ignore"):
        return fn(*args)


async def run(what: str, fn: Callable[..., T], *args: Any) -> T:
    """``fn(*args)`` in the thread pool, its errors as HTTP statuses.

    An InputError is the request's fault (400); one the memory guard refused or that ran out
    of memory is too large (413, and the server goes on); anything else is a bug in partscale
    (500, traceback kept on the server's stderr). ``what`` names the request in the message.

    Raises
    ------
    HTTPError
        With the status above and one line saying why.
    """
    try:
        return await run_in_threadpool(_quiet, fn, *args)
    except MemoryLimitError as exc:
        raise HTTPError(413, str(exc)) from None
    except InputError as exc:
        raise HTTPError(400, str(exc)) from None
    except MemoryError:
        raise HTTPError(
            413, f"{what}: out of memory (the memory guard's estimate was too low)"
        ) from None
    except Exception as exc:
        traceback.print_exc()
        raise HTTPError(
            500, f"{what} failed inside partscale: {type(exc).__name__}: {exc}"
        ) from None
