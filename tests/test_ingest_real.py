"""Import of the real objects in ../shared/data: sign, distance, geometry, colour, assemblies.

Resolution: 64 voxels along the longest side (the checks are in voxel units, so they hold the
import to the same standard at any resolution) except SheenChair, imported at the default 128,
the resolution its performance target is stated at. Each object is imported once per session.

Source surface: real assemblies contain *buried* faces (inside another piece, e.g. the hidden
end of a leg in a seat). They are not part of the object's visible surface and the import drops
them on purpose, so the source -> CSDF half of the Chamfer distance samples only source points
that are not buried (winding number of the whole source mesh >= 3/4 on both sides).
"""

from __future__ import annotations

import functools

import igl
import numpy as np
import pytest
from conftest import data_path

from partscale import ingest
from partscale.evaluate import metrics
from partscale.surface import to_mesh


def _path(rel: str):
    p = data_path(rel)
    if p.is_dir():
        p = next(p.glob("*.gltf"))
    return p


@functools.cache
def _imported(rel: str, res: int):
    mesh = ingest.load_mesh(_path(rel))
    c = ingest.from_mesh(mesh, res=res)
    return mesh, c, to_mesh(c)


def _sample(V, F, n, seed):
    rng = np.random.default_rng(seed)
    T = V[F]
    area = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    f = rng.choice(len(F), n, p=area / area.sum())
    r = rng.random((n, 2))
    flip = r.sum(1) > 1
    r[flip] = 1 - r[flip]
    b = np.stack([1 - r.sum(1), r[:, 0], r[:, 1]], 1)
    return np.einsum("nc,ncd->nd", b, T[f]), f


def _visible_samples(mesh, n, h):
    """Source surface samples that are not buried inside another piece."""
    V, F = mesh.vertices, mesh.faces
    P, f = _sample(V, F, n, 0)
    T = V[F]
    nrm = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    front = igl.fast_winding_number(V, F, P + 0.05 * h * nrm[f])
    return P[front < 0.75]


def chamfer_voxels(mesh, c, out, n=20000):
    """Mean symmetric Chamfer distance (voxels) between source and the CSDF's surface."""
    h = c.voxel_size
    P = _visible_samples(mesh, n, h)
    d_so = np.sqrt(igl.point_mesh_squared_distance(P, out.vertices, out.faces)[0])
    Q, _ = _sample(out.vertices, out.faces, n, 1)
    d_os = np.sqrt(igl.point_mesh_squared_distance(Q, mesh.vertices, mesh.faces)[0])
    return (d_so.mean() + d_os.mean()) / 2 / h


def colour_mae(mesh, out):
    """Mean abs. error (0-255) of exported vertex colours vs the source at the nearest point."""
    V, F = mesh.vertices, mesh.faces
    _d2, fi, cp = igl.point_mesh_squared_distance(out.vertices, V, F)
    T = V[F[fi]]
    bc = igl.barycentric_coordinates(cp, T[:, 0].copy(), T[:, 1].copy(), T[:, 2].copy())
    src = mesh.color_at(fi, bc).astype(int)
    return np.abs(src - out.visual.vertex_colors[:, :3].astype(int)).mean()


def _voxel_centres(c):
    idx = np.stack(np.meshgrid(*[np.arange(s) for s in c.shape], indexing="ij"), -1)
    return c.index_to_world(idx.reshape(-1, 3))


@pytest.mark.parametrize("rel", ["kenney/table.glb", "kenney/chair.glb"])
def test_closed_kenney_sign_and_band_distance(rel):
    """Closed meshes: every voxel centre more than one voxel from the surface has the sign of
    the exact winding number; in the 3-voxel band |sdf| is the exact distance (<= 0.05 voxel)."""
    mesh, c, _ = _imported(rel, 64)
    h = c.voxel_size
    p = _voxel_centres(c)
    d = np.sqrt(igl.point_mesh_squared_distance(p, mesh.vertices, mesh.faces)[0])
    s = c.sdf.ravel().astype(np.float64)
    far = d > h
    w = igl.fast_winding_number(mesh.vertices, mesh.faces, p[far])
    assert np.array_equal(s[far] < 0, w > 0.5)
    band = d < 3 * h
    assert band.sum() > 5000
    err = np.abs(np.abs(s[band]) - d[band]) / h
    assert err.max() <= 0.05, err.max()


@pytest.mark.parametrize(
    "rel, res",
    [
        ("kenney/table.glb", 64),
        ("kenney/chair.glb", 64),
        ("polyhaven/wooden_table_02", 64),
        ("polyhaven/painted_wooden_stool", 64),
        ("khronos/SheenChair.glb", 128),
    ],
)
def test_geometry_within_one_voxel(rel, res):
    """The marching-cubes surface of the CSDF is within 1 voxel mean symmetric Chamfer of the
    source, and closed (watertight)."""
    mesh, c, out = _imported(rel, res)
    assert out.is_watertight
    ch = chamfer_voxels(mesh, c, out)
    assert ch <= 1.0, ch


@pytest.mark.parametrize(
    "rel, limit",
    [
        ("kenney/table.glb", 8),
        ("kenney/chair.glb", 8),
        ("kenney/bedBunk.glb", 8),  # 8 flat materials: colour borders between pieces
        ("polyhaven/wooden_table_02", 20),
        ("polyhaven/painted_wooden_stool", 20),
    ],
)
def test_exported_colours_match_source(rel, limit):
    """Vertex colours of the exported mesh vs the source colour at the nearest source point:
    mean abs. error <= 8/255 (flat Kenney colours), <= 20/255 (Poly Haven textures)."""
    mesh, _c, out = _imported(rel, 64)
    mae = colour_mae(mesh, out)
    assert mae <= limit, mae


def test_sheenchair_colour_from_textures():
    """SheenChair (textures x factors, KHR_texture_transform tiling): <= 20/255 at res 128."""
    mesh, _c, out = _imported("khronos/SheenChair.glb", 128)
    assert colour_mae(mesh, out) <= 20


@pytest.mark.parametrize(
    "rel, res",
    [
        ("polyhaven/sofa_03", 64),
        ("polyhaven/wooden_bookshelf_worn", 64),
        ("sweethome3d/bookcase.obj", 64),
        # intersecting boxes with narrow gaps: leaked through a 2-voxel gap at 128 once
        ("kenney/bedBunk.glb", 128),
    ],
)
def test_open_assemblies_without_leaks(rel, res):
    """Non-watertight assemblies: watertight result within 1.5 voxels mean of the source, and
    inside/outside agrees with libigl's generalized winding number (inside where w > 1/2) on
    >= 99% of the voxels more than two voxels from the source surface (a random sample)."""
    mesh, c, out = _imported(rel, res)
    assert out.is_watertight
    ch = chamfer_voxels(mesh, c, out)
    assert ch <= 1.5, ch
    h = c.voxel_size
    p = _voxel_centres(c)
    d = np.sqrt(igl.point_mesh_squared_distance(p, mesh.vertices, mesh.faces)[0])
    far = np.flatnonzero(d > 2 * h)
    # a seeded sample of 40 000 of them (binomial error ~0.05%) keeps libigl's part short
    far = np.random.default_rng(0).choice(far, min(len(far), 40000), replace=False)
    w = igl.fast_winding_number(mesh.vertices, mesh.faces, p[far])
    agree = np.mean((c.sdf.ravel()[far] < 0) == (w > 0.5))
    assert agree >= 0.99, agree


@pytest.mark.parametrize("rel", ["polyhaven/sofa_03", "sweethome3d/bookcase.obj"])
def test_two_pass_winding_number_decides_as_the_default_accuracy(rel):
    """The import's cheap first pass plus recomputation near the cuts takes exactly the
    decisions libigl's default accuracy takes: triangle classes just in front of every face,
    and inside/outside at points in and around the object."""
    from partscale.ingest.mesh_sdf import CLASS_CUTS, INSIDE_CUTS, _class_of, _Winding

    mesh = ingest.load_mesh(_path(rel))
    V = np.ascontiguousarray(mesh.vertices, np.float64)
    F = np.ascontiguousarray(mesh.faces, np.int64)
    tris = V[F]
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    ln = np.linalg.norm(n, axis=1)
    ok = ln > 0
    h = float((V.max(0) - V.min(0)).max()) / 128
    front = tris[ok].mean(axis=1) + 0.05 * h * n[ok] / ln[ok, None]
    rng = np.random.default_rng(0)
    pts = rng.uniform(V.min(0) - 2 * h, V.max(0) + 2 * h, (20000, 3))
    full = igl.FastWindingNumberBVH()
    full.init(V, F)
    wn = _Winding(V, F)
    assert np.array_equal(_class_of(wn(front, CLASS_CUTS)), _class_of(full.winding_number(front)))
    inside = wn(pts, INSIDE_CUTS) > INSIDE_CUTS[0]
    assert np.array_equal(inside, full.winding_number(pts) > INSIDE_CUTS[0])
    assert 0.01 < inside.mean() < 0.99  # both sides are probed


@pytest.mark.slow
def test_cabinet_same_pieces_at_128_and_256():
    """painted_wooden_cabinet: one surface piece at 128 and at 256. Its shelf boards lie on
    big triangles classified buried, uncovered along a strip the probes miss; that strip is
    wider than the sign flood's 4 voxels at 256 only, where it once let the air into every
    board (73 pieces)."""
    for res in (128, 256):
        assert metrics.topology(_imported("polyhaven/painted_wooden_cabinet", res)[2])[1] == 1
