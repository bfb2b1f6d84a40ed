"""The editor's server: one object, exact undo, save beside the input, nothing else served."""

from __future__ import annotations

import hashlib
import json
import os
import re
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import pytest
import trimesh
from starlette.testclient import TestClient

import partscale
from partscale import shapes
from partscale.segment import segment
from partscale.serve import (
    GRID_BYTES_PER_VOXEL,
    MAX_BODY,
    allowed_hosts,
    create_app,
    edited_path,
    encode_grid,
    encode_slab,
    is_loopback,
)
from partscale.serve import session as session_mod
from partscale.serve.app import STATIC

ROOT = Path(__file__).resolve().parents[1]
WEB = ROOT / "web"
H = 0.02
BOX = ((0.0, 0.0, 0.0), (1.0, 0.5, 0.4))


def source_hash() -> tuple[str, list[str]]:
    """Same file list and hashing as sourceHash() in web/vite.config.ts."""
    files = ["index.html", "vite.config.ts", "tsconfig.json"]
    files += [p.relative_to(WEB).as_posix() for p in (WEB / "src").rglob("*") if p.is_file()]
    files.sort()
    h = hashlib.sha256()
    for f in files:
        h.update(f.encode() + b"\0")
        h.update((WEB / f).read_bytes())
        h.update(b"\0")
    return h.hexdigest(), files


@pytest.fixture
def box_file(tmp_path: Path) -> Path:
    path = tmp_path / "box.csdf.npz"
    color = lambda p: np.stack(  # noqa: E731
        [np.full(len(p), 200), 255 * np.clip(p[:, 0], 0, 1), np.full(len(p), 60)], -1
    )
    partscale.save(
        shapes.grid(lambda p: shapes.box_sdf(p, *BOX), BOX, voxel_size=H, color=color), path
    )
    return path


@pytest.fixture
def client(box_file: Path):
    with TestClient(create_app(box_file), base_url="http://127.0.0.1") as c:
        yield c


def post(client: TestClient, url: str, body=None):
    return client.post(url, json={} if body is None else body)


STRETCH = {"edits": [{"axis": "x", "zone": [0.3, 0.7], "to": 0.9, "mode": "stretch"}]}


def glb_vertex_colours(mesh: trimesh.Trimesh) -> np.ndarray:
    """(V, 3) float in [0, 1]: COLOR_0 as trimesh loads it (beside a material it stays a vertex
    attribute, linear as glTF stores it; without one it becomes sRGB ``vertex_colors``)."""
    attrs = getattr(mesh.visual, "vertex_attributes", {})
    if "color" in attrs:
        return np.asarray(attrs["color"], dtype=float)[:, :3]
    assert mesh.visual.kind == "vertex", f"no vertex colours in the GLB ({mesh.visual.kind})"
    return np.asarray(mesh.visual.vertex_colors, dtype=float)[:, :3] / 255


# -- the built page ---------------------------------------------------------------------------
def test_built_page_is_current_with_its_sources():
    built = json.loads((STATIC / "build.json").read_text())
    digest, files = source_hash()
    assert built["files"] == files, "web/ files changed: run `npx vite build` in web/"
    assert built["source_hash"] == digest, "web/ sources changed: run `npx vite build` in web/"
    html = (STATIC / "index.html").read_text()
    for ref in re.findall(r'(?:src|href)="/assets/([^"]+)"', html):
        assert (STATIC / "assets" / ref).is_file(), ref


def test_page_and_its_assets_are_served(client):
    r = client.get("/")
    assert r.status_code == 200 and "text/html" in r.headers["content-type"]
    assert "frame-ancestors 'none'" in r.headers["content-security-policy"]
    refs = re.findall(r'(?:src|href)="(/assets/[^"]+)"', r.text)
    assert any(ref.endswith(".js") for ref in refs)
    for ref in refs:
        a = client.get(ref)
        assert a.status_code == 200 and a.content == (STATIC / ref.lstrip("/")).read_bytes()


# -- the object -------------------------------------------------------------------------------
def test_state_describes_the_object(client, box_file):
    c = partscale.load(box_file)
    s = client.get("/api/state").json()
    assert s["shape"] == list(c.shape)
    assert s["voxel_size"] == pytest.approx(H)
    np.testing.assert_allclose(s["origin"], c.origin)
    np.testing.assert_allclose(s["solid_bounds"], BOX, atol=1e-6)
    assert s["revision"] == 0 and not s["can_undo"] and not s["can_redo"]
    assert s["name"] == "box.csdf.npz" and s["save_as"] == "box.edited.csdf.npz"
    assert client.get("/api/schema").json()["title"] == "partscale recipe"


def split_grid(raw: bytes, shape) -> tuple[np.ndarray, np.ndarray]:
    """The two planes of encode_grid: (X, Y, Z) float16 distances, (X, Y, Z, 3) uint8 sRGB."""
    n = int(np.prod(shape))
    assert len(raw) == n * GRID_BYTES_PER_VOXEL == n * 5
    dist = np.frombuffer(raw, "<f2", count=n).reshape(shape)
    return dist, np.frombuffer(raw, np.uint8, offset=2 * n).reshape(*shape, 3)


def test_grid_is_half_distances_then_srgb_bytes_in_grid_order(client, box_file):
    c = partscale.load(box_file)
    X, Y, Z = c.shape
    r = client.get("/api/grid")
    assert r.headers["x-partscale-shape"] == f"{X},{Y},{Z}"
    assert r.headers["x-partscale-revision"] == "0" and "x-partscale-delta" not in r.headers
    assert client.get("/api/state").json()["encoding"]["version"] == 2  # web/src/api.ts
    dist, rgb = split_grid(r.content, c.shape)  # C order: index (i, j, k) = world x, y, z
    i, j, k = 7, 5, 3
    assert dist[i, j, k] == pytest.approx(c.sdf[i, j, k] / H, rel=1e-3, abs=1e-3)
    # every voxel, to float16 precision (relative 2^-11); the colour exactly as stored
    np.testing.assert_allclose(dist, c.sdf / H, rtol=1e-3, atol=1e-3)
    assert np.array_equal(rgb, c.rgb)
    parts = np.frombuffer(client.get("/api/parts").content, "<i2").reshape(X, Y, Z)
    assert (parts == -1).all()


def test_grid_encoding_is_numpys_float16_bit_for_bit():
    rng = np.random.default_rng(1)
    scale = 10.0 ** rng.integers(-9, 7, size=(8, 9, 10))
    sdf = rng.normal(size=(8, 9, 10)) * scale  # subnormal, normal and overflowing halves
    sdf.flat[:6] = [0.0, -0.0, 65504.0, 65520.0, 2.98e-8, -1e6]
    rgb = rng.integers(0, 256, size=(8, 9, 10, 3), dtype=np.uint8)
    c = partscale.make(sdf, rgb, voxel_size=1.0)
    raw = encode_grid(c)
    with np.errstate(over="ignore"):
        want = c.sdf.astype("<f2").view("<u2")
    assert np.array_equal(np.frombuffer(raw, "<u2", count=c.sdf.size).reshape(8, 9, 10), want)
    assert np.array_equal(split_grid(raw, c.shape)[1], rgb)
    # a slab is the same bytes as the whole grid cut to those layers, along any axis
    for axis in range(3):
        box = tuple(slice(2, 5) if a == axis else slice(None) for a in range(3))
        d, colour = split_grid(encode_slab(c, axis, 2, 5), want[box].shape)
        assert np.array_equal(d.view("<u2"), want[box]) and np.array_equal(colour, rgb[box])


def splice(base: np.ndarray, new_shape, delta: str, body: np.ndarray) -> np.ndarray:
    """What the page does with X-Partscale-Delta (web/src/grid.ts spliceLayers)."""
    axis, head, tail = map(int, delta.split(","))
    n, nb = new_shape[axis], base.shape[axis]
    out = np.empty(tuple(new_shape) + base.shape[3:], base.dtype)
    take = lambda a, lo, hi: a[(slice(None),) * axis + (slice(lo, hi),)]  # noqa: E731
    take(out, 0, head)[...] = take(base, 0, head)
    take(out, head, n - tail)[...] = body
    take(out, n - tail, n)[...] = take(base, nb - tail, nb)
    return out


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_grid_after_apply_and_undo_is_only_the_changed_layers(tmp_path, axis):
    path = tmp_path / "parts.csdf.npz"
    boxes = [((0, 0, 0), (0.3, 0.3, 0.3)), ((0.5, 0.4, 0.2), (0.9, 0.7, 0.6))]
    c = segment(
        shapes.grid(
            lambda p: shapes.boxes_sdf(p, boxes), ((0, 0, 0), (0.9, 0.7, 0.6)), voxel_size=H
        ),
        cache=False,
    )
    assert c.n_parts >= 2
    partscale.save(c, path)
    recipe = {"edits": [{"axis": axis, "zone": ["35%", "60%"], "to": "80%", "mode": "stretch"}]}
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        session = client.app.state.session
        # what the page holds: per kind, (revision, the whole decoded arrays)
        held = {"grid": (0, *split_grid(client.get("/api/grid").content, c.shape))}
        held["parts"] = (0, np.frombuffer(client.get("/api/parts").content, "<i2").reshape(c.shape))
        for step in ("apply", "undo", "redo"):
            r = post(client, f"/api/{step}", recipe if step == "apply" else None)
            assert r.status_code == 200, r.text
            want = session.current
            for kind, (base, *arrays) in held.items():
                r = client.get(f"/api/{kind}?base={base}")
                assert r.headers["x-partscale-revision"] == str(session.revision)
                shape = [int(v) for v in r.headers["x-partscale-shape"].split(",")]
                assert shape == list(want.shape)
                delta = r.headers["x-partscale-delta"]
                a, head, tail = map(int, delta.split(","))
                assert a == "xyz".index(axis)
                # the zone's layers and a little more are sent; the rest is the base's
                assert 0 < shape[a] - head - tail <= 0.6 * shape[a], (head, tail, shape)
                body_shape = list(shape)
                body_shape[a] -= head + tail
                if kind == "grid":
                    body = split_grid(r.content, body_shape)
                    got = [splice(x, shape, delta, y) for x, y in zip(arrays, body, strict=True)]
                    w_d, w_c = split_grid(encode_grid(want), want.shape)
                    assert np.array_equal(got[0].view("<u2"), w_d.view("<u2"))
                    assert np.array_equal(got[1], w_c)
                else:
                    body = np.frombuffer(r.content, "<i2").reshape(body_shape)
                    got = [splice(arrays[0], shape, delta, body)]
                    assert np.array_equal(got[0], want.parts)
                held[kind] = (session.revision, *got)
        # a base the session no longer knows, or none: the whole object
        for q in ("", "?base=9999"):
            r = client.get("/api/grid" + q)
            assert "x-partscale-delta" not in r.headers
            assert r.content == encode_grid(session.current)
        assert client.get("/api/grid?base=-1").status_code == 400
        assert client.get("/api/parts?base=x").status_code == 400


# -- apply, undo, redo ------------------------------------------------------------------------
def test_apply_stretches_to_the_expected_extent_and_undo_restores_exactly(client, box_file):
    session = client.app.state.session
    original = session.current
    grid0 = client.get("/api/grid").content
    r = post(client, "/api/apply", STRETCH)
    assert r.status_code == 200, r.text
    s = r.json()
    # the box [0, 1] with [0.3, 0.7] -> [0.3, 0.9] ends at 1.2; other axes unchanged
    lo, hi = np.array(s["solid_bounds"])
    assert abs(hi[0] - 1.2) <= 0.25 * H and abs(lo[0]) <= 0.25 * H
    np.testing.assert_allclose(hi[1:], BOX[1][1:], atol=0.25 * H)
    assert s["can_undo"] and s["revision"] == 1 and len(s["history"]) == 1
    assert len(client.get("/api/grid").content) == np.prod(s["shape"]) * GRID_BYTES_PER_VOXEL

    s = post(client, "/api/undo").json()
    assert session.current is original  # the very arrays, not a recomputation
    assert client.get("/api/grid").content == grid0
    assert s["can_redo"] and not s["can_undo"] and s["history"] == []

    s = post(client, "/api/redo").json()
    assert abs(s["solid_bounds"][1][0] - 1.2) <= 0.25 * H
    assert post(client, "/api/redo").status_code == 409


def test_apply_says_what_the_edit_changed_like_the_cli(tmp_path):
    """A tile whose END plane cuts the fourth of five boards: Apply's state carries the same
    line ``partscale scale`` prints (the sliver left out), and the history records it."""
    h = 0.02
    c, boxes = shapes.bars(5, width=4 * h, gap=8 * h, height=0.3, depth=0.2, voxel_size=h)
    path = tmp_path / "boards.csdf.npz"
    partscale.save(c, path)
    start, end = boxes[2][0][0] - 4 * h, boxes[3][0][0] + 1.3 * h
    edit = {"axis": "x", "zone": [start, end], "to": 2 * end - start, "mode": "tile"}
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        s = post(client, "/api/apply", {"edits": [edit]}).json()
    said = " ".join(s["notes"])
    assert "END plane (" in said and "cuts an element" in said and "left out" in said, said
    assert set(s["history"][-1]["slivers_left_out"]) == {"end"}


def test_apply_names_the_knob_its_stretch_zone_held(tmp_path):
    """A stretch zone across a cabinet's knob: Apply's notes name it, as ``scale`` does."""
    h = 0.02

    def sdf(p):
        box = shapes.box_sdf(p, (0, 0, 0), (0.8, 0.6, 0.3))
        return np.minimum(box, shapes.sphere_sdf(p, (0.62, 0.45, 0.32), 0.05))

    path = tmp_path / "cabinet.csdf.npz"
    partscale.save(shapes.grid(sdf, np.array([[0, 0, 0], [0.8, 0.6, 0.37]]), voxel_size=h), path)
    edit = {"axis": "x", "zone": [0.05, 0.75], "to": 0.9, "mode": "stretch"}
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        s = post(client, "/api/apply", {"edits": [edit]}).json()
    assert any("holds 1 local feature" in n for n in s["notes"]), s["notes"]


def test_zones_in_sequence_and_percent_positions(client):
    session = client.app.state.session
    original = session.current
    assert post(client, "/api/apply", STRETCH).status_code == 200
    # then 25% taller along y, by percent of the (new) solid's extent
    tall = {"edits": [{"axis": "y", "zone": ["40%", "60%"], "to": "85%", "mode": "stretch"}]}
    s = post(client, "/api/apply", tall).json()
    assert abs(s["solid_bounds"][1][1] - 0.625) <= 0.25 * H
    assert abs(s["solid_bounds"][1][0] - 1.2) <= 0.25 * H
    assert len(s["history"]) == 2
    post(client, "/api/undo")
    post(client, "/api/undo")
    assert session.current is original
    assert post(client, "/api/undo").status_code == 409


def test_bad_recipes_are_refused_with_the_reason(client):
    session = client.app.state.session
    cases = [
        ({"edits": [{"axis": "w", "zone": [0.3, 0.7], "to": 0.9}]}, "axis"),
        ({"edits": [{"axis": "x", "zone": [0.3], "to": 0.9}]}, "zone"),
        ({"edits": [{"axis": "x", "zone": [0.3, 0.7], "to": 0.9, "path": "/etc"}]}, "path"),
        ({"edits": []}, "edits"),
        ({"edits": [{"axis": "x", "zone": [0.7, 0.3], "to": 0.9}]}, "zone"),
    ]
    for body, word in cases:
        r = post(client, "/api/apply", body)
        assert r.status_code == 400, (body, r.text)
        assert word in r.json()["error"], (word, r.json())
    r = client.post(
        "/api/apply", content=b"{not json", headers={"content-type": "application/json"}
    )
    assert r.status_code == 400 and "JSON" in r.json()["error"]
    assert session.revision == 0 and not session.undo_stack


def test_concurrent_applies_are_serialised(client):
    session = client.app.state.session
    original = session.current
    results = []

    def one():
        results.append(post(client, "/api/apply", STRETCH).status_code)

    threads = [threading.Thread(target=one) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == [200, 200, 200]
    # each apply saw the previous one's result: three stretches of +0.2
    s = client.get("/api/state").json()
    assert s["revision"] == 3 and len(s["history"]) == 3
    assert abs(s["solid_bounds"][1][0] - 1.6) <= 0.5 * H
    for _ in range(3):
        post(client, "/api/undo")
    assert session.current is original


def test_grid_header_describes_the_grid_sent_even_when_an_apply_lands_meanwhile(
    client, monkeypatch
):
    original = client.app.state.session.current
    real = session_mod.encode_grid
    encoding, release = threading.Event(), threading.Event()

    def held(c):  # the first encoding (the GET below) waits until the apply has landed
        if not encoding.is_set():
            encoding.set()
            assert release.wait(10)
        return real(c)

    monkeypatch.setattr(session_mod, "encode_grid", held)
    got = {}
    t = threading.Thread(target=lambda: got.update(r=client.get("/api/grid")))
    t.start()
    try:
        assert encoding.wait(10)
        assert post(client, "/api/apply", STRETCH).status_code == 200
    finally:
        release.set()
        t.join(10)
    r = got["r"]
    shape = [int(v) for v in r.headers["x-partscale-shape"].split(",")]
    assert client.app.state.session.current.shape != original.shape
    # the body is the object as it was asked for; the header must say so
    assert shape == list(original.shape)
    assert len(r.content) == GRID_BYTES_PER_VOXEL * int(np.prod(shape))


def test_progress_is_busy_until_the_last_apply_in_flight_ends(client, monkeypatch):
    session = client.app.state.session
    real = session.apply
    entered = [threading.Event(), threading.Event()]
    release = [threading.Event(), threading.Event()]
    calls = iter(range(2))

    def held(recipe, **kw):  # each apply waits for its turn, then runs for real
        i = next(calls)
        entered[i].set()
        assert release[i].wait(10)
        return real(recipe, **kw)

    monkeypatch.setattr(session, "apply", held)
    codes = []
    threads = [
        threading.Thread(target=lambda: codes.append(post(client, "/api/apply", STRETCH)))
        for _ in range(2)
    ]
    try:
        threads[0].start()
        assert entered[0].wait(10)
        threads[1].start()
        assert entered[1].wait(10)
        release[0].set()
        threads[0].join(10)
        assert len(codes) == 1 and codes[0].status_code == 200
        p = client.get("/api/progress").json()
        assert p["busy"] is True, p  # the second apply is still running
    finally:
        for e in release:
            e.set()
        for t in threads:
            t.join(10)
    assert [r.status_code for r in codes] == [200, 200]
    p = client.get("/api/progress").json()
    assert p["busy"] is False and p["fraction"] == 1.0, p


def test_request_body_limit_is_the_apps_max_body(box_file):
    body = json.dumps(STRETCH).encode()
    body = body[:-1] + b" " * (2 * MAX_BODY) + b"}"  # valid JSON, larger than the default
    with TestClient(
        create_app(box_file, max_body=4 * MAX_BODY), base_url="http://127.0.0.1"
    ) as client:
        r = client.post("/api/apply", content=body, headers={"content-type": "application/json"})
        assert r.status_code == 200, r.text
    with TestClient(create_app(box_file, max_body=1000), base_url="http://127.0.0.1") as client:
        r = client.post("/api/apply", content=body, headers={"content-type": "application/json"})
        assert r.status_code == 413 and "1000" in r.json()["error"]


@pytest.mark.parametrize(
    ("body", "words"),
    [
        (b"[" * 200 + b"]" * 200, "nest"),
        (b'{"version": 1, "edits": [], "x": NaN}', "nan"),
        (b'{"version": 1, "x": 1e400}', "1e400"),
        (b'{"version": ' + b"9" * 4300 + b"}", "digits"),
    ],
)
def test_hostile_json_bodies_are_one_line_400s(client, body, words):
    r = client.post("/api/apply", content=body, headers={"content-type": "application/json"})
    assert r.status_code == 400, r.text
    message = r.json()["error"]
    assert "\n" not in message and words in message.lower(), message
    assert client.get("/api/state").json()["revision"] == 0


# -- save and export --------------------------------------------------------------------------
def test_save_writes_beside_the_input_unless_overwrite(client, box_file, tmp_path):
    before = box_file.read_bytes()
    post(client, "/api/apply", STRETCH)
    s = post(client, "/api/save").json()
    out = edited_path(box_file)
    assert s["saved"] == out.name and out.is_file() and not s["unsaved"]
    assert box_file.read_bytes() == before
    saved = partscale.load(out)
    assert saved.shape == client.app.state.session.current.shape
    assert np.array_equal(saved.sdf, client.app.state.session.current.sdf)
    # a path in the body is not a thing the server reads
    r = post(client, "/api/save", {"overwrite": False, "path": str(tmp_path / "x.csdf.npz")})
    assert r.status_code == 400 and not (tmp_path / "x.csdf.npz").exists()
    assert post(client, "/api/save", {"overwrite": "yes"}).status_code == 400
    s = post(client, "/api/save", {"overwrite": True}).json()
    assert s["saved"] == box_file.name
    assert partscale.load(box_file).shape == saved.shape
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.csdf.npz", "box.edited.csdf.npz"]


def test_export_mesh_is_a_glb_with_vertex_colours(client, tmp_path):
    r = client.get("/api/export/mesh")
    assert r.status_code == 200, r.text
    assert 'filename="box.edited.glb"' in r.headers["content-disposition"]
    path = tmp_path / "dl.glb"
    path.write_bytes(r.content)
    scene = trimesh.load(path)
    (mesh,) = scene.geometry.values()
    colours = glb_vertex_colours(mesh)
    assert len(mesh.vertices) > 100 and colours.shape == (len(mesh.vertices), 3)
    np.testing.assert_allclose(mesh.bounds, BOX, atol=0.5 * H)
    assert np.ptp(colours[:, 1]) > 0.5  # the green ramp along x survives


def test_export_texture_downloads_a_file(client):
    r = client.get("/api/export/texture")
    assert r.status_code == 200, r.text
    assert "attachment" in r.headers["content-disposition"] and len(r.content) > 1000


@pytest.mark.parametrize("stem", ['椅子 "x"', "modèle\\1"])
def test_export_of_any_file_name_is_a_valid_attachment_header(tmp_path, stem):
    path = tmp_path / f"{stem}.csdf.npz"
    partscale.save(shapes.box(*BOX, voxel_size=0.05), path)
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        for url, suffix in (("/api/export/mesh", ".glb"), ("/api/export/texture", ".nrrd")):
            r = client.get(url)
            assert r.status_code == 200, r.text
            cd = r.headers["content-disposition"]
            cd.encode("ascii")  # headers are Latin-1 on the wire; ASCII is safe everywhere
            m = re.fullmatch(r'attachment; filename="([ -~]*)"; filename\*=UTF-8\'\'(\S+)', cd)
            assert m, cd
            assert '"' not in m.group(1) and "\\" not in m.group(1)
            assert m.group(1).endswith(".edited" + suffix)
            # RFC 5987: the exact name, percent-encoded UTF-8
            assert unquote(m.group(2), encoding="utf-8", errors="strict") == (
                f"{stem}.edited{suffix}"
            )


def test_save_or_export_refused_by_the_file_system_is_a_json_error(
    client, box_file, tmp_path, monkeypatch
):
    target = edited_path(box_file)
    target.mkdir()
    r = post(client, "/api/save")
    assert r.status_code == 400, r.text
    err = r.json()["error"]
    assert "expected a writable file" in err and str(target) in err
    assert target.is_dir() and not any(target.iterdir())
    # export writes to a temporary folder first: one that cannot be created
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "no such folder"))
    r = client.get("/api/export/mesh")
    assert r.status_code == 400 and r.json()["error"].startswith("export: expected"), r.text


def test_a_bug_inside_partscale_is_a_json_500_not_a_400(client, monkeypatch, capsys):
    def boom(*a, **k):
        raise RuntimeError("kaboom")

    monkeypatch.setattr(client.app.state.session, "apply", boom)
    r = post(client, "/api/apply", STRETCH)
    assert r.status_code == 500, r.text
    assert r.json()["error"] == "apply failed inside partscale: RuntimeError: kaboom"
    assert "Traceback" in capsys.readouterr().err  # kept for whoever runs the server


# -- what is refused --------------------------------------------------------------------------
@pytest.mark.parametrize(
    "url",
    [
        "/assets/..%2F..%2Fapp.py",
        "/assets/%2e%2e/session.py",
        "/assets/../app.py",
        "/../../../../etc/passwd",
        "/static/index.html",
        "/app.py",
        "/api/file/etc/passwd",
        "/api/grid/../../box.csdf.npz",
        "/box.csdf.npz",
        "/build.json",
        "/api/export/../../../etc/passwd",
        "/api/export/other",
    ],
)
def test_other_paths_are_not_served(client, url):
    r = client.get(url)
    assert r.status_code == 404, (url, r.status_code)
    assert b"partscale.csdf" not in r.content and b"import" not in r.content


def test_query_strings_cannot_pick_another_object(client, box_file, tmp_path):
    other = tmp_path / "other.csdf.npz"
    partscale.save(shapes.sphere((0, 0, 0), 0.3, voxel_size=H), other)
    grid = client.get("/api/grid").content
    for q in (f"?path={other}", f"?file={other}", "?id=1", f"?name={other.name}"):
        assert client.get("/api/grid" + q).content == grid
        assert client.get("/api/state" + q).json()["name"] == "box.csdf.npz"


def test_oversized_and_foreign_requests_are_refused(client):
    big = b'{"edits": [' + b" " * (MAX_BODY + 10) + b"]}"
    r = client.post("/api/apply", content=big, headers={"content-type": "application/json"})
    assert r.status_code == 413

    def chunks():  # no Content-Length: the limit holds on the streamed body too
        for _ in range(MAX_BODY // 1000 + 2):
            yield b" " * 1000

    r = client.post("/api/apply", content=chunks(), headers={"content-type": "application/json"})
    assert r.status_code == 413
    # a form post from another site (no JSON content type) is refused before anything happens
    r = client.post("/api/save", content=b"overwrite=true", headers={"content-type": "text/plain"})
    assert r.status_code == 415
    assert client.get("/api/apply").status_code == 405
    # DNS rebinding: a loopback server answers loopback names only
    assert client.get("/api/state", headers={"host": "evil.example"}).status_code == 400
    assert client.get("/api/state", headers={"host": "evil.example:80"}).status_code == 400
    assert client.get("/api/state", headers={"host": "[::2]:8000"}).status_code == 400
    for host in ("localhost:8000", "127.0.0.1", "[::1]:8000"):
        assert client.get("/api/state", headers={"host": host}).status_code == 200, host
    assert client.app.state.session.revision == 0


@pytest.mark.parametrize(
    ("bound", "names"),
    [
        ("0.0.0.0", ["localhost:8000", "127.0.0.1"]),
        ("192.0.2.5", ["192.0.2.5:8000", "localhost"]),
        ("MyHost.LAN.", ["myhost.lan:8000", "MYHOST.lan"]),
        ("LOCALHOST", ["localhost:8000", "[::1]"]),
        ("127.000.000.001", ["127.0.0.1:8000", "127.000.000.001"]),
    ],
)
def test_host_check_holds_whatever_host_the_server_was_started_with(box_file, bound, names):
    # a page on evil.example rebinds its name to this machine: never answered, whatever
    # --host was, so it cannot apply edits or save over the input
    app = create_app(box_file, allowed_hosts=allowed_hosts(bound))
    with TestClient(app, base_url="http://127.0.0.1") as c:
        for host in ("evil.example", "evil.example:8000", "127.0.0.1.evil.example"):
            r = c.get("/api/state", headers={"host": host})
            assert r.status_code == 400 and "host: expected one of" in r.json()["error"], host
            r = c.post("/api/save", json={"overwrite": True}, headers={"host": host})
            assert r.status_code == 400, host
        for host in names:
            assert c.get("/api/state", headers={"host": host}).status_code == 200, host
    assert not edited_path(box_file).exists()


def test_loopback_spellings_are_loopback():
    for host in ("LOCALHOST", "localhost.", "127.000.000.001", "127.1", "::1", "[0:0::1]"):
        assert is_loopback(host), host
    for host in ("evil.example", "0.0.0.0", "192.0.2.5", "localhost.evil.example"):
        assert not is_loopback(host), host


def test_state_changing_requests_from_another_origin_are_refused(client):
    session = client.app.state.session
    for origin in ("http://evil.example", "null", "http://localhost", "https://127.0.0.1"):
        for url, body in (("/api/apply", STRETCH), ("/api/save", {"overwrite": True})):
            r = client.post(url, json=body, headers={"origin": origin})
            assert r.status_code == 403, (origin, url, r.text)
            assert r.json()["error"].startswith("origin: expected"), r.json()
    assert session.revision == 0 and not edited_path(session.path).exists()
    # the page's own origin (and requests without one: scripts, curl) are answered
    for origin in ("http://127.0.0.1", "http://127.0.0.1:80"):
        r = client.post("/api/apply", json=STRETCH, headers={"origin": origin})
        assert r.status_code == 200, (origin, r.text)
    assert client.get("/api/state", headers={"origin": "http://evil.example"}).status_code == 200


def test_apply_beyond_the_pages_limits_is_refused_before_computing(client, monkeypatch):
    from partscale import edit

    session = client.app.state.session
    nx = session.current.shape[0]
    grow = {"edits": [{"axis": "x", "zone": [0.3, 0.7], "to": 0.7 + 10 * H}]}  # +10 voxels
    computed = []
    real = edit.apply_recipe
    monkeypatch.setattr(edit, "apply_recipe", lambda *a, **k: computed.append(1) or real(*a, **k))
    r = post(client, "/api/apply", {**grow, "limits": {"max_voxels_per_axis": nx + 9}})
    assert r.status_code == 400, r.text
    err = r.json()["error"]
    assert err.startswith("apply: expected at most") and "voxels per axis" in err, err
    assert "\n" not in err and f"{nx + 10} × " in err, err
    assert not computed and session.revision == 0 and not session.undo_stack
    r = post(client, "/api/apply", {**grow, "limits": {"max_voxels": 10}})
    assert r.status_code == 400 and "voxels" in r.json()["error"] and not computed
    for bad in ({"max_voxels_per_axis": 0}, {"gpu": 1}, [1], {"max_voxels": True}):
        r = post(client, "/api/apply", {**grow, "limits": bad})
        assert r.status_code == 400 and r.json()["error"].startswith("limits"), (bad, r.text)
    r = post(client, "/api/apply", {**grow, "limits": {"max_voxels_per_axis": nx + 10}})
    assert r.status_code == 200 and r.json()["shape"][0] == nx + 10
    assert computed and r.json()["can_undo"]


def test_an_apply_response_describes_the_revision_it_made(client, monkeypatch):
    # the response of apply 1 was built after the lock was released: an apply landing in
    # between made it describe revision 2 (20 parallel applies carried 7-9 distinct revisions)
    real = session_mod.header
    first, landed = threading.Event(), threading.Event()

    def slow_header(c):
        if not first.is_set():
            first.set()
            assert landed.wait(10)
        return real(c)

    monkeypatch.setattr(session_mod, "header", slow_header)
    got = {}
    t = threading.Thread(target=lambda: got.update(r=post(client, "/api/apply", STRETCH)))
    t.start()
    try:
        assert first.wait(30)
        second = post(client, "/api/apply", STRETCH).json()
    finally:
        landed.set()
        t.join(30)
    one = got["r"].json()
    assert (one["revision"], len(one["history"])) == (1, 1), one["revision"]
    assert (second["revision"], len(second["history"])) == (2, 2)
    assert one["shape"] != second["shape"]


def test_save_refuses_an_object_the_page_does_not_show(client):
    session = client.app.state.session
    assert post(client, "/api/apply", STRETCH).status_code == 200
    r = post(client, "/api/save", {"overwrite": False, "revision": 0})
    assert r.status_code == 400 and "revision" in r.json()["error"], r.text
    assert not edited_path(session.path).exists()
    r = post(client, "/api/save", {"overwrite": False, "revision": 1})
    assert r.status_code == 200 and edited_path(session.path).exists()


def test_missing_or_invalid_object_is_refused(tmp_path, cli):
    from conftest import assert_bad_input

    assert_bad_input(cli("editor", tmp_path / "nope.csdf.npz", "--no-browser"), "nope.csdf.npz")
    bad = tmp_path / "bad.csdf.npz"
    bad.write_bytes(b"not a zip")
    assert_bad_input(cli("editor", bad, "--no-browser"), "bad.csdf.npz")


def test_the_old_command_name_still_opens_the_editor_but_is_not_listed(tmp_path, cli):
    from conftest import assert_bad_input

    # same command under its first name: the same refusal, naming the file
    assert_bad_input(cli("edit", tmp_path / "nope.csdf.npz", "--no-browser"), "nope.csdf.npz")
    listed = cli("--help", check=True).stdout
    # a command's row starts with its name (after the table's border)
    assert re.search(r"^\W*editor\s", listed, re.M), listed
    assert not re.search(r"^\W*edit\s", listed, re.M), listed


def test_busy_port_and_foreign_address_are_refused(box_file, cli):
    from conftest import assert_bad_input

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        proc = cli("editor", box_file, "--no-browser", "--port", str(port))
    assert_bad_input(proc, "--port", str(port))
    # TEST-NET-3: never an address of this machine
    assert_bad_input(cli("editor", box_file, "--no-browser", "--host", "203.0.113.7"), "--host")


# -- the command ------------------------------------------------------------------------------
def _start(args: list[str]) -> tuple[subprocess.Popen, str, list[str]]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.Popen(
        [sys.executable, "-m", "partscale", "editor", *args, "--no-browser"],
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        env=env,
    )
    lines: list[str] = []
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        lines.append(line)
        m = re.search(r"(http://\S+/)", line)
        if m:
            return proc, m.group(1), lines
    _stop(proc)
    raise AssertionError(f"no URL printed: {''.join(lines)}")


def _stop(proc: subprocess.Popen) -> None:
    proc.terminate()
    proc.wait(timeout=20)
    proc.stderr.close()


def _get_state(url: str):
    """GET the editor's state, waiting up to ~10 s for the server to listen."""
    import httpx

    for _ in range(100):
        try:
            return httpx.get(url + "api/state", timeout=5)
        except httpx.ConnectError:
            time.sleep(0.1)
    return httpx.get(url + "api/state", timeout=5)  # raises what keeps it from answering


def test_edit_command_serves_on_loopback_and_warns_otherwise(box_file):
    proc, url, lines = _start([str(box_file)])
    try:
        assert url.startswith("http://127.0.0.1:")
        assert not any("warning" in ln for ln in lines)
        r = _get_state(url)
        assert r.status_code == 200 and r.json()["name"] == "box.csdf.npz"
    finally:
        _stop(proc)
    proc, url, lines = _start([str(box_file), "--host", "0.0.0.0", "--expose"])
    try:
        warn = [ln for ln in lines if "warning" in ln]
        assert len(warn) == 1 and "not loopback" in warn[0] and "any web page" in warn[0], lines
        # exposed on purpose, still no DNS rebinding: a name the server was not started with
        r = _get_state(url)
        assert r.status_code == 200, r.text
        import httpx

        r = httpx.get(url + "api/state", headers={"Host": "evil.example"}, timeout=5)
        assert r.status_code == 400 and "host" in r.json()["error"], r.text
    finally:
        _stop(proc)


def test_edit_command_on_another_loopback_address_answers_at_its_url(box_file):
    import httpx

    # all of 127.0.0.0/8 is loopback (on Linux every address of it reaches lo)
    try:
        with socket.socket() as s:
            s.bind(("127.0.0.2", 0))
    except OSError as exc:
        pytest.skip(f"127.0.0.2 cannot be bound here: {exc}")
    proc, url, lines = _start([str(box_file), "--host", "127.0.0.2"])
    try:
        assert url.startswith("http://127.0.0.2:") and not any("warning" in ln for ln in lines)
        r = _get_state(url)
        assert r.status_code == 200, r.text
        # still a DNS-rebinding guard: a foreign name is refused
        r = httpx.get(url + "api/state", headers={"Host": "evil.example"}, timeout=5)
        assert r.status_code == 400
    finally:
        _stop(proc)


# -- a real object ----------------------------------------------------------------------------
def test_real_table_stretch_undo_and_export(data, tmp_path):
    from partscale.ingest import load

    path = tmp_path / "table.csdf.npz"
    partscale.save(load(data("kenney/table.glb"), res=64), path)
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        session = client.app.state.session
        original = session.current
        h = original.voxel_size
        lo0, hi0 = np.array(client.get("/api/state").json()["solid_bounds"])
        length = hi0[0] - lo0[0]
        r = post(
            client, "/api/apply", {"edits": [{"axis": "x", "zone": ["35%", "65%"], "to": "105%"}]}
        )
        assert r.status_code == 200, r.text
        lo, hi = np.array(r.json()["solid_bounds"])
        # 40 % longer along x, the rest of the box where it was (re-evaluation may move the
        # surface by a fraction of a voxel)
        assert abs((hi[0] - lo[0]) - 1.4 * length) <= 0.5 * h
        np.testing.assert_allclose(lo, lo0, atol=0.5 * h)
        np.testing.assert_allclose(hi[1:], hi0[1:], atol=0.5 * h)
        glb = tmp_path / "dl.glb"
        glb.write_bytes(client.get("/api/export/mesh").content)
        (mesh,) = trimesh.load(glb).geometry.values()
        assert abs(mesh.extents[0] - 1.4 * length) <= 1.0 * h
        # the table's wood colour, linear in the GLB as glTF wants it
        surface = original.rgb[np.abs(original.sdf) < h] / 255.0
        srgb = np.median(surface, axis=0)
        linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
        assert np.abs(srgb - 0.5).max() > 0.1  # not the grey of an uncoloured import
        np.testing.assert_allclose(np.median(glb_vertex_colours(mesh), axis=0), linear, atol=0.03)
        post(client, "/api/undo")
        assert session.current is original


# -- zones: suggest, snap, fit (thin layers over partscale.zones) ------------------------------


def shelf_file(tmp_path: Path, n=5, pitch=0.3, board=0.04, width=0.8, depth=0.3) -> Path:
    """Two side panels and ``n`` boards along y, ``pitch`` apart (a bookcase), saved."""
    height = (n - 1) * pitch + board
    boxes = [((0, 0, 0), (0.04, height, depth)), ((width - 0.04, 0, 0), (width, height, depth))]
    boxes += [((0, m * pitch, 0), (width, m * pitch + board, depth)) for m in range(n)]
    bounds = np.array([[0, 0, 0], [width, height, depth]], float)
    path = tmp_path / "shelf.csdf.npz"
    partscale.save(shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H), path)
    return path


def test_suggest_snap_and_fit_are_the_zones_functions_on_the_current_object(tmp_path):
    from partscale import zones

    path = shelf_file(tmp_path)
    c = partscale.load(path)
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        # suggest: every axis, best first, exactly zones.suggest's candidates
        got = client.get("/api/suggest").json()["candidates"]
        assert got == json.loads(json.dumps([k.to_json() for k in zones.suggest(c)]))
        y = client.get("/api/suggest?axis=y").json()["candidates"]
        assert y and {k["axis"] for k in y} == {"y"}
        tile = next(k for k in y if k["kind"] == "tile")
        assert abs(tile["period"] - 0.3) <= H  # the boards' pitch, within a voxel

        # snap: a naive tile zone moved to one whole period, as `scale --snap` does
        naive = {"axis": "y", "zone": [0.4, 0.8], "to": 1.0, "mode": "tile"}
        r = post(client, "/api/snap", naive)
        assert r.status_code == 200, r.text
        edit, moves = zones.snap(c, naive)
        assert r.json()["edit"] == edit.to_json()
        assert r.json()["moves"] == [m.to_json() for m in moves]
        assert r.json()["message"].startswith("snap: moved ")

        # fit: the recipe and its reasons, nothing applied
        r = post(client, "/api/fit", {"size": ["=", "+30cm", "="]})
        assert r.status_code == 200, r.text
        recipe, why = zones.fit(c, ["=", "+30cm", "="])
        assert r.json() == {"recipe": recipe.to_json(), "why": why}
        assert client.get("/api/state").json()["revision"] == 0
        # applying the fitted recipe reaches the target height within half a voxel
        state = post(client, "/api/apply", r.json()["recipe"]).json()
        lo, hi = np.array(state["solid_bounds"])
        assert abs((hi[1] - lo[1]) - (1.24 + 0.3)) <= 0.5 * H
        # the suggestions now describe the applied object
        after = client.get("/api/suggest?axis=y").json()["candidates"]
        assert after != y


def test_suggest_lists_the_warp_zones_and_apply_makes_them(tmp_path):
    """/api/suggest (all axes) also answers the object's radial plan, flights, spirals and rings
    as zones.warp_candidates finds them, each with a recipe edit; /api/apply of that edit makes
    what apply_recipe makes (one more step; a star base's fifth arm), /api/undo restores the
    very object; one axis answers the candidates alone."""
    from partscale import zones
    from partscale.edit import Recipe, apply_recipe

    steps = [((0.2 * i, 0, 0), (0.2 * (i + 1), 0.15 * (i + 1), 0.6)) for i in range(5)]
    bounds = np.array([[0, 0, 0], [1.0, 0.75, 0.6]])
    c = shapes.grid(lambda p: shapes.boxes_sdf(p, steps), bounds, voxel_size=H)
    path = tmp_path / "stair.csdf.npz"
    partscale.save(c, path)
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        body = client.get("/api/suggest").json()
        found = zones.warp_candidates(c)
        assert {k: body[k] for k in ("radial", "steps", "helix", "rotation")} == json.loads(
            json.dumps(found.to_json())
        )
        (step,) = body["steps"]
        assert step["axis"] == "x" and abs(step["rise"] - 0.15) <= 0.5 * H
        assert step["edit"] == found.steps[0].zone(1).to_json() and step["ground"] is not None
        assert set(client.get("/api/suggest?axis=x").json()) == {"candidates"}
        session = client.app.state.session
        original = session.current
        r = post(client, "/api/apply", {"version": 1, "edits": [step["edit"]]})
        assert r.status_code == 200, r.text
        want = apply_recipe(c, Recipe.parse({"version": 1, "edits": [step["edit"]]}))
        assert np.array_equal(session.current.sdf, want.sdf)
        _, hi = np.array(r.json()["solid_bounds"])
        assert abs(hi[1] - (0.75 + step["rise"])) <= 0.5 * H  # one more rise
        assert post(client, "/api/undo").status_code == 200
        assert session.current is original
    # a star base: its ring of four arms, whose edit adds a fifth
    from test_rotation import star

    c = star(4)
    path = tmp_path / "star.csdf.npz"
    partscale.save(c, path)
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        body = client.get("/api/suggest").json()
        (ring,) = body["rotation"]
        assert ring["count"] == 4 and ring["closed"] and body["steps"] == body["helix"] == []
        assert ring["edit"] == zones.find_rotations(c)[0].zone(1).to_json()
        r = post(client, "/api/apply", {"version": 1, "edits": [ring["edit"]]})
        assert r.status_code == 200, r.text
        want = apply_recipe(c, Recipe.parse({"version": 1, "edits": [ring["edit"]]}))
        assert np.array_equal(client.app.state.session.current.sdf, want.sdf)


def test_snap_uses_the_candidates_the_server_found_for_suggest(tmp_path, monkeypatch):
    """/api/snap snaps to the cached /api/suggest candidates: found once, not again."""
    import dataclasses

    from partscale import zones

    path = shelf_file(tmp_path)
    found = []
    real = zones.suggest

    def doubled(c, axis=None, **kw):
        # a tile period the shelf does not have: a snap to it can only come from this cache
        out = [
            dataclasses.replace(k, period=2 * k.period) if k.kind == "tile" else k
            for k in real(c, axis, **kw)
        ]
        found.append((axis, out))
        return out

    monkeypatch.setattr(zones, "suggest", doubled)
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        client.get("/api/suggest?axis=y")
        naive = {"axis": "y", "zone": [0.4, 0.8], "to": 1.0, "mode": "tile"}
        r = post(client, "/api/snap", naive)
        assert r.status_code == 200, r.text
        post(client, "/api/snap", naive)
    assert [axis for axis, _ in found] == ["y"]
    c = partscale.load(path)
    want, _ = zones.snap(c, naive, candidates=found[0][1])
    assert r.json()["edit"] == want.to_json()
    zone = r.json()["edit"]["zone"]
    assert abs((zone[1] - zone[0]) - 0.6) <= H  # twice the boards' pitch


def sofa_file(tmp_path: Path, widths=(0.55, 0.6, 0.55), gap=0.04) -> Path:
    """Two armrests, a base, a back and a seat cushion per width, ``gap`` (two voxels) apart
    along x, saved: a repeat group of ``len(widths)`` elements along x, none along y or z."""
    arm = 0.15
    width = 2 * arm + sum(widths) + gap * (len(widths) - 1)
    boxes = [
        ((0, 0, 0), (arm, 0.6, 0.8)),
        ((width - arm, 0, 0), (width, 0.6, 0.8)),
        ((arm, 0, 0), (width - arm, 0.2, 0.65)),
        ((arm, 0, 0.65), (width - arm, 0.8, 0.8)),
    ]
    x = arm
    for w in widths:
        boxes.append(((x, 0.2, 0), (x + w, 0.4, 0.65)))
        x += w + gap
    bounds = np.array([[0, 0, 0], [width, 0.8, 0.8]], float)
    path = tmp_path / "sofa.csdf.npz"
    partscale.save(shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H), path)
    return path


def round_table_file(tmp_path: Path, h: float = 0.01) -> Path:
    """A disc top (radius 0.5) on a column on a round foot, y up, saved: growing it along x and
    z deforms the round top whatever zone takes it."""

    def cyl(p, r, y0, y1):
        q = np.stack(
            [np.hypot(p[:, 0], p[:, 2]) - r, np.abs(p[:, 1] - (y0 + y1) / 2) - (y1 - y0) / 2], 1
        )
        return np.minimum(q.max(1), 0) + np.linalg.norm(np.maximum(q, 0), axis=1)

    def sdf(p):
        top = cyl(p, 0.5, 0.7, 0.74)
        return np.minimum(np.minimum(top, cyl(p, 0.06, 0.05, 0.7)), cyl(p, 0.25, 0, 0.05))

    path = tmp_path / "round.csdf.npz"
    bounds = np.array([[-0.5, 0, -0.5], [0.5, 0.74, 0.5]])
    partscale.save(shapes.grid(sdf, bounds, voxel_size=h), path)
    return path


def test_elements_are_find_elements_per_axis_found_once_per_object(tmp_path, monkeypatch):
    """/api/elements: zones.find_elements of the current object on each axis (with its summary),
    found once per object and axis, found again after an apply."""
    from partscale import zones

    path = sofa_file(tmp_path)
    c = partscale.load(path)
    calls = []
    real = zones.find_elements
    monkeypatch.setattr(zones, "find_elements", lambda c, ax, **kw: calls.append(ax) or real(c, ax))
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        r = client.get("/api/elements")
        assert r.status_code == 200, r.text
        got = r.json()["axes"]
        want = [real(c, ax) for ax in "xyz"]
        assert got == json.loads(
            json.dumps([{**f.to_json(), "summary": zones.element_phrase(f)} for f in want])
        )
        x = got[0]
        assert x["axis"] == "x" and x["groups"][0]["count"] == 3
        assert x["summary"].startswith("3 alike elements")
        assert got[1]["groups"] == [] and got[1]["summary"] == "no repeated element"
        # one axis; and every axis is found once per object
        one = client.get("/api/elements?axis=x").json()["axes"]
        assert one == [x]
        assert calls == ["x", "y", "z"]
        # after an apply (one cushion fewer), the elements of the new object
        recipe = post(client, "/api/add", {"axis": "x", "n": -1}).json()["recipe"]
        post(client, "/api/apply", recipe)
        after = client.get("/api/elements?axis=x").json()["axes"][0]
        assert after["groups"][0]["count"] == 2
        assert calls == ["x", "y", "z", "x"]


@pytest.mark.parametrize("n", [1, -1])
def test_add_is_fit_add_on_the_current_object_not_applied(tmp_path, n):
    """/api/add: the recipe and notes of ``fit --add x N``, nothing applied; applied, the sofa is
    one cushion (and its gap) longer or shorter; undo restores it exactly."""
    from partscale import zones

    path = sofa_file(tmp_path)
    c = partscale.load(path)
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        original = client.app.state.session.current
        r = post(client, "/api/add", {"axis": "x", "n": n})
        assert r.status_code == 200, r.text
        recipe, why = zones.fit(c, add={"x": n})
        assert r.json() == {"recipe": recipe.to_json(), "why": why}
        assert why[0].startswith(f"x: {'add' if n > 0 else 'remove'} 1 element")
        assert client.get("/api/state").json()["revision"] == 0
        state = post(client, "/api/apply", r.json()["recipe"]).json()
        lo, hi = np.array(state["solid_bounds"])
        sb = c.surface_bounds()
        grew = (hi[0] - lo[0]) - (sb[1, 0] - sb[0, 0])
        # one cushion (0.55 or 0.6 m) and its 4 cm gap, in whole voxels
        assert 0.55 + 0.04 - H <= n * grew <= 0.6 + 0.04 + H, grew
        np.testing.assert_allclose(hi[1:] - lo[1:], sb[1, 1:] - sb[0, 1:], atol=H / 2)
        post(client, "/api/undo")
        assert client.app.state.session.current is original  # the very object again
        np.testing.assert_array_equal(original.sdf, c.sdf)


def test_a_fit_only_a_deformation_reaches_is_refused_unless_allowed(tmp_path):
    """/api/fit on a round top 20 % wider (x alone: a radial zone grows x and z alike): 400
    with fit's one line naming the alternatives; with allow_deform the deforming recipe (not
    applied)."""
    from partscale import zones
    from partscale.errors import InputError

    path = round_table_file(tmp_path)
    c = partscale.load(path)
    size = ["120%", "=", "="]
    with pytest.raises(InputError) as refused:
        zones.fit(c, size)
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        for body in ({"size": size}, {"size": size, "allow_deform": False}):
            r = post(client, "/api/fit", body)
            assert r.status_code == 400, r.text
            assert r.json() == {"error": str(refused.value)}
            assert "\n" not in r.json()["error"] and "alternatives" in r.json()["error"]
        r = post(client, "/api/fit", {"size": size, "allow_deform": True})
        assert r.status_code == 200, r.text
        recipe, why = zones.fit(c, size, allow_deform=True)
        assert r.json() == {"recipe": recipe.to_json(), "why": why}
        assert client.get("/api/state").json()["revision"] == 0


@pytest.mark.parametrize(
    "body, words",
    [
        ({"axis": "y", "n": 1}, "found none"),  # no repeat along y
        ({"axis": "x", "n": 0}, "add.n: expected a whole number of elements other than 0"),
        ({"axis": "x", "n": 1.5}, "add.n: expected a whole number"),
        ({"axis": "x", "n": 1.0}, "add.n: expected a whole number"),
        ({"axis": "x", "n": "1"}, "add.n: expected a whole number"),
        ({"axis": "x", "n": True}, "add.n: expected a whole number"),
        ({"axis": "x", "n": 101}, "at most 100"),
        ({"axis": "x", "n": -3}, "at most 2 of its 3"),  # one element stays
        ({"axis": "w", "n": 1}, "add.axis: expected x, y or z"),
        ({"axis": "x"}, "add: expected"),
        ({"axis": "x", "n": 1, "size": "="}, "add: expected"),
        (["x", 1], "add: expected"),
    ],
)
def test_add_refuses_bad_input_with_one_line(tmp_path, body, words):
    with TestClient(create_app(sofa_file(tmp_path)), base_url="http://127.0.0.1") as client:
        r = post(client, "/api/add", body)
        assert r.status_code == 400, r.text
        message = r.json()["error"]
        assert words in message and "\n" not in message, message
        assert client.get("/api/state").json()["revision"] == 0


@pytest.mark.parametrize(
    "url, body, words",
    [
        ("/api/suggest?axis=w", None, "suggest.axis: expected x, y or z"),
        ("/api/elements?axis=w", None, "elements.axis: expected x, y or z"),
        ("/api/fit", {"size": ["=", "+10cm", "="], "allow_deform": "yes"}, "fit.allow_deform"),
        ("/api/fit", {"size": ["=", "+10cm", "="], "deform": True}, "fit: expected"),
        ("/api/snap", {"axis": "x", "zone": [0.3, 0.6], "to": 0.7, "mode": "tile"}, "found none"),
        ("/api/snap", {"axis": "q", "zone": [0.3, 0.6], "to": 0.7}, "axis"),
        ("/api/fit", {"size": ["=", "0", "="]}, "positive length"),
        ("/api/fit", {"size": ["=", "3furlongs", "="]}, "size y"),
        # named as the other size messages are (not "size along y")
        ("/api/fit", {"size": ["=", "5cm", "="]}, "size y: expected at least"),
        ("/api/fit", {"size": ["=", "="]}, "fit: expected"),
        ("/api/fit", {"size": ["=", "=", "="]}, "got the current size"),
        ("/api/fit", ["=", "=", "="], "fit: expected"),
    ],
)
def test_zone_routes_refuse_bad_input_with_one_line(client, url, body, words):
    r = client.get(url) if body is None else post(client, url, body)
    assert r.status_code == 400, r.text
    message = r.json()["error"]
    assert words in message and "\n" not in message
