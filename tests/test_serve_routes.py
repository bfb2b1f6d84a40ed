"""The editor app's steps, each on its own: the host policy (hosts.py), what every route shares
(handling.py: errors as statuses, the JSON body), the request readers and route classes
(routes.py), the page read once and the app assembled from them (app.py). The routes' behaviour
through HTTP is tests/test_serve.py's.
"""

from __future__ import annotations

import asyncio
import doctest
import threading

import pytest
from starlette.requests import Request
from starlette.routing import Route

from partscale import shapes
from partscale.errors import InputError, MemoryLimitError
from partscale.serve import app as app_mod
from partscale.serve import handling, hosts, routes
from partscale.serve.handling import HTTPError
from partscale.serve.session import PageLimits


@pytest.mark.parametrize("module", [hosts, handling, routes], ids=lambda m: m.__name__)
def test_the_step_modules_examples_run(module, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


# -- hosts ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("raw", "want"),
    [
        ("127.0.0.1:8000", ("127.0.0.1", 8000)),
        ("LOCALHOST.", ("localhost", None)),
        ("127.000.000.001:80", ("127.0.0.1", 80)),
        ("[0:0::1]:9", ("[::1]", 9)),
        ("127.0.0.1:80x", ("", None)),  # junk after the port: no host
        ("[::1]junk", ("", None)),
    ],
)
def test_split_host_reads_a_host_header_as_browsers_spell_it(raw, want):
    assert hosts.split_host(raw) == want


@pytest.mark.parametrize(
    ("origin", "same"),
    [
        ("http://127.0.0.1:8000", True),
        ("http://127.1:8000/", True),  # another spelling of the same address
        ("https://127.0.0.1:8000", False),  # another scheme
        ("http://127.0.0.1:8001", False),  # another port
        ("http://127.0.0.1:8000/x", False),  # a path: no origin
        ("http://evil.example:8000", False),
        ("null", False),
    ],
)
def test_same_origin_is_this_servers_own_page_only(origin, same):
    assert hosts.same_origin(origin, "127.0.0.1", 8000) is same


def test_allowed_hosts_are_the_loopback_names_and_the_one_started_with():
    assert hosts.allowed_hosts("127.0.0.1") == hosts.LOOPBACK_HOSTS
    assert hosts.allowed_hosts("LOCALHOST") == hosts.LOOPBACK_HOSTS  # no second spelling
    assert hosts.allowed_hosts("::1") == hosts.LOOPBACK_HOSTS
    assert hosts.allowed_hosts("10.1.2.3") == [*hosts.LOOPBACK_HOSTS, "10.1.2.3"]
    wild = hosts.allowed_hosts("0.0.0.0")
    assert wild[:3] == hosts.LOOPBACK_HOSTS and "0.0.0.0" not in wild


# -- handling ---------------------------------------------------------------------------------


def _raise(exc: BaseException):
    raise exc


@pytest.mark.parametrize(
    ("exc", "status", "words"),
    [
        (InputError("zone: expected 0 < start, got -1"), 400, "zone: expected"),
        (MemoryLimitError("apply: needs 90 GiB"), 413, "needs 90 GiB"),
        (MemoryError(), 413, "apply: out of memory"),
        (ZeroDivisionError("oops"), 500, "apply failed inside partscale: ZeroDivisionError"),
    ],
)
def test_run_maps_the_librarys_errors_to_statuses(exc, status, words, capsys):
    with pytest.raises(HTTPError) as info:
        asyncio.run(handling.run("apply", _raise, exc))
    assert info.value.status == status and words in str(info.value)
    if status == 500:  # a bug: its traceback stays on the server's stderr
        assert "ZeroDivisionError" in capsys.readouterr().err


def test_run_returns_the_result_without_numpys_warnings():
    import numpy as np

    got = asyncio.run(handling.run("x", lambda a: np.float64(1.0) / a, np.float64(0.0)))
    assert got == np.inf  # filterwarnings=error: a warning would have failed this


def _request(body: bytes, ctype: str | None) -> Request:
    headers = [(b"content-type", ctype.encode())] if ctype else []
    sent = False

    async def receive():
        nonlocal sent
        if sent:
            return {"type": "http.disconnect"}
        sent = True
        return {"type": "http.request", "body": body, "more_body": False}

    scope = {"type": "http", "method": "POST", "headers": headers, "path": "/", "query_string": b""}
    return Request(scope, receive)


def test_json_body_needs_json_and_reads_it_once():
    assert asyncio.run(handling.json_body(_request(b'{"a": [1, 2]}', "application/json"))) == {
        "a": [1, 2]
    }
    assert asyncio.run(handling.json_body(_request(b"", "application/json; charset=utf-8"))) == {}
    with pytest.raises(HTTPError) as info:
        asyncio.run(handling.json_body(_request(b"{}", "text/plain")))
    assert info.value.status == 415 and "got 'text/plain'" in str(info.value)
    with pytest.raises(HTTPError) as info:
        asyncio.run(handling.json_body(_request(b'{"a": NaN}', "application/json")))
    assert info.value.status == 400


# -- request readers --------------------------------------------------------------------------


def _refused(fn, *args) -> str:
    with pytest.raises(HTTPError) as info:
        fn(*args)
    assert info.value.status == 400
    return str(info.value)


def test_parse_axes_and_base():
    assert routes.parse_axes("z", "elements") == ["z"]
    assert routes.parse_axes(None, "elements") == ["x", "y", "z"]
    assert _refused(routes.parse_axes, "w", "elements") == (
        "elements.axis: expected x, y or z, got 'w'"
    )
    assert routes.parse_base(None, "grid") is None
    assert routes.parse_base("17", "grid") == 17
    for bad in ("-1", "1.5", "٣", "9" * 16):
        assert _refused(routes.parse_base, bad, "parts").startswith("parts.base: expected")


def test_parse_fit_add_and_save():
    assert routes.parse_fit({"size": ["+20cm", "=", 0.5]}) == (["+20cm", "=", 0.5], False)
    assert routes.parse_fit({"size": [1, 2, 3], "allow_deform": True}) == ([1, 2, 3], True)
    for bad in ({"size": [1, 2]}, {"size": [1, 2, True]}, {"size": [1, 2, 3], "x": 1}, [1, 2, 3]):
        assert _refused(routes.parse_fit, bad).startswith('fit: expected {"size"')
    # the editor reads yes/no as the command line, manifests and the library do (one check)
    assert _refused(routes.parse_fit, {"size": [1, 2, 3], "allow_deform": 1}) == (
        "fit.allow_deform: expected true or false, got 1"
    )

    assert routes.parse_add({"axis": "y", "n": -2}) == ("y", -2)
    assert _refused(routes.parse_add, {"axis": "y"}).startswith("add: expected")
    assert _refused(routes.parse_add, {"axis": "w", "n": 1}).startswith("add.axis")
    for n in (0, True, 1.0, routes.MAX_ADD + 1, -routes.MAX_ADD - 1):
        assert _refused(routes.parse_add, {"axis": "x", "n": n}).startswith("add.n")
    assert routes.parse_add({"axis": "x", "n": -routes.MAX_ADD}) == ("x", -routes.MAX_ADD)

    assert routes.parse_save({}) == (False, None)
    assert routes.parse_save({"overwrite": True, "revision": 3}) == (True, 3)
    assert _refused(routes.parse_save, {"path": "/etc"}).startswith("save: expected")
    assert _refused(routes.parse_save, {"overwrite": "yes"}) == (
        "save.overwrite: expected true or false, got 'yes'"
    )
    assert _refused(routes.parse_save, {"revision": True}).startswith("save.revision")


def test_split_limits_takes_the_pages_limits_out_of_the_recipe():
    recipe = {"version": 1, "edits": []}
    assert routes.split_limits(recipe) == (recipe, None)
    body = {**recipe, "limits": {"max_voxels_per_axis": 256}}
    got, limits = routes.split_limits(body)
    assert got == recipe and limits == PageLimits(max_voxels_per_axis=256)
    assert "limits" in body  # the request's body is left as it came
    for bad, got in ((-1, "-1"), (1.5, "1.5"), (True, "True"), (2**53 + 1, str(2**53 + 1))):
        assert _refused(routes.split_limits, {**recipe, "limits": {"max_voxels": bad}}) == (
            f"limits.max_voxels: expected an integer in [2, {2**53}], got {got}"
        )
    assert routes.split_limits({"limits": {"max_voxels": 2**53}})[1] == PageLimits(max_voxels=2**53)


# -- state the routes keep --------------------------------------------------------------------


def test_progress_is_busy_until_the_last_apply_in_flight_ends():
    p = routes.Progress()
    assert p.snapshot() == {"fraction": 1.0, "message": "", "busy": False}
    first_in, second_done, release = threading.Event(), threading.Event(), threading.Event()

    def first():
        with p.applying():
            first_in.set()
            release.wait(10)

    t = threading.Thread(target=first)
    t.start()
    assert first_in.wait(10)
    assert p.snapshot() == {"fraction": 0.0, "message": "applying", "busy": True}
    with p.applying():  # a second one waiting: starting it does not reset the first's progress
        p.report(0.25, "stretch x")
    second_done.set()
    assert p.snapshot() == {"fraction": 0.25, "message": "stretch x", "busy": True}
    release.set()
    t.join(10)
    assert p.snapshot() == {"fraction": 1.0, "message": "", "busy": False}


def test_found_per_axis_finds_once_per_object_and_axis_and_keeps_the_last_few():
    calls: list[tuple[int, str]] = []
    found = routes.FoundPerAxis(lambda c, ax: calls.append((id(c), ax)) or ax.upper(), keep=2)
    a = shapes.box((0, 0, 0), (1, 1, 1), voxel_size=0.25)
    b = a.replace(meta={"units": "m"})
    assert [found(a, "x"), found(a, "x"), found(b, "x"), found(a, "x")] == ["X"] * 4
    assert calls == [(id(a), "x"), (id(b), "x")]
    found(a, "y")  # a third entry: (a, x), the oldest, goes
    found(a, "x")
    assert calls[-1] == (id(a), "x") and len(calls) == 4


# -- the app assembled ------------------------------------------------------------------------


def test_read_page_reads_the_index_and_the_assets_it_can_serve(tmp_path):
    with pytest.raises(InputError, match="expected the built editor page"):
        app_mod.read_page(tmp_path)
    (tmp_path / "index.html").write_text("<!doctype html>")
    (tmp_path / "assets").mkdir()
    (tmp_path / "assets" / "main.js").write_text("x")
    (tmp_path / "assets" / "notes.txt").write_text("not a page asset")
    (tmp_path / "assets" / "sub").mkdir()
    page, assets = app_mod.read_page(tmp_path)
    assert page == b"<!doctype html>"
    assert assets == {"main.js": (b"x", routes.MEDIA[".js"])}


def test_create_app_assembles_the_documented_routes_and_nothing_else(tmp_path):
    from partscale import save

    path = save(shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1), tmp_path / "b.csdf.npz")
    app = app_mod.create_app(path)
    got = {(r.path, tuple(sorted(r.methods or ()))) for r in app.routes if isinstance(r, Route)}
    get, post = ("GET", "HEAD"), ("POST",)
    want = {("/", get), ("/index.html", get), ("/assets/{name}", get)}
    want |= {(f"/api/{n}", get) for n in ("state", "grid", "parts", "schema", "progress")}
    want |= {(f"/api/{n}", get) for n in ("suggest", "elements", "export/mesh", "export/texture")}
    want |= {(f"/api/{n}", post) for n in ("snap", "fit", "add", "apply", "undo", "redo", "save")}
    assert got == want
    assert len(app.routes) == len(want)
    for p, _ in want:  # and the module's table documents each of them
        assert p.replace("{name}", "NAME") in (app_mod.__doc__ or ""), p
