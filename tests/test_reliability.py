"""Hostile inputs and faults (issue 14): each is one line on stderr, exit 2, nothing left behind.

The commands run in-process through :func:`partscale.cli.main` (as the console script does),
so a traceback shows up as an exception here rather than as text.
"""

from __future__ import annotations

import errno
import io
import json
import os
import signal
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

import partscale
from partscale import shapes
from partscale.cli import main

H = 0.04


@pytest.fixture(scope="module")
def ball_file(tmp_path_factory) -> Path:
    c = shapes.grid(
        lambda p: np.linalg.norm(p, axis=-1) - 0.3, ((-0.4,) * 3, (0.4,) * 3), voxel_size=H
    )
    return partscale.save(c, tmp_path_factory.mktemp("in") / "ball.csdf.npz")


def run(capsys, monkeypatch, *args) -> tuple[int, list[str]]:
    """``partscale ARGS`` in-process: (exit code, non-empty stderr lines)."""
    monkeypatch.setattr(sys, "argv", ["partscale", *map(str, args)])  # no pytest -v
    capsys.readouterr()
    try:
        main([str(a) for a in args])
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    err = capsys.readouterr().err
    return code, [ln for ln in err.splitlines() if ln.strip()]


def assert_one_line(code: int, lines: list[str], *fragments: str) -> None:
    assert code == 2, (code, lines)
    assert len(lines) == 1, lines
    assert lines[0].startswith("partscale: error: ")
    for f in fragments:
        assert f.lower() in lines[0].lower(), (f, lines[0])


def only(folder: Path, *names: str) -> None:
    """Nothing but ``names`` in ``folder`` (no output, no hidden temporary)."""
    assert sorted(p.name for p in folder.iterdir()) == sorted(names)


def npz_with(path: Path, **arrays) -> Path:
    """A .csdf.npz-like zip of the given arrays (each a numpy array)."""
    with zipfile.ZipFile(path, "w") as zf:
        for name, a in arrays.items():
            buf = io.BytesIO()
            np.lib.format.write_array(buf, np.asarray(a), allow_pickle=False)
            zf.writestr(f"{name}.npy", buf.getvalue())
    return path


def ball_arrays(ball_file: Path) -> dict:
    c = partscale.load(ball_file)
    return {
        "sdf": c.sdf,
        "rgb": c.rgb,
        "parts": c.parts,
        "origin": c.origin,
        "voxel_size": np.float64(c.voxel_size),
        "meta": np.array(json.dumps(c.meta)),
    }


# -- 2: loading has a memory check -----------------------------------------------------------


def test_declared_petabytes_refused_before_reading(tmp_path, capsys, monkeypatch):
    f = tmp_path / "huge.csdf.npz"
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f4", "fortran_order": False, "shape": (10**6, 10**6, 10**6)}
    )
    with zipfile.ZipFile(f, "w") as zf:
        zf.writestr("sdf.npy", b"\x93NUMPY\x01\x00" + header.getvalue()[8:])
    code, lines = run(capsys, monkeypatch, "info", f)
    assert_one_line(code, lines, str(f), "would need", "memory")


def test_load_over_the_memory_limit_refused(ball_file, capsys, monkeypatch):
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", "100000")  # the ball's arrays are ~200 kB
    code, lines = run(capsys, monkeypatch, "info", ball_file)
    assert_one_line(code, lines, "would need")


def test_load_keeps_one_copy_of_the_arrays(tmp_path):
    import tracemalloc

    n = 64
    c = partscale.make(np.ones((n, n, n), np.float32))
    f = partscale.save(c, tmp_path / "b.csdf.npz", compress=False)
    arrays = n**3 * (4 + 3 + 2)
    tracemalloc.start()
    try:
        loaded = partscale.load(f)
        _cur, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert loaded.shape == (n, n, n)
    # the arrays once, plus the finiteness mask and the zip's buffers; a second copy is 2x
    assert peak < 1.5 * arrays, peak / arrays


# -- 3: disk full ----------------------------------------------------------------------------


def test_disk_full_is_one_line_naming_the_destination(ball_file, tmp_path, capsys, monkeypatch):
    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np.lib.format, "write_array", full)
    out = tmp_path / "o.csdf.npz"
    code, lines = run(
        capsys, monkeypatch, "scale", ball_file, "-o", out, "--axis", "x", "--zone", "0%",
        "50%", "--to", "0.2",
    )  # fmt: skip
    assert_one_line(code, lines, str(out), "no space left")
    only(tmp_path)


# -- 5: one hardened JSON reader ---------------------------------------------------------------

HOSTILE_JSON = {
    "deep": "[" * 100000 + "]" * 100000,
    "big int": '{"edits": [{"axis": "x", "zone": [0, 1], "to": 1' + "0" * 4300 + "}]}",
    "1e400": '{"edits": [{"axis": "x", "zone": [0, 1], "to": 1e400}]}',
    "NaN": '{"edits": [{"axis": "x", "zone": [0, NaN], "to": 1}]}',
    "Infinity": '{"edits": [{"axis": "x", "zone": [0, 1], "to": -Infinity}]}',
}


@pytest.mark.parametrize("name", HOSTILE_JSON)
def test_hostile_recipe_is_one_line(name, ball_file, tmp_path, capsys, monkeypatch):
    recipe = tmp_path / "r.json"
    recipe.write_text(HOSTILE_JSON[name])
    out = tmp_path / "o.csdf.npz"
    code, lines = run(capsys, monkeypatch, "scale", ball_file, "-o", out, "--recipe", recipe)
    assert_one_line(code, lines, str(recipe))
    only(tmp_path, "r.json")


@pytest.mark.parametrize("name", HOSTILE_JSON)
def test_hostile_suite_is_one_line(name, tmp_path, capsys, monkeypatch):
    suite = tmp_path / "s.json"
    suite.write_text(HOSTILE_JSON[name])
    code, lines = run(capsys, monkeypatch, "eval", suite, "-o", tmp_path / "out")
    assert_one_line(code, lines, str(suite))


@pytest.mark.parametrize("name", ["deep", "big int", "1e400", "NaN", "Infinity"])
def test_hostile_meta_is_one_line(name, ball_file, tmp_path, capsys, monkeypatch):
    arrays = ball_arrays(ball_file)
    meta = json.loads(str(arrays["meta"]))
    text = json.dumps(meta)
    bad = {
        "deep": '"x": ' + "[" * 100000 + "]" * 100000,
        "big int": '"x": 1' + "0" * 4300,
        "1e400": '"x": 1e400',
        "NaN": '"x": NaN',
        "Infinity": '"x": Infinity',
    }[name]
    arrays["meta"] = np.array(text[:-1] + ", " + bad + "}")
    f = npz_with(tmp_path / "m.csdf.npz", **arrays)
    code, lines = run(capsys, monkeypatch, "info", f, "--json")
    assert_one_line(code, lines, str(f), "meta")


def test_meta_with_nan_is_refused_by_make():
    with pytest.raises(partscale.errors.InputError, match="meta"):
        partscale.make(np.ones((4, 4, 4), np.float32), meta={"x": float("nan")})


def test_hostile_json_is_refused_by_the_server_too(ball_file):
    # the editor's request bodies go through the same hardened reader as recipes and meta
    from starlette.testclient import TestClient

    from partscale.serve import create_app

    app = create_app(ball_file, max_body=1 << 20)  # room for the 200 kB nesting
    with TestClient(app, base_url="http://127.0.0.1") as client:
        for text in HOSTILE_JSON.values():
            r = client.post(
                "/api/apply", content=text.encode(), headers={"content-type": "application/json"}
            )
            assert r.status_code == 400, r.text
            assert r.json()["error"].startswith("request body: expected"), r.json()
        assert client.get("/api/state").json()["revision"] == 0


# -- 6: finite but absurd values ---------------------------------------------------------------


@pytest.mark.parametrize(
    "field, value, fragment",
    [
        ("voxel_size", np.float64(1e300), "voxel size"),
        ("voxel_size", np.float64(1e-300), "voxel size"),
        ("origin", np.array([1e300, 0.0, 0.0]), "origin"),
        ("sdf", "3e38", "sdf"),
    ],
)
def test_absurd_values_refused_on_load(
    field, value, fragment, ball_file, tmp_path, capsys, monkeypatch
):
    arrays = ball_arrays(ball_file)
    if field == "sdf":
        sdf = arrays["sdf"].copy()
        sdf[0, 0, 0] = 3e38
        value = sdf
    arrays[field] = value
    f = npz_with(tmp_path / "a.csdf.npz", **arrays)
    for command in (["info", f], ["export", f, "--mesh", tmp_path / "a.glb"]):
        code, lines = run(capsys, monkeypatch, *command)
        assert_one_line(code, lines, str(f), fragment)
    only(tmp_path, "a.csdf.npz")


def test_obj_vertex_inf_is_one_line(tmp_path, capsys, monkeypatch):
    obj = tmp_path / "t.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 inf\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
    code, lines = run(capsys, monkeypatch, "import", obj, "-o", tmp_path / "t.csdf.npz")
    assert_one_line(code, lines, str(obj))
    only(tmp_path, "t.obj")


# -- 7: huge --res / --pad ---------------------------------------------------------------------


@pytest.mark.parametrize("option", ["--res", "--pad"])
def test_huge_res_and_pad_refused(option, tmp_path, capsys, monkeypatch):
    grid = tmp_path / "g.npy"
    x = np.linspace(-1, 1, 20)
    np.save(
        grid, (np.sqrt(sum(np.meshgrid(x, x, x, indexing="ij")[i] ** 2 for i in range(3))) - 0.5)
    )
    code, lines = run(
        capsys, monkeypatch, "import", grid, "-o", tmp_path / "g.csdf.npz", option,
        "99999999999999999999",
    )  # fmt: skip
    assert_one_line(code, lines, option)
    only(tmp_path, "g.npy")


# -- 10: a texture and its sidecar are one pair ------------------------------------------------


@pytest.mark.parametrize("suffix", [".raw", ".png"])
def test_interrupted_pair_write_is_never_misread(suffix, ball_file, tmp_path, monkeypatch):
    from partscale import export

    c = partscale.load(ball_file)
    tex = tmp_path / f"t{suffix}"
    export.export_texture(c, tex)
    real = os.replace

    def second_fails(src, dst):
        if str(dst).endswith(".json"):
            raise OSError(errno.EIO, "Input/output error")
        return real(src, dst)

    # same grid size (the old sidecar would fit), other content
    moved = c.replace(sdf=c.sdf + np.float32(H), origin=c.origin + 1.0)
    monkeypatch.setattr(os, "replace", second_fails)
    with pytest.raises(partscale.errors.InputError, match="json"):
        export.export_texture(moved, tex)
    monkeypatch.setattr(os, "replace", real)
    # the pair is renamed as one set: the texture renamed before the failure is put back
    np.testing.assert_allclose(export.read_texture(tex).origin, c.origin)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    export.export_texture(moved, tex)  # a whole write makes a whole pair again
    np.testing.assert_allclose(export.read_texture(tex).origin, moved.origin)


# -- 11: temporaries of killed writers and SIGTERM -----------------------------------------------


def test_stale_temporaries_removed_on_next_write(ball_file, tmp_path):
    import subprocess

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    pid = int(dead.stdout)
    out = tmp_path / "o.csdf.npz"
    stale = tmp_path / f".o.csdf.npz.{pid}.abcd1234.tmp.npz"
    stale.write_bytes(b"x" * 1000)
    live = tmp_path / f".o.csdf.npz.{os.getppid()}.abcd1234.tmp.npz"  # a writer still running
    live.write_bytes(b"x")
    partscale.save(partscale.load(ball_file), out)
    assert not stale.exists()
    assert live.exists()


def test_a_folder_is_swept_of_dead_writers_temporaries_once_per_process(tmp_path, monkeypatch):
    import subprocess

    from partscale import _files

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    stale = tmp_path / f".other.glb.{int(dead.stdout)}.abcd1234.tmp.glb"  # another file's
    stale.write_bytes(b"x")
    user = tmp_path / ".hidden.1.notours"  # a user's own hidden file: not ours, kept
    user.write_bytes(b"y")
    listed = []
    real = os.listdir
    monkeypatch.setattr(os, "listdir", lambda p: listed.append(p) or real(p))
    for i in range(50):  # a batch writing many files into one folder
        with _files.atomic_path(tmp_path / f"o{i}.txt") as tmp:
            tmp.write_text("ok")
    assert not stale.exists() and user.exists()
    assert len(listed) == 1  # listed once, not once per file
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == [user.name]


def test_sigterm_cleans_up_like_ctrl_c(ball_file, tmp_path, capsys, monkeypatch):
    real = np.lib.format.write_array

    def terminated_while_writing(file, *a, **k):
        real(file, *a, **k)
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler interrupts this

    monkeypatch.setattr(np.lib.format, "write_array", terminated_while_writing)
    out = tmp_path / "o.csdf.npz"
    code, lines = run(
        capsys, monkeypatch, "scale", ball_file, "-o", out, "--axis", "x", "--zone", "0%",
        "50%", "--to", "0.2",
    )  # fmt: skip
    assert code == 143 and len(lines) == 1 and "terminated" in lines[0], (code, lines)
    only(tmp_path)
    assert signal.getsignal(signal.SIGTERM) is not None  # the handler is restored after


# -- 12: smaller ones --------------------------------------------------------------------------


def test_eval_into_an_impossible_folder(tmp_path, capsys, monkeypatch):
    suite = Path(__file__).resolve().parents[1] / "eval" / "suite.json"
    blocker = tmp_path / "file"
    blocker.write_text("")
    code, lines = run(capsys, monkeypatch, "eval", suite, "-o", blocker / "sub")
    assert_one_line(code, lines, str(blocker / "sub"))


@pytest.mark.parametrize("what", ["csdf", "--color", "--recipe"])
def test_a_directory_is_called_a_directory(what, ball_file, tmp_path, capsys, monkeypatch):
    d = tmp_path / "dir"
    d.mkdir()
    out = tmp_path / "o.csdf.npz"
    args = {
        "csdf": ["info", d],
        "--color": ["import", tmp_path / "g.npy", "-o", out, "--color", d],
        "--recipe": ["scale", ball_file, "-o", out, "--recipe", d],
    }[what]
    if what == "--color":
        np.save(tmp_path / "g.npy", np.asarray(partscale.load(ball_file).sdf))
    code, lines = run(capsys, monkeypatch, *args)
    assert_one_line(code, lines, str(d), "a directory")


def test_a_10_mb_recipe_value_is_not_echoed(ball_file, tmp_path, capsys, monkeypatch):
    recipe = tmp_path / "r.json"
    recipe.write_text(json.dumps({"edits": [{"axis": "x" * 10_000_000, "zone": [0, 1], "to": 2}]}))
    code, lines = run(
        capsys, monkeypatch, "scale", ball_file, "-o", tmp_path / "o.csdf.npz", "--recipe", recipe
    )
    assert_one_line(code, lines, str(recipe), "axis")
    assert len(lines[0]) < 400


@pytest.mark.parametrize("command", ["import", "segment", "scale"])
def test_unwritable_output_found_before_the_work(command, ball_file, tmp_path, capsys, monkeypatch):
    import partscale.edit
    import partscale.ingest
    import partscale.segment

    def never(*a, **k):
        raise AssertionError("computed before checking the output")

    for mod, name in ((partscale.ingest, "load"), (partscale.segment, "segment"),
                      (partscale.edit, "apply_recipe")):  # fmt: skip
        monkeypatch.setattr(mod, name, never)
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = blocker / "o.csdf.npz"  # a file where the folder should be
    args = {
        "import": ["import", ball_file, "-o", out],
        "segment": ["segment", ball_file, "-o", out],
        "scale": ["scale", ball_file, "-o", out, "--axis", "x", "--zone", "0%", "50%", "--to", "1"],
    }[command]
    code, lines = run(capsys, monkeypatch, *args)
    assert_one_line(code, lines, str(out), "output folder")


# -- what a user met ---------------------------------------------------------------------------


def test_scale_says_when_the_destination_snapped(ball_file, tmp_path, capsys, monkeypatch):
    out = tmp_path / "o.csdf.npz"
    code, lines = run(
        capsys, monkeypatch, "scale", ball_file, "-o", out, "--axis", "x", "--zone", "0%",
        "50%", "--to", "0.123",
    )  # fmt: skip
    assert code == 0, lines
    assert "0.123 -> 0.12 m (-0.003 m)" in lines[0] and "wrote" in lines[1], lines
    h = partscale.load(out).meta["history"][-1]
    assert h["edit"]["to"] == pytest.approx(0.123) and h["to_snapped"] == pytest.approx(0.12)


def test_missing_mtl_is_said_like_a_missing_texture(tmp_path, capsys, monkeypatch):
    """A missing material library: one line, exit 0, the materials grey, the note recorded."""
    obj = tmp_path / "t.obj"
    obj.write_text(
        "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl red\n"
        "f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"
    )
    out = tmp_path / "t.csdf.npz"
    code, lines = run(capsys, monkeypatch, "import", obj, "-o", out, "--res", "16")
    assert code == 0, lines
    said = [ln for ln in lines if "gone.mtl" in ln]
    assert len(said) == 1 and "missing" in said[0], lines
    assert "gone.mtl" in partscale.load(out).meta["history"][0]["notes"][0]


def test_every_option_of_every_command_is_explained():
    # `partscale CMD --help` explains every option and argument
    import typer

    from partscale.cli import app

    commands = typer.main.get_command(app).commands  # type: ignore[attr-defined]
    assert {"import", "complete", "info", "segment", "export", "render", "batch"} <= set(commands)
    for name, command in commands.items():
        assert command.help, name
        for param in command.params:
            text = getattr(param, "help", None)
            assert text and text.strip(), (name, param.name)


_REFAULT = """
import resource, sys
import numpy as np
if sys.argv[1] == "reuse":
    import partscale
    assert partscale.reuse_freed_memory()
n = 100 << 20
a = np.ones(n, np.uint8)
del a
f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
b = np.ones(n, np.uint8)
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0)
"""


_RELEASE = """
import os, sys
import numpy as np
from partscale import release_freed_memory, reuse_freed_memory
def resident():
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
assert reuse_freed_memory()
a = np.ones(100 << 20, np.uint8)
del a
kept = resident()
assert release_freed_memory()
print(kept - resident())
"""


@pytest.mark.skipif(
    "CS_GNU_LIBC_VERSION" not in getattr(os, "confstr_names", {}),
    reason="release_freed_memory calls glibc's malloc_trim only",
)
def test_a_batch_job_hands_its_freed_pages_back():
    """A batch job reuses freed grids' pages and releases them when it ends (so the next job's
    measured peak is its own): after reuse_freed_memory a freed 100 MB array stays resident,
    and release_freed_memory returns at least 90 MB of it to the system."""
    import subprocess

    proc = subprocess.run(
        [sys.executable, "-c", _RELEASE], capture_output=True, text=True, check=True
    )
    assert int(proc.stdout) >= 90 << 20, proc.stdout


@pytest.mark.skipif(
    "CS_GNU_LIBC_VERSION" not in getattr(os, "confstr_names", {}),
    reason="reuse_freed_memory tunes glibc's malloc only",
)
def test_a_freed_grid_is_reused_not_faulted_in_again():
    """After reuse_freed_memory (the CLI calls it), a 100 MB array allocated where one was just
    freed touches pages already mapped: (almost) no page faults, where glibc's default maps and
    zeroes fresh ones (half of a 256³ tile's time went to that)."""
    import subprocess

    def faults(mode):
        proc = subprocess.run(
            [sys.executable, "-c", _REFAULT, mode], capture_output=True, text=True, check=True
        )
        return int(proc.stdout)

    pages = (100 << 20) // 4096
    reused, fresh = faults("reuse"), faults("default")
    assert reused <= pages // 100 and reused < fresh, (reused, fresh)
