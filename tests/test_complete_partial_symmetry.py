"""partscale.complete finds a mirror plane from partial evidence: a back and one side of a
mirror-symmetric chair and sofa at their real size (the plane's other half never seen)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import data_path

from partscale import ingest
from partscale.complete import api
from partscale.evaluate import virtual_scan

KENNEY_M = 0.7
"""Metres per Kenney unit (its chair 0.95 m tall, its lounge sofa 2.3 m wide)."""


@pytest.mark.parametrize(
    ("name", "floor"),
    [
        ("kenney/chair.glb", True),
        ("kenney/chair.glb", False),
        ("kenney/loungeSofa.glb", True),
        ("kenney/loungeSofa.glb", False),
    ],
)
def test_mirror_plane_found_from_the_back_and_one_side(name, floor):
    mesh = ingest.load_mesh(data_path(name))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * KENNEY_M)
    # the object faces +z and is mirror-symmetric about x = 0: seen from straight behind and
    # from its right side, nothing of its left side but what the back view shows edge-on
    frames = virtual_scan(mesh, azimuths=(180.0, 90.0), floor=floor)
    sy = api.find_symmetries(api.observe(frames), 128, True)
    assert sy.syms, "expected the left-right mirror plane"
    # the first plane is x = 0 of the upright frame: its normal in the world is U's first row
    normal = sy.U[0, :3]
    assert abs(normal[0]) >= np.cos(np.radians(5.0))
    # and it passes within a centimetre of the middle of the mesh's x extent
    V = np.asarray(mesh.vertices)
    middle = (V[:, 0].max() + V[:, 0].min()) / 2
    assert abs(-sy.U[0, 3] / normal[0] - middle) <= 0.01
