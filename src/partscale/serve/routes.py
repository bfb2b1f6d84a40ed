"""The editor's routes, each a method over the app's state: the session's object and history
(:class:`EditorRoutes`) and the zone finders on it (:class:`ZoneRoutes`); what a request body
must hold is read by the ``parse_*`` functions, which answer 400 with one line otherwise.

The table of routes and what each answers is in :mod:`partscale.serve.app`.
"""

from __future__ import annotations

import hashlib
import threading
import time
from collections.abc import Callable
from contextlib import contextmanager
from typing import Any

from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Route

from .. import zones
from .._options import yes_no
from ..edit import JSON_SCHEMA, Edit
from ..errors import InputError
from .handling import (
    NO_STORE,
    HTTPError,
    checked,
    content_disposition,
    error,
    json_body,
    run,
)
from .session import EditSession, PageLimits

#: Most elements one /api/add adds or removes (the page asks for one; its GPU limits the rest).
MAX_ADD = 100
#: Media types of the page's files, by suffix.
MEDIA = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json",
    ".svg": "image/svg+xml",
    ".png": "image/png",
}
#: The page loads only its own assets and talks only to this server; no other site may frame it
#: (a framed editor could be clicked into saving over the input).
PAGE_HEADERS = {
    "Content-Security-Policy": (
        "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; "
        "connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'none'"
    ),
    "X-Frame-Options": "DENY",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    **NO_STORE,
}
_AXES = ("x", "y", "z")


# -- request bodies and query parameters --------------------------------------------------------


def parse_axes(raw: str | None, what: str) -> list[str]:
    """``?axis=``: one axis, or all three when absent.

    Examples
    --------
    >>> from partscale.serve.routes import parse_axes
    >>> parse_axes("y", "suggest"), parse_axes(None, "suggest")
    (['y'], ['x', 'y', 'z'])
    """
    if raw is None:
        return list(_AXES)
    if raw not in _AXES:
        raise HTTPError(400, f"{what}.axis: expected x, y or z, got {raw[:20]!r}")
    return [raw]


def parse_base(raw: str | None, what: str) -> int | None:
    """``?base=N`` of the grid and parts routes: a revision number (None when absent)."""
    if raw is None:
        return None
    if not (raw.isascii() and raw.isdigit() and len(raw) <= 15):
        raise HTTPError(400, f"{what}.base: expected a revision number, got {raw[:20]!r}")
    return int(raw)


def parse_fit(body: Any) -> tuple[list, bool]:
    """``{"size": [X, Y, Z], "allow_deform": false}`` of /api/fit: ``(size, allow_deform)``.

    Each size is a string, an int or a float (``"="``, ``2.1``, ``"210cm"``, ``"+20cm"``,
    ``"120%"``); what the strings mean is :func:`partscale.zones.fit`'s to read.
    """
    keys = set(body) if isinstance(body, dict) else set()
    size = body.get("size") if "size" in keys and keys <= {"size", "allow_deform"} else None
    if not (
        isinstance(size, list)
        and len(size) == 3
        and all(isinstance(v, str | int | float) and not isinstance(v, bool) for v in size)
    ):
        raise HTTPError(
            400,
            'fit: expected {"size": [X, Y, Z], "allow_deform": false} (each "=", 2.1, '
            f'"210cm", "+20cm", "120%"), got {str(body)[:80]!r}',
        )
    return size, checked(yes_no, body.get("allow_deform", False), "fit.allow_deform")


def parse_add(body: Any) -> tuple[str, int]:
    """``{"axis": "x", "n": 1}`` of /api/add: ``(axis, n)``, n whole, not 0, at most
    :data:`MAX_ADD` either way.
    """
    if not isinstance(body, dict) or set(body) != {"axis", "n"}:
        raise HTTPError(
            400,
            f'add: expected {{"axis": "x", "n": 1}} (n elements more, or -n fewer), got '
            f"{str(body)[:80]!r}",
        )
    axis, n = body["axis"], body["n"]
    if axis not in _AXES:
        raise HTTPError(400, f"add.axis: expected x, y or z, got {str(axis)[:20]!r}")
    if isinstance(n, bool) or not isinstance(n, int) or n == 0 or abs(n) > MAX_ADD:
        raise HTTPError(
            400,
            f"add.n: expected a whole number of elements other than 0, at most {MAX_ADD} "
            f"either way, got {str(n)[:20]!r}",
        )
    return axis, n


def parse_save(body: Any) -> tuple[bool, int | None]:
    """``{"overwrite": bool, "revision": N}`` of /api/save (both optional):
    ``(overwrite, revision or None)``.
    """
    if not isinstance(body, dict) or set(body) - {"overwrite", "revision"}:
        raise HTTPError(
            400,
            f"save: expected {{'overwrite': true|false, 'revision': N}}, got {str(body)[:80]!r}",
        )
    overwrite = checked(yes_no, body.get("overwrite", False), "save.overwrite")
    revision = body.get("revision")
    if revision is not None and (isinstance(revision, bool) or not isinstance(revision, int)):
        raise HTTPError(400, f"save.revision: expected an integer, got {str(revision)[:40]!r}")
    return overwrite, revision


def split_limits(body: Any) -> tuple[Any, PageLimits | None]:
    """/api/apply's body: ``(the recipe, the page's limits or None)``, the ``limits`` key taken
    out of the recipe (:class:`~partscale.serve.session.PageLimits`).
    """
    if not (isinstance(body, dict) and "limits" in body):
        return body, None
    recipe = dict(body)
    try:
        return recipe, PageLimits.parse(recipe.pop("limits"))
    except InputError as exc:
        raise HTTPError(400, str(exc)) from None


# -- the applies' progress --------------------------------------------------------------------


class Progress:
    """What /api/progress reports: the fraction and message of the apply in flight, and whether
    one is (busy until the last of the applies running or waiting for the session ends).

    Examples
    --------
    >>> from partscale.serve.routes import Progress
    >>> p = Progress()
    >>> with p.applying():
    ...     p.report(0.5, "stretch")
    ...     p.snapshot()
    {'fraction': 0.5, 'message': 'stretch', 'busy': True}
    >>> p.snapshot()
    {'fraction': 1.0, 'message': '', 'busy': False}
    """

    def __init__(self) -> None:
        self.fraction, self.message, self.in_flight = 1.0, "", 0
        self.lock = threading.Lock()  # applies run in worker threads

    def snapshot(self) -> dict[str, Any]:
        """``{"fraction", "message", "busy"}`` now."""
        with self.lock:
            return {"fraction": self.fraction, "message": self.message, "busy": self.in_flight > 0}

    def report(self, fraction: float, message: str) -> None:
        """The progress callback an apply reports through."""
        with self.lock:
            self.fraction, self.message = float(fraction), str(message)

    @contextmanager
    def applying(self):
        """One apply in flight for the ``with`` block (the first starts at 0, the last ends at 1)."""
        with self.lock:
            self.in_flight += 1
            if self.in_flight == 1:
                self.fraction, self.message = 0.0, "applying"
        try:
            yield self
        finally:
            with self.lock:
                self.in_flight -= 1
                if self.in_flight == 0:
                    self.fraction, self.message = 1.0, ""


# -- the object, its history and its files ----------------------------------------------------


class EditorRoutes:
    """The page, its assets and the routes over the session's object: state, grid, parts,
    schema, progress, apply, undo, redo, save and export.

    Parameters
    ----------
    session : EditSession
        The one object and its history.
    page : bytes
        The built ``index.html``.
    assets : dict
        Asset file name -> (its bytes, its media type): all the page can ever get.
    """

    def __init__(self, session: EditSession, page: bytes, assets: dict[str, tuple[bytes, str]]):
        self.session, self.page_bytes, self.assets = session, page, assets
        self.progress_state = Progress()

    def state(self, body: dict[str, Any] | None = None, **extra: Any) -> JSONResponse:
        """The session's state as JSON (``body``: one built under the session lock by the
        request's own step, apply, undo...), with ``extra`` keys.
        """
        body = dict(self.session.state() if body is None else body)
        body.update(extra)
        return JSONResponse(body, headers=NO_STORE)

    async def page(self, request: Request) -> Response:
        """GET / and /index.html."""
        return Response(self.page_bytes, media_type=MEDIA[".html"], headers=PAGE_HEADERS)

    async def asset(self, request: Request) -> Response:
        """GET /assets/NAME: one of the assets read when the app was made, else 404."""
        hit = self.assets.get(request.path_params["name"])
        if hit is None:
            return error("not found", 404)
        data, media = hit
        etag = hashlib.sha1(data).hexdigest()[:16]
        return Response(data, media_type=media, headers={"ETag": etag, **PAGE_HEADERS})

    async def get_state(self, request: Request) -> Response:
        """GET /api/state."""
        return self.state()

    async def encoded(self, request: Request, kind: str) -> Response:
        """GET /api/grid or /api/parts (``kind``), whole or since ``?base=N``."""
        base = parse_base(request.query_params.get("base"), kind)
        # the headers describe the CSDF that was encoded, not whatever is current by now
        e = await run_in_threadpool(self.session.encoded, kind, base)
        headers = {
            "X-Partscale-Shape": ",".join(map(str, e.csdf.shape)),
            "X-Partscale-Revision": str(e.revision),
            **NO_STORE,
        }
        if e.delta is not None:
            headers["X-Partscale-Delta"] = e.delta.header()
        return Response(e.data, media_type="application/octet-stream", headers=headers)

    async def grid(self, request: Request) -> Response:
        """GET /api/grid."""
        return await self.encoded(request, "grid")

    async def parts(self, request: Request) -> Response:
        """GET /api/parts."""
        return await self.encoded(request, "parts")

    async def schema(self, request: Request) -> Response:
        """GET /api/schema."""
        return JSONResponse(JSON_SCHEMA)

    async def progress(self, request: Request) -> Response:
        """GET /api/progress."""
        return JSONResponse(self.progress_state.snapshot(), headers=NO_STORE)

    def _apply(self, recipe: Any, limits: PageLimits | None) -> tuple[dict[str, Any], float]:
        t0 = time.perf_counter()
        with self.progress_state.applying():
            after = self.session.apply(recipe, limits=limits, progress=self.progress_state.report)
        return after, (time.perf_counter() - t0) * 1000.0

    async def apply(self, request: Request) -> Response:
        """POST /api/apply: the recipe (and the page's limits) applied; the new state."""
        recipe, limits = split_limits(await json_body(request))
        after, ms = await run("apply", self._apply, recipe, limits)
        return self.state(after, apply_ms=ms)

    async def _history(self, request: Request, step: Callable, what: str, missing: str):
        await json_body(request)
        after = await run_in_threadpool(step)
        if after is None:
            return error(f"{what}: expected {missing}, got none", 409)
        return self.state(after)

    async def undo(self, request: Request) -> Response:
        """POST /api/undo: the new state, or 409 with nothing to undo."""
        return await self._history(request, self.session.undo, "undo", "an edit to undo")

    async def redo(self, request: Request) -> Response:
        """POST /api/redo: the new state, or 409 with nothing to redo."""
        return await self._history(request, self.session.redo, "redo", "an undone edit to redo")

    async def save(self, request: Request) -> Response:
        """POST /api/save: the object written beside the input (or over it); the state with
        ``saved``, the file's name.
        """
        overwrite, revision = parse_save(await json_body(request))
        written = await run(
            "save", lambda: self.session.save(overwrite=overwrite, revision=revision)
        )
        return self.state(saved=written.name)

    async def export(self, kind: str) -> Response:
        """The current object as a download: ``kind`` is ``mesh`` (GLB) or ``texture``."""
        data, name, media = await run("export", self.session.export, kind)
        return Response(
            data,
            media_type=media,
            headers={"Content-Disposition": content_disposition(name), **NO_STORE},
        )

    async def export_mesh(self, request: Request) -> Response:
        """GET /api/export/mesh."""
        return await self.export("mesh")

    async def export_texture(self, request: Request) -> Response:
        """GET /api/export/texture."""
        return await self.export("texture")

    def table(self) -> list[Route]:
        """The routes, in the order they are matched."""
        return [
            Route("/", self.page),
            Route("/index.html", self.page),
            Route("/assets/{name}", self.asset),
            Route("/api/state", self.get_state),
            Route("/api/grid", self.grid),
            Route("/api/parts", self.parts),
            Route("/api/schema", self.schema),
            Route("/api/progress", self.progress),
            Route("/api/apply", self.apply, methods=["POST"]),
            Route("/api/undo", self.undo, methods=["POST"]),
            Route("/api/redo", self.redo, methods=["POST"]),
            Route("/api/save", self.save, methods=["POST"]),
            Route("/api/export/mesh", self.export_mesh),
            Route("/api/export/texture", self.export_texture),
        ]


# -- the zone finders on the object -----------------------------------------------------------


class FoundPerAxis:
    """``fn(csdf, axis)`` kept for the last few (object, axis) pairs: what a zones function found
    on the editor's object (seconds at 256³) is found once per object and axis. The object is
    held with its entry, so its id is not reused while the entry is.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.serve.routes import FoundPerAxis
    >>> calls = []
    >>> found = FoundPerAxis(lambda c, ax: calls.append(ax) or len(calls))
    >>> c = shapes.box((0, 0, 0), (1, 1, 1), voxel_size=0.25)
    >>> found(c, "x"), found(c, "x"), found(c, "y"), calls
    (1, 1, 2, ['x', 'y'])
    """

    def __init__(self, fn: Callable[[Any, str], Any], keep: int = 9):
        self.fn, self.keep = fn, keep
        self.found: dict[tuple[int, str], tuple[Any, Any]] = {}
        self.lock = threading.Lock()  # the routes asking run in worker threads

    def __call__(self, c: Any, ax: str) -> Any:
        """What ``fn(c, ax)`` returned, found now or kept from before."""
        with self.lock:
            hit = self.found.get((id(c), ax))
        if hit is None:
            hit = (c, self.fn(c, ax))
            with self.lock:
                self.found[(id(c), ax)] = hit
                while len(self.found) > self.keep:
                    del self.found[next(iter(self.found))]
        return hit[1]


class ZoneRoutes:
    """The routes over :mod:`partscale.zones` on the session's current object (thin layers):
    ``/api/suggest``, ``/api/snap``, ``/api/elements``, ``/api/fit`` and ``/api/add``; what
    suggest, find_elements and warp_candidates found is kept per object and axis.
    """

    def __init__(self, session: EditSession):
        self.session = session
        self.candidates = FoundPerAxis(lambda c, ax: zones.suggest(c, ax))
        self.found_elements = FoundPerAxis(lambda c, ax: zones.find_elements(c, ax))
        self.warps = FoundPerAxis(lambda c, _: zones.warp_candidates(c), keep=3)

    def _suggest(self, axes: list[str]) -> list[dict]:
        c = self.session.current
        out = [k.to_json() for ax in axes for k in self.candidates(c, ax)]
        return sorted(out, key=lambda k: -k["score"])

    def _warps(self) -> dict[str, Any]:
        return self.warps(self.session.current, "warps").to_json()

    async def suggest(self, request: Request) -> Response:
        """GET /api/suggest[?axis=]: the candidates, best first; for all axes the warps too."""
        axis = request.query_params.get("axis")
        found = await run("suggest", self._suggest, parse_axes(axis, "suggest"))
        body: dict[str, Any] = {"candidates": found}
        if axis is None:  # all axes: and the zones that are no slab across one
            body.update(await run("suggest", self._warps))
        return JSONResponse(body, headers=NO_STORE)

    def _snap(self, body: Any) -> dict[str, Any]:
        c = self.session.current
        edit = Edit.parse(body)
        # the candidates /api/suggest found (or finds now, for both): computed once per object
        cands = None if edit.mode == "global" else self.candidates(c, edit.axis)
        edit, moves = zones.snap(c, edit, candidates=cands)
        return {
            "edit": edit.to_json(),
            "moves": [m.to_json() for m in moves],
            "message": zones.describe_moves(moves, c.meta.get("units")),
        }

    async def snap(self, request: Request) -> Response:
        """POST /api/snap: the edit snapped for its mode, and the moves."""
        body = await json_body(request)
        return JSONResponse(await run("snap", self._snap, body), headers=NO_STORE)

    def _elements(self, axes: list[str]) -> list[dict]:
        c = self.session.current
        out = []
        for ax in axes:
            found_ax = self.found_elements(c, ax)
            out.append({**found_ax.to_json(), "summary": zones.element_phrase(found_ax)})
        return out

    async def elements(self, request: Request) -> Response:
        """GET /api/elements[?axis=]: the elements per axis."""
        axes = parse_axes(request.query_params.get("axis"), "elements")
        return JSONResponse({"axes": await run("elements", self._elements, axes)}, headers=NO_STORE)

    def _fit(self, size: Any = None, allow_deform: bool = False, add: Any = None) -> dict:
        recipe, why = zones.fit(self.session.current, size, allow_deform=allow_deform, add=add)
        return {"recipe": recipe.to_json(), "why": why}

    async def fit(self, request: Request) -> Response:
        """POST /api/fit: the recipe fitting the size, and why (not applied)."""
        size, allow = parse_fit(await json_body(request))
        return JSONResponse(await run("fit", self._fit, size, allow), headers=NO_STORE)

    async def add(self, request: Request) -> Response:
        """POST /api/add: the recipe adding (or removing) whole elements, and why (not applied)."""
        axis, n = parse_add(await json_body(request))
        return JSONResponse(await run("add", self._fit, None, False, {axis: n}), headers=NO_STORE)

    def table(self) -> list[Route]:
        """The routes, in the order they are matched."""
        return [
            Route("/api/suggest", self.suggest),
            Route("/api/snap", self.snap, methods=["POST"]),
            Route("/api/elements", self.elements),
            Route("/api/fit", self.fit, methods=["POST"]),
            Route("/api/add", self.add, methods=["POST"]),
        ]
