"""Hashed outputs of the whole pipeline, to show that a refactoring changed nothing.

For each object: import, segment, a stretch, a tile, a fit, the GLB and OBJ exports and a
render, each reduced to a SHA-256 of its arrays (or of the file's bytes). ``make`` writes the
hashes to a JSON file; ``check`` runs the same steps and lists every output whose hash differs.
Run ``make`` before a renovation and ``check`` after it, on the same machine (numba's parallel
reductions and BLAS may round differently on other CPUs)::

    python bench/baseline_outputs.py make /tmp/baseline.json
    python bench/baseline_outputs.py check /tmp/baseline.json

Objects: the table the package ships plus objects of ``../shared/data`` (``PARTSCALE_DATA``),
those absent skipped with a note. Not a test: it takes a minute or two at the default 64 voxels.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

import partscale
from partscale import data
from partscale.edit import apply_recipe, scale
from partscale.export import export_mesh
from partscale.ingest import load
from partscale.render import render
from partscale.segment import segment
from partscale.zones import fit

DATA = Path(
    os.environ.get("PARTSCALE_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)
OBJECTS = [
    "kenney/table.glb",
    "kenney/bookcaseOpen.glb",
    "kenney/tableRound.glb",
    "sweethome3d/dresser.obj",
    "sweethome3d/bookcase.obj",
    "polyhaven/sofa_03/sofa_03_1k.gltf",
    "khronos/SheenChair.glb",
]


def _digest(*arrays: np.ndarray) -> str:
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()[:16]


def _csdf_digest(c: partscale.CSDF) -> str:
    parts = c.parts if c.parts is not None else np.zeros(0, np.int32)
    return _digest(c.sdf, c.rgb, parts, np.asarray(c.origin, np.float64), np.float64(c.voxel_size))


def _file_digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16]


def object_hashes(path: Path, res: int, tmp: Path) -> dict[str, str]:
    """Hashes of every step's output on one object, keyed by the step's name."""
    out: dict[str, str] = {}
    c = load(path, res=res)
    out["import"] = _csdf_digest(c)
    c = segment(c, cache=False)
    out["segment"] = _csdf_digest(c)
    out["stretch"] = _csdf_digest(scale(c, axis="x", zone=("35%", "65%"), to="80%"))
    out["tile"] = _csdf_digest(scale(c, axis="x", zone=("35%", "65%"), to="95%", mode="tile"))
    try:
        recipe, _ = fit(c, ["120%", "=", "="], allow_deform=True)
        out["fit"] = _csdf_digest(apply_recipe(c, recipe))
    except partscale.InputError as err:
        out["fit"] = f"refused: {err}"
    for suffix in (".glb", ".obj"):
        dest = export_mesh(c, tmp / f"out{suffix}")
        out[f"export{suffix}"] = _file_digest(dest)
    out["render"] = _digest(render(c, size=128))
    return out


def all_hashes(res: int, log: Callable[[str], None]) -> dict[str, dict[str, str]]:
    """Hashes of every object present (the shipped table first)."""
    paths = {"shipped/table.glb": Path(data.table())}
    for rel in OBJECTS:
        p = DATA / rel
        if p.exists():
            paths[rel] = p
        else:
            log(f"note: {rel} not found under {DATA}; skipped")
    result = {}
    with tempfile.TemporaryDirectory() as d:
        for name, p in paths.items():
            log(f"{name} ...")
            result[name] = object_hashes(p, res, Path(d))
    return result


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("action", choices=["make", "check"])
    ap.add_argument("baseline", type=Path, help="the JSON file of hashes")
    ap.add_argument("--res", type=int, default=64)
    args = ap.parse_args(argv)

    def log(msg: str) -> None:
        print(msg, file=sys.stderr)

    got = all_hashes(args.res, log)
    if args.action == "make":
        args.baseline.write_text(json.dumps({"res": args.res, "hashes": got}, indent=1) + "\n")
        print(f"wrote {sum(len(v) for v in got.values())} hashes of {len(got)} objects")
        return 0
    want = json.loads(args.baseline.read_text())["hashes"]
    changed = [
        f"{obj} {step}: {want.get(obj, {}).get(step)} -> {h}"
        for obj, steps in got.items()
        for step, h in steps.items()
        if want.get(obj, {}).get(step) != h
    ]
    print("\n".join(changed) if changed else f"all {sum(len(v) for v in got.values())} identical")
    return 1 if changed else 0


if __name__ == "__main__":
    raise SystemExit(main())
