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


def test_every_case_is_one_line_or_success(tmp_path, capsys, monkeypatch):
    cases = _cases(tmp_path)
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
        for p in tmp_path.rglob(".*"):  # no hidden temporaries anywhere
            pytest.fail(f"{what}: left {p}")
    # the fuzz reaches both outcomes (a generator that only made garbage would test little)
    assert kinds[0] >= 10 and kinds[2] >= 100, kinds
