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
