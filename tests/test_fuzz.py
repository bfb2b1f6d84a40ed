"""A bounded, seeded fuzz of the CLI: every case keeps the one-line contract.

Damaged files of every format (truncated, bit-flipped, empty, junk, hostile JSON) and absurd
options go through ``info``, ``import``, ``scale`` and ``export`` in-process. Each case must end
with exit 0 and no warning lines, or exit 2 and exactly one ``partscale: error:`` line; never a
traceback, and never a hidden temporary file left beside an output. The seed is fixed, so a
failure names a case that reproduces.
"""

from __future__ import annotations

import io
import json
import random
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import partscale
from partscale import shapes
from partscale.cli import main

SEED = 14
N_CASES = 240


def _ball() -> partscale.CSDF:
    return shapes.grid(
        lambda p: np.linalg.norm(p, axis=-1) - 0.3, ((-0.4,) * 3, (0.4,) * 3), voxel_size=0.05
    )


OBJ = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl red\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
MTL = "newmtl red\nKd 0.8 0.1 0.1\n"
PLY = (
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"
)
RECIPE = {"version": 1, "edits": [{"axis": "x", "zone": ["10%", "60%"], "to": "80%"}]}
HOSTILE_JSON = [
    "[" * 5000 + "]" * 5000,
    '{"edits": [{"axis": "x", "zone": [0, 1], "to": 1' + "0" * 4300 + "}]}",
    '{"edits": [{"axis": "x", "zone": [0, 1], "to": 1e400}]}',
    '{"edits": [{"axis": "x", "zone": [0, NaN], "to": 1}]}',
    '{"edits": [{"axis": "x", "zone": [0, 1], "to": -Infinity}]}',
    '{"edits": [{"axis": "' + "x" * 100000 + '", "zone": [0, 1], "to": 2}]}',
    '{"edits": []}',
    "[1, 2]",
    "null",
]
ABSURD_NUMBERS = ["0", "-1", "1e300", "-1e300", "nan", "inf", "99999999999999999999", "1e-300", "x"]


def _mutate(data: bytes, rng: random.Random) -> bytes:
    kind = rng.choice(["truncate", "flip", "flip", "empty", "junk", "zero-run"])
    if kind == "truncate" or not data:
        return data[: rng.randrange(len(data) + 1)]
    if kind == "flip":
        b = bytearray(data)
        for _ in range(rng.randint(1, 8)):
            b[rng.randrange(len(b))] ^= 1 << rng.randrange(8)
        return bytes(b)
    if kind == "empty":
        return b""
    if kind == "junk":
        return bytes(rng.randrange(256) for _ in range(rng.randint(1, 512)))
    i = rng.randrange(len(data))
    return data[:i] + b"\0" * rng.randint(1, 64) + data[i + 64 :]


def _hostile_csdf(ball: partscale.CSDF, rng: random.Random) -> bytes:
    """A .csdf.npz whose arrays are each valid npy, with one hostile value."""
    arrays = {
        "sdf": ball.sdf,
        "rgb": ball.rgb,
        "parts": ball.parts,
        "origin": ball.origin,
        "voxel_size": np.float64(ball.voxel_size),
        "meta": np.array(json.dumps(ball.meta)),
    }
    name = rng.choice(list(arrays))
    bad = {
        "sdf": [ball.sdf * np.float32(1e38), ball.sdf.astype(np.float64), ball.sdf[:1]],
        "rgb": [ball.rgb.astype(np.float32), ball.rgb[..., :2]],
        "parts": [ball.parts.astype(np.float32), np.full(ball.shape, -5, np.int16)],
        "origin": [np.array([1e300, 0, 0]), np.array([np.nan, 0, 0]), np.zeros(2)],
        "voxel_size": [np.float64(1e300), np.float64(0), np.float64(-1), np.float64(1e-300)],
        "meta": [np.array(t) for t in HOSTILE_JSON] + [np.array('{"format": "x"}')],
    }[name]
    arrays[name] = bad[rng.randrange(len(bad))]
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for n, a in arrays.items():
            item = io.BytesIO()
            np.lib.format.write_array(item, np.asarray(a), allow_pickle=False)
            zf.writestr(f"{n}.npy", item.getvalue())
    return buf.getvalue()


def _cases(folder: Path) -> list[tuple[str, list[str]]]:
    """(description, argv) for every case; the input files are written into ``folder``."""
    rng = random.Random(SEED)
    ball = _ball()
    good = partscale.save(ball, folder / "good.csdf.npz")
    good_bytes = good.read_bytes()
    grid = np.asarray(ball.sdf)
    npy = io.BytesIO()
    np.save(npy, grid)
    sources = {
        ".csdf.npz": good_bytes,
        ".npy": npy.getvalue(),
        ".obj": OBJ.encode(),
        ".ply": PLY.encode(),
        ".json": json.dumps(RECIPE).encode(),
    }
    (folder / "m.mtl").write_text(MTL)
    cases = []
    for i in range(N_CASES):
        out = folder / f"out{i}"
        out.mkdir()
        kind = rng.choice(["csdf", "csdf", "hostile-csdf", "mesh", "npy", "recipe", "options"])
        if kind in ("csdf", "hostile-csdf"):
            f = folder / f"in{i}.csdf.npz"
            data = _mutate(good_bytes, rng) if kind == "csdf" else _hostile_csdf(ball, rng)
            f.write_bytes(data)
            cmd = rng.choice(
                [
                    ["info", f],
                    ["info", f, "--json"],
                    ["export", f, "--mesh", out / "o.glb"],
                    ["export", f, "--texture", out / "o.raw"],
                    [
                        "scale",
                        f,
                        "-o",
                        out / "o.csdf.npz",
                        "--axis",
                        "y",
                        "--zone",
                        "0%",
                        "50%",
                        "--to",
                        "60%",
                    ],
                ]
            )
        elif kind in ("mesh", "npy"):
            suffix = rng.choice([".obj", ".ply"]) if kind == "mesh" else ".npy"
            f = folder / f"in{i}{suffix}"
            f.write_bytes(_mutate(sources[suffix], rng))
            cmd = ["import", f, "-o", out / "o.csdf.npz", "--res", "16"]
        elif kind == "recipe":
            f = folder / f"in{i}.json"
            text = rng.choice([*HOSTILE_JSON, None])
            f.write_bytes(_mutate(sources[".json"], rng) if text is None else text.encode())
            cmd = ["scale", good, "-o", out / "o.csdf.npz", "--recipe", f]
        else:
            v = rng.choice(ABSURD_NUMBERS)
            cmd = rng.choice(
                [
                    ["import", folder / "m.obj", "-o", out / "o.csdf.npz", "--res", v],
                    ["import", folder / "m.obj", "-o", out / "o.csdf.npz", "--pad", v],
                    [
                        "scale",
                        good,
                        "-o",
                        out / "o.csdf.npz",
                        "--axis",
                        "x",
                        "--zone",
                        "0%",
                        "50%",
                        "--to",
                        v,
                    ],
                    [
                        "scale",
                        good,
                        "-o",
                        out / "o.csdf.npz",
                        "--axis",
                        "x",
                        "--zone",
                        v,
                        "50%",
                        "--to",
                        "60%",
                    ],
                    ["export", good, "--texture", out / "o.raw", "--grid", v],
                    ["render", good, "-o", out / "o.png", "--pixels", v],
                ]
            )
            f = None
        cases.append((f"case {i} ({kind}): partscale {' '.join(map(str, cmd))[:200]}", cmd))
    (folder / "m.obj").write_text(OBJ)
    return cases


def _run_cases(cases, root: Path, capsys, monkeypatch) -> dict[int, int]:
    """Run every (description, argv) in-process; each ends with exit 0 and no partscale line,
    or exit 2 and exactly one ``partscale: error:`` line; no hidden temporary under ``root``."""
    kinds = {0: 0, 2: 0}
    for what, cmd in cases:
        argv = [str(a) for a in cmd]
        monkeypatch.setattr(sys, "argv", ["partscale", *argv])
        capsys.readouterr()
        try:
            main(argv)
            code = 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        except BaseException as exc:  # a traceback is the failure this test exists for
            pytest.fail(f"{what}: raised {type(exc).__name__}: {str(exc)[:300]}")
        lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
        assert code in (0, 2), (what, code, lines)
        kinds[code] += 1
        if code == 2:
            assert len(lines) == 1 and lines[0].startswith("partscale: error: "), (what, lines)
            assert len(lines[0]) <= 1100, (what, len(lines[0]))
        else:
            assert not any(ln.startswith("partscale: ") for ln in lines), (what, lines)
        for p in root.rglob(".*"):  # no hidden temporaries anywhere
            pytest.fail(f"{what}: left {p}")
    return kinds


def test_every_case_is_one_line_or_success(tmp_path, capsys, monkeypatch):
    kinds = _run_cases(_cases(tmp_path), tmp_path, capsys, monkeypatch)
    # the fuzz reaches both outcomes (a generator that only made garbage would test little)
    assert kinds[0] >= 10 and kinds[2] >= 100, kinds


# -- structured input: JSON, CSV and option values that must be validated before use ----------

STRUCTURED_SEED = 40
N_STRUCTURED = 160
HOSTILE_VALUES = [
    10**25,
    -(10**25),
    [500],
    [[1]],
    json.loads("[" * 40 + "]" * 40),
    "500",
    "abc",
    "1.5",
    None,
    True,
    1e300,
    -1e300,
    1e-300,
    0,
    -1,
    {"a": 1},
    "x\u0000y",
    "",
    [],
]
"""JSON values of the wrong type, size or range: put in place of one value of a valid input."""
HOSTILE_CELLS = ["abc", "nan", "inf", "-1", "x\x00y", "1.5", "9" * 40, "1e3"]
"""Status-table cells no count (attempts) or state takes; the first five no figure (seconds)."""
HOSTILE_SIZES = ["1e308", "+1e308m", "1e300%", "-1e308m", "1e-300", "nan", "inf", "abc", "0"]
HOSTILE_MEMORY = ["inf", "1e308", "nanG", "-1G", "abc", "0", "1e400"]
HOSTILE_BOX = ["nan,0,10,10", "inf,0,10,10", "0,0,1e30,1e30", "-1e30,0,1,1", "a,b,c,d", "1,2,3"]
INTRINSICS = {"fx": 50, "fy": 50, "cx": 32, "cy": 24}
K9 = [[50, 0, 32], [0, 50, 24], [0, 0, 1]]
POSE = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]


def _poke(doc, rng: random.Random):
    """``doc`` (a JSON value) with one leaf or key's value replaced by a hostile value."""
    doc = json.loads(json.dumps(doc))
    parent, key = None, None
    node = doc
    while isinstance(node, dict | list) and node and (parent is None or rng.random() < 0.6):
        parent = node
        key = rng.choice(list(node)) if isinstance(node, dict) else rng.randrange(len(node))
        node = node[key]
    value = rng.choice(HOSTILE_VALUES)
    if parent is None:
        return value
    parent[key] = value
    return doc


def _structured_cases(folder: Path) -> list[tuple[str, list]]:
    """(description, argv) of hostile structured inputs; the files are written into ``folder``."""
    from PIL import Image
    from test_schema import _glb

    rng = random.Random(STRUCTURED_SEED)
    good = partscale.save(_ball(), folder / "good.csdf.npz")
    # an empty depth frame: a case its checks pass fails fast (no readings), still in one line
    Image.fromarray(np.zeros((48, 64), np.uint16)).save(folder / "d.png")
    from partscale.batch.status import COLUMNS

    cases = []
    for i in range(N_STRUCTURED):
        out = folder / f"out{i}"
        out.mkdir()
        kind = rng.choice(
            ["intrinsics", "views", "box", "status", "manifest", "recipe", "size", "memory",
             "budget", "mesh"]
        )  # fmt: skip
        f = folder / f"in{i}.json"
        if kind == "intrinsics":
            base = rng.choice([INTRINSICS, {"intrinsic_matrix": [v for row in K9 for v in row]}])
            f.write_text(json.dumps(_poke(base, rng)))
            cmd = [
                "complete",
                "--depth",
                folder / "d.png",
                "--intrinsics",
                f,
                "-o",
                out / "c.csdf.npz",
            ]
        elif kind == "views":
            view = {"depth": "d.png", "intrinsics": K9, "pose": POSE, "depth_scale": 5000}
            f.write_text(json.dumps([_poke(view, rng)]))
            cmd = ["complete", "--views", f, "-o", out / "c.csdf.npz"]
        elif kind == "box":
            k = folder / "k.json"
            k.write_text(json.dumps(INTRINSICS))
            cmd = ["complete", "--depth", folder / "d.png", "--intrinsics", k, "-o",
                   out / "c.csdf.npz", "--box", rng.choice(HOSTILE_BOX)]  # fmt: skip
        elif kind == "status":
            src = folder / f"src{i}"
            src.mkdir()
            (src / "ball.csdf.npz").write_bytes(good.read_bytes())
            row = dict.fromkeys(COLUMNS, "") | {"name": "ball", "state": "failed"}
            column = rng.choice(["attempts", "seconds", "peak_memory_mib", "state"])
            figures = column in ("seconds", "peak_memory_mib")  # 1e3 is a fine figure
            row[column] = rng.choice(HOSTILE_CELLS[:5] if figures else HOSTILE_CELLS)
            (out / "status.csv").write_text(
                ",".join(COLUMNS) + "\n" + ",".join(json.dumps(row[c]) for c in COLUMNS) + "\n"
            )
            cmd = ["batch", src, "-o", out, "--workers", "1"]
        elif kind == "manifest":
            key = rng.choice(["path", "name", "res", "square", "segment", "recipe", "size",
                              "render", "allow_deform"])  # fmt: skip
            row = {"path": str(good), key: rng.choice(HOSTILE_VALUES)}
            row["export"] = "bogus"  # a row its checks pass stops here: no job runs
            m = folder / f"m{i}.jsonl"
            m.write_text(json.dumps(row) + "\n")
            cmd = ["batch", m, "-o", out / "b", "--workers", "1"]
        elif kind == "recipe":
            edit = rng.choice(
                [
                    {"axis": "x", "zone": ["10%", "60%"], "to": "80%", "mode": "tile"},
                    {"normal": [1, 0, 0], "zone": [0.0, 0.1], "to": 0.2},
                    {"radial": {"center": [0, 0]}, "zone": [0.1, 0.2], "to": 0.25},
                    {"screw": {"axis": "x", "step": [0.1, 0.1, 0], "cut": 0.0}, "copies": 1},
                    {"axis": "x", "copies": "+1"},
                ]
            )
            f.write_text(json.dumps({"version": 1, "edits": [_poke(edit, rng)]}))
            cmd = ["scale", good, "-o", out / "o.csdf.npz", "--recipe", f]
        elif kind == "size":
            size = ["=", "=", "="]
            size[rng.randrange(3)] = rng.choice(HOSTILE_SIZES)
            cmd = ["fit", good, "-o", out / "o.csdf.npz", "--size", *size]
        elif kind == "memory":
            cmd = ["batch", good, "-o", out / "b", "--memory", rng.choice(HOSTILE_MEMORY)]
        elif kind == "budget":
            budget = rng.choice([["--error", "10"], ["--error", "1e308"], ["--faces", "4"]])
            cmd = ["export", good, "--mesh", out / "o.glb", *budget]
        else:
            mesh = rng.choice(
                [
                    _glb(indices=(0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, rng.randrange(4, 2**31))),
                    _glb(mode=rng.choice([0, 1, 3])),
                    _glb({"matrix": [0.0] * 16}),
                    _glb({"scale": [0, 0, 0]}),
                    _glb({"scale": [1e300, 1e300, 1e300]}),
                    _glb(extras="[" * (d := rng.randrange(65, 20001)) + "]" * d),
                    _glb(extras="1" + "0" * rng.randrange(31, 5000)),
                ]
            )
            f = folder / f"in{i}.glb"
            f.write_bytes(mesh)
            cmd = rng.choice(
                [
                    ["import", f, "-o", out / "o.csdf.npz", "--res", "16"],
                    ["scale", f, "-o", out / "o.glb", "--axis", "x", "--zone", "10%", "60%",
                     "--to", "80%"],
                ]
            )  # fmt: skip
        cases.append((f"case {i} ({kind}): partscale {' '.join(map(str, cmd))[:200]}", cmd))
    return cases


def test_structured_inputs_are_one_line_or_success(tmp_path, capsys, monkeypatch):
    kinds = _run_cases(_structured_cases(tmp_path), tmp_path, capsys, monkeypatch)
    assert kinds[2] >= 100, kinds


def test_server_survives_hostile_bodies(tmp_path):
    """Every hostile request body is a 4xx with one line, and the server keeps answering."""
    from starlette.testclient import TestClient

    from partscale.serve import create_app

    rng = random.Random(STRUCTURED_SEED)
    path = partscale.save(_ball(), tmp_path / "ball.csdf.npz")
    templates = [
        ("/api/apply", {"version": 1, "edits": [{"axis": "x", "zone": ["10%", "60%"], "to": "80%"}]}),
        ("/api/apply", {"version": 1, "edits": [{"normal": [1, 0, 0], "zone": [0, 0.1], "to": 0.2}]}),
        ("/api/snap", {"axis": "x", "zone": [0.0, 0.1], "to": 0.2, "mode": "tile"}),
        ("/api/fit", {"size": ["=", "=", "120%"], "allow_deform": False}),
        ("/api/add", {"axis": "x", "n": 1}),
        ("/api/save", {"overwrite": False, "revision": 1}),
    ]  # fmt: skip
    with TestClient(create_app(path), base_url="http://127.0.0.1") as client:
        for _ in range(150):
            url, body = rng.choice(templates)
            body = _poke(body, rng)
            r = client.post(url, json=body)
            assert r.status_code < 500, (url, body, r.status_code, r.text[:300])
            if r.status_code >= 400:
                msg = r.json()["error"]
                assert "\n" not in msg and len(msg) <= 1100, msg
            assert client.get("/api/state").status_code == 200
