"""Editor round trips on a 128³ (or ``--res N``) object: HTTP apply (+ grid download) against
in-process apply_recipe.

Usage: PYTHONPATH=src python bench/bench_editor.py [--repeat 5] [--frames 0] [--res 128 256]

Prints a table of median times. The baseline is ``apply_recipe`` called in this process on the
same object and recipe; the HTTP figures add what the editor adds: JSON request, the lock, the
undo stack, finding the layers the edit changed, their encoding (float16 distance + sRGB bytes)
and their download over loopback, as the page asks for them (``GET /api/grid?base=N``, N the
revision it shows). ``--frames N`` also renders
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

import partscale  # noqa: E402
from partscale import shapes  # noqa: E402
from partscale.edit import apply_recipe  # noqa: E402
from partscale.serve import GRID_BYTES_PER_VOXEL, encode_grid  # noqa: E402

RECIPE = {"edits": [{"axis": "x", "zone": ["35%", "65%"], "to": "80%", "mode": "stretch"}]}


def table(res: int = 128) -> partscale.CSDF:
    """A table filling a unit cube: (res + 1)³ voxels (res - 6 + 2 x 3 margin + 1)."""
    h = 1.0 / (res - 6)
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
    """``partscale editor PATH --no-browser`` in a subprocess, as a user runs it."""

    def __init__(self, path: Path):
        import os

        env = dict(os.environ)
        # the same partscale this script imported
        env["PYTHONPATH"] = str(Path(partscale.__file__).resolve().parents[1])
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "partscale", "editor", str(path), "--no-browser"],
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        self.url = ""

    def __enter__(self):
        import re

        import httpx

        assert self.proc.stderr is not None  # started with stderr=PIPE
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
        if self.proc.stderr is not None:
            self.proc.stderr.close()


def ms_since(t0: float) -> float:
    return (time.perf_counter() - t0) * 1000


def browser_frames(url: str, frames: int, out: str) -> tuple[dict, str] | None:
    """Frame time at 1280x720 in headless Chromium (software rendering here), or None."""
    node, chromium = shutil.which("node"), shutil.which("chromium")
    if not (node and chromium):
        print("frame time: skipped (node or chromium not found)")
        return None
    args = {
        "url": url,
        "chromium": chromium,
        "web": str(ROOT / "web"),
        "out": out,
        "canvas": [1280, 720],
        "benchmark": frames,
    }
    proc = subprocess.run(
        [node, str(ROOT / "tests/browser/editor.mjs"), json.dumps(args)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    res = json.loads(proc.stdout.splitlines()[-1])
    return res["benchmark"], res["renderer"]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--frames", type=int, default=0)
    ap.add_argument("--res", type=int, nargs="+", default=[128], help="resolutions, in turn")
    args = ap.parse_args()
    # as the CLI does (the editor runs under it): freed grids' pages are reused
    print(f"freed memory reused (glibc): {'yes' if partscale.reuse_freed_memory() else 'no'}")
    for res in args.res:
        run(res, args.repeat, args.frames)


def run(res: int, repeat: int, frames: int) -> None:
    import httpx

    c = table(res)
    times: dict[str, list[float]] = {k: [] for k in ROWS}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"table{res}.csdf.npz"
        partscale.save(c, path)
        apply_recipe(c, RECIPE)  # warm: numba caches, imports
        with EditorProcess(path) as server, httpx.Client(base_url=server.url, timeout=60) as client:
            client.post("api/apply", json=RECIPE).raise_for_status()  # warm the server too
            client.post("api/undo", json={}).raise_for_status()
            shown = int(client.get("api/grid").headers["x-partscale-revision"])  # the page's
            sent: list[int] = []
            # interleaved, so load from other processes hits baseline and editor alike
            for _ in range(repeat):
                t0 = time.perf_counter()
                out = apply_recipe(c, RECIPE)
                times["baseline"].append(ms_since(t0))
                t0 = time.perf_counter()
                encode_grid(out)
                times["encode"].append(ms_since(t0))
                t0 = time.perf_counter()
                r = client.post("api/apply", json=RECIPE)
                r.raise_for_status()
                times["post"].append(ms_since(t0))
                times["server"].append(r.json()["apply_ms"])
                g = client.get("api/grid", params={"base": shown})
                times["round"].append(ms_since(t0))
                shown = check_delta(g, r.json()["shape"])
                sent.append(len(g.content))
                t0 = time.perf_counter()
                client.post("api/undo", json={}).raise_for_status()
                g = client.get("api/grid", params={"base": shown})
                times["undo"].append(ms_since(t0))
                shown = check_delta(g, c.shape)
            frame = browser_frames(server.url, frames, tmp) if frames else None
    base = statistics.median(times["baseline"])
    print(f"editor round trips, {'x'.join(map(str, c.shape))} grid, {repeat} runs")
    print(f"{'step':52s} {'median ms':>10s} {'min ms':>8s} {'x baseline':>11s}")
    for key, name in ROWS.items():
        med = statistics.median(times[key])
        print(f"{name:52s} {med:10.1f} {min(times[key]):8.1f} {med / base:11.2f}")
    whole = np.prod(out.shape) * GRID_BYTES_PER_VOXEL
    print(
        f"grid sent after apply: {statistics.median(sent) / 1e6:.1f} MB "
        f"(the whole {'x'.join(map(str, out.shape))} grid: {whole / 1e6:.1f} MB)"
    )
    if frame:
        b, renderer = frame
        print(
            f"frame at 1280x720 ({renderer}): mean {b['mean']:.1f} ms, median {b['median']:.1f} ms"
            f" over {b['n']} frames"
        )


def check_delta(r, shape) -> int:
    """The revision of a grid answer, after checking it holds the changed layers of ``shape``."""
    assert r.headers["x-partscale-shape"] == ",".join(map(str, shape))
    axis, head, tail = map(int, r.headers["x-partscale-delta"].split(","))
    body = list(shape)
    body[axis] -= head + tail
    assert len(r.content) == np.prod(body) * GRID_BYTES_PER_VOXEL
    return int(r.headers["x-partscale-revision"])


ROWS = {
    "baseline": "apply_recipe in process (baseline)",
    "encode": "encode_grid in process (whole grid, 5 B a voxel)",
    "server": "server: apply_recipe + changed layers (apply_ms)",
    "post": "HTTP POST /api/apply",
    "round": "HTTP apply + GET /api/grid?base (round trip)",
    "undo": "HTTP undo + GET /api/grid?base",
}


if __name__ == "__main__":
    main()
