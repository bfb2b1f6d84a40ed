"""``partscale scale``: the command a user runs, and every class of bad input it refuses."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from conftest import assert_bad_input

from partscale import shapes
from partscale.csdf import load, save
from partscale.edit import JSON_SCHEMA, Recipe, apply_recipe, recipe_from_history


@pytest.fixture(scope="module")
def box_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("in") / "box.csdf.npz"
    save(shapes.box((0, 0, 0), (1.0, 0.5, 0.3), voxel_size=0.02), path)
    return path


def test_scale_writes_the_edited_object(cli, box_file, tmp_path):
    out = tmp_path / "long.csdf.npz"
    proc = cli("scale", box_file, "-o", out, "--axis", "x", "--zone", "30%", "60%", "--to", "90%")
    assert proc.returncode == 0, proc.stderr
    c = load(out)
    lo, hi = c.surface_bounds()[:, 0]
    assert hi - lo == pytest.approx(1.3, abs=0.01)
    assert c.meta["history"][-1]["given"]["zone"] == ["30%", "60%"]


def test_recipe_file_matches_the_library_bit_for_bit(cli, box_file, tmp_path):
    recipe = {
        "version": 1,
        "edits": [
            {"axis": "x", "zone": [0.2, 0.5], "to": 0.9, "mode": "tile"},
            {"axis": "z", "zone": ["20%", "70%"], "to": "50%"},
        ],
    }
    rfile = tmp_path / "r.json"
    rfile.write_text(json.dumps(recipe))
    out = tmp_path / "r.csdf.npz"
    proc = cli("scale", box_file, "-o", out, "--recipe", rfile)
    assert proc.returncode == 0, proc.stderr
    got = load(out)
    want = apply_recipe(load(box_file), Recipe.parse(recipe))
    assert np.array_equal(got.sdf, want.sdf) and np.array_equal(got.rgb, want.rgb)
    replay = apply_recipe(load(box_file), recipe_from_history(got, after=load(box_file)))
    assert np.array_equal(got.sdf, replay.sdf)


def test_recipe_file_reads_lengths_with_units_as_the_cli_does(cli, box_file, tmp_path):
    """``"20cm"``, ``"0.5m"``, ``"900mm"`` in a recipe: the same object as 0.2, 0.5, 0.9."""
    with_units = {"edits": [{"axis": "x", "zone": ["20cm", " 0.5m"], "to": "900mm"}]}
    rfile = tmp_path / "r.json"
    rfile.write_text(json.dumps(with_units))
    out = tmp_path / "r.csdf.npz"
    proc = cli("scale", box_file, "-o", out, "--recipe", rfile)
    assert proc.returncode == 0, proc.stderr
    want = apply_recipe(
        load(box_file), Recipe.parse([{"axis": "x", "zone": [0.2, 0.5], "to": 0.9}])
    )
    assert np.array_equal(load(out).sdf, want.sdf)
    assert Recipe.parse(with_units, units="m").edits[0].dest == pytest.approx(0.9, abs=1e-12)
    # the library converts with the object's units too, and the schema admits such positions
    got = apply_recipe(load(box_file), with_units)
    assert np.array_equal(got.sdf, want.sdf)
    unit_pattern = JSON_SCHEMA["$defs"]["position"]["oneOf"][2]["pattern"]
    assert all(re.match(unit_pattern, v) for v in ("20cm", " 0.5m", "900mm", "+20cm", "2.1m"))
    assert not any(re.match(unit_pattern, v) for v in ("20ft", "cm", "20%", "20"))


@pytest.mark.parametrize(
    ("position", "meta_units", "fragments"),
    [
        ("50ft", "m", ["edits[0].zone[1]", "unit", "'ft'"]),
        ("50cm", None, ["edits[0].zone[1]", "units are unknown", "cannot be converted"]),
    ],
)
def test_recipe_length_with_a_bad_unit_is_one_line(cli, tmp_path, position, meta_units, fragments):
    src = tmp_path / "b.csdf.npz"
    c = shapes.box((0, 0, 0), (1.0, 0.5, 0.3), voxel_size=0.02)
    save(c.replace(meta={**c.meta, "units": meta_units}), src)
    rfile = tmp_path / "r.json"
    rfile.write_text(json.dumps({"edits": [{"axis": "x", "zone": [0.2, position], "to": 0.9}]}))
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(cli("scale", src, "-o", out, "--recipe", rfile), str(rfile), *fragments)
    assert not out.exists()


def test_a_zone_plane_cutting_a_board_is_said_and_recorded(cli, tmp_path):
    """END cuts the fourth of five boards 1.3 voxels in: the sliver is not repeated at the inner
    seam, and scale says so on stderr (the plane, where, how much) and in the history."""
    h = 0.02
    c, boxes = shapes.bars(5, width=4 * h, gap=8 * h, height=0.3, depth=0.2, voxel_size=h)
    src = tmp_path / "boards.csdf.npz"
    save(c, src)
    start, end = boxes[2][0][0] - 4 * h, boxes[3][0][0] + 1.3 * h
    out = tmp_path / "o.csdf.npz"
    to = end + (end - start)
    proc = cli(
        "scale", src, "-o", out, "--axis", "x", "--zone", start, end, "--to", to, "--mode", "tile"
    )
    assert proc.returncode == 0, proc.stderr
    said = " ".join(proc.stderr.split())
    assert "END plane (" in said and "cuts an element" in said and "left out" in said, proc.stderr
    assert "START plane" not in said and "--snap puts the planes in gaps" in said
    entry = load(out).meta["history"][-1]
    assert set(entry["slivers_left_out"]) == {"end"}
    # after a snap (where no phase of the period misses every element) no --snap hint
    from partscale.edit import describe_changes

    (line,) = [w for w in describe_changes([{**entry, "snapped": []}], load(out)) if "cuts" in w]
    assert "--snap" not in line, line


BAD = [
    (["--axis", "w", "--zone", "0.2", "0.5", "--to", "0.7"], ["--axis", "x, y, z"]),
    (["--axis", "x", "--zone", "0.2", "0.5", "--to", "0.7", "--mode", "squash"], ["--mode"]),
    (["--axis", "x", "--zone", "0.5", "0.2", "--to", "0.7"], ["START < END"]),
    (["--axis", "x", "--zone", "0.2", "0.5", "--to", "0.1"], ["DEST > START"]),
    (["--axis", "x", "--zone", "0.2", "0.5", "--to", "0.2"], ["DEST == START", "mode tile"]),
    (["--axis", "x", "--zone", "0.2", "0.5", "--to", "0.1", "--mode", "tile"], ["DEST > START"]),
    # positions are echoed as typed, with the world value they resolved to
    (["--axis", "x", "--zone", "10%", "90%", "--to", "-5%"], ["START 10% (", "got -5% ("]),
    (["--axis", "x", "--zone", "1.5", "1.8", "--to", "2.0"], ["zone", "extent"]),
    (["--axis", "x", "--zone", "0.2", "0.23", "--to", "0.4"], ["two voxels"]),
    (["--axis", "x", "--zone", "abc", "0.5", "--to", "0.7"], ["--zone START", "number"]),
    (["--axis", "x", "--zone", "0.2", "0.5"], ["--to"]),
    (["--axis", "x", "--zone", "0.2", "0.5", "--to", "1e400%"], ["--to", "finite percentage"]),
    (["--axis", "x", "--zone", "0.2", "inf", "--to", "0.7"], ["--zone END", "finite number"]),
]


@pytest.mark.parametrize(("args", "fragments"), BAD)
def test_bad_input_is_one_line_and_writes_nothing(cli, box_file, tmp_path, args, fragments):
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(cli("scale", box_file, "-o", out, *args), *fragments)
    assert not out.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("content", "fragments"),
    [
        ("{not json", ["expected JSON"]),
        ('{"edits": [{"axis": "x", "zone": [0.2], "to": 0.7}]}', ["zone"]),
        ('{"edits": [{"axis": "x", "zone": [0.2, 0.5], "to": 0.7, "speed": 1}]}', ["unknown"]),
        ('{"edits": []}', ["non-empty"]),
    ],
)
def test_bad_recipe_file(cli, box_file, tmp_path, content, fragments):
    rfile = tmp_path / "r.json"
    rfile.write_text(content)
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(cli("scale", box_file, "-o", out, "--recipe", rfile), *fragments)
    assert not out.exists()


@pytest.mark.parametrize(
    ("extra", "fragments"),
    [
        (["--mode", "tile"], ["--recipe", "alone", "--mode"]),
        (["--mode", "stretch"], ["--recipe", "alone", "--mode"]),
        (["--axis", "x"], ["--recipe", "alone", "--axis"]),
    ],
)
def test_recipe_comes_alone(cli, box_file, tmp_path, extra, fragments):
    """--mode with --recipe would be ignored (each edit has its own mode): refused."""
    rfile = tmp_path / "r.json"
    rfile.write_text('{"edits": [{"axis": "x", "zone": [0.2, 0.5], "to": 0.7}]}')
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(cli("scale", box_file, "-o", out, "--recipe", rfile, *extra), *fragments)
    assert not out.exists()


def test_result_beyond_the_memory_limit_is_refused(box_file, tmp_path):
    import os
    import subprocess
    import sys

    from conftest import ROOT

    out = tmp_path / "o.csdf.npz"
    env = dict(os.environ, PARTSCALE_MAX_MEMORY="1000000", PYTHONPATH=str(ROOT / "src"))
    args = ["scale", box_file, "-o", out, "--axis", "x", "--zone", "0.2", "0.5", "--to", "3"]
    proc = subprocess.run(
        [sys.executable, "-m", "partscale", *map(str, args)],
        capture_output=True,
        text=True,
        env=env,
    )
    assert_bad_input(proc, "memory", "would need")
    assert not out.exists()
