"""Assets for engines: budgeted, atlased export beside the full-resolution export; the mesh
route's edit beside the CSDF route's, same run.

- export: ``export_mesh(csdf, OUT.glb, faces=20000, atlas=1024)`` (marching cubes, meshoptimizer,
  xatlas, bake) against ``export_mesh(csdf, OUT.glb, error=None)`` (full resolution, vertex
  colours: what ``export`` wrote before budgets), on khronos/SheenChair at ``--res 128``;
  the stages of the atlased export are timed separately.
- edit: the suite's ``bookshelf-two-shelves`` tile (polyhaven/wooden_bookshelf_worn) by
  :func:`partscale.meshedit.apply_recipe_to_scene` (the source mesh, loading and writing not
  counted) against :func:`partscale.edit.apply_recipe` on its CSDF at ``--res 128`` (import not
  counted), medians of ``--repeat``.

Run: ``PYTHONPATH=src .venv/bin/python bench/bench_assets.py [--repeat 3]``
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from _timing import timed

from partscale import export, ingest
from partscale.edit import Recipe, apply_recipe
from partscale.meshedit import apply_recipe_to_scene, load_scene
from partscale.surface import to_mesh

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
CHAIR = DATA / "khronos" / "SheenChair.glb"
SHELF = DATA / "polyhaven" / "wooden_bookshelf_worn" / "wooden_bookshelf_worn_1k.gltf"
SHELF_EDIT = {"axis": "y", "zone": ["24.5%", "38.3%"], "to": "65.9%", "mode": "tile"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    c = ingest.load(CHAIR, res=128)
    print(f"SheenChair at 128: {' x '.join(map(str, c.shape))} voxels")
    with tempfile.TemporaryDirectory() as d:
        full = Path(d) / "full.glb"
        small = Path(d) / "small.glb"
        t_full, _ = timed(lambda: export.export_mesh(c, full), args.repeat)
        t_small, _ = timed(
            lambda: export.export_mesh(c, small, faces=20000, atlas=1024), args.repeat
        )
        # the atlased export's stages, once
        t0 = time.perf_counter()
        mesh = to_mesh(c)
        t1 = time.perf_counter()
        dec = export.simplify(mesh, voxel_size=c.voxel_size, faces=20000)
        t2 = time.perf_counter()
        vmap, faces, uv = export.unwrap(dec.vertices, dec.faces, 1024)
        t3 = time.perf_counter()
        export.bake(c, dec.vertices[vmap], faces, uv, 1024)
        t4 = time.perf_counter()
        print(
            f"export full resolution (vertex colours): {t_full:.2f} s, "
            f"{len(mesh.faces):,} triangles, {full.stat().st_size / 1024:,.0f} KB"
        )
        print(
            f"export --faces 20000 --atlas 1024: {t_small:.2f} s, {len(dec.faces):,} triangles, "
            f"{small.stat().st_size / 1024:,.0f} KB  (marching cubes {t1 - t0:.2f} s, "
            f"meshoptimizer {t2 - t1:.2f} s, xatlas {t3 - t2:.2f} s, bake {t4 - t3:.2f} s)"
        )
    recipe = Recipe.parse([SHELF_EDIT])
    scene = load_scene(SHELF)
    t_mesh, (out, seams) = timed(lambda: apply_recipe_to_scene(scene, recipe), args.repeat)
    n_in = sum(len(g.faces) for g in scene.geometry.values())
    n_out = sum(len(g.faces) for g in out.geometry.values())
    shelf = ingest.load(SHELF, res=128)
    t_csdf, _ = timed(lambda: apply_recipe(shelf, recipe), args.repeat)
    welded = sum(s.ok for s in seams)
    print(
        f"mesh route, bookshelf tile (+2 shelves): {t_mesh * 1000:.0f} ms, "
        f"{n_in:,} -> {n_out:,} triangles, {welded}/{len(seams)} seams welded"
    )
    print(
        f"CSDF route, same recipe at 128 ({' x '.join(map(str, shelf.shape))}): "
        f"{t_csdf * 1000:.0f} ms (import not counted)"
    )


if __name__ == "__main__":
    main()
