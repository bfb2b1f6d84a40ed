"""The editor's HTTP API (starlette): the page's assets, the one object, apply/undo/redo, save.

Routes (nothing else is served; no route reads a path, a file name or an object id from the
request):

==========================  ==================================================================
GET  /, /index.html         the page
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
(Origin), whatever address the server is bound to (:class:`HostGuard`, applying the host policy
of :mod:`partscale.serve.hosts`).

Each route is a method of :class:`~partscale.serve.routes.EditorRoutes` or
:class:`~partscale.serve.routes.ZoneRoutes` (the zones routes); :func:`create_app` assembles them.
"""

from __future__ import annotations

from pathlib import Path

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.responses import Response
from starlette.types import ASGIApp, Receive, Scope, Send

from ..errors import InputError
from .handling import HTTPError, error, http_error
from .hosts import LOOPBACK_HOSTS, canonical_host, same_origin, split_host
from .routes import MEDIA, EditorRoutes, ZoneRoutes
from .session import EditSession

STATIC = Path(__file__).parent / "static"
#: Largest request body accepted (a recipe is a few hundred bytes).
MAX_BODY = 64 * 1024


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
    :func:`~partscale.serve.hosts.canonical_host` spells them: ``LOCALHOST`` is
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
        host, port = split_host(raw)
        if host not in self.hosts:
            shown = raw if len(raw) <= 60 else raw[:57] + "..."
            await error(f"host: expected one of {sorted(self.hosts)}, got {shown!r}")(
                scope, receive, send
            )
            return
        origin = headers.get(b"origin")
        if origin is not None and scope.get("method", "GET") not in ("GET", "HEAD"):
            text = origin.decode("latin-1")
            if not same_origin(text, host, port):
                shown = text if len(text) <= 60 else text[:57] + "..."
                await error(
                    f"origin: expected this editor's page (http://{raw}), got {shown!r}", 403
                )(scope, receive, send)
                return
        await self.app(scope, receive, send)


def _too_large(limit: int) -> Response:
    return error(f"request body: expected at most {limit} bytes, got more", 413)


def read_page(static: Path = STATIC) -> tuple[bytes, dict[str, tuple[bytes, str]]]:
    """The built page, read once: ``index.html``'s bytes and every asset under ``assets/``
    (file name -> (bytes, media type)); the page can only ever get these bytes.

    Raises
    ------
    InputError
        There is no built page (``index.html``) in ``static``.
    """
    index = static / "index.html"
    if not index.is_file():
        raise InputError(f"{static}: expected the built editor page (index.html), got none")
    table: dict[str, tuple[bytes, str]] = {}
    assets = static / "assets"
    if assets.is_dir():
        for f in sorted(assets.iterdir()):
            if f.is_file() and f.suffix in MEDIA:
                table[f.name] = (f.read_bytes(), MEDIA[f.suffix])
    return index.read_bytes(), table


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
        with (:func:`~partscale.serve.hosts.allowed_hosts`). There is no wildcard.
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
    page, assets = read_page()
    editor = EditorRoutes(session, page, assets)
    routes = [*editor.table(), *ZoneRoutes(session).table()]
    hosts = LOOPBACK_HOSTS if allowed_hosts is None else allowed_hosts
    middleware = [
        Middleware(LimitBody, limit=max_body),
        Middleware(HostGuard, hosts=hosts),
    ]
    # starlette types every handler as taking Exception, though it calls one only for its class
    handlers = {HTTPError: http_error}
    app = Starlette(
        routes=routes,
        middleware=middleware,
        exception_handlers=handlers,  # type: ignore[arg-type]
    )
    app.state.session = session
    return app
