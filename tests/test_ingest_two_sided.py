"""Two-sided faces (each triangle stored once per winding, as Kenney's furniture does): the
bodies they close up are solid, as a viewer shows them; pairs inside a solid stay as they are."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import data_path

from partscale import ingest, shapes


def _cells(breaks, solid) -> trimesh.Trimesh:
    """The closed surface of a union of grid cells (``breaks``: 3 lists of coordinates;
    ``solid``: bool array of cells), outward, faces meeting edge to edge."""
    solid = np.pad(np.asarray(solid, bool), 1)
    corners = np.array(np.meshgrid(*[np.arange(len(b)) for b in breaks], indexing="ij"))
    V = np.stack(
        [np.asarray(b, float)[c] for b, c in zip(breaks, corners, strict=True)], -1
    ).reshape(-1, 3)
    vid = np.arange(len(V)).reshape(corners.shape[1:])
    quads = []
    for ax in range(3):
        step = np.roll(solid, -1, axis=ax) != solid  # cell i (padded) vs cell i + 1
        for i, j, k in zip(*np.nonzero(step), strict=True):
            lo = [i - 1, j - 1, k - 1]
            lo[ax] += 1
            u, v = [a for a in range(3) if a != ax]
            q = []
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                c = list(lo)
                c[u] += du
                c[v] += dv
                q.append(vid[tuple(c)])
            out_up = solid[i, j, k]  # solid below: the face looks up the axis
            quads.append(q if out_up == ((ax % 2 == 0) ^ (u > v)) else q[::-1])
    Q = np.array(quads)
    F = np.concatenate([Q[:, [0, 1, 2]], Q[:, [0, 2, 3]]])
    mesh = trimesh.Trimesh(V, F, process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


# an open-fronted cabinet as one closed body, walls 0.06 thick (~4 voxels at 64)
CABINET = _cells(
    ([0, 0.06, 0.94, 1], [0, 0.06, 0.74, 0.8], [0, 0.06, 0.5]),
    np.ones((3, 3, 2), bool) & ~np.pad(np.ones((1, 1, 1), bool), ((1, 1), (1, 1), (1, 0))),
)


def _two_sided(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.Trimesh(mesh.vertices, np.concatenate([mesh.faces, mesh.faces[:, ::-1]]))


def _centres(c):
    idx = np.stack(np.meshgrid(*[np.arange(s) for s in c.shape], indexing="ij"), -1)
    return c.index_to_world(idx.reshape(-1, 3))


def test_two_sided_box_imports_as_the_box():
    """A box whose every triangle is stored once per winding (w = 0 everywhere, so its inside
    was lost) imports exactly as the one-sided box: sdf and colours bit for bit."""
    box = trimesh.creation.box(bounds=[[0, 0, 0], [1, 0.8, 0.6]])
    one = ingest.from_mesh(ingest.from_trimesh(box), res=40)
    two = ingest.from_mesh(ingest.from_trimesh(_two_sided(box)), res=40)
    assert np.array_equal(one.sdf, two.sdf) and np.array_equal(one.rgb, two.rgb)
    assert two.meta["history"][0]["two_sided_copies_dropped"] == 12
    assert "two_sided_copies_dropped" not in one.meta["history"][0]


def test_two_sided_open_cabinet_walls_are_solid():
    """An open-fronted cabinet, one closed body of two-sided faces (the defect of Kenney's
    kitchenCabinetUpperDouble: w = 0 in its walls, so they were lost): imported as the
    one-sided body, bit for bit, its walls solid."""
    assert CABINET.is_watertight and CABINET.is_winding_consistent and CABINET.volume > 0
    one = ingest.from_mesh(ingest.from_trimesh(CABINET), res=64)
    two = ingest.from_mesh(ingest.from_trimesh(_two_sided(CABINET)), res=64)
    assert np.array_equal(one.sdf, two.sdf)
    h = two.voxel_size
    # mid-wall points of a side wall, the top and the back; then the middle of the cabinet
    at = np.array([[0.03, 0.4, 0.25], [0.5, 0.77, 0.25], [0.5, 0.4, 0.03], [0.5, 0.4, 0.3]])
    sdf = two.sdf[tuple(np.round(two.world_to_index(at)).astype(int).T)]
    assert (sdf[:3] < -h).all() and sdf[3] > h, sdf / h
    assert np.abs(two.surface_bounds() - CABINET.bounds).max() <= h


def test_touching_boxes_keep_their_shared_faces():
    """Two closed boxes touching face to face through the same triangles (one per winding,
    inside the union on both sides) are not two-sided faces: the union, as before."""
    a = trimesh.creation.box(bounds=[[0, 0, 0], [1, 0.5, 0.5]])
    b = trimesh.Trimesh(a.vertices * (-1, 1, 1) + (2, 0, 0), a.faces[:, ::-1])  # mirrored at x=1
    mesh = trimesh.util.concatenate([a, b])
    c = ingest.from_mesh(ingest.from_trimesh(mesh), res=40)
    assert "two_sided_copies_dropped" not in c.meta["history"][0]
    h = c.voxel_size
    p = _centres(c)
    e = shapes.box_sdf(p, (0, 0, 0), (2, 0.5, 0.5))
    far = np.abs(e) > h
    assert np.array_equal(c.sdf.ravel()[far] < 0, e[far] < 0)


@pytest.mark.parametrize(
    "rel",
    [
        "kenney/kitchenCabinetUpperDouble.glb",  # every wall two-sided: side walls, top lost
        "kenney/stairsOpenSingle.glb",  # the stringer two-sided: steps floated
        "kenney/stairsOpen.glb",  # two coincident two-sided stringers
    ],
)
def test_real_two_sided_bodies_span_the_mesh(rel):
    """Kenney objects built of two-sided faces: the imported solid spans the mesh's bounds
    within a voxel (the bodies a viewer shows are there)."""
    mesh = ingest.load_mesh(data_path(rel))
    c = ingest.from_mesh(mesh, res=96)
    V = np.asarray(mesh.vertices)
    err = np.abs(c.surface_bounds() - np.stack([V.min(axis=0), V.max(axis=0)])) / c.voxel_size
    assert err.max() <= 1.0, err
    assert c.meta["history"][0]["two_sided_copies_dropped"] > 0
