"""Editor round trips on a 128³ object: HTTP apply (+ grid download) against in-process apply_recipe.

Usage: PYTHONPATH=src python bench/bench_editor.py [--repeat 5] [--frames 0]

Prints a table of median times. The baseline is ``apply_recipe`` called in this process on the
same object and recipe; the HTTP figures add what the editor adds: JSON request, the lock, the
undo stack, the float16 grid encoding and its download over loopback. ``--frames N`` also renders
N frames at 1280x720 in headless Chromium (software rendering here: not a GPU measure).
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

from partscale import csdf as csdf_mod  # noqa: E402
from partscale import shapes  # noqa: E402
from partscale.edit import apply_recipe  # noqa: E402
from partscale.serve import encode_grid  # noqa: E402

RECIPE = {"edits": [{"axis": "x", "zone": ["35%", "65%"], "to": "80%", "mode": "stretch"}]}


def table_128() -> csdf_mod.CSDF:
    """A table filling a unit cube: 129³ voxels (122 + 2 x 3 margin + 1)."""
    h = 1.0 / 122
    top = ((0.0, 0.9, 0.0), (1.0, 1.0, 1.0))
    legs = [((x, 0.0, z), (x + 0.08, 0.9, z + 0.08)) for x in (0.04, 0.88) for z in (0.04, 0.88)]

    def colour(p):
        return np.stack(
            [np.full(len(p), 200), 120 + 100 * (p[:, 1] > 0.89), 60 + 150 * p[:, 0].clip(0, 1)],
            -1,
        )

    return shapes.grid(
        lambda p: shapes.boxes_sdf(p, [top, *legs]),
        ((0, 0, 0), (1, 1, 1)),
        voxel_size=h,
        color=colour,
        source="bench table",
    )


class EditorProcess:
    """``partscale edit PATH --no-browser`` in a subprocess, as a user runs it."""

    def __init__(self, path: Path):
        import os

        env = dict(os.environ)
        import partscale

        # the same partscale this script imported
        env["PYTHONPATH"] = str(Path(partscale.__file__).resolve().parents[1])
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "partscale", "edit", str(path), "--no-browser"],
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        self.url = ""

    def __enter__(self):
        import re

        import httpx

        for line in self.proc.stderr:
            m = re.search(r"(http://\S+/)", line)
            if m:
                self.url = m.group(1)
                break
        for _ in range(200):
            try:
                httpx.get(self.url + "api/state", timeout=5)
                return self
            except httpx.ConnectError:
                time.sleep(0.05)
        raise RuntimeError("editor did not start")

    def __exit__(self, *exc):
        self.proc.terminate()
        self.proc.wait(timeout=20)
        self.proc.stderr.close()


def median_ms(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1000)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--frames", type=int, default=0)
    args = ap.parse_args()

    import httpx

    c = table_128()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "table128.csdf.npz"
        csdf_mod.save(c, path)
        base = median_ms(lambda: apply_recipe(c, RECIPE), args.repeat)
        rows.append(("apply_recipe in process (baseline)", base))
        out = apply_recipe(c, RECIPE)
        rows.append(("encode_grid (float16 RGBA)", median_ms(lambda: encode_grid(out), 3)))
        with EditorProcess(path) as server, httpx.Client(base_url=server.url, timeout=60) as client:
            client.get("api/grid")

            def apply_only():
                r = client.post("api/apply", json=RECIPE)
                r.raise_for_status()
                client.post("api/undo", json={}).raise_for_status()

            def round_trip():
                r = client.post("api/apply", json=RECIPE)
                r.raise_for_status()
                grid = client.get("api/grid").content
                assert len(grid) == np.prod(r.json()["shape"]) * 8
                client.post("api/undo", json={}).raise_for_status()

            undo = median_ms(lambda: client.post("api/undo", json={}), 1)  # warm (409)
            del undo
            # undo itself is O(1); time it separately and subtract from the loops
            client.post("api/apply", json=RECIPE).raise_for_status()
            t_undo = (
                median_ms(
                    lambda: (client.post("api/undo", json={}), client.post("api/redo", json={})),
                    args.repeat,
                )
                / 2
            )
            client.post("api/undo", json={})
            rows.append(("HTTP POST /api/apply", median_ms(apply_only, args.repeat) - t_undo))
            rows.append(
                (
                    "HTTP apply + GET /api/grid (round trip)",
                    median_ms(round_trip, args.repeat) - t_undo,
                )
            )
            frame = None
            if args.frames:
                node, chromium = shutil.which("node"), shutil.which("chromium")
                if node and chromium:
                    res = json.loads(
                        subprocess.run(
                            [
                                node,
                                str(ROOT / "tests/browser/editor.mjs"),
                                json.dumps(
                                    {
                                        "url": server.url,
                                        "chromium": chromium,
                                        "web": str(ROOT / "web"),
                                        "out": tmp,
                                        "canvas": [1280, 720],
                                        "benchmark": args.frames,
                                    }
                                ),
                            ],
                            capture_output=True,
                            text=True,
                            timeout=600,
                        ).stdout.splitlines()[-1]
                    )
                    frame = res.get("benchmark"), res.get("renderer")
    print(f"editor round trips, {'x'.join(map(str, c.shape))} grid, median of {args.repeat}")
    print(f"{'step':44s} {'ms':>9s} {'x baseline':>11s}")
    for name, ms in rows:
        print(f"{name:44s} {ms:9.1f} {ms / base:11.2f}")
    if frame:
        (b, renderer) = frame
        print(
            f"frame at 1280x720 ({renderer}): mean {b['mean']:.1f} ms, median {b['median']:.1f} ms"
            f" over {b['n']} frames"
        )


if __name__ == "__main__":
    main()
