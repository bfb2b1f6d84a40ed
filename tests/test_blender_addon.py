"""The Blender add-on (integrations/blender): its command lines, and the add-on run in Blender.

In Blender: the add-on is installed from the zip the build makes and enabled, a real glTF is
imported with Blender's own importer, and one more shelf is added through the add-on's
operator, which runs the partscale installed in this repository's .venv. Blender is the bpy
wheel in ``.venv-bpy`` (``./dev.sh test`` installs it where it can), ``PARTSCALE_BLENDER_PYTHON``
(a Python with bpy) or a ``blender`` binary on PATH; the tests skip with the reason otherwise.
Undo needs Blender with a window (an undo step is taken only there): it runs in ``blender``
under ``xvfb-run`` where both are installed.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, data_path


def _load_core():
    """The add-on's core module on its own (its package's __init__ needs bpy)."""
    import importlib.util

    path = ROOT / "integrations" / "blender" / "partscale_blender" / "core.py"
    spec = importlib.util.spec_from_file_location("partscale_blender_core", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


core = _load_core()

SCRIPT = ROOT / "tests" / "blender" / "addon_run.py"
UNDO_SCRIPT = ROOT / "tests" / "blender" / "addon_undo.py"
PARTSCALE = Path(sys.executable).with_name("partscale")


# -- the add-on's command lines (no Blender needed) ---------------------------------------------
def test_blender_axes_map_to_partscale_axes_across_y_up():
    src, dst = "a.glb", "b.glb"
    assert core.edit_args(core.Request(axis="Z", mode="ADD", count=1), src, dst) == [
        "fit", src, "-o", dst, "--add", "y", "1",
    ]  # fmt: skip
    assert core.edit_args(core.Request(axis="Y", mode="SIZE", size=1.5), src, dst)[-3:] == [
        "=", "=", "1.5m",
    ]  # fmt: skip
    args = core.edit_args(core.Request(axis="X", mode="ZONE", start=30, end=70, to=120), src, dst)
    assert args[args.index("--zone") + 1 : args.index("--zone") + 3] == ["30%", "70%"]
    assert args[args.index("--to") + 1] == "120%" and args[args.index("--axis") + 1] == "x"


def test_a_zone_along_blender_y_mirrors_into_partscale_z_and_grows_alike():
    req = core.Request(axis="Y", mode="ZONE", start=20, end=50, to=80, zone_mode="tile")
    args = core.edit_args(req, "a.glb", "b.glb")
    z = args.index("--zone")
    start, end = (float(a.rstrip("%")) for a in args[z + 1 : z + 3])
    to = float(args[args.index("--to") + 1].rstrip("%"))
    # Blender's 20..50 % along Y is partscale's 50..80 % along z (z = -Y); it grows by 30 %
    assert (start, end) == (50.0, 80.0) and to - end == pytest.approx(80 - 50)
    assert args[args.index("--axis") + 1] == "z" and args[-1] == "tile"


def test_bad_requests_and_missing_partscale_are_one_line(tmp_path, monkeypatch):
    with pytest.raises(core.PartscaleError, match="count other than 0"):
        core.edit_args(core.Request(mode="ADD", count=0), "a", "b")
    with pytest.raises(core.PartscaleError, match="expected an executable at"):
        core.find_partscale(str(tmp_path / "nothing"))
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(core.PartscaleError, match="not found on PATH") as exc:
        core.find_partscale("")
    assert "\n" not in str(exc.value)
    assert core.find_partscale(str(PARTSCALE)) == [str(PARTSCALE)]
    assert core.find_partscale(sys.executable)[1:] == ["-m", "partscale"]


def test_partscale_refusals_come_back_as_its_one_error_line():
    with pytest.raises(core.PartscaleError) as exc:
        core.run([sys.executable, "-m", "partscale"], "fit", "missing.glb", "-o", "o.glb")
    msg = str(exc.value)
    assert msg.startswith("partscale: error:") and "missing.glb" in msg and "\n" not in msg


def test_suggestions_are_shown_along_blender_axes():
    text = json.dumps(
        {
            "candidates": [
                {"axis": "z", "kind": "stretch", "zone": [-0.2, 0.1], "score": 0.75},
                {"axis": "y", "kind": "tile", "zone": [0.6, 1.3], "score": 0.7},
            ],
            "elements": {"y": {"elements": [{"length": 0.6}, {"length": 0.61}]}},
        }
    )
    lines = core.summarise_suggestions(text)
    assert lines["Z"][0] == "2 elements, 0.60-0.61 m"
    assert lines["Z"][1] == "tile 0.60..1.30 m"
    assert lines["Y"] == ["stretch -0.10..0.20 m"]  # Y = -z
    assert lines["X"] == []


# -- in Blender ---------------------------------------------------------------------------------
def blender_command() -> list[str]:
    """How to run a script in Blender: a Python with bpy, or the blender binary; else skip."""
    candidates = [os.environ.get("PARTSCALE_BLENDER_PYTHON"), str(ROOT / ".venv-bpy/bin/python")]
    for py in filter(None, candidates):
        if Path(py).is_file():
            ok = subprocess.run([py, "-c", "import bpy"], capture_output=True, timeout=120)
            if ok.returncode == 0:
                return [py]
    blender = shutil.which("blender")
    if blender:
        return [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python"]
    pytest.skip(
        "Blender not found: no bpy in .venv-bpy (./dev.sh test installs the bpy wheel where it "
        "can) or PARTSCALE_BLENDER_PYTHON, and no blender on PATH"
    )


@pytest.fixture(scope="module")
def addon_zip(tmp_path_factory):
    out = tmp_path_factory.mktemp("addon") / "partscale_blender.zip"
    subprocess.run(
        [sys.executable, str(ROOT / "integrations/blender/build.py"), str(out)], check=True
    )
    return out


@pytest.fixture(scope="module")
def bookcase_run(addon_zip, tmp_path_factory):
    glb = data_path("kenney/bookcaseOpen.glb")
    out = tmp_path_factory.mktemp("blender")
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(out / "scripts"))
    cmd = [
        *blender_command(),
        str(SCRIPT),
        "--",
        str(addon_zip),
        str(glb),
        str(PARTSCALE),
        str(out),
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=900)
    assert proc.returncode == 0 and (out / "result.json").is_file(), proc.stdout + proc.stderr
    return json.loads((out / "result.json").read_text()), out


def test_one_more_shelf_through_the_addon_keeps_name_transform_materials_uvs(bookcase_run):
    r, _ = bookcase_run
    before, after = r["before"], r["after"]
    assert r["suggest_error"] is None and r["apply_error"] is None
    assert json.loads(r["suggestions"])["elements"]["y"]["elements"]  # the panel's shelf rows
    # the object itself: name, transform, modifiers, materials, UV maps as they were
    assert after["name"] == before["name"] and after["mesh_name"] == before["mesh_name"]
    assert np.allclose(after["matrix"], before["matrix"], atol=0)
    assert after["modifiers"] == before["modifiers"] == [["Bevel", "BEVEL"]]
    assert after["materials"] == before["materials"] == ["wood"]
    assert after["material_users"] == before["material_users"]  # the same material, not a copy
    assert after["n_materials_in_file"] == before["n_materials_in_file"]  # no leftovers
    assert after["n_meshes_in_file"] == before["n_meshes_in_file"]
    assert after["n_objects_in_file"] == before["n_objects_in_file"]
    assert after["uv_layers"] == before["uv_layers"] == ["UVMap"]
    # tiling copies the shelf's UVs: the UV range stays the source's
    assert np.allclose(after["uv_range"], before["uv_range"], atol=1e-5)
    assert after["faces"] > before["faces"]
    # taller by one shelf row; the bottom is where it was, the top moved up rigidly
    vb, va = np.array(before["vertices"]), np.array(after["vertices"])
    h0, h1 = np.ptp(vb[:, 2]), np.ptp(va[:, 2])
    grow = h1 - h0
    assert va[:, 2].min() == pytest.approx(vb[:, 2].min(), abs=1e-6)
    low = vb[vb[:, 2] < vb[:, 2].min() + 0.1 * h0]
    high = vb[vb[:, 2] > vb[:, 2].max() - 0.1 * h0] + (0, 0, grow)
    for pts in (low, high):
        d = np.min(np.linalg.norm(pts[:, None, :] - va[None, :, :], axis=2), axis=1)
        assert d.max() < 1e-5  # these vertices did not move (the top ones only rigidly)


def test_one_more_shelf_counted_by_partscales_element_finder(bookcase_run):
    from partscale import ingest, zones

    r, out = bookcase_run
    src = ingest.load(data_path("kenney/bookcaseOpen.glb"), res=96)
    res = ingest.load(out / "after.glb", res=96)
    n0 = len(zones.find_elements(src, "y").elements)
    n1 = len(zones.find_elements(res, "y").elements)
    assert n0 >= 2 and n1 == n0 + 1, (n0, n1)
    # the element's length is the source's: one period added, not a stretch
    grow = np.ptp(np.array(r["after"]["vertices"])[:, 2]) - np.ptp(
        np.array(r["before"]["vertices"])[:, 2]
    )
    scale = r["before"]["matrix"][2][2]  # the node's uniform scale (Blender Z row)
    period = np.diff([e.start for e in zones.find_elements(src, "y").elements]).mean()
    assert abs(grow * scale - period) < 0.05 * period


def test_a_cube_made_in_blender_resized_to_a_target_size_stays_one_closed_mesh(bookcase_run):
    r, _ = bookcase_run
    assert r["cube_error"] is None
    before, after = r["cube_before"], r["cube_after"]
    assert np.allclose(r["cube_dimensions"], (3.0, 2.0, 2.0), atol=1e-4)
    assert after["name"] == "Box" and after["materials"] == before["materials"] == ["paint"]
    assert after["uv_layers"] == before["uv_layers"] and after["matrix"] == before["matrix"]
    # glTF's split vertices merged back: closed (every edge between two faces), as it was
    assert r["cube_boundary_edges"] == 0 and r["cube_loose_edges"] == 0
    # one vertex per position, as in Blender's cube (the exported copy had 24 for 8 corners)
    pts = np.round(np.array(after["vertices"]), 6)
    assert len(np.unique(pts, axis=0)) == len(pts) and len(before["vertices"]) == 8


def test_a_zone_along_blender_y_is_the_zone_the_user_gave(bookcase_run):
    """Blender's Y is partscale's -z: the zone 0..25 % from -Y, its end taken to 75 %."""
    r, _ = bookcase_run
    assert r["slab_error"] is None
    v = np.array(r["slab_after"]["vertices"])  # local: the cube spans -1..1
    # the zone [-1, -0.5] became 1.5 long: the object is 3 long along Y, X and Z unchanged
    assert np.ptp(v[:, 1]) == pytest.approx(3.0, abs=1e-5)
    assert np.ptp(v[:, 0]) == pytest.approx(2.0, abs=1e-6)
    assert np.ptp(v[:, 2]) == pytest.approx(2.0, abs=1e-6)
    # the cut at the zone's plane at Y = -0.5 (25 % from -Y) is there and did not move; a zone
    # taken from +Y would cut at Y = +0.5 instead
    ys = np.unique(np.round(v[:, 1], 5))
    assert -0.5 in ys and 0.5 not in ys, ys


def test_bad_input_in_blender_is_one_line_report(bookcase_run):
    r, _ = bookcase_run
    for key, words in [
        ("non_mesh_error", "expected a mesh object"),
        ("bad_path_error", "expected an executable at"),
        ("no_partscale_error", "not found on PATH"),
        ("refused_error", "partscale: error: elements along y"),
    ]:
        msg = r[key]
        assert msg is not None and words in msg, (key, msg)
        assert len([ln for ln in msg.splitlines() if ln.strip()]) == 1, (key, msg)


def test_apply_is_an_undoable_operator(bookcase_run):
    r, _ = bookcase_run
    assert r["apply_options"] == ["REGISTER", "UNDO"]


# -- in Blender with a window: Undo, and the panel's picture ------------------------------------
def test_undo_restores_the_mesh_in_blender_with_a_window(addon_zip, tmp_path):
    """Apply run as a button runs it (with an undo step), then Edit > Undo and Redo."""
    blender, xvfb = shutil.which("blender"), shutil.which("xvfb-run")
    if not (blender and xvfb):
        pytest.skip("Undo needs Blender with a window: blender and xvfb-run not both on PATH")
    glb = data_path("kenney/bookcaseOpen.glb")
    empty = tmp_path / "empty.blend"  # a file to open: Blender shows no splash over the view
    subprocess.run(
        [blender, "-b", "--factory-startup", "--python-expr",
         f"import bpy; bpy.ops.wm.save_as_mainfile(filepath={str(empty)!r})"],
        capture_output=True, timeout=300, check=True,
    )  # fmt: skip
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(tmp_path / "scripts"))
    cmd = [
        xvfb, "-a", "-s", "-screen 0 1400x900x24", blender, "--factory-startup",
        "--enable-event-simulate", str(empty), "--python", str(UNDO_SCRIPT), "--",
        str(addon_zip), str(glb), str(PARTSCALE), str(tmp_path),
    ]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=900)
    assert (tmp_path / "undo.json").is_file(), proc.stdout[-3000:] + proc.stderr[-3000:]
    r = json.loads((tmp_path / "undo.json").read_text())
    assert "error" not in r, r["error"]
    before, after, undone, redone = r["before"], r["after"], r["undone"], r["redone"]
    assert after["faces"] > before["faces"]
    assert undone == before  # faces, vertices, materials, UV maps, name, transform
    assert redone == after
    assert (tmp_path / "panel.png").stat().st_size > 10_000


def test_viewport_planes_cross_the_box_at_the_zone_and_the_elements():
    lo, hi = (0.0, -1.0, 0.0), (2.0, 1.0, 3.0)
    at = core.zone_planes(lo[2], hi[2], 25, 50)
    assert at == [0.75, 1.5]
    tris = np.array(core.plane_quads(lo, hi, "Z", at))
    assert tris.shape == (12, 3)  # two rectangles of two triangles
    assert set(np.round(tris[:, 2], 6)) == {0.75, 1.5}
    assert tris[:, 0].min() == 0 and tris[:, 0].max() == 2 and np.ptp(tris[:, 1]) == 2
    text = json.dumps({"elements": {"z": {"elements": [{"start": 0.1, "end": 0.4}]}}})
    assert core.element_planes(text, "Y") == [-0.4, -0.1]  # Blender's Y is partscale's -z
    assert core.element_planes("not json", "Y") == []
