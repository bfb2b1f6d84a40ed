"""Structured input is validated before numpy, pathlib or ``int()`` see it.

Intrinsics and views JSON, batch manifests and status rows, recipes and editor request bodies,
fit sizes, export budgets and mesh scenes: each hostile value is one line on stderr, exit 2,
nothing written (the server: a 4xx with one line, and it keeps answering). Commands run
in-process through :func:`partscale.cli.main`, so a traceback shows up as an exception here.
"""

from __future__ import annotations

import json
import struct
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import data_path
from PIL import Image
from starlette.testclient import TestClient

import partscale
from partscale import _schema, shapes
from partscale.cli import main
from partscale.errors import InputError
from partscale.serve import create_app

BOX = ((-0.4, -0.2, -0.2), (0.4, 0.2, 0.2))
K = {"fx": 50, "fy": 50, "cx": 32, "cy": 24}


def run(capsys, monkeypatch, *args) -> tuple[int, list[str]]:
    """``partscale ARGS`` in-process: (exit code, non-empty stderr lines)."""
    monkeypatch.setattr(sys, "argv", ["partscale", *map(str, args)])
    capsys.readouterr()
    try:
        main([str(a) for a in args])
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    return code, [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]


def assert_one_line(code: int, lines: list[str], *fragments: str) -> None:
    assert code == 2, (code, lines)
    assert len(lines) == 1, lines
    assert lines[0].startswith("partscale: error: "), lines
    for f in fragments:
        assert f.lower() in lines[0].lower(), (f, lines[0])


@pytest.fixture(scope="module")
def box_file(tmp_path_factory) -> Path:
    c = shapes.grid(lambda p: shapes.box_sdf(p, *BOX), BOX, voxel_size=0.05)
    return partscale.save(c, tmp_path_factory.mktemp("in") / "box.csdf.npz")


@pytest.fixture
def frame(tmp_path: Path) -> Path:
    """A 64x48 depth PNG (a 1 m plane in its middle) in ``tmp_path``."""
    d = np.zeros((48, 64), np.uint16)
    d[10:40, 10:50] = 5000
    Image.fromarray(d).save(tmp_path / "d.png")
    return tmp_path / "d.png"


# -- the readers themselves -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("value", "kw"),
    [
        (True, {}),
        ([500], {}),
        ("500", {}),
        (float("nan"), {}),
        (float("inf"), {}),
        (10**400, {}),
        (1e300, {"hi": 1e7}),
        (1e-300, {"lo": 1}),
        (0, {"lo": 0, "lo_open": True}),
    ],
)
def test_number_refuses_what_is_not_a_finite_number_in_range(value, kw):
    with pytest.raises(InputError, match=r"^fx: expected "):
        _schema.number(value, "fx", **kw)


@pytest.mark.parametrize("value", ["abc", "1.5", "nan", "9" * 40, 1.0, True, None, [1]])
def test_integer_refuses_what_is_not_a_whole_number(value):
    with pytest.raises(InputError, match=r"^attempts: expected a whole number"):
        _schema.integer(value, "attempts", lo=0, text=True)


def test_readers_accept_what_they_promise():
    assert _schema.number("  2.5 ", "x", text=True) == 2.5
    assert _schema.integer(np.int64(3), "n", lo=0) == 3
    assert _schema.integer("-7", "n", text=True) == -7
    assert _schema.matrix([1, 2, 3, 4], "m", (2, 2)).tolist() == [[1, 2], [3, 4]]
    assert _schema.matrix(np.eye(2), "m", (2, 2)).tolist() == [[1, 0], [0, 1]]
    assert _schema.path("a.png", "p", base=Path("d")) == Path("d/a.png")
    with pytest.raises(InputError, match="control characters"):
        _schema.path("a\x00.png", "p")
    with pytest.raises(InputError, match=r"m\[1\]\[0\]: expected a number"):
        _schema.matrix([[1, 2], [[3], 4]], "m", (2, 2))
    with pytest.raises(InputError, match="expected a count"):
        _schema.whole(float("inf"), "copies")


# -- complete: intrinsics, views, --box ---------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "text", "fragment"),
    [
        ("bigint", '{"fx": 1' + "0" * 25 + ', "fy": 50, "cx": 32, "cy": 24}', "fx"),
        ("list", '{"fx": [50], "fy": 50, "cx": 32, "cy": 24}', "fx"),
        ("deep", '{"fx": ' + "[" * 50 + "1" + "]" * 50 + ', "fy": 50, "cx": 32, "cy": 24}', "fx"),
        ("huge", '{"fx": 1e300, "fy": 1e300, "cx": 32, "cy": 24}', "fx"),
        ("tiny", '{"fx": 1e-300, "fy": 1e-300, "cx": 32, "cy": 24}', "fx"),
        ("text", '{"fx": "50", "fy": 50, "cx": 32, "cy": 24}', "fx"),
        ("ragged", '{"intrinsic_matrix": [[1, 2], [3]]}', "intrinsic_matrix"),
        ("word", '{"intrinsic_matrix": [50, 0, 0, 0, 50, 0, 32, 24, "x"]}', "intrinsic_matrix"),
    ],
)
def test_intrinsics_are_validated(tmp_path, frame, capsys, monkeypatch, name, text, fragment):
    k = tmp_path / f"k_{name}.json"
    k.write_text(text)
    out = tmp_path / "o" / "c.csdf.npz"
    out.parent.mkdir()
    code, lines = run(
        capsys, monkeypatch, "complete", "--depth", frame, "--intrinsics", k, "-o", out
    )
    assert_one_line(code, lines, k.name, fragment)
    assert not any(out.parent.iterdir())


@pytest.mark.parametrize(
    ("view", "fragment"),
    [
        ({"depth": "d.png", "intrinsics": [[50, 0, 32], [0, 50, 24], [0, 0, 1]],
          "pose": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, [1]]]}, "pose[3][3]"),
        ({"depth": "d.png", "intrinsics": {"fx": 1}}, "intrinsics"),
        ({"depth": "d.png", "intrinsics": [[50, 0, 32], [0, 50, 24], [0, 0, 1]],
          "depth_scale": [1]}, "depth_scale"),
        ({"depth": "d.png", "intrinsics": [[50, 0, 32], [0, 50, 24], [0, 0, 1]],
          "depth_scale": 1e-300}, "depth_scale"),
        ({"points": 5}, "points"),
        ({"depth": {"a": 1}, "intrinsics": [[50, 0, 32], [0, 50, 24], [0, 0, 1]]}, "depth"),
        ({"depth": "d.png", "color": 7, "intrinsics": [[50, 0, 32], [0, 50, 24], [0, 0, 1]]},
         "color"),
        ({"depth": "d\x00.png", "intrinsics": [[50, 0, 32], [0, 50, 24], [0, 0, 1]]}, "depth"),
        ({"depth": "d.png", "intrinsics": [[1e25, 0, 32], [0, 50, 24], [0, 0, 1]]},
         "intrinsics"),
    ],
)  # fmt: skip
def test_views_are_validated(tmp_path, frame, capsys, monkeypatch, view, fragment):
    views = tmp_path / "views.json"
    views.write_text(json.dumps([view]))
    out = tmp_path / "o" / "c.csdf.npz"
    out.parent.mkdir()
    code, lines = run(capsys, monkeypatch, "complete", "--views", views, "-o", out)
    assert_one_line(code, lines, "view 0", fragment)
    assert not any(out.parent.iterdir())


@pytest.mark.parametrize("box", ["nan,0,10,10", "inf,0,10,10", "0,0,1e30,1e30"])
def test_complete_box_is_finite_and_bounded(tmp_path, frame, capsys, monkeypatch, box):
    k = tmp_path / "k.json"
    k.write_text(json.dumps(K))
    out = tmp_path / "o" / "c.csdf.npz"
    out.parent.mkdir()
    code, lines = run(
        capsys, monkeypatch, "complete", "--depth", frame, "--intrinsics", k, "-o", out,
        "--box", box,
    )  # fmt: skip
    assert_one_line(code, lines, "--box")
    assert not any(out.parent.iterdir())


# -- batch: status rows, manifests, options ---------------------------------------------------


def _status(row: dict[str, str]) -> str:
    from partscale.batch.status import COLUMNS

    full = {c: "" for c in COLUMNS} | row
    return ",".join(COLUMNS) + "\n" + ",".join(full[c] for c in COLUMNS) + "\n"


@pytest.mark.parametrize(
    ("cell", "fragment"),
    [
        ({"attempts": "abc"}, "attempts"),
        ({"attempts": "1.5"}, "attempts"),
        ({"attempts": "nan"}, "attempts"),
        ({"attempts": "9" * 40}, "attempts"),
        ({"seconds": "inf"}, "seconds"),
        ({"state": "exploded"}, "state"),
        ({"error": "e" * 200_000}, "field larger than field limit"),
    ],
)
def test_status_rows_are_validated(tmp_path, capsys, monkeypatch, cell, fragment):
    src = tmp_path / "in"
    src.mkdir()
    (src / "ball.csdf.npz").write_bytes(b"not read: the table is refused first")
    out = tmp_path / "out"
    out.mkdir()
    table = _status(
        {"name": "ball", "state": "failed", "input_hash": "h", "options_hash": "o"} | cell
    )
    (out / "status.csv").write_text(table)
    code, lines = run(capsys, monkeypatch, "batch", src, "-o", out, "--workers", "1")
    assert_one_line(code, lines, "status.csv", fragment)
    assert (out / "status.csv").read_text() == table  # untouched
    assert sorted(p.name for p in out.iterdir()) == ["status.csv"]


@pytest.mark.parametrize(
    ("line", "fragment"),
    [
        ('{"path": "ball.csdf.npz", "res": NaN}', "strict JSON"),
        ('{"path": "ball.csdf.npz", "res": 1' + "0" * 5000 + "}", "digits"),
        ('{"path": "ball.csdf.npz", "res": ' + "[" * 5000 + "]" * 5000 + "}", "nested"),
        ('{"path": "ball.csdf.npz", "recipe": 5}', "recipe"),
        ('{"path": "ball.csdf.npz", "recipe": [1, 2]}', "recipe"),
        ('{"path": "ball.csdf.npz", "export": 5}', "export"),
        ('{"path": "ball.csdf.npz", "size": 5}', "size"),
        ('{"path": "ball.csdf.npz", "res": true}', "res"),
        ('{"path": "ba\\u0000ll.csdf.npz"}', "control characters"),
        ('{"path": "ball.csdf.npz", "name": "a\\u0000b"}', "control characters"),
        (
            '{"path": "ball.csdf.npz", "recipe": {"edits": [{"axis": "x", "zone": [[0], 1], '
            '"to": 2}]}}',
            "zone[0]",
        ),
    ],
)
def test_manifest_rows_are_validated(box_file, tmp_path, capsys, monkeypatch, line, fragment):
    (tmp_path / "ball.csdf.npz").write_bytes(box_file.read_bytes())
    m = tmp_path / "m.jsonl"
    m.write_text(line + "\n")
    out = tmp_path / "out"
    code, lines = run(capsys, monkeypatch, "batch", m, "-o", out, "--workers", "1")
    assert_one_line(code, lines, fragment)
    assert not out.exists()


def test_csv_manifest_field_over_the_csv_limit(box_file, tmp_path, capsys, monkeypatch):
    m = tmp_path / "m.csv"
    m.write_text(f"path,res\n{box_file},{'1' * 200_000}\n")
    code, lines = run(capsys, monkeypatch, "batch", m, "-o", tmp_path / "out")
    assert_one_line(code, lines, "m.csv", "field limit")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("memory", ["inf", "1e308", "nanG", "-1G"])
def test_batch_memory_is_a_finite_size(box_file, tmp_path, capsys, monkeypatch, memory):
    out = tmp_path / "out"
    code, lines = run(capsys, monkeypatch, "batch", box_file, "-o", out, "--memory", memory)
    assert_one_line(code, lines, "--memory")
    assert not out.exists()


# -- recipes, sizes and budgets -----------------------------------------------------------------


@pytest.mark.parametrize(
    "edit",
    [
        {"axis": "x", "zone": [[0.1], 0.2], "to": 0.3},
        {"axis": "x", "zone": [["10%"], "60%"], "to": "80%"},
        {"normal": [1, 0, 0], "zone": [[0.1], 0.2], "to": 0.3},
        {"axis": "x", "copies": 10**25},
    ],
)
def test_recipe_zone_holding_a_list(box_file, tmp_path, capsys, monkeypatch, edit):
    r = tmp_path / "r.json"
    r.write_text(json.dumps({"version": 1, "edits": [edit]}))
    out = tmp_path / "o.csdf.npz"
    code, lines = run(capsys, monkeypatch, "scale", box_file, "-o", out, "--recipe", r)
    assert_one_line(code, lines, "edits[0]")
    assert not out.exists()


@pytest.mark.parametrize("size", [("=", "1e308", "="), ("=", "+1e308m", "="), ("1e300%", "=", "=")])
def test_fit_refuses_finite_but_huge_sizes(box_file, tmp_path, capsys, monkeypatch, size):
    out = tmp_path / "o.csdf.npz"
    code, lines = run(capsys, monkeypatch, "fit", box_file, "-o", out, "--size", *size)
    assert_one_line(code, lines, "size", "times the current extent")
    assert not out.exists()


@pytest.mark.parametrize("budget", [("--error", "10"), ("--error", "1e308")])
def test_export_budget_that_leaves_no_triangle(box_file, tmp_path, capsys, monkeypatch, budget):
    out = tmp_path / "o.glb"
    code, lines = run(capsys, monkeypatch, "export", box_file, "--mesh", out, *budget)
    assert_one_line(code, lines, budget[0], "leaves a surface")
    assert not out.exists()


# -- the server ------------------------------------------------------------------------------


SERVER_BODIES = [
    ("/api/apply", {"version": 1, "edits": [{"axis": "x", "zone": [[0.1], 0.2], "to": 0.3}]}),
    ("/api/apply", {"version": 1, "edits": [{"axis": "x", "zone": [["10%"], "60%"], "to": "80%"}]}),
    ("/api/apply", {"version": 1, "edits": [{"normal": [1, 0, 0], "zone": [[0.1], 0.2], "to": 0.3}]}),
    ("/api/snap", {"axis": "x", "zone": [[0.1], 0.2], "to": 0.3}),
    ("/api/fit", {"size": ["=", 1e308, "="]}),
    ("/api/fit", {"size": ["=", "+1e308m", "="]}),
]  # fmt: skip


def test_server_requests_are_4xx_and_it_keeps_answering(box_file, tmp_path):
    path = tmp_path / "box.csdf.npz"
    path.write_bytes(box_file.read_bytes())
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        for url, body in SERVER_BODIES:
            r = client.post(url, json=body)
            assert 400 <= r.status_code < 500, (url, body, r.status_code, r.text)
            msg = r.json()["error"]
            assert "\n" not in msg and "expected" in msg, msg
            assert client.get("/api/state").status_code == 200


# -- mesh scenes on both routes ---------------------------------------------------------------


def _glb(node: dict | None = None, indices=(0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3), mode=4,
         extras: str = "") -> bytes:  # fmt: skip
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32).tobytes()
    i = np.array(indices, np.uint32).tobytes()
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, **(node or {})}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": mode}]}],
        "buffers": [{"byteLength": len(v) + len(i)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(v)},
            {"buffer": 0, "byteOffset": len(v), "byteLength": len(i)},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 1]},
            {"bufferView": 1, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
        ],
    }  # fmt: skip
    text = json.dumps(doc)
    if extras:
        text = text[:-1] + f', "extras": {extras}}}'
    j = text.encode()
    j += b" " * (-len(j) % 4)
    b = v + i
    body = struct.pack("<II", len(j), 0x4E4F534A) + j + struct.pack("<II", len(b), 0x004E4942) + b
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


MESHES = {
    "past.glb": (_glb(indices=(0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 99)), "face indices"),
    "points.glb": (_glb(mode=0), "triangles"),
    "singular.glb": (_glb({"matrix": [0.0] * 16}), "non-zero extent"),
    "flat.glb": (_glb({"scale": [0, 0, 0]}), "non-zero extent"),
    "deep.glb": (_glb(extras="[" * 20000 + "]" * 20000), "nested"),
    "notri.obj": (b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "triangles"),
    "nan.obj": (b"v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
                "finite vertex"),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("route", ["import", "mesh"])
def test_mesh_scenes_are_validated_on_both_routes(tmp_path, capsys, monkeypatch, name, route):
    data, fragment = MESHES[name]
    src = tmp_path / name
    src.write_bytes(data)
    out = tmp_path / "o"
    out.mkdir()
    if route == "import":
        args = ("import", src, "-o", out / "o.csdf.npz", "--res", "16")
    else:
        args = ("scale", src, "-o", out / "o.glb", "--axis", "x", "--zone", "10%", "60%",
                "--to", "80%")  # fmt: skip
    code, lines = run(capsys, monkeypatch, *args)
    assert_one_line(code, lines, name, fragment)
    assert "zone:" not in lines[0]  # the mesh is named, not what NaN did to a zone
    assert not any(out.iterdir())


# -- fit's plan and numpy's warnings ----------------------------------------------------------


def test_fit_does_not_print_a_plan_it_then_refuses(tmp_path, capsys, monkeypatch):
    """A thousand more steps on a flight of stairs (a mesh, so through its CSDF) would need far
    more memory than there is: the refusal comes alone, before any plan line."""
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", str(1 << 30))
    stairs = data_path("kenney/stairs.glb")
    out = tmp_path / "o.glb"
    code, lines = run(capsys, monkeypatch, "fit", stairs, "-o", out, "--add", "x", "1000")
    assert_one_line(code, lines, "fit --add x 1000", "would need", "memory")
    assert not out.exists()


def test_numpy_floating_point_warnings_do_not_reach_the_user(capsys):
    from partscale.cli import _one_line_warnings

    with _one_line_warnings():
        np.array([1e300, np.nan]).astype(np.float32).astype(np.int64)
    assert capsys.readouterr().err == ""
