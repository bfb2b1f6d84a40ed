"""The first run on a machine: where numba keeps the kernels, and the note while they compile."""

from __future__ import annotations

import os
import pty
import select
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT


def _on_a_terminal(args: list[str], env: dict, cwd: Path) -> tuple[int, str]:
    """Run ``python -m partscale ARGS`` with stderr on a pseudo-terminal (as a user's shell);
    returns the exit code and what the terminal showed."""
    leader, follower = pty.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "partscale", *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=follower,
        env=env,
        cwd=cwd,
    )
    os.close(follower)
    chunks = []
    while True:
        ready, _, _ = select.select([leader], [], [], 600)
        if not ready:
            proc.kill()
            break
        try:
            data = os.read(leader, 65536)
        except OSError:  # the terminal closed: the command ended
            break
        if not data:
            break
        chunks.append(data)
    os.close(leader)
    return proc.wait(timeout=60), b"".join(chunks).decode("utf-8", "replace")


def test_a_first_compile_says_so_once_on_a_terminal_and_not_after(tmp_path):
    """With nothing compiled (an empty numba cache), ``partscale info`` on a terminal prints one
    note that it is compiling and about how long for; run again (compiled), no note; with stderr
    piped (a script, CI), no note either (like the progress bars)."""
    from partscale import save, shapes

    src = tmp_path / "box.csdf.npz"
    save(shapes.box((0, 0, 0), (0.3, 0.2, 0.2), voxel_size=0.02), src)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), COLUMNS="300")
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    code, shown = _on_a_terminal(["info", str(src)], env, tmp_path)
    assert code == 0, shown
    assert shown.count("compiling partscale's kernels") == 1, shown
    assert "about 10 s for info" in shown and "python -m partscale.warmup" in shown, shown
    code, shown = _on_a_terminal(["info", str(src)], env, tmp_path)
    assert code == 0 and "compiling" not in shown, shown
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "cache2")
    proc = subprocess.run(
        [sys.executable, "-m", "partscale", "info", str(src)],
        env=env,
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 0 and "compiling" not in proc.stderr, proc.stderr


def _immutable(folder: Path, on: bool) -> bool:
    """chattr +i / -i every folder under ``folder`` (even root cannot write there then)."""
    chattr = shutil.which("chattr")
    if chattr is None:
        return False
    dirs = [str(p) for p in [folder, *folder.rglob("*")] if p.is_dir()]
    proc = subprocess.run([chattr, "+i" if on else "-i", *dirs], capture_output=True)
    return proc.returncode == 0


def test_a_read_only_install_caches_its_kernels_where_it_can(tmp_path):
    """partscale installed where nothing can be written (the package's folders immutable) and
    run by a user whose home cannot be written either: it still imports and runs (numba would
    refuse), its kernels cached in a per-user folder of the temporary directory; with a
    writable home, numba's own user cache is used and nothing is set."""
    pkg = tmp_path / "site" / "partscale"
    shutil.copytree(
        ROOT / "src" / "partscale", pkg, ignore=shutil.ignore_patterns("__pycache__", "*.nbi")
    )
    if not _immutable(tmp_path / "site", True):
        pytest.skip(
            "cannot make folders read-only here (chattr +i needs root's CAP_LINUX_IMMUTABLE)"
        )
    try:
        code = (
            "import os, partscale, partscale.thickness as t; from partscale import shapes;"
            "t.thin_features(shapes.box((0, 0, 0), (0.2, 0.2, 0.2), voxel_size=0.05));"
            "print(os.environ.get('NUMBA_CACHE_DIR'))"
        )
        base = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "HOME")}
        base["PYTHONPATH"] = str(tmp_path / "site")
        tmpdir = tmp_path / "tmp"
        tmpdir.mkdir()
        locked = dict(base, HOME=str(pkg), XDG_CACHE_HOME=str(pkg / "data"), TMPDIR=str(tmpdir))
        proc = subprocess.run(
            [sys.executable, "-c", code], env=locked, capture_output=True, text=True
        )
        assert proc.returncode == 0, proc.stderr[-2000:]
        used = Path(proc.stdout.strip())
        assert used.parent == tmpdir and used.name.startswith("partscale-numba-"), proc.stdout
        assert list(used.rglob("_thickness_kernel.thin_pass-*.nbc")), list(used.rglob("*"))
        home = tmp_path / "home"
        homely = dict(base, HOME=str(home), TMPDIR=str(tmpdir))
        homely.pop("XDG_CACHE_HOME", None)
        proc = subprocess.run(
            [sys.executable, "-c", code], env=homely, capture_output=True, text=True
        )
        assert proc.returncode == 0 and proc.stdout.strip() == "None", proc.stderr[-2000:]
        assert list((home / ".cache" / "numba").rglob("_thickness_kernel.thin_pass-*.nbc"))
    finally:
        _immutable(tmp_path / "site", False)
