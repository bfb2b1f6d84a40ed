"""partscale.complete's guard: a completion the scan speaks against gives way to the scan as
observed, closed, and says why; a completion the scan supports is kept."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh
from conftest import data_path

from partscale import ingest
from partscale.complete import api, complete, guard
from partscale.complete.column import sure_carver
from partscale.errors import PartscaleWarning
from partscale.evaluate import virtual
from partscale.ingest import from_trimesh

RES = 64


@pytest.fixture(scope="module")
def lamp_post():
    """A low bench (0.9 x 0.3 x 0.5 m) with a back 1 m tall and 0.3 m wide at its +x end only:
    no mirror plane across x, and one view from the front right sees the bench's top at -x
    empty."""
    bench = trimesh.creation.box((0.9, 0.3, 0.5))
    bench.apply_translation((0, 0.15, 0))
    post = trimesh.creation.box((0.3, 1.0, 0.5))
    post.apply_translation((0.3, 0.8, 0))
    mesh = from_trimesh(trimesh.util.concatenate([bench, post]))
    frames = virtual.virtual_scan(mesh, 1)
    ob = api.observe(frames)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PartscaleWarning)
        observed = complete(frames, res=RES, symmetry=False)
    return ob, observed


def _mirrored_across_x(c):
    """The completion and its mirror image across the grid's middle x plane, forced in: the
    back copied onto the bench's far end, where the camera saw through."""
    return c.replace(sdf=np.minimum(c.sdf, c.sdf[::-1]).astype(np.float32))


def test_forced_wrong_mirror_gives_way_to_the_observed_scan(lamp_post):
    ob, observed = lamp_post
    bad = _mirrored_across_x(observed)
    carver = sure_carver(ob.frames, 0.0)
    assert guard.evidence(bad, ob.points, carver).in_free > guard.MAX_IN_FREE
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        kept = guard.choose(bad, ob.points, carver, lambda: observed)
    record = kept.meta["completion"]["guard"]
    assert record["kept"] == "observed"
    assert np.array_equal(kept.sdf, observed.sdf)
    assert "saw through" in record["reason"]
    assert record["evidence"]["in_free"] > record["evidence_observed"]["in_free"]
    notes = [str(w.message) for w in caught if issubclass(w.category, PartscaleWarning)]
    assert any("kept the scan as observed" in n for n in notes), notes
    assert kept.meta["history"][-1]["guard"] == "observed"


def test_forced_completion_is_kept_and_says_what_spoke_against_it(lamp_post):
    ob, observed = lamp_post
    bad = _mirrored_across_x(observed)
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        kept = guard.choose(
            bad, ob.points, sure_carver(ob.frames, 0.0), lambda: observed, force=True
        )
    record = kept.meta["completion"]["guard"]
    assert record["kept"] == "completion" and record["forced"]
    assert "saw through" in record["reason"]
    assert np.array_equal(kept.sdf, bad.sdf)


def test_the_scan_supports_its_own_closure(lamp_post):
    # what was observed, closed, keeps the observed surface and stays out of free space
    ob, observed = lamp_post
    ev = guard.evidence(observed, ob.points, sure_carver(ob.frames, 0.0))
    assert ev.on_surface >= guard.MIN_ON_SURFACE
    assert ev.in_free <= guard.MAX_IN_FREE
    assert observed.meta["completion"]["guard"]["kept"] == "completion"


def test_a_supported_completion_is_kept():
    # the shipped table, one view: the completion's evidence holds and it is what comes back
    from partscale import data

    frames = virtual.virtual_scan(ingest.load_mesh(data.table()), 1)
    c = complete(frames, res=RES)
    record = c.meta["completion"]["guard"]
    assert record["kept"] == "completion", record
    assert record["reason"] is None
    assert record["evidence"]["on_surface"] >= guard.MIN_ON_SURFACE


def _chair2_truth():
    from partscale.evaluate import completion

    mesh = ingest.load_mesh(data_path("sweethome3d/chair2.obj"))
    gt = ingest.from_mesh(mesh, res=128)
    tau = completion.f_tau(gt)
    return mesh, completion.surface_samples(gt, tau=tau)[0], tau


def test_thin_sheet_chair_is_no_maze_of_struts():
    # a chair with thin sheet sides, one view at its real size (metres): at most a handful of
    # struts, whichever result the guard keeps, and no worse than the raw scan's points
    from partscale.evaluate import completion

    mesh, G, tau = _chair2_truth()
    frames = virtual.virtual_scan(mesh, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PartscaleWarning)
        c = complete(frames, res=128)
    m = c.meta["completion"]
    assert len(m["struts"]) <= guard.MAX_STRUTS, (len(m["struts"]), m["guard"])
    raw = completion.chamfer_fscore(api.observe(frames).points, G, tau)["fscore"]
    full = completion.chamfer_fscore(completion.surface_samples(c, tau=tau)[0], G, tau)["fscore"]
    assert full >= raw, (full, raw)


def test_floor_is_found_from_a_camera_pitched_45_degrees_down():
    # a handheld scan from above: the floor lies 45 degrees off the camera's own up; the floor
    # gives up and the completion stays on the chair (not the floor around it)
    mesh, G, _ = _chair2_truth()
    frames = virtual.virtual_scan(mesh, azimuths=(69.0,), elevation=45.0)
    c = complete(frames, res=64)
    m = c.meta["completion"]
    assert m["up_from"] == "floor"
    assert np.degrees(np.arccos(min(1.0, m["up"][1]))) <= 2.0, m["up"]
    from partscale.evaluate import completion

    P, _ = completion.surface_samples(c, 4000)
    slack = 0.05  # metres: the closure and the noise beyond the chair's box
    assert (P.min(0) >= G.min(0) - slack).all() and (P.max(0) <= G.max(0) + slack).all()


def _desk():
    """A desk (0.8 x 0.72 x 0.5 m): a top on four legs and a modesty panel at the back, mirror
    symmetric across x only."""
    parts = []
    top = trimesh.creation.box((0.8, 0.04, 0.5))
    top.apply_translation((0, 0.7, 0))
    parts.append(top)
    for x in (-0.35, 0.35):
        for z in (-0.2, 0.2):
            leg = trimesh.creation.box((0.05, 0.68, 0.05))
            leg.apply_translation((x, 0.34, z))
            parts.append(leg)
    panel = trimesh.creation.box((0.8, 0.3, 0.03))
    panel.apply_translation((0, 0.55, -0.22))
    parts.append(panel)
    return from_trimesh(trimesh.util.concatenate(parts), color=(150, 100, 60))


@pytest.fixture(scope="module")
def desk_scans():
    """The desk seen once from 30 degrees above, with and without the floor under it, and
    level without a floor ("level")."""
    mesh = _desk()
    out = {
        floor: virtual.virtual_scan(mesh, 1, floor=floor, elevation=30.0, azimuths=(30.0,))
        for floor in (True, False)
    }
    out["level"] = virtual.virtual_scan(mesh, 1, floor=False, elevation=0.0, azimuths=(30.0,))
    return out


def test_symmetry_on_a_known_up_is_kept(desk_scans):
    # the floor gives up: the mirror plane's copies stand and the completion is what comes back
    c = complete(desk_scans[True], res=48)
    m = c.meta["completion"]
    assert m["up_from"] == "floor"
    assert m["guard"]["kept"] == "completion" and m["guard"]["weak"] == []
    assert m["mirrored"] > 0.05 and any(s["kind"] == "mirror" for s in m["symmetries"])


def test_symmetry_on_the_faces_up_is_kept(desk_scans):
    # no floor from 30 degrees above: the camera's own axis is 30 degrees off, the desk's level
    # top and upright legs give up, and the mirror plane's copies stand on it
    c = complete(desk_scans[False], res=48)
    m = c.meta["completion"]
    assert m["up_from"].startswith("faces")
    assert np.degrees(np.arccos(np.clip(np.asarray(m["up"]) @ [0, 1, 0], -1, 1))) <= 1.0
    assert m["guard"]["kept"] == "completion" and m["guard"]["weak"] == []
    assert m["mirrored"] > 0.05


@pytest.fixture(scope="module")
def desk_without_floor(desk_scans):
    """The desk completed from its level view without a floor, and the warnings it gave."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        c = complete(desk_scans["level"], res=48)
    return c, [str(w.message) for w in caught if issubclass(w.category, PartscaleWarning)]


def test_symmetry_on_the_cameras_up_gives_way_to_the_observed_scan(desk_scans, desk_without_floor):
    # seen level without a floor: no level face seen, no level underside: up is the camera's own
    # axis (right here, but nothing in the scan says so), and so are the mirror planes found by
    # it: the scan as observed, closed, comes back, and says so
    c, notes = desk_without_floor
    m = c.meta["completion"]
    record = m["guard"]
    assert record["kept"] == "observed" and record["weak"], record
    assert "camera's axis for up" in record["reason"]
    assert m["mirrored"] == 0.0 and m["symmetries"] == [] and m["struts"] == []
    assert c.meta["history"][-1]["guard"] == "observed"
    assert sum("camera's axis for up" in n for n in notes) == 1, notes
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PartscaleWarning)
        forced = complete(desk_scans["level"], res=48, force_completion=True)
    kept = forced.meta["completion"]
    assert kept["guard"]["kept"] == "completion" and kept["mirrored"] > 0.0
    assert "camera's axis for up" in kept["guard"]["reason"]


def test_a_completion_the_guard_would_set_aside_for_its_symmetries_is_not_made(
    desk_scans, monkeypatch
):
    # the symmetries are found first: where they rest on the camera's axis for up, the scan as
    # observed is what comes back whatever the completion's evidence, so only it is fused
    from partscale.complete import api

    fused = []
    real = api.fuse_solid

    def counted(*args, **kwargs):
        fused.append(kwargs.get("fill_between"))
        return real(*args, **kwargs)

    monkeypatch.setattr(api, "fuse_solid", counted)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PartscaleWarning)
        c = complete(desk_scans["level"], res=48)
    record = c.meta["completion"]["guard"]
    assert record["kept"] == "observed" and record["weak"]
    assert fused == [False]  # the observed closure alone (no fill between faces)
    assert record["evidence"] is None
    assert record["evidence_observed"]["on_surface"] >= guard.MIN_ON_SURFACE


def test_info_says_why_the_scan_was_kept_as_observed(desk_without_floor, tmp_path):
    import json

    from conftest import run_cli

    from partscale import csdf

    p = csdf.save(desk_without_floor[0], tmp_path / "desk.csdf.npz")
    text = run_cli("info", p, check=True).stdout
    assert "kept the scan as observed, closed" in text and "camera's axis for up" in text
    summary = json.loads(run_cli("info", p, "--json", check=True).stdout)["completion"]
    assert "camera's axis for up" in summary["guard_reason"]


@pytest.mark.parametrize("violation, kept", [(0.1, "completion"), (0.3, "observed")])
def test_a_turn_whose_copies_stand_in_free_space_gives_way(lamp_post, violation, kept):
    # a 4-fold turn found on the scan: kept while its copies mostly land on what the scan saw,
    # the scan as observed, closed, where more than a fifth stand where the cameras saw through
    ob, observed = lamp_post
    comp = dict(observed.meta["completion"])
    comp["symmetries"] = [{"kind": "rotation", "fold": 4, "support": 0.8, "violation": violation}]
    turned = observed.replace(meta={**observed.meta, "completion": comp})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = guard.choose(turned, ob.points, sure_carver(ob.frames, 0.0), lambda: observed)
    record = out.meta["completion"]["guard"]
    assert record["kept"] == kept
    notes = [str(w.message) for w in caught if issubclass(w.category, PartscaleWarning)]
    if kept == "observed":
        assert "4-fold turn's copies stand where the cameras saw through" in record["reason"]
        assert len(notes) == 1 and record["weak"]
    else:
        assert record["reason"] is None and not notes and record["weak"] == []


def test_the_scan_kept_as_observed_is_closed_thinly():
    # Sweet Home's radiator seen level from its side without a floor: its symmetries rest on
    # the camera's axis for up, so the scan is kept as observed; closed, it grew a block up to
    # 29 voxels deep behind the side no camera saw past (filled between faces, carried in as
    # slabs): every voxel of it now lies within 3 voxels of what the camera saw, but for the
    # middles of the sensor's holes closed through the board (14 voxels of 23631, 3.4 voxels)
    from scipy.spatial import cKDTree

    mesh = ingest.load_mesh(data_path("sweethome3d/electricRadiator.obj"))
    frames = virtual.virtual_scan(mesh, azimuths=(292.0,), elevation=0.0, floor=False)
    with pytest.warns(PartscaleWarning) as said:
        c = complete(frames, res=128)
    # one line says why; another that the scan holds it in pieces (its side's boards apart)
    assert any("as observed" in str(w.message) for w in said)
    assert c.meta["completion"]["guard"]["kept"] == "observed"
    T = np.asarray(c.meta["completion"]["to_input_frame"], np.float64)
    solid = c.origin + np.argwhere(c.sdf < 0) * c.voxel_size
    d = cKDTree(api.observe(frames).points).query(solid @ T[:3, :3].T + T[:3, 3])[0]
    assert (d > 3 * c.voxel_size).mean() <= 0.002
    assert d.max() <= 4 * c.voxel_size
