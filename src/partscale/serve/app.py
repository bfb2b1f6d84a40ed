"""The editor's HTTP API (starlette): the page's assets, the one object, apply/undo/redo, save.

Routes (nothing else is served; no route reads a path, a file name or an object id from the
request):

==========================  ==================================================================
GET  /                      the page
GET  /assets/NAME           one of the built assets listed when the app was created
GET  /api/state             JSON header: shape, origin, voxel size, bounds, parts, history...
GET  /api/grid              binary 3D textures, see :func:`partscale.serve.session.encode_grid`;
                            ``?base=N``: only what changed since revision N (see below)
GET  /api/parts             binary int16 part indices, C order (z fastest); ``?base=N`` too
GET  /api/schema            the recipe JSON schema
GET  /api/progress          progress of the apply in flight
GET  /api/suggest           zone candidates of the current object (``?axis=x|y|z``: one axis);
                            for all axes also ``radial``, ``steps``, ``helix`` and
                            ``rotation``, the zones that are no slab across an axis, each
                            with its recipe ``edit``
                            (:meth:`~partscale.zones.WarpCandidates.to_json`)
GET  /api/elements          the current object's elements per axis, ``{"axes": [...]}`` (each
                            :meth:`~partscale.zones.AxisElements.to_json` with ``summary``, a
                            few words on its repeat group); ``?axis=x|y|z``: one axis
POST /api/snap              body: one recipe edit; the edit snapped for its mode and the moves
POST /api/fit               body: {"size": [X, Y, Z], "allow_deform": false}; the fitted recipe
                            and why (not applied); a size only a deformation reaches is refused
                            (400, one line naming the alternatives) unless allow_deform
POST /api/add               body: {"axis": "x", "n": 1}; the recipe adding n whole elements (n
                            < 0: removing them) and why (not applied), as ``fit --add``
POST /api/apply             body: recipe JSON, optionally with ``limits`` (what the page can
                            show, see :class:`~partscale.serve.session.PageLimits`; a result
                            beyond them is refused before computing); returns the new state
POST /api/undo, /api/redo   returns the new state
POST /api/save              body: {"overwrite": bool, "revision": N}; writes
                            NAME.edited.csdf.npz (or NAME); refused unless N (the revision the
                            page shows, optional) is the current one
GET  /api/export/mesh       GLB download; /api/export/texture: the 3D texture file
==========================  ==================================================================

Grid and parts deltas: both answers carry ``X-Partscale-Shape: X,Y,Z`` (the object encoded)
and ``X-Partscale-Revision: R`` (the revision that showed it; the page sends it back as
``?base=R`` on its next fetch). When the server still holds the base's object and the two differ
along one axis only, the answer adds ``X-Partscale-Delta: axis,head,tail`` and holds only the
layers ``head : shape[axis] - tail`` along that axis (the box encoded as the whole grid would
be); the first ``head`` layers are the base's first, the last ``tail`` the base's last
(:class:`~partscale.serve.session.GridDelta`). Without that header the body is the whole object.

POST bodies must be JSON (``Content-Type: application/json``): a page on another origin cannot
send that without a CORS preflight, which this server never grants. Every request must name this
server in its Host header, and a POST from a browser must come from this server's own page
(Origin), whatever address the server is bound to (:class:`HostGuard`).
"""

from __future__ import annotations

import hashlib
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar
from urllib.parse import quote, urlsplit

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Route
from starlette.types import ASGIApp, Receive, Scope, Send

from .. import zones
from .._files import parse_json
from ..edit import JSON_SCHEMA, Edit
from ..errors import InputError, MemoryLimitError
from .server import canonical_host
from .session import EditSession, PageLimits

T = TypeVar("T")
STATIC = Path(__file__).parent / "static"
#: Largest request body accepted (a recipe is a few hundred bytes).
MAX_BODY = 64 * 1024
LOOPBACK_HOSTS = ["127.0.0.1", "localhost", "[::1]"]
#: Most elements one /api/add adds or removes (the page asks for one; its GPU limits the rest).
MAX_ADD = 100

_MEDIA = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json",
    ".svg": "image/svg+xml",
    ".png": "image/png",
}
_NO_STORE = {"Cache-Control": "no-store"}
#: The page loads only its own assets and talks only to this server; no other site may frame it
#: (a framed editor could be clicked into saving over the input).
_PAGE_HEADERS = {
    "Content-Security-Policy": (
        "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; "
        "connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'none'"
    ),
    "X-Frame-Options": "DENY",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    **_NO_STORE,
}


class _BodyTooLarge(Exception):
    pass


class LimitBody:
    """ASGI middleware: 413 for a body over ``limit`` bytes, declared or streamed."""

    def __init__(self, app: ASGIApp, limit: int):
        self.app, self.limit = app, limit

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Pass the request on, or answer 413 once its body is over the limit."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        for name, value in scope.get("headers", []):
            if name == b"content-length":
                try:
                    declared = int(value)
                except ValueError:
                    declared = self.limit + 1
                if declared > self.limit:
                    await _too_large(self.limit)(scope, receive, send)
                    return
        seen = 0
        started = False

        async def counting_receive():
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.limit:
                    raise _BodyTooLarge
            return message

        async def tracking_send(message):
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, counting_receive, tracking_send)
        except _BodyTooLarge:
            if not started:
                await _too_large(self.limit)(scope, receive, send)


class HostGuard:
    """ASGI middleware: the DNS-rebinding and cross-site guard, on every request.

    400 unless the Host header names one of ``hosts`` (compared as
    :func:`~partscale.serve.server.canonical_host` spells them: ``LOCALHOST`` is
    ``localhost``, ``127.000.000.001`` is ``127.0.0.1``; bracketed IPv6 read whole). A request
    that can change something (any method but GET and HEAD) that carries an Origin header
    (browsers send one) gets 403 unless that origin is this server's own
    (``http://`` + the Host header): a page of another site never acts through the user's
    browser. No host list switches the guard off.
    """

    def __init__(self, app: ASGIApp, hosts: list[str]):
        self.app, self.hosts = app, {canonical_host(h) for h in hosts}

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Pass the request on, or answer 400 (host) or 403 (origin)."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = dict(scope.get("headers", []))
        raw = headers.get(b"host", b"").decode("latin-1")
        host, port = _split_host(raw)
        if host not in self.hosts:
            shown = raw if len(raw) <= 60 else raw[:57] + "..."
            await _error(f"host: expected one of {sorted(self.hosts)}, got {shown!r}")(
                scope, receive, send
            )
            return
        origin = headers.get(b"origin")
        if origin is not None and scope.get("method", "GET") not in ("GET", "HEAD"):
            text = origin.decode("latin-1")
            if not _same_origin(text, host, port):
                shown = text if len(text) <= 60 else text[:57] + "..."
                await _error(
                    f"origin: expected this editor's page (http://{raw}), got {shown!r}", 403
                )(scope, receive, send)
                return
        await self.app(scope, receive, send)


def _split_host(raw: str) -> tuple[str, int | None]:
    """``(canonical host, port or None)`` of a Host header value (``[::1]:8000`` read whole)."""
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


def _same_origin(origin: str, host: str, port: int | None) -> bool:
    parts = urlsplit(origin)
    if parts.scheme != "http" or parts.path not in ("", "/") or parts.query or parts.fragment:
        return False
    o_host, o_port = _split_host(parts.netloc)
    return o_host == host and (o_port or 80) == (port or 80)


def _too_large(limit: int) -> Response:
    return _error(f"request body: expected at most {limit} bytes, got more", 413)


def _error(message: str, status: int = 400) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status, headers=_NO_STORE)


def content_disposition(name: str) -> str:
    r"""``attachment`` header for ``name`` (RFC 6266): an ASCII fallback and the UTF-8 name.

    Headers are Latin-1 on the wire, and a ``"`` or ``\`` would end or escape the quoted
    string: the fallback replaces those and anything outside printable ASCII with ``_``;
    ``filename*`` (RFC 5987) carries the exact name percent-encoded.
    """
    fallback = "".join(c if " " <= c <= "~" and c not in '"\\' else "_" for c in name)
    return f"attachment; filename=\"{fallback}\"; filename*=UTF-8''{quote(name, safe='')}"


async def _json_body(request: Request) -> Any:
    """The request's JSON body (``{}`` when empty); :class:`LimitBody` bounds its size."""
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if ctype != "application/json":
        raise _HTTPError(415, f"request: expected Content-Type application/json, got {ctype!r}")
    body = await request.body()
    if not body:
        return {}
    try:  # the one hardened reader: depth, size and number limits, no NaN/Infinity
        return parse_json(body, what="request body")
    except InputError as exc:
        raise _HTTPError(400, str(exc)) from None


class _HTTPError(Exception):
    """Ends a request with a JSON ``{"error": message}`` and ``status`` (see ``_http_error``)."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


async def _http_error(request: Request, exc: _HTTPError) -> Response:
    return _error(str(exc), exc.status)


def _quiet(fn: Callable[..., T], *args: Any) -> T:
    """``fn(*args)`` without numpy's floating-point warnings on the server's stderr (inputs
    are validated first; a request never learns of them).
    """
    import numpy as np

    with np.errstate(all="ignore"):
        return fn(*args)


async def _run(what: str, fn: Callable[..., T], *args: Any) -> T:
    """``fn(*args)`` in the thread pool: an InputError is the request's fault (400), one the
    memory guard refused or that ran out of memory is too large (413, and the server goes on);
    anything else is a bug in partscale (500, traceback kept on the server's stderr).
    """
    try:
        return await run_in_threadpool(_quiet, fn, *args)
    except MemoryLimitError as exc:
        raise _HTTPError(413, str(exc)) from None
    except InputError as exc:
        raise _HTTPError(400, str(exc)) from None
    except MemoryError:
        raise _HTTPError(
            413, f"{what}: out of memory (the memory guard's estimate was too low)"
        ) from None
    except Exception as exc:
        traceback.print_exc()
        raise _HTTPError(
            500, f"{what} failed inside partscale: {type(exc).__name__}: {exc}"
        ) from None


def _asset_table() -> dict[str, tuple[bytes, str]]:
    """Every built asset, read once: the page can only ever get these bytes."""
    table: dict[str, tuple[bytes, str]] = {}
    assets = STATIC / "assets"
    if assets.is_dir():
        for f in sorted(assets.iterdir()):
            if f.is_file() and f.suffix in _MEDIA:
                table[f.name] = (f.read_bytes(), _MEDIA[f.suffix])
    return table


class _FoundPerAxis:
    """``fn(csdf, axis)`` kept for the last few (object, axis) pairs: what a zones function found
    on the editor's object (seconds at 256³) is found once per object and axis. The object is
    held with its entry, so its id is not reused while the entry is.
    """

    def __init__(self, fn: Callable[[Any, str], Any], keep: int = 9):
        self.fn, self.keep = fn, keep
        self.found: dict[tuple[int, str], tuple[Any, Any]] = {}
        self.lock = threading.Lock()  # the routes asking run in worker threads

    def __call__(self, c: Any, ax: str) -> Any:
        with self.lock:
            hit = self.found.get((id(c), ax))
        if hit is None:
            hit = (c, self.fn(c, ax))
            with self.lock:
                self.found[(id(c), ax)] = hit
                while len(self.found) > self.keep:
                    del self.found[next(iter(self.found))]
        return hit[1]


def _zone_routes(session: EditSession) -> list[Route]:
    """The routes over :mod:`partscale.zones` on the session's current object (thin layers):
    ``/api/suggest``, ``/api/snap``, ``/api/elements``, ``/api/fit`` and ``/api/add``.
    """
    # what suggest and find_elements found, per object and axis
    candidates = _FoundPerAxis(lambda c, ax: zones.suggest(c, ax))
    found_elements = _FoundPerAxis(lambda c, ax: zones.find_elements(c, ax))
    warps = _FoundPerAxis(lambda c, _: zones.warp_candidates(c), keep=3)

    def _suggest(axes: list[str]) -> list[dict]:
        c = session.current
        out = [k.to_json() for ax in axes for k in candidates(c, ax)]
        return sorted(out, key=lambda k: -k["score"])

    def _warps() -> dict[str, Any]:
        return warps(session.current, "warps").to_json()

    async def suggest(request: Request) -> Response:
        axis = request.query_params.get("axis")
        if axis is not None and axis not in ("x", "y", "z"):
            return _error(f"suggest.axis: expected x, y or z, got {axis[:20]!r}")
        found = await _run("suggest", _suggest, [axis] if axis else ["x", "y", "z"])
        body: dict[str, Any] = {"candidates": found}
        if axis is None:  # all axes: and the zones that are no slab across one
            body.update(await _run("suggest", _warps))
        return JSONResponse(body, headers=_NO_STORE)

    def _snap(body: Any) -> dict[str, Any]:
        c = session.current
        edit = Edit.parse(body)
        # the candidates /api/suggest found (or finds now, for both): computed once per object
        cands = None if edit.mode == "global" else candidates(c, edit.axis)
        edit, moves = zones.snap(c, edit, candidates=cands)
        return {
            "edit": edit.to_json(),
            "moves": [m.to_json() for m in moves],
            "message": zones.describe_moves(moves, c.meta.get("units")),
        }

    async def snap(request: Request) -> Response:
        body = await _json_body(request)
        return JSONResponse(await _run("snap", _snap, body), headers=_NO_STORE)

    def _elements(axes: list[str]) -> list[dict]:
        c = session.current
        out = []
        for ax in axes:
            found_ax = found_elements(c, ax)
            out.append({**found_ax.to_json(), "summary": zones.element_phrase(found_ax)})
        return out

    async def elements(request: Request) -> Response:
        axis = request.query_params.get("axis")
        if axis is not None and axis not in ("x", "y", "z"):
            return _error(f"elements.axis: expected x, y or z, got {axis[:20]!r}")
        found_axes = await _run("elements", _elements, [axis] if axis else ["x", "y", "z"])
        return JSONResponse({"axes": found_axes}, headers=_NO_STORE)

    def _fit(size: Any, allow_deform: bool) -> dict[str, Any]:
        recipe, why = zones.fit(session.current, size, allow_deform=allow_deform)
        return {"recipe": recipe.to_json(), "why": why}

    async def fit(request: Request) -> Response:
        body = await _json_body(request)
        keys = set(body) if isinstance(body, dict) else set()
        size = body.get("size") if "size" in keys and keys <= {"size", "allow_deform"} else None
        if not (
            isinstance(size, list)
            and len(size) == 3
            and all(isinstance(v, str | int | float) and not isinstance(v, bool) for v in size)
        ):
            return _error(
                'fit: expected {"size": [X, Y, Z], "allow_deform": false} (each "=", 2.1, '
                f'"210cm", "+20cm", "120%"), got {str(body)[:80]!r}'
            )
        allow = body.get("allow_deform", False)
        if not isinstance(allow, bool):
            return _error(f"fit.allow_deform: expected true or false, got {str(allow)[:40]!r}")
        return JSONResponse(await _run("fit", _fit, size, allow), headers=_NO_STORE)

    def _add(axis: str, n: int) -> dict[str, Any]:
        recipe, why = zones.fit(session.current, add={axis: n})
        return {"recipe": recipe.to_json(), "why": why}

    async def add(request: Request) -> Response:
        body = await _json_body(request)
        if not isinstance(body, dict) or set(body) != {"axis", "n"}:
            return _error(
                f'add: expected {{"axis": "x", "n": 1}} (n elements more, or -n fewer), got '
                f"{str(body)[:80]!r}"
            )
        axis, n = body["axis"], body["n"]
        if axis not in ("x", "y", "z"):
            return _error(f"add.axis: expected x, y or z, got {str(axis)[:20]!r}")
        if isinstance(n, bool) or not isinstance(n, int) or n == 0 or abs(n) > MAX_ADD:
            return _error(
                f"add.n: expected a whole number of elements other than 0, at most {MAX_ADD} "
                f"either way, got {str(n)[:20]!r}"
            )
        return JSONResponse(await _run("add", _add, axis, n), headers=_NO_STORE)

    return [
        Route("/api/suggest", suggest),
        Route("/api/snap", snap, methods=["POST"]),
        Route("/api/elements", elements),
        Route("/api/fit", fit, methods=["POST"]),
        Route("/api/add", add, methods=["POST"]),
    ]


def create_app(
    path: str | Path,
    *,
    allowed_hosts: list[str] | None = None,
    max_body: int = MAX_BODY,
) -> Starlette:
    """The editor's ASGI app for the one ``.csdf.npz`` at ``path``.

    Parameters
    ----------
    path : path
        The object to edit; loaded (and validated) now. Save writes ``NAME.edited.csdf.npz``
        beside it, or over it when the page asks to overwrite.
    allowed_hosts : list of str, optional
        Host header values accepted (guards against DNS rebinding), in any spelling a browser
        reads the same. Default: loopback names only; ``serve`` adds the names it was started
        with (:func:`~partscale.serve.server.allowed_hosts`). There is no wildcard.
    max_body : int
        Largest request body in bytes; larger ones get 413.

    Returns
    -------
    starlette.applications.Starlette
        The ASGI app: the page, its assets and the ``/api/...`` routes.

    Raises
    ------
    InputError
        ``path`` is not a readable ``.csdf.npz``.

    Notes
    -----
    ``app.state.session`` is the :class:`~partscale.serve.session.EditSession`.

    Examples
    --------
    With starlette's test client (a request must name an allowed host):

    >>> from starlette.testclient import TestClient
    >>> from partscale import save, shapes
    >>> from partscale.serve import create_app
    >>> path = save(shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1), "box.csdf.npz")
    >>> with TestClient(create_app("box.csdf.npz"), base_url="http://127.0.0.1") as client:
    ...     state = client.get("/api/state").json()
    ...     refused = client.get("/api/state", headers={"host": "evil.example"})
    >>> state["shape"], state["revision"], state["save_as"]
    ([17, 12, 12], 0, 'box.edited.csdf.npz')
    >>> refused.status_code
    400
    """
    session = EditSession.open(path)
    index = STATIC / "index.html"
    if not index.is_file():
        raise InputError(f"{STATIC}: expected the built editor page (index.html), got none")
    index_bytes = index.read_bytes()
    assets = _asset_table()
    progress_state: dict[str, Any] = {"fraction": 1.0, "message": ""}
    # applies in flight (running or waiting for the session lock): busy until the last ends
    in_flight = 0
    progress_lock = threading.Lock()

    def state(body: dict[str, Any] | None = None, **extra: Any) -> JSONResponse:
        # body: a state built under the session lock by the request's own step (apply, undo...)
        body = dict(session.state() if body is None else body)
        body.update(extra)
        return JSONResponse(body, headers=_NO_STORE)

    async def page(request: Request) -> Response:
        return Response(index_bytes, media_type=_MEDIA[".html"], headers=_PAGE_HEADERS)

    async def asset(request: Request) -> Response:
        hit = assets.get(request.path_params["name"])
        if hit is None:
            return _error("not found", 404)
        data, media = hit
        etag = hashlib.sha1(data).hexdigest()[:16]
        return Response(data, media_type=media, headers={"ETag": etag, **_PAGE_HEADERS})

    async def get_state(request: Request) -> Response:
        return state()

    def _encoded(kind: str):
        async def handler(request: Request) -> Response:
            raw = request.query_params.get("base")
            base = None
            if raw is not None:
                if not (raw.isascii() and raw.isdigit() and len(raw) <= 15):
                    return _error(f"{kind}.base: expected a revision number, got {raw[:20]!r}")
                base = int(raw)
            # the headers describe the CSDF that was encoded, not whatever is current by now
            e = await run_in_threadpool(session.encoded, kind, base)
            headers = {
                "X-Partscale-Shape": ",".join(map(str, e.csdf.shape)),
                "X-Partscale-Revision": str(e.revision),
                **_NO_STORE,
            }
            if e.delta is not None:
                headers["X-Partscale-Delta"] = e.delta.header()
            return Response(e.data, media_type="application/octet-stream", headers=headers)

        return handler

    grid, parts = _encoded("grid"), _encoded("parts")

    async def schema(request: Request) -> Response:
        return JSONResponse(JSON_SCHEMA)

    async def progress(request: Request) -> Response:
        with progress_lock:
            body = {**progress_state, "busy": in_flight > 0}
        return JSONResponse(body, headers=_NO_STORE)

    def _progress(fraction: float, message: str) -> None:
        with progress_lock:
            progress_state.update(fraction=float(fraction), message=str(message))

    def _apply(recipe: Any, limits: PageLimits | None) -> tuple[dict[str, Any], float]:
        nonlocal in_flight
        t0 = time.perf_counter()
        with progress_lock:
            in_flight += 1
            if in_flight == 1:
                progress_state.update(fraction=0.0, message="applying")
        try:
            after = session.apply(recipe, limits=limits, progress=_progress)
        finally:
            with progress_lock:
                in_flight -= 1
                if in_flight == 0:
                    progress_state.update(fraction=1.0, message="")
        return after, (time.perf_counter() - t0) * 1000.0

    async def apply(request: Request) -> Response:
        recipe = await _json_body(request)
        limits = None
        if isinstance(recipe, dict) and "limits" in recipe:  # what the page can show
            recipe = dict(recipe)
            try:
                limits = PageLimits.parse(recipe.pop("limits"))
            except InputError as exc:
                return _error(str(exc))
        after, ms = await _run("apply", _apply, recipe, limits)
        return state(after, apply_ms=ms)

    def history_step(step, what: str, missing: str):
        async def handler(request: Request) -> Response:
            await _json_body(request)
            after = await run_in_threadpool(step)
            if after is None:
                return _error(f"{what}: expected {missing}, got none", 409)
            return state(after)

        return handler

    undo = history_step(session.undo, "undo", "an edit to undo")
    redo = history_step(session.redo, "redo", "an undone edit to redo")

    async def save(request: Request) -> Response:
        body = await _json_body(request)
        if not isinstance(body, dict) or set(body) - {"overwrite", "revision"}:
            return _error(
                f"save: expected {{'overwrite': true|false, 'revision': N}}, got {str(body)[:80]!r}"
            )
        overwrite = body.get("overwrite", False)
        if not isinstance(overwrite, bool):
            return _error(f"save.overwrite: expected true or false, got {overwrite!r}")
        revision = body.get("revision")
        if revision is not None and (isinstance(revision, bool) or not isinstance(revision, int)):
            return _error(f"save.revision: expected an integer, got {str(revision)[:40]!r}")
        written = await _run("save", lambda: session.save(overwrite=overwrite, revision=revision))
        return state(saved=written.name)

    def _export(kind: str):
        async def handler(request: Request) -> Response:
            data, name, media = await _run("export", session.export, kind)
            return Response(
                data,
                media_type=media,
                headers={"Content-Disposition": content_disposition(name), **_NO_STORE},
            )

        return handler

    routes = [
        Route("/", page),
        Route("/index.html", page),
        Route("/assets/{name}", asset),
        Route("/api/state", get_state),
        Route("/api/grid", grid),
        Route("/api/parts", parts),
        Route("/api/schema", schema),
        Route("/api/progress", progress),
        *_zone_routes(session),
        Route("/api/apply", apply, methods=["POST"]),
        Route("/api/undo", undo, methods=["POST"]),
        Route("/api/redo", redo, methods=["POST"]),
        Route("/api/save", save, methods=["POST"]),
        Route("/api/export/mesh", _export("mesh")),
        Route("/api/export/texture", _export("texture")),
    ]
    hosts = LOOPBACK_HOSTS if allowed_hosts is None else allowed_hosts
    middleware = [
        Middleware(LimitBody, limit=max_body),
        Middleware(HostGuard, hosts=hosts),
    ]
    # starlette types every handler as taking Exception, though it calls one only for its class
    handlers = {_HTTPError: _http_error}
    app = Starlette(
        routes=routes,
        middleware=middleware,
        exception_handlers=handlers,  # type: ignore[arg-type]
    )
    app.state.session = session
    return app
