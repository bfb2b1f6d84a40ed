"""Import of meshes and grids against analytic truth, synthetic files and bad input.

Real objects from ../shared/data are checked in ``test_ingest_real.py``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from conftest import assert_bad_input, data_path
from scipy import ndimage

import partscale
from partscale import ingest, shapes
from partscale.color import linear_to_srgb8, srgb_to_linear
from partscale.evaluate import metrics
from partscale.surface import to_mesh


def _centres(c):
    idx = np.stack(np.meshgrid(*[np.arange(s) for s in c.shape], indexing="ij"), -1)
    return c.index_to_world(idx.reshape(-1, 3))


# -- analytic shapes -------------------------------------------------------------------


@pytest.mark.parametrize(
    "kind, res",
    [("box", 32), ("sphere", 40)],
)
def test_closed_form_sdf_in_band_and_sign_everywhere(kind, res):
    """Box and sphere meshes: |sdf - exact| <= 0.05 voxel within the 3-voxel band; every voxel
    centre more than one voxel from the surface has the right sign.

    The sphere mesh is an icosphere (5120 faces, radius 1) whose facets deviate from the sphere
    by ``facet`` (~1e-3 radius, ~0.06 voxel at res 40): the tolerance is 0.05 voxel + that.
    """
    if kind == "box":
        lo, hi = np.array([-0.4, -0.25, -0.1]), np.array([0.6, 0.35, 0.3])
        mesh = trimesh.creation.box(bounds=np.stack([lo, hi]))
        exact = lambda p: shapes.box_sdf(p, lo, hi)  # noqa: E731
        facet = 0.0
    else:
        mesh = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
        exact = lambda p: shapes.sphere_sdf(p, (0, 0, 0), 1.0)  # noqa: E731
        # the facets lie between the inscribed sphere of their planes and the unit sphere
        facet = float(1.0 - np.einsum("ij,ij->i", mesh.triangles[:, 0], mesh.face_normals).min())
    c = ingest.from_mesh(ingest.from_trimesh(mesh), res=res)
    h = c.voxel_size
    p = _centres(c)
    e = exact(p)
    s = c.sdf.ravel()
    band = np.abs(e) < 3 * h - facet
    assert band.sum() > 1000
    err = np.abs(s[band] - e[band]) / h
    assert err.max() <= 0.05 + facet / h, err.max()
    far = np.abs(e) > h + facet
    assert np.array_equal(s[far] < 0, e[far] < 0)


def test_grid_layout_res_pad_and_meta():
    """--res voxels along the longest side, cubic voxels, pad empty voxels around the object."""
    mesh = trimesh.creation.box(extents=(2.0, 1.0, 0.5))
    c = ingest.from_mesh(ingest.from_trimesh(mesh, source="box"), res=20, pad=4)
    assert c.voxel_size == pytest.approx(0.1)
    assert c.shape == (20 + 1 + 8, 10 + 1 + 8, 5 + 1 + 8)
    for ax in range(3):  # the surface never touches the border: the border layers are outside
        assert (np.take(c.sdf, [0, -1], axis=ax) > 0).all()
    sb = c.surface_bounds()
    assert np.allclose(sb[1] - sb[0], (2.0, 1.0, 0.5), atol=0.5 * c.voxel_size)
    op = c.meta["history"][0]
    assert op["op"] == "import" and op["res"] == 20 and op["pad"] == 4


def test_open_sheet_becomes_thin_solid_not_a_leak():
    """A single open square (no volume at all) becomes a thin watertight slab around it;
    an open-topped box becomes a thin-walled cup, its inside stays outside (no inversion)."""
    sheet = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    c = ingest.from_mesh(ingest.from_trimesh(sheet), res=32)
    h = c.voxel_size
    m = to_mesh(c)
    assert m.is_watertight
    thickness = m.bounds[1, 2] - m.bounds[0, 2]
    assert h <= thickness <= 2.5 * h
    cup = trimesh.creation.box(extents=(1, 1, 1))
    keep = cup.face_normals[:, 2] < 0.5  # drop the top face: an open box
    cup = trimesh.Trimesh(cup.vertices, cup.faces[keep])
    c = ingest.from_mesh(ingest.from_trimesh(cup), res=32)
    centre = c.world_to_index(np.zeros((1, 3)))[0].round().astype(int)
    assert c.sdf[tuple(centre)] > 0.3  # the cup's inside is air
    assert c.sdf[tuple(centre - (0, 0, 16))] < 0.05  # its floor is solid
    assert to_mesh(c).is_watertight


def test_intersecting_pieces_union_buried_faces_ignored():
    """Two overlapping closed boxes: the solid is their union, exact distance outside.

    Partly buried faces are classified in pieces (adaptively refined towards the curves where
    the boxes intersect, down to 2 voxels), so right at those curves a sliver of face may be
    missed and a distance be off by up to ~1 voxel: 98% of the outside band is within
    0.05 voxel, all of it within 1.5 voxels; signs are right beyond one voxel everywhere."""
    a = trimesh.creation.box(bounds=[[0, 0, 0], [1, 0.5, 0.5]])
    b = trimesh.creation.box(bounds=[[0.6, 0.2, 0.1], [1.4, 0.9, 0.4]])
    mesh = trimesh.util.concatenate([a, b])
    c = ingest.from_mesh(ingest.from_trimesh(mesh), res=40)
    h = c.voxel_size
    p = _centres(c)
    e = np.minimum(
        shapes.box_sdf(p, (0, 0, 0), (1, 0.5, 0.5)),
        shapes.box_sdf(p, (0.6, 0.2, 0.1), (1.4, 0.9, 0.4)),
    )
    s = c.sdf.ravel()
    far = np.abs(e) > h
    assert np.array_equal(s[far] < 0, e[far] < 0)
    out = (e > 0) & (e < 3 * h)  # outside the union, min of box SDFs is the exact distance
    err = np.abs(s[out] - e[out]) / h
    assert np.mean(err <= 0.05) >= 0.98 and err.max() <= 1.5, (np.mean(err <= 0.05), err.max())


def test_hollow_box_with_walls_a_few_voxels_thick():
    """A closed box with a closed cavity (inner surface facing in), walls 2.4-3.6 voxels thick
    (too thick for the thin-piece offset, too thin for any voxel > 1 voxel from both faces):
    wall voxels are inside, the sealed cavity is outside, signs right beyond 1/4 voxel."""
    outer = trimesh.creation.box(bounds=[[0, 0, 0], [1, 0.8, 0.6]])
    inner = trimesh.creation.box(bounds=[[0.06, 0.06, 0.09], [0.94, 0.74, 0.51]])
    inner.invert()
    mesh = trimesh.util.concatenate([outer, inner])
    c = ingest.from_mesh(ingest.from_trimesh(mesh), res=40)
    h = c.voxel_size
    p = _centres(c)
    e = np.maximum(
        shapes.box_sdf(p, (0, 0, 0), (1, 0.8, 0.6)),
        -shapes.box_sdf(p, (0.06, 0.06, 0.09), (0.94, 0.74, 0.51)),
    )
    s = c.sdf.ravel()
    clear = np.abs(e) > h / 4
    assert np.count_nonzero(e < -h / 4) > 1000  # the walls hold voxels to check
    assert np.array_equal(s[clear] < 0, e[clear] < 0)


def _pieces(c) -> int:
    return metrics.topology(to_mesh(c))[1]


@pytest.mark.parametrize("res", [24, 48])
def test_partly_covered_face_and_one_sided_panel_same_pieces_at_two_resolutions(res):
    """A closed box whose top face (two big triangles) is covered by a closed plate except a
    strip 0.12 wide along one edge (2.4 voxels at 24, 4.8 at 48: the probes see the cover
    only, so the faces are classified buried over that strip too), and apart from it a
    one-sided panel (an open sheet). At both resolutions: two pieces (box and plate as one
    solid, the panel thickened), the box's inside inside; the buried faces do not open the
    box to the air through the strip."""
    box = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 0.4]])
    plate = trimesh.creation.box(bounds=[[0, 0, 0.39], [0.88, 1, 0.45]])
    panel = trimesh.Trimesh(
        [[0, 1.2, 0], [1, 1.2, 0], [1, 1.2, 0.45], [0, 1.2, 0.45]], [[0, 1, 2], [0, 2, 3]]
    )
    c = ingest.from_mesh(
        ingest.from_trimesh(trimesh.util.concatenate([box, plate, panel])), res=res
    )
    assert _pieces(c) == 2
    p = _centres(c)
    e = np.minimum(
        shapes.box_sdf(p, (0, 0, 0), (1, 1, 0.4)), shapes.box_sdf(p, (0, 0, 0.39), (0.88, 1, 0.45))
    )
    deep = e < -c.voxel_size
    assert deep.sum() > 1000
    assert np.all(c.sdf.ravel()[deep] < 0)


# -- colour ----------------------------------------------------------------------------


def _glb_with_texture(path, factor_linear, texels_srgb):
    """One quad, UVs spanning a 2x2 texture, with a base colour factor; two nodes."""
    from PIL import Image
    from trimesh.visual.material import PBRMaterial

    img = Image.fromarray(np.asarray(texels_srgb, np.uint8))
    quad = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]], process=False
    )
    mat = PBRMaterial(baseColorFactor=[*factor_linear, 1.0], baseColorTexture=img)
    quad.visual = trimesh.visual.TextureVisuals(uv=[[0, 0], [1, 0], [1, 1], [0, 1]], material=mat)
    box = trimesh.creation.box(extents=(0.2, 0.2, 0.2))
    scene = trimesh.Scene()
    scene.add_geometry(quad, node_name="quad", geom_name="quad")
    t = np.eye(4)
    t[:3, 3] = (5.0, 0.0, 0.0)
    scene.add_geometry(box, node_name="box", geom_name="box", transform=t)
    scene.export(path)


def test_gltf_texture_times_factor_in_linear_light_and_node_transforms(tmp_path):
    """colour = sRGB(linear(texel) * factor); texels at their UVs; nodes placed by transforms."""
    texels = [[[200, 30, 90], [10, 250, 128]], [[255, 255, 255], [60, 60, 200]]]
    factor = (0.5, 0.8, 1.0)
    path = tmp_path / "quad.glb"
    _glb_with_texture(path, factor, texels)
    m = ingest.load_mesh(path)
    assert m.vertices[:, 0].max() == pytest.approx(5.1)  # the box node's translation
    # texel centres of a 2x2 image at u, v in {1/4, 3/4} (v up: row 0 is v = 3/4)
    quad_faces = np.nonzero(m.vertices[m.faces][:, :, 0].max(axis=1) <= 1.0)[0]
    pts = np.array([[0.25, 0.75], [0.75, 0.75], [0.25, 0.25], [0.75, 0.25]])
    expect_px = [texels[0][0], texels[0][1], texels[1][0], texels[1][1]]
    tri = m.vertices[m.faces[quad_faces]]
    for (u, v), px in zip(pts, expect_px, strict=True):
        q = np.array([u, v, 0.0])
        for f, t in zip(quad_faces, tri, strict=True):
            bc = trimesh.triangles.points_to_barycentric(t[None], q[None])[0]
            if (bc >= -1e-9).all():
                got = m.color_at(np.array([f]), bc[None])[0]
                lin = (np.asarray(px) / 255.0) ** 2.2  # independent approximate sRGB decode
                want = 255 * (lin * factor) ** (1 / 2.2)
                assert np.abs(got.astype(float) - want).max() <= 4, (got, want)
                break
        else:
            raise AssertionError("point not on the quad")


def test_srgb_round_trip():
    x = np.arange(256, dtype=np.float32) / 255
    assert np.array_equal(linear_to_srgb8(srgb_to_linear(x)), np.arange(256))


def test_flat_material_colour_is_the_factor_in_srgb():
    """Kenney table: one material, baseColorFactor (linear) -> sRGB, read from the raw glTF."""
    path = data_path("kenney/table.glb")
    raw = path.read_bytes()
    n = int.from_bytes(raw[12:16], "little")
    factor = json.loads(raw[20 : 20 + n])["materials"][0]["pbrMetallicRoughness"][
        "baseColorFactor"
    ][:3]
    want = [round(255 * (1.055 * f ** (1 / 2.4) - 0.055)) for f in factor]
    m = ingest.load_mesh(path)
    got = m.color_at(np.arange(4), np.full((4, 3), 1 / 3))
    assert np.abs(got.astype(int) - want).max() <= 1


def test_textured_colour_follows_uvs():
    """Poly Haven stool: the colour at a triangle corner is the texture's texel at its UV."""
    from PIL import Image

    folder = data_path("polyhaven/painted_wooden_stool")
    m = ingest.load_mesh(next(folder.glob("*.gltf")))
    img = np.asarray(Image.open(next((folder / "textures").glob("*diff*"))).convert("RGB"))
    rng = np.random.default_rng(0)
    f = rng.choice(m.n_faces, 300, replace=False)
    corner = rng.integers(0, 3, 300)
    bary = np.eye(3)[corner]
    got = m.color_at(f, bary).astype(int)
    uv = m.uv[f, corner].astype(np.float64) % 1.0
    hgt, wid = img.shape[:2]
    px = img[
        np.clip((1 - uv[:, 1]) * hgt, 0, hgt - 1).astype(int),
        np.clip(uv[:, 0] * wid, 0, wid - 1).astype(int),
    ].astype(int)
    # bilinear vs nearest texel: a mean within 6/255 on a photographed texture
    assert np.abs(got - px).mean() <= 6


def _color_at_numpy(m, tri_ids, bary, encode=linear_to_srgb8):
    """The plain numpy ``ColoredMesh.color_at`` (before its numba kernels), for comparison."""
    from partscale.ingest.mesh import sample_texture

    lin = np.ones((len(tri_ids), 3), np.float32)
    if m.corner_color is not None:
        lin *= np.einsum("nc,ncj->nj", bary, m.corner_color[tri_ids]).astype(np.float32)
    mats = m.face_material[tri_ids]
    uv = None if m.uv is None else np.einsum("nc,ncj->nj", bary, m.uv[tri_ids])
    for m_id in np.unique(mats):
        mat = m.materials[m_id]
        sel = mats == m_id
        col = np.broadcast_to(mat.factor, (int(sel.sum()), 3)).astype(np.float32)
        if mat.texture is not None and uv is not None:
            u = uv[sel]
            if mat.uv_transform is not None:
                u = u @ mat.uv_transform[:, :2].T + mat.uv_transform[:, 2]
            col = col * sample_texture(mat.texture, u)
        lin[sel] *= col
    return encode(lin)


def test_color_at_is_the_numpy_evaluation_bit_for_bit():
    """color_at's numba passes give exactly the plain numpy evaluation's colours (textures with
    and without a UV transform, flat materials, vertex colours) at random points, including
    UVs far outside [0, 1] (wrapped); the linear float32 values before 8-bit rounding too."""
    import dataclasses

    from partscale.ingest.mesh import Material

    rng = np.random.default_rng(3)
    n_f = 500
    tex_a = rng.random((37, 53, 3)).astype(np.float32)
    tex_b = rng.random((16, 8, 3)).astype(np.float32)
    tf = np.array([[2.98858409, -0.26146725, -0.60209115], [0.26146725, 2.98858409, -3.1136]])
    mats = (
        Material(rng.random(3).astype(np.float32), tex_a, tf),
        Material(rng.random(3).astype(np.float32)),
        Material(rng.random(3).astype(np.float32), tex_b),
        Material(np.ones(3, np.float32), tex_a, tf[:, [1, 0, 2]]),
    )
    base = ingest.ColoredMesh(
        vertices=rng.random((3 * n_f, 3)),
        faces=np.arange(3 * n_f).reshape(-1, 3),
        face_material=rng.integers(0, 3, n_f).astype(np.int32) + (np.arange(n_f) % 7 == 0),
        materials=mats,
        uv=(rng.random((n_f, 3, 2)) * 40 - 20).astype(np.float32),
        source="random",
    )
    meshes = [
        base,
        dataclasses.replace(base, corner_color=rng.random((n_f, 3, 3)).astype(np.float32)),
        dataclasses.replace(base, uv=None),
    ]
    tri = rng.integers(0, n_f, 20000)
    bary = rng.random((20000, 3))
    bary /= bary.sum(axis=1, keepdims=True)
    bary[:50] = np.eye(3)[rng.integers(0, 3, 50)]
    for m in meshes:
        assert np.array_equal(m.color_at(tri, bary), _color_at_numpy(m, tri, bary))
        # before rounding to 8 bits (where a last-bit difference would hide): the float32
        # linear colours themselves
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr("partscale.ingest.mesh.linear_to_srgb8", lambda x: x)
            got = m.color_at(tri, bary)
        assert got.dtype == np.float32
        assert np.array_equal(got, _color_at_numpy(m, tri, bary, encode=lambda x: x))


def test_voxel_colour_is_nearest_surface_colour():
    """Two touching boxes of different colours: voxels take the colour of their nearest box."""
    a = ingest.from_trimesh(trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]), color=(255, 0, 0))
    b = ingest.from_trimesh(trimesh.creation.box(bounds=[[2, 0, 0], [3, 1, 1]]), color=(0, 0, 255))
    mesh = ingest.ColoredMesh(
        vertices=np.concatenate([a.vertices, b.vertices]),
        faces=np.concatenate([a.faces, b.faces + len(a.vertices)]),
        face_material=np.concatenate([a.face_material, b.face_material + 1]),
        materials=(a.materials[0], b.materials[0]),
    )
    c = ingest.from_mesh(mesh, res=30)
    x = c.axis_coords(0)
    left = x < 1.4
    right = x > 1.6
    assert (c.rgb[left][..., 0] == 255).all() and (c.rgb[left][..., 2] == 0).all()
    assert (c.rgb[right][..., 2] == 255).all() and (c.rgb[right][..., 0] == 0).all()


# -- grids -----------------------------------------------------------------------------


def _autosdf_sphere(path, n=64, radius=0.5):
    import h5py

    ax = np.linspace(-1, 1, n)
    p = np.stack(np.meshgrid(ax, ax, ax, indexing="ij"), -1)
    sdf = np.clip(np.linalg.norm(p, axis=-1) - radius, -0.2, 0.2).astype(np.float32)
    with h5py.File(path, "w") as f:
        f.create_dataset("pc_sdf_sample", data=sdf.reshape(-1))


def test_autosdf_surface_at_level_002_and_true_distances(tmp_path, cli):
    """AutoSDF: surface at level 0.02 of a clamped field -> sphere of radius r + 0.02;
    after resampling to --res 64 the band holds true distances to it (<= 0.1 new voxel)."""
    src = tmp_path / "shape.h5"
    _autosdf_sphere(src)
    out = tmp_path / "shape.csdf.npz"
    cli("import", src, "-o", out, "--res", "64", check=True)
    c = partscale.load(out)
    h = c.voxel_size
    assert h == pytest.approx(2 * 0.52 / 64, rel=0.01)
    p = _centres(c)
    e = np.linalg.norm(p, axis=1) - 0.52
    s = c.sdf.ravel()
    band = np.abs(e) < 2.5 * h
    assert np.abs(s[band] - e[band]).max() / h <= 0.1
    assert np.array_equal(s[np.abs(e) > h] < 0, e[np.abs(e) > h] < 0)
    assert c.meta["history"][0]["iso"] == pytest.approx(0.02)


def test_autosdf_axis_order_and_y_up(tmp_path):
    """An off-centre box of distinct extents (x 0.8, y 0.4, z 0.2) comes back where it was:
    flat data read as (x, y, z) C-order, Y up and not flipped, surface at level 0.02."""
    import h5py

    n = 48
    ax = np.linspace(-1, 1, n)
    p = np.stack(np.meshgrid(ax, ax, ax, indexing="ij"), -1)
    lo, hi = np.array([-0.2, 0.1, -0.05]), np.array([0.6, 0.5, 0.15])
    sdf = np.clip(shapes.box_sdf(p, lo, hi), -0.2, 0.2).reshape(-1)
    with h5py.File(tmp_path / "box.h5", "w") as f:
        f.create_dataset("pc_sdf_sample", data=sdf.astype(np.float32))
    c = ingest.load(tmp_path / "box.h5", res=32)
    sb = c.surface_bounds()
    want = np.stack([lo - 0.02, hi + 0.02])
    assert np.abs(sb - want).max() <= 0.5 * c.voxel_size, (sb, want)


def test_npz_grid_with_colours_kept_at_its_own_sampling():
    """from_grid without res keeps the grid: values shifted by iso, colours as given."""
    ax = np.arange(-1, 1.0001, 0.1)
    p = np.stack(np.meshgrid(ax, ax, ax, indexing="ij"), -1)
    vol = np.linalg.norm(p, axis=-1) - 0.5
    col = np.zeros((*vol.shape, 3), np.uint8)
    col[..., 1] = 200
    c = ingest.from_grid(vol + 0.1, iso=0.1, colors=col, origin=(-1, -1, -1), voxel_size=0.1)
    assert np.allclose(c.sdf, vol, atol=1e-6)
    assert (c.rgb[..., 1] == 200).all()


def test_npy_grid_resampled_with_colour_volume(tmp_path):
    """A coarse .npy grid resampled to --res 32 with a colour volume (.npy) beside it."""
    ax = np.linspace(-1, 1, 24)
    p = np.stack(np.meshgrid(ax, ax, ax, indexing="ij"), -1)
    np.save(tmp_path / "g.npy", (np.abs(p).max(axis=-1) - 0.6).astype(np.float32))
    col = np.zeros((24, 24, 24, 3), np.uint8)
    col[..., 0] = np.where(p[..., 0] > 0, 250, 20)
    np.save(tmp_path / "c.npy", col)
    c = ingest.load(tmp_path / "g.npy", res=32, colors=tmp_path / "c.npy")
    sb = c.surface_bounds()
    # no origin/voxel size in a bare .npy: world units are the input's sample spacing
    assert np.allclose(sb[1] - sb[0], 1.2 / (ax[1] - ax[0]), atol=0.1)
    x = c.axis_coords(0) - c.axis_coords(0).mean()
    mid = c.shape[1] // 2, c.shape[2] // 2
    assert c.rgb[x > 3][:, mid[0], mid[1], 0].min() >= 200
    assert c.rgb[x < -3][:, mid[0], mid[1], 0].max() <= 40


# -- bad input -------------------------------------------------------------------------


def _refused(tmp_path, cli, src, *fragments, args=()):
    """``partscale import SRC`` exits 2 with one line holding ``fragments``, writing nothing."""
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(cli("import", src, "-o", out, *args), *fragments)
    assert not out.exists()
    assert not list(out.parent.glob(f".{out.name}*")), "a temporary file was left behind"


def test_missing_file(tmp_path, cli):
    _refused(tmp_path, cli, tmp_path / "nope.glb", "nope.glb", "no such file")


def _truncated_glb() -> bytes:
    return data_path("kenney/table.glb").read_bytes()[:3000]


@pytest.mark.parametrize(
    "name, content, fragment",
    [
        ("model.xyz", b"hello\n", "unknown format"),
        ("truncated.glb", _truncated_glb, "expected"),
        ("garbage.glb", b"\x01\x02 not a mesh at all" * 10, "expected"),
        ("broken.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 10\n", "expected"),
        ("broken.npz", b"PK\x03\x04" + b"\x00" * 40, "expected"),
        ("empty.glb", b"", "empty file (0 bytes)"),
        ("empty.ply", b"", "empty file (0 bytes)"),
        ("empty.npz", b"", "empty file (0 bytes)"),
        ("empty.h5", b"", "empty file (0 bytes)"),
        ("empty.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "triangles"),
    ],
)
def test_unreadable_unknown_or_empty_input(tmp_path, cli, name, content, fragment):
    src = tmp_path / name
    src.write_bytes(content() if callable(content) else content)
    _refused(tmp_path, cli, src, name, fragment)


def test_nan_in_grid(tmp_path, cli):
    g = np.ones((20, 20, 20), np.float32)
    g[5:10, 5:10, 5:10] = -1
    g[3, 4, 5] = np.nan
    src = tmp_path / "nan.npy"
    np.save(src, g)
    _refused(tmp_path, cli, src, "nan.npy", "nan")


def test_res_below_16(tmp_path, cli):
    chair = data_path("kenney/chair.glb")
    _refused(tmp_path, cli, chair, "chair.glb", "--res in [16,", "got 8", args=("--res", "8"))


def test_res_beyond_memory(tmp_path, cli, monkeypatch):
    """PARTSCALE_MAX_MEMORY stands in for a small machine: the message says what it would need."""
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", str(200 << 20))
    chair = data_path("kenney/chair.glb")
    _refused(
        tmp_path, cli, chair, "chair.glb", "--res 512", "would need", "GiB", args=("--res", "512")
    )


def test_iso_on_a_mesh_is_refused(tmp_path, cli):
    chair = data_path("kenney/chair.glb")
    _refused(tmp_path, cli, chair, "chair.glb", "iso", args=("--iso", "0.1"))


def test_cli_import_writes_a_loadable_csdf(tmp_path, cli):
    out = tmp_path / "chair.csdf.npz"
    proc = cli("import", data_path("kenney/chair.glb"), "-o", out, "--res", "32", check=True)
    assert "wrote" in proc.stderr
    c = partscale.load(out)
    assert max(c.shape) == 32 + 1 + 2 * (partscale.csdf.BAND_VOXELS + 2)
    assert c.meta["source"].endswith("chair.glb")
    assert c.meta["history"][0]["res"] == 32


def test_unknown_option_lists_known_ones():
    with pytest.raises(TypeError, match="options are"):
        ingest.from_mesh(ingest.from_trimesh(trimesh.creation.box()), resolution=32)


def test_ply_vertex_colours(tmp_path):
    """PLY vertex colours (sRGB) come back at the vertices and blend inside triangles."""
    box = trimesh.creation.box(extents=(1, 1, 1))
    rng = np.random.default_rng(3)
    cols = rng.integers(0, 256, (len(box.vertices), 4), dtype=np.uint8)
    cols[:, 3] = 255
    box.visual = trimesh.visual.ColorVisuals(box, vertex_colors=cols)
    path = tmp_path / "box.ply"
    box.export(path)
    m = ingest.load_mesh(path)
    f = np.arange(m.n_faces)
    for corner in range(3):
        got = m.color_at(f, np.eye(3)[np.full(m.n_faces, corner)])
        # the reader may reorder vertices: match by position
        pos = m.vertices[m.faces[:, corner]]
        idx = [int(np.argmin(np.linalg.norm(box.vertices - p, axis=1))) for p in pos]
        assert np.abs(got.astype(int) - cols[idx, :3].astype(int)).max() <= 1


def test_obj_mtl_kd(tmp_path):
    """OBJ + MTL: Kd is the piece's (display) colour; pieces keep their own material."""
    (tmp_path / "m.mtl").write_text(
        "newmtl red\nKd 0.8 0.1 0.1\n\nnewmtl blue\nKd 0.1 0.2 0.9\n", encoding="utf-8"
    )
    (tmp_path / "m.obj").write_text(
        "mtllib m.mtl\n"
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
        "usemtl red\nf 1 3 2\nf 1 2 4\nusemtl blue\nf 1 4 3\nf 2 3 4\n",
        encoding="utf-8",
    )
    m = ingest.load_mesh(tmp_path / "m.obj")
    got = m.color_at(np.arange(m.n_faces), np.full((m.n_faces, 3), 1 / 3)).astype(int)
    red, blue = np.array([204, 26, 26]), np.array([26, 51, 230])
    is_red = np.abs(got - red).max(axis=1) <= 1
    is_blue = np.abs(got - blue).max(axis=1) <= 1
    assert is_red.sum() == 2 and is_blue.sum() == 2


def _enclosed_voids(c) -> int:
    lab, n = ndimage.label(c.sdf > 0)
    border = set()
    for ax in range(3):
        border |= set(np.unique(np.take(lab, [0, -1], axis=ax)).tolist())
    return n - len(border - {0})


@pytest.mark.parametrize(("thickness", "voids"), [(0.3, 0), (3.0, 1)])
def test_sub_voxel_crevices_are_no_bubbles_but_real_cavities_stay(thickness, voids):
    """A closed cavity ``thickness`` voxels thin inside a box (the crevice two touching pieces
    leave): thinner than a voxel it would be a bubble wherever a voxel centre falls in it (more
    of them the finer the grid); the import fills it. A cavity of three voxels stays."""
    from partscale.ingest.mesh_sdf import grid_for_bounds

    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.6, 0.4])
    origin, h, _ = grid_for_bounds(lo, hi, 40, 5)
    # the cavity straddles a row of voxel centres across y
    k = np.round((0.3 - origin[1]) / h)
    yc = origin[1] + k * h
    cav_lo = np.array([0.2, yc - thickness * h / 2, 0.1])
    cav_hi = np.array([0.8, yc + thickness * h / 2, 0.3])
    outer = trimesh.creation.box(bounds=np.stack([lo, hi]))
    cavity = trimesh.creation.box(bounds=np.stack([cav_lo, cav_hi]))
    cavity.invert()  # facing into the cavity: the winding number there is 0
    c = ingest.from_mesh(ingest.from_trimesh(trimesh.util.concatenate([outer, cavity])), res=40)
    assert _enclosed_voids(c) == voids
    filled = c.meta["history"][0]["filled_bubble_voxels"]
    assert filled > 0 if voids == 0 else filled == 0
