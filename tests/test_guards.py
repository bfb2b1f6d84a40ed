"""Guards on every route: memory refused before the work, signals never swallowed, outputs
staged and checked before they are renamed, batch output names unique and safe, the editor kept
on loopback unless exposed, and a query with no answer not an error.

Commands run in-process through :func:`partscale.cli.main` (a traceback shows up as an
exception here), except where a signal or a memory cap needs a process of its own.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import partscale
from partscale import shapes
from partscale.cli import main
from partscale.errors import PartscaleWarning

ROOT = Path(__file__).resolve().parents[1]


def run(capsys, monkeypatch, *args) -> tuple[int, list[str], str]:
    """``partscale ARGS`` in-process: (exit code, non-empty stderr lines, stdout)."""
    monkeypatch.setattr(sys, "argv", ["partscale", *map(str, args)])  # no pytest -v
    capsys.readouterr()
    try:
        main([str(a) for a in args])
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    out = capsys.readouterr()
    return code, [ln for ln in out.err.splitlines() if ln.strip()], out.out


def assert_one_line(code: int, lines: list[str], *fragments: str) -> None:
    assert code == 2, (code, lines)
    assert len(lines) == 1, lines
    assert lines[0].startswith("partscale: error: ")
    for f in fragments:
        assert f.lower() in lines[0].lower(), (f, lines[0])


def only(folder: Path, *names: str) -> None:
    """Nothing but ``names`` in ``folder`` (no output, no hidden temporary)."""
    assert sorted(p.name for p in folder.iterdir()) == sorted(names)


def _env(**extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    env.pop("PARTSCALE_MAX_MEMORY", None)
    env.update(extra)
    return env


@pytest.fixture(scope="module")
def long_file(tmp_path_factory) -> Path:
    """A bar 30,000 voxels long and 11 across (a 4 MB file): its profile along x has 9e8 pairs."""
    h = 0.01
    bar = shapes.grid(
        lambda p: shapes.boxes_sdf(p, [((0, 0, 0), (299.9, 0.04, 0.04))]),
        [(0, 0, 0), (300, 0.04, 0.04)],
        voxel_size=h,
    )
    assert bar.shape[0] > 30000
    return partscale.save(bar, tmp_path_factory.mktemp("long") / "long.csdf.npz")


# -- 1: memory ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args",
    [
        ("suggest",),
        ("suggest", "--axis", "x"),
        ("fit", "--size", "400", "=", "=", "-o", "OUT.csdf.npz"),
        (
            "scale",
            "-o",
            "OUT.csdf.npz",
            "--axis",
            "x",
            "--zone",
            "10%",
            "20%",
            "--to",
            "30%",
            "--snap",
        ),
    ],
    ids=["suggest", "suggest-x", "fit", "snap"],
)
def test_profile_of_a_long_object_is_refused_by_its_memory(
    args, long_file, tmp_path, capsys, monkeypatch
):
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", str(16 << 30))
    args = tuple(str(tmp_path / a) if a.startswith("OUT") else a for a in args)
    code, lines, _ = run(capsys, monkeypatch, args[0], long_file, *args[1:])
    # 30007 layers: 9.0e8 pairs at 256 bytes each
    assert_one_line(code, lines, "30007 layers", "would need", "GiB of memory")
    need = float(re.search(r"need ([\d.]+) GiB", lines[0]).group(1))
    assert need > 16
    only(tmp_path)


@pytest.mark.parametrize(
    "given, expected", [("500M", 500 << 20), ("2GiB", 2 << 30), ("4096", 4096)]
)
def test_the_memory_limit_is_read_as_a_size(given, expected, monkeypatch):
    from partscale._memory import available_memory

    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", given)
    assert available_memory() == expected


def test_a_memory_limit_that_is_no_size_is_refused_in_one_line(long_file, capsys, monkeypatch):
    # it was read with float(): "30M" ended in a traceback
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", "30 megs")
    code, lines, _ = run(capsys, monkeypatch, "suggest", long_file)
    assert_one_line(code, lines, "PARTSCALE_MAX_MEMORY", "expected a size", "30 megs")


def test_profile_within_memory_still_works():
    from partscale import zones

    boards = [((0, 0, 0), (0.02, 1.2, 0.3)), ((0.78, 0, 0), (0.8, 1.2, 0.3))]
    boards += [((0.02, y, 0), (0.78, y + 0.02, 0.3)) for y in (0.0, 0.295, 0.59, 0.885, 1.18)]
    bookcase = shapes.grid(
        lambda p: shapes.boxes_sdf(p, boards), [(0, 0, 0), (0.8, 1.2, 0.3)], voxel_size=0.02
    )
    assert any(c.kind == "tile" for c in zones.suggest(bookcase, "y"))


def _start_capped(path: Path, cap: int) -> tuple[subprocess.Popen, str]:
    """``partscale editor PATH`` in a process whose address space is capped at ``cap`` bytes."""
    import resource

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    proc = subprocess.Popen(
        [sys.executable, "-m", "partscale", "editor", str(path), "--no-browser"],
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        env=_env(),
        preexec_fn=limit,
    )
    lines: list[str] = []
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        lines.append(line)
        m = re.search(r"(http://\S+/)", line)
        if m:
            return proc, m.group(1)
    proc.kill()
    proc.wait()
    raise AssertionError(f"no URL printed: {''.join(lines)}")


def test_server_under_a_4_gib_cap_refuses_long_profiles_and_keeps_answering(long_file):
    import httpx

    proc, url = _start_capped(long_file, 4 << 30)
    try:
        for _ in range(100):
            try:
                assert httpx.get(url + "api/state", timeout=10).status_code == 200
                break
            except httpx.ConnectError:
                time.sleep(0.1)
        requests = [
            ("get", "api/suggest?axis=x", None),
            ("get", "api/suggest", None),
            ("post", "api/fit", {"size": [400, "=", "="], "allow_deform": False}),
        ]
        for method, path, body in requests:
            kw = {"json": body} if body is not None else {}
            r = getattr(httpx, method)(url + path, timeout=300, **kw)
            assert r.status_code == 413, (path, r.status_code, r.text)
            message = r.json()["error"]
            assert "\n" not in message and "would need" in message, message
            # the server is still there, and answers
            assert proc.poll() is None
            assert httpx.get(url + "api/state", timeout=10).status_code == 200
    finally:
        proc.terminate()
        proc.wait(timeout=30)
        proc.stderr.close()


# -- 6: the editor stays on loopback unless exposed -----------------------------------------


@pytest.mark.parametrize("host", ["", "0.0.0.0", "::", "192.0.2.1"])
def test_editor_beyond_loopback_needs_expose(host, long_file, capsys, monkeypatch):
    code, lines, _ = run(capsys, monkeypatch, "editor", long_file, "--no-browser", "--host", host)
    assert_one_line(code, lines, "--host", "--expose", "view, edit and save")
    assert repr(host) in lines[0]


def test_expose_with_a_wildcard_serves_and_says_what_it_exposes(long_file):
    import httpx

    proc = subprocess.Popen(
        [sys.executable, "-m", "partscale", "editor", str(long_file), "--no-browser",
         "--host", "", "--expose"],
        stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True, env=_env(),
    )  # fmt: skip
    try:
        lines = [proc.stderr.readline() for _ in range(2)]
        assert "every interface" in lines[0] and "warning" in lines[0], lines
        url = re.search(r"(http://\S+/)", lines[1]).group(1)
        for _ in range(100):
            try:
                assert httpx.get(url + "api/state", timeout=10).status_code == 200
                break
            except httpx.ConnectError:
                time.sleep(0.1)
    finally:
        proc.terminate()
        proc.wait(timeout=30)
        proc.stderr.close()


@pytest.mark.parametrize(
    "dest",
    [("--copies", "1000000"), ("--to", "1e308", "--mode", "tile")],
    ids=["copies", "tile-to-1e308"],
)
def test_mesh_route_copies_refused_by_their_memory(dest, tmp_path, capsys, monkeypatch):
    from partscale import data

    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", str(1 << 30))
    out = tmp_path / "o.glb"
    args = ("scale", data.table(), "-o", out, "--axis", "x", "--zone", "30%", "70%", *dest)
    code, lines, _ = run(capsys, monkeypatch, *args)
    assert_one_line(code, lines, "tile along x", "copies of", "would need", "memory")
    only(tmp_path)


def test_mesh_route_tile_within_memory_still_works(tmp_path, capsys, monkeypatch):
    from partscale import data

    out = tmp_path / "o.glb"
    args = ("scale", data.table(), "-o", out, "--axis", "x", "--zone", "30%", "70%")
    code, lines, _ = run(capsys, monkeypatch, *args, "--copies", "3")
    assert code == 0, lines
    only(tmp_path, "o.glb")


def test_depth_frame_refused_by_its_size_before_decoding(tmp_path, capsys, monkeypatch):
    from PIL import Image

    Image.fromarray(np.full((1500, 2000), 10000, np.uint16)).save(tmp_path / "d.png")
    (tmp_path / "k.json").write_text('{"fx": 500, "fy": 500, "cx": 1000, "cy": 750}')
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", str(100 << 20))  # 3e6 pixels need 183 MiB
    out = tmp_path / "o.csdf.npz"
    args = ("complete", "--depth", tmp_path / "d.png", "--intrinsics", tmp_path / "k.json")
    code, lines, _ = run(capsys, monkeypatch, *args, "-o", out)
    assert_one_line(code, lines, "2000x1500 depth image", "would need", "MiB of memory")
    only(tmp_path, "d.png", "k.json")


# -- 4: outputs checked before they are renamed ----------------------------------------------


@pytest.mark.parametrize("suffix", [".glb", ".obj", ".ply"])
def test_mesh_route_never_writes_infinite_vertices(suffix, tmp_path, capsys, monkeypatch):
    from partscale import data

    out = tmp_path / f"o{suffix}"
    args = ("scale", data.table(), "-o", out, "--axis", "x", "--zone", "30%", "70%")
    code, lines, _ = run(capsys, monkeypatch, *args, "--to", "1e308")
    assert_one_line(code, lines, "expected finite vertices", "nothing written")
    only(tmp_path)


def test_mesh_route_refuses_a_nan_node_matrix(tmp_path, capsys, monkeypatch):
    import trimesh

    from partscale import meshedit
    from partscale.edit import Recipe

    scene = trimesh.Scene()
    matrix = np.eye(4)
    matrix[0, 0] = np.nan
    scene.add_geometry(trimesh.creation.box(), transform=matrix)
    recipe = Recipe.parse({"edits": [{"axis": "y", "zone": ["40%", "60%"], "to": "120%"}]})
    with pytest.raises(partscale.InputError, match="expected finite vertices"):
        meshedit.save_scene(meshedit.apply_recipe_to_scene(scene, recipe)[0], tmp_path / "o.glb")
    only(tmp_path)


def test_complete_refuses_an_absurd_box(tmp_path, capsys, monkeypatch):
    from PIL import Image

    Image.fromarray(np.full((48, 64), 10000, np.uint16)).save(tmp_path / "d.png")
    (tmp_path / "k.json").write_text('{"fx": 50, "fy": 50, "cx": 32, "cy": 24}')
    out = tmp_path / "o.csdf.npz"
    args = ("complete", "--depth", tmp_path / "d.png", "--intrinsics", tmp_path / "k.json")
    code, lines, _ = run(capsys, monkeypatch, *args, "--box", "0,0,1e30,1e30", "-o", out)
    assert_one_line(code, lines, "--box", "1e30")  # the schema's range check
    only(tmp_path, "d.png", "k.json")


@pytest.mark.parametrize(
    ("option", "typed"),
    [("--box", ["370", "230", "540", "440"]), ("--camera", ["1", "0", "0", "0"])],
)
def test_complete_names_the_form_of_numbers_typed_with_spaces(
    tmp_path, capsys, monkeypatch, option, typed
):
    # unquoted, the option takes the first number and the rest would be stray arguments: the
    # option itself is refused, naming the form it expects
    code, lines, _ = run(
        capsys, monkeypatch, "complete", "x.ply", option, *typed, "-o", tmp_path / "o.csdf.npz"
    )
    assert_one_line(code, lines, option, "separated by commas", f"got '{typed[0]}'")
    only(tmp_path)


@pytest.mark.parametrize(
    ("args", "option", "got"),
    [
        (["fit", "--size", "=,+20cm,=", "-o"], "--size", "got '=,+20cm,=' '-o'"),
        (["batch", "--size", "=,+20cm,=", "-o"], "--size", "got '=,+20cm,=' '-o'"),
        (["fit", "--add", "x,1", "-o"], "--add", "got 'x,1' '-o'"),
        (["scale", "--axis", "x", "--zone", "40%,60%", "--to", "120%", "-o"], "--zone", "'--to'"),
        (["scale", "--radial", "--center", "0,0", "--to", "30cm", "-o"], "--center", "'--to'"),
    ],
)
def test_values_typed_with_commas_are_refused_as_the_option(
    tmp_path, capsys, monkeypatch, args, option, got
):
    # an option of several values typed with commas takes the next words (an option, its
    # value) for its other values: refused as that option, naming the form, not as a missing
    # -o or a stray argument further on
    target = tmp_path / "t.csdf.npz"
    partscale.save(shapes.box((0, 0, 0), (1, 1, 1), voxel_size=0.1), target)
    command, *rest = args
    code, lines, _ = run(capsys, monkeypatch, command, target, *rest, tmp_path / "o.csdf.npz")
    assert_one_line(code, lines, option, "separated by spaces", got)
    only(tmp_path, "t.csdf.npz")


def test_add_names_a_count_that_is_not_whole(tmp_path, capsys, monkeypatch):
    target = tmp_path / "t.csdf.npz"
    partscale.save(shapes.box((0, 0, 0), (1, 1, 1), voxel_size=0.1), target)
    args = ("fit", target, "--add", "x", "one", "-o", tmp_path / "o.csdf.npz")
    code, lines, _ = run(capsys, monkeypatch, *args)
    assert_one_line(code, lines, "--add", "whole number", "got 'one'")
    only(tmp_path, "t.csdf.npz")


def test_save_refuses_meta_its_own_reader_would_refuse(tmp_path):
    box = shapes.box((0, 0, 0), (1, 1, 1), voxel_size=0.1)
    odd = box.replace(meta={**box.meta, "box": [0, 0, 10**30, 10**30]})
    with pytest.raises(partscale.InputError, match="read back"):
        partscale.save(odd, tmp_path / "o.csdf.npz")
    only(tmp_path)
    partscale.save(box, tmp_path / "o.csdf.npz")
    assert partscale.load(tmp_path / "o.csdf.npz").shape == box.shape


# -- 2: signals are never swallowed; multi-file outputs are one set ------------------------

# Run as its own process: trimesh's OBJ exporter is made to receive the signal while it encodes
# the atlas material, inside its own ``except BaseException`` (where it swallowed it before).
_SIGNAL_IN_TRIMESH = """
import os, signal, sys, time
import trimesh.visual.material as material
real = material.SimpleMaterial.to_obj
def to_obj(self, *a, **k):
    os.kill(os.getpid(), signal.{sig})
    time.sleep(30)  # the handler raises here, inside trimesh's try
    return real(self, *a, **k)
material.SimpleMaterial.to_obj = to_obj
from partscale.cli import main
from partscale.errors import PartscaleWarning
sys.argv = ["partscale", *sys.argv[1:]]
main()
"""


@pytest.fixture(scope="module")
def ball_file(tmp_path_factory) -> Path:
    c = shapes.grid(
        lambda p: np.linalg.norm(p, axis=-1) - 0.3, ((-0.4,) * 3, (0.4,) * 3), voxel_size=0.04
    )
    return partscale.save(c, tmp_path_factory.mktemp("in") / "ball.csdf.npz")


@pytest.mark.parametrize(("sig", "code"), [("SIGTERM", 143), ("SIGINT", 130)])
def test_signal_during_an_atlased_obj_export_leaves_nothing(sig, code, ball_file, tmp_path):
    out = tmp_path / "o.obj"
    out.write_text("the previous export\n")
    script = _SIGNAL_IN_TRIMESH.format(sig=sig)
    args = ["export", str(ball_file), "--mesh", str(out), "--atlas", "512"]
    proc = subprocess.run(
        [sys.executable, "-c", script, *args], capture_output=True, text=True, env=_env(),
        timeout=300,
    )  # fmt: skip
    assert proc.returncode == code, (proc.returncode, proc.stderr)
    assert "Traceback" not in proc.stderr, proc.stderr
    only(tmp_path, "o.obj")
    assert out.read_text() == "the previous export\n"  # the destination untouched


def _full_on_write(csdf, path):
    """A 3D texture writer that meets a full disk half-way through its file."""
    import errno

    from partscale._files import atomic_path

    with atomic_path(path) as tmp:
        tmp.write_bytes(b"half a texture")
        raise OSError(errno.ENOSPC, "No space left on device")


def test_export_with_two_outputs_leaves_neither_when_the_second_fails(
    ball_file, tmp_path, capsys, monkeypatch
):
    from partscale.export import write

    monkeypatch.setitem(write.TEXTURE_WRITERS, ".raw", _full_on_write)
    mesh, tex = tmp_path / "o.glb", tmp_path / "o.raw"
    code, lines, _ = run(capsys, monkeypatch, "export", ball_file, "--mesh", mesh, "--texture", tex)
    assert_one_line(code, lines, str(tex), "no space left")
    only(tmp_path)
    mesh.write_bytes(b"the previous mesh")  # a destination that existed keeps what it had
    code, lines, _ = run(capsys, monkeypatch, "export", ball_file, "--mesh", mesh, "--texture", tex)
    assert code == 2
    only(tmp_path, "o.glb")
    assert mesh.read_bytes() == b"the previous mesh"


def test_a_failed_rename_in_a_set_puts_back_what_was_there(tmp_path, monkeypatch):
    import errno

    from partscale._files import atomic_path, staged_writes

    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old a")
    real, calls = os.replace, []

    def replace(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise OSError(errno.EIO, "Input/output error")
        real(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(partscale.InputError, match=r"b\.txt"), staged_writes():
        for p in (a, b):
            with atomic_path(p) as tmp:
                tmp.write_text("new")
    monkeypatch.setattr(os, "replace", real)
    only(tmp_path, "a.txt")
    assert a.read_text() == "old a"


def test_a_noted_signal_stops_a_set_before_any_rename(tmp_path):
    import signal as sig

    from partscale import _interrupt
    from partscale._files import atomic_path, staged_writes

    try:
        with pytest.raises(KeyboardInterrupt), staged_writes():
            with atomic_path(tmp_path / "a.txt") as tmp:
                tmp.write_text("a")
            _interrupt.note(sig.SIGTERM)  # as a library that swallowed the exception
    finally:
        _interrupt.clear()
    only(tmp_path)


# -- 3: batch output names unique and safe --------------------------------------------------


def _copies(root: Path, *rels: str) -> None:
    import shutil

    from partscale import data

    for rel in rels:
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(data.table(), p)


def test_batch_names_collide_nowhere_and_the_batch_keeps_every_object(tmp_path):
    import warnings

    from partscale import batch

    _copies(tmp_path / "in", "a/x.glb", "b/x.glb", "a__x.glb")
    with warnings.catch_warnings(record=True) as notes:
        warnings.simplefilter("always")
        items = batch.discover([tmp_path / "in"])
    names = {it.path.relative_to(tmp_path / "in").as_posix(): it.name for it in items}
    assert names == {"a/x.glb": "a__x", "a__x.glb": "a__x~2", "b/x.glb": "b__x"}
    said = [str(n.message) for n in notes]
    assert len(said) == 1 and "a__x.glb" in said[0] and "'a__x~2'" in said[0], said
    with pytest.warns(PartscaleWarning, match="a__x~2"):
        result = batch.run([tmp_path / "in"], tmp_path / "out", res=16, workers=1)
    assert sorted(result.done) == ["a__x", "a__x~2", "b__x"]
    assert sorted(batch.read_status(tmp_path / "out" / "status.csv")) == sorted(result.done)


def test_batch_names_differing_only_in_case_are_told_apart(tmp_path):
    from partscale.batch.inputs import unique_names

    with pytest.warns(PartscaleWarning, match="Chair~2"):
        got = unique_names([("b/Chair.glb", "Chair", False), ("a/chair.glb", "chair", False)])
    assert got == ["Chair~2", "chair"]
    # a manifest's name keeps it; an input that wanted it moves aside, past the taken ~2
    with pytest.warns(PartscaleWarning):
        got = unique_names([("a/x.glb", "x", False), ("m.csv", "x~2", True), ("z", "x", True)])
    assert got == ["x~3", "x~2", "x"]


@pytest.mark.parametrize(
    ("stem", "want"),
    [
        ("status.csv", "status.csv_"),
        ("workers.log", "workers.log_"),
        (".status.lock", "_status.lock"),
        ("STATUS.CSV", "STATUS.CSV_"),
        ("a\x00b", "a_b"),
        ("..", "__."),
    ],
)
def test_reserved_and_unsafe_names_are_renamed_with_a_note(stem, want):
    from partscale.batch.inputs import Input, assign_names

    item = Input(Path(f"/in/{stem}.glb"), (Path(f"/in/{stem}.glb"),))
    with pytest.warns(PartscaleWarning, match="output folder named"):
        (named,) = assign_names([item])
    assert named.name == want


def test_batch_of_reserved_names_writes_beside_its_own_files(tmp_path):
    import warnings

    from partscale import batch

    _copies(tmp_path / "in", "status.csv.glb", "workers.log.glb", "x/.status.lock.glb")
    # a hidden file is no input of a folder search: named on its own, as a file
    sources = [tmp_path / "in", tmp_path / "in" / "x" / ".status.lock.glb"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = batch.run(sources, tmp_path / "out", res=16, workers=1)
    assert sorted(result.done) == ["_status.lock", "status.csv_", "workers.log_"]
    out = tmp_path / "out"
    assert (out / "status.csv").is_file() and (out / "status.csv_").is_dir()
    assert sorted(batch.read_status(out / "status.csv")) == sorted(result.done)


def test_a_manifest_name_that_is_no_safe_folder_is_refused(tmp_path):
    from partscale.batch.inputs import Input, assign_names

    for bad in ("status.csv", "a\x00b", ".hidden"):
        item = Input(Path("/in/x.glb"), (Path("/in/x.glb"),), name=bad)
        with pytest.raises(partscale.InputError, match="expected a folder name"):
            assign_names([item])


# -- 7: a query with no answer is not an error -----------------------------------------------


def _cone(p: np.ndarray) -> np.ndarray:
    """A cone along y, apex up: its cross-section changes at every layer."""
    r, y = np.linalg.norm(p[..., [0, 2]], axis=-1), p[..., 1]
    return np.maximum.reduce([(r - 0.35 * (0.3 - y) / 0.6) * 0.86, -y - 0.3, y - 0.3])


def test_suggest_that_finds_nothing_says_so_and_exits_0(tmp_path, capsys, monkeypatch):
    import json

    cone = shapes.grid(_cone, ((-0.4,) * 3, (0.4,) * 3), voxel_size=0.02)
    path = partscale.save(cone, tmp_path / "cone.csdf.npz")
    code, lines, out = run(capsys, monkeypatch, "suggest", path, "--axis", "y")
    assert code == 0 and not any("error" in ln for ln in lines), (code, lines)
    assert "y: no candidate" in out
    code, lines, out = run(capsys, monkeypatch, "suggest", path, "--axis", "y", "--json")
    assert code == 0, lines
    assert json.loads(out)["candidates"] == []


def test_available_memory_heeds_an_address_space_cap():
    code = (
        "import resource; cap = 3 << 30; resource.setrlimit(resource.RLIMIT_AS, (cap, cap)); "
        "from partscale._memory import available_memory; print(available_memory(), cap)"
    )
    env = _env()
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    have, cap = map(int, proc.stdout.split())
    assert 0 < have < cap, proc.stderr
