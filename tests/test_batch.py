"""partscale batch: discovery, manifests, shards, resume after SIGKILL, failures, Ray vs local."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA, ROOT, assert_bad_input, data_path

import partscale
import partscale.ingest
from partscale.batch import (
    STATUS_COLUMNS,
    discover,
    read_manifest,
    read_status,
    run,
    shard,
)
from partscale.batch.inputs import assign_names
from partscale.errors import InputError

# what varies between two runs of the same batch; everything else must be equal
VARYING = {"seconds", "peak_memory_mib", "started", "finished", "attempts"}


def _small(tmp_path: Path) -> list[Path]:
    """Four small objects of every mesh format: GLB, glTF + .bin + textures, OBJ + MTL, PLY."""
    return [
        data_path("kenney/table.glb"),
        data_path("polyhaven/painted_wooden_stool"),
        data_path("sweethome3d/stool.obj"),
        data_path("scans/derived/tum_yellow_office_chair_partial.ply"),
    ]


def _batch_cmd(*args) -> list[str]:
    return [sys.executable, "-m", "partscale", "batch", *map(str, args)]


def _env(**extra) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    env.update(extra)
    return env


def _outputs(outdir: Path) -> dict[str, bytes]:
    return {
        p.relative_to(outdir).as_posix(): p.read_bytes()
        for p in sorted(outdir.rglob("*"))
        if p.is_file() and p.parent != outdir
    }


def _stable(rows: dict[str, dict[str, str]]) -> dict[str, dict[str, str]]:
    return {n: {k: v for k, v in r.items() if k not in VARYING} for n, r in rows.items()}


# -- discovery, manifests, names, shards ------------------------------------------------------


def test_discover_all_formats_assets_as_one_input():
    for folder in ("kenney", "sweethome3d", "polyhaven", "khronos", "scans"):
        data_path(folder)  # skips, with the reason, where the test objects are absent
    items = discover([DATA])
    names = [it.name for it in items]
    assert len(names) == len(set(names))
    suffixes = {it.path.suffix for it in items}
    assert suffixes == {".glb", ".gltf", ".obj", ".ply"}
    # companions travel with their asset and are never inputs of their own
    for it in items:
        assert it.files[0] == it.path
    gltf = next(it for it in items if it.path.name == "painted_wooden_stool_1k.gltf")
    assert {f.suffix for f in gltf.files[1:]} == {".bin", ".jpg"}
    obj = next(it for it in items if it.path.name == "stool.obj")
    assert [f.name for f in obj.files[1:]] == ["sh3d_default.mtl"]
    # same stem in two folders: both named by their folder, whatever the order of the sources
    assert "kenney__chair" in names and "sweethome3d__chair" in names
    again = discover(
        [
            DATA / "sweethome3d",
            DATA / "kenney",
            DATA / "polyhaven",
            DATA / "khronos",
            DATA / "scans",
        ]
    )
    assert {it.path: it.name for it in again} == {it.path: it.name for it in items}


def test_content_hash_covers_every_file_of_an_asset(tmp_path):
    obj = data_path("sweethome3d/stool.obj")
    shutil.copy(obj, tmp_path / "stool.obj")
    shutil.copy(obj.parent / "sh3d_default.mtl", tmp_path / "sh3d_default.mtl")
    (it,) = discover([tmp_path])
    h = it.content_hash()
    with open(tmp_path / "sh3d_default.mtl", "a") as fh:
        fh.write("\n# edited\n")
    assert it.content_hash() != h


def test_names_deterministic_and_unique(tmp_path):
    for rel in ("a/x/chair.obj", "b/x/chair.obj", "c/chair.ply", "c/chair.obj", "solo.ply"):
        p = tmp_path / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text("v 0 0 0\n")
    items = discover([tmp_path])
    names = {it.path.relative_to(tmp_path).as_posix(): it.name for it in items}
    assert len(set(names.values())) == len(names)
    assert names["solo.ply"] == "solo"
    assert names["a/x/chair.obj"] == "a__x__chair"
    assert names["b/x/chair.obj"] == "b__x__chair"
    assert {names["c/chair.ply"], names["c/chair.obj"]} == {"c__chair.ply", "c__chair.obj"}
    assert [it.name for it in assign_names(items[::-1])] == [it.name for it in items[::-1]]


def test_manifests_csv_and_jsonl(tmp_path):
    table = data_path("kenney/table.glb")
    (tmp_path / "r.json").write_text(
        json.dumps({"edits": [{"axis": "x", "zone": ["35%", "65%"], "to": "105%"}]})
    )
    m = tmp_path / "m.csv"
    m.write_text(f"path,name,res,recipe,export\n{table},t1,48,r.json,glb\n{table},t2,,,\n")
    rows = read_manifest(m)
    assert [r.name for r in rows] == ["t1", "t2"]
    assert rows[0].options == {"res": "48", "recipe": str(tmp_path / "r.json"), "export": "glb"}
    assert rows[1].options == {}
    j = tmp_path / "m.jsonl"
    j.write_text(json.dumps({"path": str(table), "res": 40, "render": "top"}) + "\n")
    (row,) = read_manifest(j)
    assert row.options == {"res": 40, "render": "top"} and row.name == ""
    bad = tmp_path / "bad.csv"
    bad.write_text(f"path,colour\n{table},red\n")
    with pytest.raises(InputError, match="unknown key"):
        read_manifest(bad)
    (tmp_path / "nopath.csv").write_text("file\nx.glb\n")
    with pytest.raises(InputError, match="'path' column"):
        read_manifest(tmp_path / "nopath.csv")
    dup = tmp_path / "dup.jsonl"
    dup.write_text(
        json.dumps({"path": str(table), "name": "a"})
        + "\n"
        + json.dumps({"path": str(data_path("kenney/chair.glb")), "name": "a"})
        + "\n"
    )
    with pytest.raises(InputError, match="unique manifest names"):
        discover([dup])
    twice = tmp_path / "twice.jsonl"
    twice.write_text(
        json.dumps({"path": str(table), "name": "low", "res": 32})
        + "\n"
        + json.dumps({"path": str(table), "name": "high", "res": 64})
        + "\n"
    )
    assert sorted(it.name for it in discover([twice, table])) == ["high", "low", "table"]


def test_shards_partition_exactly():
    data_path("kenney")  # skips, with the reason, where the test objects are absent
    items = discover([DATA])
    for w in (1, 2, 3, 7, len(items) + 3):
        shards = [shard(items, r, w) for r in range(w)]
        paths = [it.path for s in shards for it in s]
        assert len(paths) == len(items) and set(paths) == {it.path for it in items}
    with pytest.raises(InputError, match="rank"):
        shard(items, 3, 3)
    with pytest.raises(InputError, match="world_size"):
        shard(items, 0, 0)


def test_cli_refuses_bad_options_with_one_line(tmp_path, cli):
    table = data_path("kenney/table.glb")
    assert_bad_input(cli("batch", table, "-o", tmp_path / "o", "--engine", "spark"), "--engine")
    assert_bad_input(cli("batch", tmp_path / "nothing", "-o", tmp_path / "o"), "no such path")
    assert_bad_input(cli("batch", table, "-o", tmp_path / "o", "--export", "stl"), "export")
    assert_bad_input(cli("batch", table, "-o", tmp_path / "o", "--size", "210cm", "="), "--size")
    # import's bounds, both of them, before any object is read
    for res in ("8", "16385"):
        bad = cli("batch", table, "-o", tmp_path / "o", "--res", res)
        assert_bad_input(bad, f"expected --res in [16, 16384], got {res}")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("res", ["16385", "6.5", "many"])
def test_manifest_res_is_refused_before_work(tmp_path, cli, res):
    table = data_path("kenney/table.glb")
    m = tmp_path / "m.csv"
    m.write_text(f"path,name,res\n{table},ok,32\n{table},bad,{res}\n")
    bad = cli("batch", m, "-o", tmp_path / "o")
    assert_bad_input(bad, "res: expected", res)
    assert not (tmp_path / "o").exists()


def test_fit_brings_each_object_to_its_size(tmp_path, cli):
    table = data_path("kenney/table.glb")
    cli(
        "batch", table, "-o", tmp_path / "o", "--res", "48", "--size", "+20cm", "=", "=", check=True
    )
    (out,) = (tmp_path / "o").glob("*/*.csdf.npz")
    before = partscale.ingest.load(table, res=48).surface_bounds()
    after = partscale.load(out).surface_bounds()
    grown = (after[1] - after[0]) - (before[1] - before[0])
    h = partscale.load(out).voxel_size
    assert abs(grown[0] - 0.2) <= 0.5 * h + 1e-9, grown  # fit hits its target within half a voxel
    assert np.all(np.abs(grown[1:]) <= 1e-6), grown  # "=" keeps the other axes (float noise)


def test_a_size_only_a_deformation_reaches_fails_that_object_unless_allowed(tmp_path, cli):
    """kenney/tableRound 20 % wider along x alone: fit refuses it (a round top would flatten):
    the object fails with fit's one line in status.csv; with --allow-deform, or a manifest's
    allow_deform column, it is written."""
    table = data_path("kenney/tableRound.glb")
    out = tmp_path / "o"
    proc = cli("batch", table, "-o", out, "--res", "48", "--size", "120%", "=", "=")
    assert proc.returncode == 1, proc.stderr
    with (out / "status.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert rows[0]["state"] == "failed" and "round or curved" in rows[0]["error"], rows
    cli(
        "batch",
        table,
        "-o",
        tmp_path / "a",
        "--res",
        "48",
        "--size",
        "120%",
        "=",
        "=",
        "--allow-deform",
        check=True,
    )
    assert list((tmp_path / "a").glob("*/*.csdf.npz"))
    m = tmp_path / "m.csv"
    m.write_text(f"path,size,allow_deform\n{table},120% = =,yes\n")
    cli("batch", m, "-o", tmp_path / "m", "--res", "48", check=True)
    assert list((tmp_path / "m").glob("*/*.csdf.npz"))


def test_engine_ray_without_ray_says_how_to_install(tmp_path):
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "ray.py").write_text("raise ImportError('No module named ray')\n")
    env = _env()
    env["PYTHONPATH"] = f"{fake}{os.pathsep}{env['PYTHONPATH']}"
    proc = subprocess.run(
        _batch_cmd(data_path("kenney/table.glb"), "-o", tmp_path / "o", "--engine", "ray"),
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert_bad_input(proc, "pip install 'partscale[ray]'")


# -- running ----------------------------------------------------------------------------------


def test_resume_after_sigkill_redoes_nothing_and_matches_uninterrupted(tmp_path):
    objs = _small(tmp_path)
    opts = ["--res", "32", "--segment", "--export", "glb,csdf", "--render", "--workers", "1"]
    ref = run(
        objs, tmp_path / "ref", res=32, segment="fast", export="glb,csdf", render="iso", workers=1
    )
    assert len(ref.done) == 4 and ref.ok

    out = tmp_path / "out"
    proc = subprocess.Popen(
        _batch_cmd(*objs, "-o", out, *opts),
        env=_env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 300
    done: dict[str, dict[str, str]] = {}
    while time.monotonic() < deadline and proc.poll() is None:
        rows = read_status(out / "status.csv") if (out / "status.csv").exists() else {}
        done = {n: r for n, r in rows.items() if r["state"] == "done"}
        if 1 <= len(done) < 4 and any(r["state"] == "running" for r in rows.values()):
            break
        time.sleep(0.02)
    assert proc.poll() is None, "the batch ended before it could be killed half-way"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    killed = read_status(out / "status.csv")  # a consistent table: every row complete
    assert set(killed[n]["state"] for n in killed) <= {"done", "running"}
    done = {n: r for n, r in killed.items() if r["state"] == "done"}
    assert 1 <= len(done) < 4
    mtimes = {
        o: (out / o).stat().st_mtime_ns for r in done.values() for o in r["outputs"].split(";")
    }
    time.sleep(0.05)  # the dead worker (killed with its parent) must not write any more

    second = subprocess.run(
        _batch_cmd(*objs, "-o", out, *opts), env=_env(), capture_output=True, text=True, timeout=600
    )
    assert second.returncode == 0, second.stderr
    assert f"{4 - len(done)} done, 0 failed, {len(done)} skipped" in second.stderr
    final = read_status(out / "status.csv")
    for n, r in done.items():  # nothing done was redone
        assert final[n] == r
    for o, t in mtimes.items():
        assert (out / o).stat().st_mtime_ns == t
    assert all(r["state"] == "done" for r in final.values()) and len(final) == 4
    assert _outputs(out) == _outputs(tmp_path / "ref")
    assert _stable(final) == _stable(read_status(tmp_path / "ref" / "status.csv"))
    with open(out / "status.csv") as fh:
        assert next(csv.reader(fh)) == list(STATUS_COLUMNS)


def test_failures_are_recorded_with_one_line_and_others_complete(tmp_path):
    corrupt = tmp_path / "corrupt.glb"
    corrupt.write_bytes(b"glTF" + bytes(range(256)) * 4)
    good = data_path("sweethome3d/stool.obj")
    manifest = tmp_path / "m.jsonl"
    rows = [
        {"path": str(good), "res": 32},
        {"path": str(corrupt), "res": 32},
        # at 640 voxels the import needs well over the 700 MiB each worker may use
        {"path": str(data_path("kenney/table.glb")), "name": "hog", "res": 640},
    ]
    manifest.write_text("".join(json.dumps(r) + "\n" for r in rows))
    out = tmp_path / "out"
    args = [manifest, "-o", out, "--workers", "1", "--memory", "700MiB", "--export", "glb"]
    # no up-front guard: the worker really grows past its limit and must be stopped
    env = _env(PARTSCALE_MAX_MEMORY=str(10**13))
    proc = subprocess.run(_batch_cmd(*args), env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 1, proc.stderr
    status = read_status(out / "status.csv")
    assert status["stool"]["state"] == "done" and (out / "stool" / "stool.glb").is_file()
    assert status["corrupt"]["state"] == "failed" and "corrupt.glb" in status["corrupt"]["error"]
    assert status["hog"]["state"] == "failed"
    assert "memory limit of 700 MiB" in status["hog"]["error"]
    failed_lines = [ln for ln in proc.stderr.splitlines() if ln.startswith("failed: ")]
    assert len(failed_lines) == 2 and "Traceback" not in proc.stderr
    assert "1 done, 2 failed" in proc.stderr

    # a rerun leaves failures alone unless asked, and redoes nothing done
    again = subprocess.run(_batch_cmd(*args), env=env, capture_output=True, text=True, timeout=600)
    assert again.returncode == 1
    assert "0 done, 0 failed, 1 skipped" in again.stderr and "2 failed before" in again.stderr
    assert read_status(out / "status.csv") == status
    # the guard path: with the limit as the pipeline's memory budget the grid is refused up front
    retry = subprocess.run(
        _batch_cmd(*args, "--retry-failed"), env=_env(), capture_output=True, text=True, timeout=600
    )
    after = read_status(out / "status.csv")
    assert after["hog"]["state"] == "failed" and "memory" in after["hog"]["error"]
    assert after["hog"]["attempts"] == "2" and after["stool"] == status["stool"]
    assert retry.returncode == 1


def test_recipe_lengths_with_units_convert_per_object(tmp_path):
    """A recipe's "50cm" is 0.5 on an object in metres; one of unknown units fails, one line."""
    from partscale import shapes

    table = data_path("kenney/table.glb")
    grid = tmp_path / "grid.csdf.npz"
    c = shapes.box((-1, 0, 0), (1, 0.5, 0.3), voxel_size=0.05)
    partscale.save(c.replace(meta={**c.meta, "units": None}), grid)
    edit = {"axis": "x", "zone": ["-50cm", "0.5m"], "to": "700mm"}
    got = run([table, grid], tmp_path / "u", res=32, recipe={"edits": [edit]}, workers=1)
    numbers = {"axis": "x", "zone": [-0.5, 0.5], "to": 0.7}
    want = run([table], tmp_path / "n", res=32, recipe={"edits": [numbers]}, workers=1)
    assert got.done == want.done == ["table"]
    a = partscale.load(tmp_path / "u" / "table" / "table.csdf.npz")
    b = partscale.load(tmp_path / "n" / "table" / "table.csdf.npz")
    assert np.array_equal(a.sdf, b.sdf)
    ((name, line),) = got.failed
    assert name == "grid" and "units are unknown" in line and "\n" not in line


def test_workers_forked_after_the_warm_up_match_one_worker_byte_for_byte(tmp_path):
    """Three workers (the template loads the kernels, then forks the others; the last objects
    get more threads) write the same bytes and the same table as one worker, and the batch
    reports its phases."""
    objs = _small(tmp_path)
    opts = dict(res=32, segment="fast", export="glb,csdf", render="iso")
    one = run(objs, tmp_path / "one", workers=1, **opts)
    three = run(objs, tmp_path / "three", workers=3, **opts)
    assert one.ok and three.ok and sorted(three.done) == sorted(one.done) and len(one.done) == 4
    assert _outputs(tmp_path / "three") == _outputs(tmp_path / "one")
    a = _stable(read_status(tmp_path / "one" / "status.csv"))
    assert _stable(read_status(tmp_path / "three" / "status.csv")) == a
    phases = ("startup_seconds", "objects_seconds", "end_seconds", "objects_cpu_seconds")
    assert all(three.engine_info[k] >= 0 for k in phases)
    assert three.engine_info["objects_cpu_seconds"] > 0


def test_a_worker_given_other_threads_per_task_still_compiles_kernels():
    """A worker sets each task's threads (the last objects get more); numba rereads its thread
    variables whenever it compiles and refuses a new count once its threads run, so the task's
    threads must not reach them."""
    code = (
        "import os, numba, numpy as np\n"
        "from partscale.batch._worker import _set_threads\n"
        "@numba.njit(parallel=True)\n"
        "def total(a):\n"
        "    s = 0.0\n"
        "    for i in numba.prange(len(a)):\n"
        "        s += a[i]\n"
        "    return s\n"
        "total(np.ones(100))\n"
        "for n in (1, 2, 1):\n"
        "    _set_threads(n)\n"
        "    fresh = numba.njit(lambda x: x + n)\n"
        "    print(fresh(1), numba.get_num_threads(), os.cpu_count())\n"
    )
    env = _env(NUMBA_NUM_THREADS="2", NUMBA_THREADING_LAYER="workqueue")
    proc = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["2", "1", "1", "3", "2", "2", "2", "1", "1"]


def test_timeout_stops_a_slow_object(tmp_path):
    slow = data_path("khronos/SheenChair.glb")
    out = tmp_path / "out"
    r = run([slow], out, res=512, timeout=1.0, workers=1, export="glb")
    assert r.failed == [("SheenChair", "timed out after 1 s and was stopped")]
    assert read_status(out / "status.csv")["SheenChair"]["state"] == "failed"


def test_ray_engine_matches_local_bit_for_bit(tmp_path):
    pytest.importorskip("ray", reason="ray not installed (pip install 'partscale[ray]')")
    objs = [data_path("kenney/table.glb"), data_path("sweethome3d/stool.obj")]
    opts = dict(res=32, segment="fast", export="glb,csdf", render="iso", workers=2)
    local = run(objs, tmp_path / "local", **opts)
    ray_ = run(objs, tmp_path / "ray", engine="ray", **opts)
    assert local.ok and ray_.ok and sorted(ray_.done) == sorted(local.done)
    assert _outputs(tmp_path / "ray") == _outputs(tmp_path / "local")
    a = _stable(read_status(tmp_path / "local" / "status.csv"))
    b = _stable(read_status(tmp_path / "ray" / "status.csv"))
    assert a == b and len(a) == 2


def test_segment_and_render_values_may_be_left_out():
    from partscale.cli.batch import optional_values

    argv = ["batch", "--segment", "data", "-o", "o", "--render"]
    assert optional_values(argv) == ["batch", "--segment=fast", "data", "-o", "o", "--render=iso"]
    argv = ["batch", "--segment", "coacd", "--render", "top", "data", "-o", "o"]
    assert optional_values(argv) == argv
    assert optional_values(["scale", "--render"]) == ["scale", "--render"]
