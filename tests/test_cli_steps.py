"""The named steps of ``scale``, ``fit``, ``suggest`` and ``export``, and the mesh route's
dispatch they share (partscale.meshedit): each on its own, against what the command relies on."""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest

from partscale import data, shapes
from partscale.csdf import CSDF
from partscale.errors import InputError
from partscale.meshedit import (
    MeshEditResult,
    MeshFrame,
    Seam,
    check_square,
    edit_target,
    is_mesh_route,
    report_lines,
)

# the modules (partscale.cli's names scale, export, suggest are the commands)
scale_cli = importlib.import_module("partscale.cli.scale")
export_cli = importlib.import_module("partscale.cli.export")
suggest_cli = importlib.import_module("partscale.cli.suggest")

# -- the mesh route's dispatch (partscale.meshedit) --------------------------------------------


@pytest.mark.parametrize(
    ("src", "dst", "mesh"),
    [
        ("a.glb", "b.glb", True),
        ("a.GLTF", "b.OBJ", True),
        ("a.ply", "b.usdz", True),
        ("a.obj", "b.csdf.npz", False),  # a mesh in, a CSDF out: the CSDF route
        ("a.csdf.npz", "b.glb", False),
        ("a.gltf", "b.gltf", False),  # glTF is read, not written: GLB out
    ],
)
def test_is_mesh_route_is_a_mesh_in_and_a_mesh_out(src, dst, mesh):
    assert is_mesh_route(src, dst) is mesh


def test_check_square_refuses_it_off_the_mesh_route_naming_both_files():
    check_square(False, False, Path("a.csdf.npz"), Path("b.csdf.npz"))
    check_square(True, True, Path("a.glb"), Path("b.glb"))
    with pytest.raises(InputError, match=r"--square: expected a mesh IN.*a\.csdf\.npz -> b\.glb"):
        check_square(True, False, Path("a.csdf.npz"), Path("b.glb"))


def test_edit_target_is_the_frame_or_the_csdf_where_zones_are_found():
    frame = edit_target(data.table(), zones=False)
    assert isinstance(frame, MeshFrame) and frame.meta == {"units": "m"}
    c = edit_target(data.table(), zones=True)
    assert isinstance(c, CSDF)
    # the same object: the CSDF's solid lies within a voxel of the triangles' bounds
    assert np.abs(c.surface_bounds() - frame.surface_bounds()).max() <= c.voxel_size


def test_report_lines_say_seams_the_turn_and_the_files_in_order():
    bad = Seam("x", 0.5, welded=40, unmatched=4)
    good = Seam("x", 0.7, welded=44, unmatched=0)
    result = MeshEditResult(
        [Path("o.obj"), Path("o.mtl")], 10, 30, [good, bad], off_square_deg=20.0
    )
    lines, done = report_lines(result)
    assert [k for k, _ in lines] == ["warning", "warning"]  # the unwelded seam, then the walls
    assert lines[0][1] == bad.message()
    assert "20" in lines[1][1]
    assert done == "wrote o.obj, o.mtl (mesh route: 10 -> 30 triangles)"
    turned, _ = report_lines(MeshEditResult([Path("o.glb")], 1, 1, [], turned_deg=-12.5))
    assert [k for k, _ in turned] == ["note"] and "12.5" in turned[0][1]


# -- scale's option steps -----------------------------------------------------------------------


def test_given_keeps_the_options_given():
    assert scale_cli._given(("--to", "1"), ("--by", None), ("--copies", "")) == [("--to", "1")]
    # truthy=False: 0 sides is given (a round outline)
    assert scale_cli._given(("--sides", 0), ("--span", None), truthy=False) == [("--sides", 0)]


def test_zone_options_default_the_mode_and_refuse_what_is_missing_or_doubled():
    assert scale_cli._check_zone_options("X", ("1", "2"), None, [("--to", "3")], None) == (
        "x",
        "stretch",
    )
    assert scale_cli._check_zone_options("y", ("1", "2"), None, [("--copies", "+1")], "+1") == (
        "y",
        "tile",
    )
    with pytest.raises(InputError, match="missing --zone, --to"):
        scale_cli._check_zone_options("x", None, None, [], None)
    with pytest.raises(InputError, match="expected one of --to, --by, --copies, got --to, --by"):
        scale_cli._check_zone_options("x", ("1", "2"), None, [("--to", "3"), ("--by", "1")], None)
    with pytest.raises(InputError, match="--axis: expected one of x, y, z, got 'w'"):
        scale_cli._check_zone_options("w", ("1", "2"), None, [("--to", "3")], None)
    with pytest.raises(InputError, match="--copies: expected --mode tile, got --mode stretch"):
        scale_cli._check_zone_options("x", ("1", "2"), "stretch", [("--copies", "2")], "2")


def test_a_recipe_comes_alone():
    scale_cli._check_recipe_alone(None, None, None, [], False)
    with pytest.raises(InputError, match="got it with --axis, --to, --snap"):
        scale_cli._check_recipe_alone("x", None, None, [("--to", "1")], True)


def test_warps_refuse_the_mesh_route():
    scale_cli._check_warp_route(True, False)
    with pytest.raises(InputError, match="--normal: expected a CSDF"):
        scale_cli._check_warp_route(False, True)


# -- export's option steps ----------------------------------------------------------------------


def test_export_budget_defaults_and_full_resolution():
    mesh = Path("out.glb")
    assert export_cli._budget(mesh, None, None, None) == export_cli.DEFAULT_ERROR
    assert export_cli._budget(mesh, None, 0.0, None) is None  # --error 0: full resolution
    assert export_cli._budget(mesh, 5000, None, None) is None  # a face budget instead
    with pytest.raises(InputError, match="expected --faces or --error, got both"):
        export_cli._budget(mesh, 10, 0.1, None)
    with pytest.raises(InputError, match="PLY has no textures"):
        export_cli._budget(Path("out.ply"), None, None, 512)
    with pytest.raises(InputError, match="expected --mesh with --faces"):
        export_cli._budget(None, 10, None, None)


def test_export_outputs_are_distinct_and_some(tmp_path):
    mesh, tex = tmp_path / "a.glb", tmp_path / "a.raw"
    assert export_cli._check_outputs(mesh, [tex], None) == [mesh, tex]
    with pytest.raises(InputError, match="at least one output"):
        export_cli._check_outputs(None, [], None)
    with pytest.raises(InputError, match="the same one twice"):
        export_cli._check_outputs(None, [tex, tmp_path / "." / "a.raw"], None)
    with pytest.raises(InputError, match="existing output folder"):
        export_cli._check_outputs(tmp_path / "none" / "a.glb", [], None)


# -- suggest's findings and lines ----------------------------------------------------------------


@pytest.fixture(scope="module")
def bookcase():
    return shapes.bookcase(height=1.22)  # four rows of 30 cm along y


def test_suggest_findings_and_text_of_a_bookcase(bookcase):
    from partscale.zones import suggest

    found = suggest_cli._findings(bookcase, "y")
    assert list(found.elements) == ["y"] and found.frame is None  # the plan: every axis only
    assert found.elements["y"].best is not None  # the shelf rows
    cands = suggest(bookcase, "y")
    lines = suggest_cli._text_lines(cands, found, "y", "m")
    assert lines[0].startswith("y: ")
    ranked = [x for x in lines if x[:3].strip().rstrip(".").isdigit()]
    assert len(ranked) == len(cands) and ranked[0].startswith(" 1. y tile ")


def test_suggest_missing_and_candidate_lines(bookcase):
    from partscale.zones import suggest

    cands = suggest(bookcase, "y")
    assert suggest_cli._missing_lines(cands, "y") == []  # a tile along y
    assert suggest_cli._missing_lines([], "x") == [
        "x: no candidate (no repeated element, no constant slab)"
    ]
    stretches = [x for x in cands if x.kind == "stretch"]
    assert suggest_cli._missing_lines(stretches, "y") == [
        "y: no repeated element (no tile candidate)"
    ]
    first = suggest_cli._candidate_lines(cands[:1], "m")[0]
    x = cands[0]
    assert first.startswith(f" 1. y tile    zone {x.zone[0]:.4g} {x.zone[1]:.4g} m period")


def test_suggest_json_doc_holds_every_finding(bookcase):
    from partscale.zones import suggest

    found = suggest_cli._findings(bookcase, None)
    doc = suggest_cli._json_doc(suggest(bookcase), found)
    assert set(doc) >= {"candidates", "elements", "steps", "helix", "rotation"}
    assert set(doc["elements"]) == {"x", "y", "z"}
    assert ("radial" in doc) == (found.frame is not None)
