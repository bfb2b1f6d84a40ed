"""partscale.complete: a result that looks broken although it is what the scan holds (pieces
apart, a top above the floor with nothing under it) is said so in one line and recorded."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import data_path


def _boxes(*boxes):
    """One coloured mesh of axis-aligned boxes, each (centre (3,), extents (3,)) in metres."""
    import trimesh

    from partscale.ingest import from_trimesh

    parts = [trimesh.creation.box(extents=e) for _, e in boxes]
    for m, (c, _) in zip(parts, boxes, strict=True):
        m.apply_translation(c)
    return from_trimesh(trimesh.util.concatenate(parts), color=(150, 120, 90))


@pytest.fixture(scope="module")
def two_pieces():
    """A plinth on the floor and a plate 0.65 m over it, nothing between (a pedestal no camera
    read), completed from one view: (the CSDF, the PartscaleWarnings' lines)."""
    from partscale.complete import complete
    from partscale.errors import PartscaleWarning
    from partscale.evaluate import virtual_scan

    mesh = _boxes(((0, 0.025, 0), (0.5, 0.05, 0.5)), ((0, 0.72, 0), (0.8, 0.04, 0.8)))
    frames = virtual_scan(mesh, azimuths=(30.0,), elevation=15.0, distance=1.5)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        c = complete(frames, res=64)
    return c, [str(w.message) for w in caught if issubclass(w.category, PartscaleWarning)]


def test_a_plate_over_a_base_with_nothing_between_is_said_to_be_two_pieces(two_pieces):
    # no strut spans 0.65 m (a fifth of the object's size at most), and no pedestal stands
    # where the camera saw under the plate: the result is the two pieces the scan holds, and
    # one line says so
    c, said = two_pieces
    m = c.meta["completion"]
    assert m["pieces"] == 2 and not m["struts"]
    assert any("2 pieces apart" in s for s in said), said
    assert any("2 pieces apart" in s for s in m["guard"]["caveats"])
    # it stands on the floor: nothing said about that
    assert m["above_floor"] is not None and m["above_floor"] <= 0.03
    assert not any("above the floor" in s for s in m["guard"]["caveats"])


def test_info_says_the_result_is_in_pieces(two_pieces, tmp_path):
    import json

    from conftest import run_cli

    from partscale import csdf

    p = csdf.save(two_pieces[0], tmp_path / "two.csdf.npz")
    text = run_cli("info", p, check=True).stdout
    assert "completion:  the result is 2 pieces apart" in text
    summary = json.loads(run_cli("info", p, "--json", check=True).stdout)["completion"]
    assert any("2 pieces apart" in s for s in summary["caveats"])


def test_a_standing_table_is_one_piece_on_the_floor_and_nothing_is_said():
    from partscale import data, ingest
    from partscale.complete import complete
    from partscale.evaluate import virtual_scan

    frames = virtual_scan(ingest.load_mesh(data.table()), azimuths=(30.0,), elevation=25.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = complete(frames, res=64)
    m = c.meta["completion"]
    assert m["pieces"] == 1 and m["guard"]["caveats"] == []
    assert abs(m["above_floor"]) <= 2 * c.voxel_size


def test_above_floor_is_the_lowest_face_over_the_plane():
    # a solid whose lowest voxel centre lies 0.45 m over the plane y = 0.05 (centres at
    # y = 0.5 .. 0.7, voxels 0.1 m): its lowest face, half a voxel lower, 0.40 m
    from partscale.complete.api import above_floor
    from partscale.complete.floor import Plane
    from partscale.complete.fuse import GridFrame

    s = np.zeros((4, 10, 4), bool)
    s[1:3, 5:8, 1:3] = True  # voxel centres at y = 0.5 .. 0.7
    g = GridFrame(np.eye(4), s.shape, np.zeros(3), 0.1)
    assert above_floor(s, g, Plane(np.array([0.0, 1.0, 0.0]), 0.05)) == 0.4
    assert above_floor(np.zeros_like(s), g, Plane(np.array([0.0, 1.0, 0.0]), 0.0)) is None


def test_a_round_table_seen_only_from_above_its_top_says_it_stands_above_the_floor():
    # Kenney's round table (0.7 m a unit) from 35 degrees above at 1.5 m: its top hides its
    # pedestal; the scan holds the top and the floor, 0.6 m below it
    import dataclasses

    from partscale import ingest
    from partscale.complete import complete
    from partscale.evaluate import virtual_scan

    mesh = ingest.load_mesh(data_path("kenney/tableRound.glb"))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)
    frames = virtual_scan(mesh, azimuths=(30.0,), elevation=35.0, distance=1.5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = complete(frames, res=96)
    m = c.meta["completion"]
    assert m["above_floor"] >= 0.4
    assert any("above the floor seen" in s for s in m["guard"]["caveats"])


@pytest.mark.parametrize("distance", [0.5, 1.0])
def test_an_object_the_camera_framed_too_closely_is_said_to_run_out_of_its_frame(distance):
    # a bench 3 m long seen from half the distance that frames it: its ends and its foot lie
    # beyond the image; framed whole, nothing is said
    from partscale.complete import complete
    from partscale.evaluate import virtual_scan

    frames = virtual_scan(
        _boxes(((0, 0.4, 0), (3.0, 0.8, 0.9))), azimuths=(10.0,), elevation=15.0, distance=distance
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = complete(frames, res=64)
    m = c.meta["completion"]
    (sides,) = m["cut_by_frame"]
    said = [s for s in m["guard"]["caveats"] if "runs out of the camera's frame" in s]
    if distance < 1.0:
        assert {"left", "right"} <= set(sides) and len(said) == 1
        assert "left" in said[0] and "right" in said[0]
    else:
        assert sides == [] and said == []
