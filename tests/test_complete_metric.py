"""partscale.complete's non-metric guard: a scan whose extent or point spacing is no furniture
in metres gets one warning naming --scale and is completed at the power of ten that makes it
plausible; ``scale`` gives the factor instead; a metric scan is left alone."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from conftest import data_path

from partscale import ingest
from partscale.complete import api, complete
from partscale.complete import metric as metric_mod
from partscale.errors import InputError, PartscaleWarning
from partscale.evaluate import completion, virtual_scan

RES = 64


def test_plausibility_rules():
    P = metric_mod.Plausibility
    assert P(0.95, 0.005).plausible  # a chair seen by a depth camera
    assert P(3.3, 0.012).plausible  # a sofa from afar
    # decimetres, millimetres, a chair in centimetres: each brought back by a power of ten
    assert P(9.2, 0.055).guess() == pytest.approx(0.1)
    assert P(924.0, 5.4).guess() == pytest.approx(0.001)
    assert P(92.4, 0.55).guess() == pytest.approx(0.01)
    assert P(0.009, 0.00005).guess() == pytest.approx(100.0)
    # the table in millimetres, seen from afar: several powers fit, the one nearest 1 m wins
    assert P(2730.0, 35.9).guess() == pytest.approx(0.001)
    # too large and with no power of ten that fits both: not guessed
    assert not P(30.0, 0.0005).plausible and P(30.0, 0.0005).guess() is None
    # the stated limit: a chair 2 m tall, points 11 mm apart, is plausible (as a bookcase is)
    assert P(1.9, 0.011).plausible


@pytest.fixture(scope="module")
def chair():
    mesh = ingest.load_mesh(data_path("kenney/chair.glb"))
    # Kenney's kit is drawn large: 0.7 m per unit makes the chair 0.95 m tall
    return dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)


def _in_units(frames, unit):
    """The frames as a sensor in units of ``unit`` metres would give them (a chair in dm)."""
    return metric_mod.scale_frames(frames, 1.0 / unit)


def _score(c, G, tau):
    return completion.chamfer_fscore(completion.surface_samples(c, tau=tau)[0], G, tau)["fscore"]


def test_a_chair_scanned_in_decimetres_is_warned_about_and_completed_at_its_real_size(chair):
    frames = virtual_scan(chair, 1)
    gt = ingest.from_mesh(chair, res=RES)
    tau = completion.f_tau(gt)
    G, _ = completion.surface_samples(gt, tau=tau)
    raw = completion.chamfer_fscore(api.observe(frames).points, G, tau)["fscore"]
    dm = _in_units(frames, 0.1)  # the chair reads 9.2 units tall
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        c = complete(dm, res=RES)
    said = [str(w.message) for w in caught if issubclass(w.category, PartscaleWarning)]
    scale_lines = [m for m in said if "--scale" in m]
    assert len(scale_lines) == 1, said
    assert "\n" not in scale_lines[0] and "0.1" in scale_lines[0]
    hist = c.meta["history"][0]
    assert hist["scale"] == pytest.approx(0.1) and hist["scale_from"] == "guessed"
    # completed at its real size (metres): the chair's own height, and no worse than the raw scan
    assert max(c.shape) * c.voxel_size <= 1.3  # 0.95 m and the padding, not 9.5 m
    assert _score(c, G, tau) >= raw
    # the same scan with its scale given: no warning, the same completion
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        given = complete(dm, res=RES, scale=0.1)
    assert not [w for w in caught if "--scale" in str(w.message)]
    assert given.meta["history"][0]["scale_from"] == "option"
    assert np.array_equal(given.sdf, c.sdf)


def test_a_metric_scan_gets_no_scale_warning_and_no_scale_in_its_history(chair):
    frames = virtual_scan(chair, 1)
    ob, factor, _ = api.observe_metric(frames)
    assert factor is None
    p = metric_mod.of_points(ob.points, ob.U)
    assert p.plausible and 0.8 <= p.extent <= 1.1


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), "x"])
def test_a_bad_scale_is_refused_in_one_line(chair, bad):
    frames = virtual_scan(chair, 1)
    with pytest.raises(InputError, match="scale"):
        complete(frames, res=RES, scale=bad)


def test_cli_scale_warns_without_it_and_refuses_a_bad_one(tmp_path):
    # the shipped table's range mesh in millimetres (a PLY in the camera's frame)
    import trimesh
    from conftest import assert_bad_input, run_cli

    from partscale import data

    (seen,) = virtual_scan(ingest.load_mesh(data.table()), 1, floor=False)
    points, colors, _ = seen.points()
    in_camera = (points - seen.pose[:3, 3]) @ seen.pose[:3, :3]
    ply = tmp_path / "table_mm.ply"
    trimesh.PointCloud(in_camera * 1000.0, colors=colors).export(ply)
    out = tmp_path / "t.csdf.npz"
    proc = run_cli("complete", ply, "-o", out, "--res", "32", "--no-symmetry")
    assert proc.returncode == 0, proc.stderr
    assert "--scale" in proc.stderr and "0.001" in proc.stderr
    proc = run_cli("complete", ply, "-o", out, "--res", "32", "--no-symmetry", "--scale", "0.001")
    assert proc.returncode == 0, proc.stderr
    assert "--scale" not in proc.stderr
    bad = tmp_path / "bad.csdf.npz"
    assert_bad_input(run_cli("complete", ply, "-o", bad, "--scale", "-2"), "scale")
    assert not bad.exists()
