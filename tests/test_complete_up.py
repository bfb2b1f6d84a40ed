"""partscale.complete: "up" of a scan without a floor (the floor cut away), from the object."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import data_path


def _angle_deg(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(
        np.degrees(np.arccos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))
    )


def _swivel_chair(column: bool, slope: float = 10.0):
    """A swivel chair (metres, y up, standing on y = 0): seat, back, five legs 72 degrees apart
    rising ``slope`` degrees to a hub (as real star bases do: their tops are no level plane), and the
    gas-lift column between hub and seat only when ``column``."""
    import trimesh

    T = trimesh.transformations
    parts = [
        trimesh.creation.box([0.45, 0.06, 0.45], T.translation_matrix([0, 0.48, 0])),
        trimesh.creation.box([0.45, 0.4, 0.05], T.translation_matrix([0, 0.76, -0.2])),
        trimesh.creation.cylinder(
            0.05,
            0.06,
            transform=T.translation_matrix([0, 0.035, 0]) @ T.rotation_matrix(np.pi / 2, [1, 0, 0]),
        ),
    ]
    if column:
        parts.append(
            trimesh.creation.cylinder(
                0.025,
                0.4,
                transform=T.translation_matrix([0, 0.25, 0])
                @ T.rotation_matrix(np.pi / 2, [1, 0, 0]),
            )
        )
    for i in range(5):
        leg = trimesh.creation.box([0.3, 0.05, 0.05])
        leg.apply_translation([0.15, 0, 0])
        leg.apply_transform(T.rotation_matrix(np.radians(-slope), [0, 0, 1]))
        leg.apply_translation([0.03, 0.06, 0])
        leg.apply_transform(T.rotation_matrix(2 * np.pi * i / 5 + 0.3, [0, 1, 0]))
        parts.append(leg)
    return trimesh.util.concatenate(parts)


def _cropped_scan(mesh):
    """One virtual view of ``mesh`` from above (the camera's -y axis tilted by the view's
    elevation from up), without a floor, as a cropped range scan in that camera's frame."""
    from partscale.complete import frame_from_points
    from partscale.evaluate import virtual

    (f,) = virtual.virtual_scan(mesh, 1, floor=False)
    P, C, _ = f.points()
    cam = (P - f.pose[:3, 3]) @ f.pose[:3, :3]  # the camera frame, as derived scans are
    return frame_from_points(cam, C), f.pose[:3, :3].T @ np.array([0.0, 1.0, 0.0])


def test_a_tilted_chair_scan_without_floor_stands_up_on_its_base():
    # the seat carried by an unseen column (the sensor separated it from the base): the star
    # base's plane gives up; the camera's own down axis is 25 degrees off. Its legs rise 20
    # degrees, so no level plane holds them (as the TUM purple scan's, cut at the floor)
    from partscale.complete import api
    from partscale.ingest import from_trimesh

    mesh = from_trimesh(_swivel_chair(column=False, slope=20.0), color=(60, 60, 60))
    frame, up_true = _cropped_scan(mesh)
    prior = -frame.pose[:3, 1]
    assert _angle_deg(prior, up_true) >= 20  # the test would pass on the prior otherwise
    ob = api.observe([frame])
    assert ob.up_from == "base"
    assert _angle_deg(ob.U[1, :3], up_true) <= 5.0


def test_without_a_separate_base_up_stays_the_camera_prior():
    # nothing lies below a gap in height (the column joins seat and base): no base evidence,
    # and up is the camera's -y, as before
    from partscale.complete import api
    from partscale.ingest import from_trimesh

    mesh = from_trimesh(_swivel_chair(column=True, slope=20.0), color=(60, 60, 60))
    frame, _ = _cropped_scan(mesh)
    ob = api.observe([frame])
    assert ob.up_from == "camera"
    assert _angle_deg(ob.U[1, :3], -frame.pose[:3, 1]) <= 1e-6


def test_a_mirror_plane_tilted_across_itself_is_found_and_gives_up():
    # a left-right symmetric object (seat and back) seen in a frame rolled 6 degrees across
    # its mirror plane: the vertical plane tilts back onto the true one
    import trimesh

    from partscale.complete.symmetry import Symmetry, tilted_plane

    T = trimesh.transformations
    mesh = trimesh.util.concatenate(
        [
            trimesh.creation.box([0.45, 0.06, 0.45], T.translation_matrix([0, 0.48, 0])),
            trimesh.creation.box([0.45, 0.4, 0.05], T.translation_matrix([0, 0.76, -0.2])),
        ]
    )
    P, face = trimesh.sample.sample_surface_even(mesh, 6000, seed=0)
    N = mesh.face_normals[face]
    # rolled about a line at the object's mid-height, where the vertical plane found by voting
    # crosses the true one
    c = np.array([0.0, np.median(P[:, 1]), 0.0])
    R = T.rotation_matrix(np.radians(6.0), [0, 0, 1])[:3, :3]
    P, N = (P - c) @ R.T + c, N @ R.T
    flat = Symmetry(
        "mirror", np.diag([-1.0, 1, 1]), np.zeros(3), 1.0, 0.0, params={"theta": 0.0, "offset": 0.0}
    )
    n, off = tilted_plane(flat, P, N, 0.01)
    true_n = R @ np.array([1.0, 0, 0])
    assert _angle_deg(n, true_n) <= 0.5
    assert abs(off - true_n @ c) <= 0.003


def test_the_derived_purple_tum_chair_completes_upright():
    # truth: the raw frame's floor (the derived mesh is that frame's points, floor cut away);
    # the camera's -y is 27 degrees off it, the base's plane 5 (its legs rise to the hub),
    # the mirror plane's tilt takes the rest across the plane
    from partscale.complete import complete_file, read_frame
    from partscale.complete.api import observe

    root = data_path("scans/tum_rgbd_frame")
    raw = observe(
        [
            read_frame(
                root / "TUM_depth.png", root / "TUM_color.png", root / "camera_primesense.json"
            )
        ]
    )
    up_true = raw.floor[0].normal
    assert _angle_deg(up_true, [0, -1, 0]) >= 20
    path = data_path("scans/derived/tum_purple_office_chair_partial.ply")
    assert _angle_deg(observe_file_up(path), up_true) <= 10.0
    c = complete_file(path, res=48, upright=True)
    comp = c.meta["completion"]
    assert comp["up_from"] == "base+mirror" == c.meta["history"][0]["up_from"]
    assert _angle_deg(comp["up"], up_true) <= 3.0


def observe_file_up(path) -> np.ndarray:
    """Up of a range mesh in the camera frame as the observation finds it (before symmetry)."""
    from partscale.complete import frame_from_points, read_points
    from partscale.complete.api import observe

    P, C = read_points(path)
    return observe([frame_from_points(P, C)]).U[1, :3]


def _kenney_scan(name: str, **view):
    """One virtual sensor frame (the room beyond, a floor where ``view`` says) of a Kenney
    model at real size (0.7 m a unit), y up."""
    import dataclasses

    from partscale import ingest
    from partscale.evaluate import virtual

    mesh = ingest.load_mesh(data_path(f"kenney/{name}.glb"))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)
    return virtual.virtual_scan(mesh, **view)


@pytest.mark.parametrize("pitch", [15.0, 30.0, 45.0])
def test_the_faces_of_a_table_give_up_without_a_floor(pitch):
    # the camera's own down axis is off by its pitch; the table's level top and upright legs
    # and apron give up within a degree. At 45 degrees the quarter turn (the apron's front
    # level, the top upright) holds as many patches: its level faces face down, and it loses
    from partscale.complete import floor
    from partscale.complete.scan import denoise

    (f,) = _kenney_scan("table", azimuths=(200.0,), elevation=pitch, floor=False)
    f = denoise(f)  # as the observation reads a sensor frame
    found = floor.faces_up(f.points()[0], f.pose)
    assert found.clear
    assert _angle_deg(found.up, [0, 1, 0]) <= 1.0


def test_upright_faces_alone_leave_up_to_the_camera():
    # a floor lamp from 15 degrees above: its shade, a shallow cone, has no level face seen and
    # held its normals square to an up 10 degrees off; the camera's axis is 15 off, but the
    # floor search and the lamp's isolation then keep its base and shade (with the faces' up
    # the shade fell off the object)
    import dataclasses

    from partscale import ingest
    from partscale.complete import api, floor
    from partscale.complete.scan import denoise
    from partscale.evaluate import virtual

    mesh = ingest.load_mesh(data_path("kenney/lampRoundFloor.glb"))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)
    frames = virtual.virtual_scan(mesh, azimuths=(31.0,), elevation=15.0, floor=False)
    f = denoise(frames[0])
    assert not floor.faces_up(f.points()[0], f.pose).clear
    ob = api.observe(frames)
    assert ob.up_from != "faces"
    assert np.ptp(ob.points[:, 1]) >= 0.9 * 1.75  # base to the shade's top


def test_a_chair_seen_from_above_without_a_floor_is_found_upright():
    # a desk chair from 45 degrees above, no floor in view: a plane of the chair near the
    # camera's down axis (45 degrees off) was taken for a level underside, and the object
    # then held no points ("expected an object of at least 30 points, got 0")
    from partscale.complete import api

    frames = _kenney_scan("chairDesk", azimuths=(253.0,), elevation=45.0, floor=False)
    ob = api.observe(frames)
    assert ob.up_from == "faces"
    assert _angle_deg(ob.U[1, :3], [0, 1, 0]) <= 1.0
    assert np.ptp(ob.points[:, 1]) >= 0.8 * 1.23  # the chair, 1.23 m tall, most of it


def test_a_plane_of_the_object_far_off_its_faces_up_is_no_floor():
    # a cushioned chair from 45 degrees above without a floor: its back (upright) lay within
    # the floor search's 40 degrees of the camera's axis and was taken for the floor, the
    # chair completed lying on its back
    from partscale.complete import api

    frames = _kenney_scan("chairCushion", azimuths=(253.0,), elevation=45.0, floor=False)
    ob = api.observe(frames)
    assert ob.floor is None
    assert _angle_deg(ob.U[1, :3], [0, 1, 0]) <= 1.0


def test_an_object_whose_legs_the_sensor_barely_saw_is_still_found():
    # a chair on thin legs seen from 45 degrees above: each leg a cluster of 80-90 points, too
    # few to be an object; the seat floats 0.28 m above the floor. No object stood on the floor,
    # and the scan had none; the nearest object-sized cluster is taken, its legs joined under it
    from partscale.complete import api
    from partscale.evaluate import virtual
    from partscale.ingest import load_mesh

    mesh = load_mesh(data_path("khronos/SheenChair.glb"))
    ob = api.observe(virtual.virtual_scan(mesh, azimuths=(353.0,), elevation=45.0, floor=True))
    assert ob.up_from == "floor"
    y = ob.points[:, 1]
    assert y.max() >= 0.6 and y.min() <= 0.1  # the back's top, and a leg's foot


def test_the_faces_votes_are_the_kernels_summed_over_every_direction():
    # the votes are reckoned a block of directions at a time, skipping the pairs whose kernel
    # is below exp(-20): the sums are those of the kernels over every pair, to float precision
    from partscale.complete import floor

    rng = np.random.default_rng(3)
    n = rng.normal(size=(3 * floor.VOTES_BLOCK + 17, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n[: floor.VOTES_BLOCK] = [0.0, 1.0, 0.0]  # a level face, seen many times
    U, _ = floor._up_candidates(np.eye(4))
    vote, level, face = floor._votes(n, U)
    d = n @ U.T
    s2 = np.radians(floor.FACES_SIGMA_DEG) ** 2
    lev = np.exp(-(1.0 - np.abs(d)) / s2)
    want_level = lev.mean(axis=0)
    want_vote = want_level + floor.FACES_UPRIGHT_VOTE * np.exp(-0.5 * d * d / s2).mean(axis=0)
    want_face = (lev * np.sign(d)).mean(axis=0)
    assert np.abs(level - want_level).max() <= 1e-5 * want_level.max()
    assert np.abs(vote - want_vote).max() <= 1e-5 * want_vote.max()
    assert np.abs(face - want_face).max() <= 1e-5 * np.abs(want_face).max()
    assert want_level.max() > 0.2  # the level face counts
