"""Shared fixtures: where the real test objects are, and a temporary CLI runner."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("PARTSCALE_DATA", ROOT.parent / "shared" / "data"))


def data_path(rel: str) -> Path:
    """Path of a real object under ../shared/data, or skip the test with the reason."""
    p = DATA / rel
    if not p.exists():
        pytest.skip(f"test object {rel} not found under {DATA} (set PARTSCALE_DATA)")
    return p


def complete_tum_frame(box: tuple[int, int, int, int], res: int = 128):
    """The raw TUM RGB-D frame's object in ``box`` (pixels) completed upright at ``res``."""
    from partscale.complete import complete_file

    root = data_path("scans/tum_rgbd_frame")
    return complete_file(
        depth=root / "TUM_depth.png",
        color=root / "TUM_color.png",
        intrinsics=root / "camera_primesense.json",
        box=box,
        res=res,
        upright=True,
    )


@pytest.fixture
def data():
    return data_path


def run_cli(
    *args: str, check: bool = False, cwd: Path | None = None
) -> subprocess.CompletedProcess:
    """Run ``python -m partscale ARGS`` in a subprocess, as a user would, capturing output."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    env.setdefault("COLUMNS", "200")
    proc = subprocess.run(
        [sys.executable, "-m", "partscale", *map(str, args)],
        capture_output=True,
        text=True,
        env=env,
        cwd=cwd,
        timeout=600,
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"partscale {' '.join(map(str, args))} failed:\n{proc.stderr}")
    return proc


@pytest.fixture
def cli():
    return run_cli


def assert_bad_input(proc: subprocess.CompletedProcess, *fragments: str) -> None:
    """Exit code 2, exactly one line on stderr naming the problem, no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    for f in fragments:
        assert f.lower() in lines[0].lower(), (f, lines[0])


def gltf_validator_report(path: Path, *, required: bool = True) -> dict | None:
    """The Khronos glTF validator's JSON report on ``path``.

    When node or web/node_modules/gltf-validator is missing: skip the test if ``required``,
    else return None (the caller's other checks still run).
    """
    import json
    import shutil

    node = shutil.which("node")
    missing = None
    if node is None:
        missing = "node is not installed: cannot run the Khronos glTF validator"
    elif not (ROOT / "web" / "node_modules" / "gltf-validator").is_dir():
        missing = "web/node_modules/gltf-validator missing (run `npm ci` in web/)"
    if missing is not None:
        if required:
            pytest.skip(missing)
        return None
    proc = subprocess.run(
        [node, str(ROOT / "tests" / "tools" / "validate_gltf.mjs"), str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def render_glbs(*paths: Path) -> list[dict]:
    """Each GLB drawn by three.js's GLTFLoader in headless Chromium (tests/browser/glb_render.mjs).

    One dict per file: "unlit" and "lit", (256, 256, 3) uint8 RGB; black is background.
    Skips when node, Chromium or the web/ node modules are missing.
    """
    import base64
    import json

    import numpy as np
    from test_browser import WEB, find_tools

    node, chromium = find_tools()
    args = {"chromium": chromium, "web": str(WEB), "files": [str(p) for p in paths]}
    proc = subprocess.run(
        [node, str(ROOT / "tests" / "browser" / "glb_render.mjs"), json.dumps(args)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    assert not res["errors"], res["errors"]

    def pixels(b64: str) -> np.ndarray:
        return np.frombuffer(base64.b64decode(b64), np.uint8).reshape(256, 256, 4)[..., :3]

    return [{k: pixels(r[k]) for k in ("unlit", "lit")} for r in res["renders"]]
