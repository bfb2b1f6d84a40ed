"""The demo of ``./dev.sh setup`` on a fresh clone: the shipped table, no test data beside it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
from conftest import ROOT


def test_shipped_table_is_the_packaged_cc0_file_and_imports():
    from partscale import data, ingest

    path = data.table()
    assert path.is_file() and path.suffix == ".glb"
    licence = path.parent / "LICENSE_Kenney.txt"
    assert "Creative Commons Zero" in licence.read_text(encoding="utf-8")
    c = ingest.load(path, res=48)
    sb = c.surface_bounds()
    ext = sb[1] - sb[0]
    # a table: longer (x) than deep (z), deeper than tall (y); standing on the floor (y = 0)
    assert ext[0] > ext[2] > ext[1] > 0.5, ext
    assert abs(sb[0, 1]) <= c.voxel_size, sb


def test_python_m_partscale_data_prints_the_path():
    proc = subprocess.run(
        [sys.executable, "-m", "partscale.data", "table"], capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr
    from partscale import data

    assert Path(proc.stdout.strip()) == data.table()
    bad = subprocess.run(
        [sys.executable, "-m", "partscale.data", "chair"], capture_output=True, text=True
    )
    assert bad.returncode == 2 and "expected one of table" in bad.stderr


def test_demo_runs_on_a_fresh_clone_without_test_data(tmp_path):
    """``dev.sh``'s demo steps (what ``./dev.sh setup`` runs after installing), from a copy of
    ``dev.sh`` in a folder with no ``../shared`` beside it and PARTSCALE_DATA at an empty folder:
    the pictures and the GLB are written and the longer table is 40% longer."""
    clone = tmp_path / "clone"
    clone.mkdir()
    shutil.copy(ROOT / "dev.sh", clone / "dev.sh")
    empty = tmp_path / "empty"
    empty.mkdir()
    out = tmp_path / "out"
    env = dict(os.environ)
    env.pop("PARTSCALE_DEMO_OBJECT", None)
    env.update(
        PARTSCALE_PYTHON=sys.executable,
        PARTSCALE_DEMO_OUT=str(out),
        PARTSCALE_DATA=str(empty),
        PARTSCALE_CACHE=str(tmp_path / "cache"),
    )
    proc = subprocess.run(
        ["bash", str(clone / "dev.sh"), "demo-steps"],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert not (tmp_path / "shared").exists()
    for name in ("table.png", "table_parts.png", "table_longer.png", "table_longer.glb"):
        assert (out / name).stat().st_size > 1000, name
    from partscale import load

    before, after = load(out / "table.csdf.npz"), load(out / "table_longer.csdf.npz")
    assert before.n_parts >= 3  # top, legs, rails
    ext = [c.surface_bounds()[1] - c.surface_bounds()[0] for c in (before, after)]
    # zone 35%..65% with its end taken to 105%: 40% of the length added, within two voxels
    assert abs(ext[1][0] - 1.4 * ext[0][0]) <= 2 * before.voxel_size, ext
    np.testing.assert_allclose(ext[1][1:], ext[0][1:], atol=before.voxel_size)
