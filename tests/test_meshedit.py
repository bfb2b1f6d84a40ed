"""The mesh route: recipes applied to the source mesh (partscale.meshedit), on real objects."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from partscale import ingest
from partscale.edit import Recipe, apply_recipe
from partscale.errors import InputError, PartscaleWarning
from partscale.meshedit import apply_recipe_to_scene, load_scene, save_scene
from partscale.surface import sample_linear

BOOKCASE = (
    "kenney/bookcaseOpen.glb",
    {"axis": "y", "zone": ["26.625%", "53.875%"], "to": "81.125%", "mode": "tile"},
)
TABLE = ("kenney/table.glb", {"axis": "x", "zone": ["25%", "75%"], "to": "125%", "mode": "stretch"})
SHELF = (
    "polyhaven/wooden_bookshelf_worn/wooden_bookshelf_worn_1k.gltf",
    {"axis": "y", "zone": ["24.5%", "38.3%"], "to": "65.9%", "mode": "tile"},
)


def _world(scene):
    """(V, 3) world vertices of every node, in node order, and the per-node mesh."""
    out = []
    for node in scene.graph.nodes_geometry:
        T, name = scene.graph[node]
        m = scene.geometry[name]
        out.append((node, m, np.asarray(m.vertices) @ T[:3, :3].T + T[:3, 3]))
    return out


def _check_edit(before, after, edit):
    """Vertices before the zone bit-identical, beyond translated, UVs and materials kept."""
    ax = "xyz".index(edit["axis"])
    allv = np.concatenate([w for _, _, w in _world(before)])
    lo, hi = allv[:, ax].min(), allv[:, ax].max()
    from partscale.edit import Edit

    s, e, d = Edit.parse(edit).resolve(lo, hi)
    n_before = n_beyond = 0
    for (n0, m0, w0), (n1, m1, w1) in zip(_world(before), _world(after), strict=True):
        assert n0 == n1
        v0, v1 = np.asarray(m0.vertices), np.asarray(m1.vertices)
        # the edit appends vertices: the source's rows come first, in order
        assert len(v1) >= len(v0)
        pre = w0[:, ax] < s
        assert np.array_equal(v1[: len(v0)][pre], v0[pre])  # bit for bit
        post = w0[:, ax] > e
        moved = w1[: len(v0)][post] - w0[post]
        # translated by DEST - END along the axis only (float64 round-off of the node frame)
        assert np.abs(moved[:, ax] - (d - e)).max(initial=0) <= 1e-9 * (hi - lo)
        assert np.abs(np.delete(moved, ax, axis=1)).max(initial=0) <= 1e-9 * (hi - lo)
        n_before += pre.sum()
        n_beyond += post.sum()
        uv0 = getattr(m0.visual, "uv", None)
        if uv0 is not None:
            uv1 = m1.visual.uv
            assert uv1 is not None and len(uv1) == len(v1)
            assert np.array_equal(uv1[: len(v0)][pre], uv0[pre])
            assert np.array_equal(uv1[: len(v0)][post], uv0[post])
        assert getattr(m1.visual, "material", None) is getattr(m0.visual, "material", None)
    assert n_before > 0 and n_beyond > 0
    return s, e, d


def _merged(scene):
    m = scene.to_mesh()
    m.merge_vertices(merge_tex=True, merge_norm=True)
    return m


@pytest.mark.parametrize(
    "case", [BOOKCASE, TABLE, SHELF], ids=["bookcase-tile", "table-stretch", "shelf-tile"]
)
def test_mesh_route_keeps_source_outside_the_zone(data, case, tmp_path):
    rel, edit = case
    scene = load_scene(data(rel))
    out, seams = apply_recipe_to_scene(scene, Recipe.parse([edit]))
    _s, e, d = _check_edit(scene, out, edit)
    ax = "xyz".index(edit["axis"])
    # the whole object grew by exactly the shift
    assert out.bounds[1, ax] - scene.bounds[1, ax] == pytest.approx(d - e, abs=1e-9)
    assert len(out.geometry) == len(scene.geometry)
    if _merged(scene).is_watertight:
        assert _merged(out).is_watertight
    if edit["mode"] == "tile":
        # each internal seam welded: the planes' cross-sections are the same outline
        assert seams and all(sm.ok for sm in seams), [sm.message() for sm in seams]
    # written and read back: triangles and materials survive the file
    written = save_scene(out, tmp_path / "out.glb")
    back = trimesh.load(written[0], force="scene", process=False)
    assert sum(len(g.faces) for g in back.geometry.values()) == sum(
        len(out.geometry[out.graph[n][1]].faces) for n in out.graph.nodes_geometry
    )
    mats = {id(getattr(g.visual, "material", None)) for g in scene.geometry.values()}
    back_mats = {getattr(g.visual, "material", None).name for g in back.geometry.values()}
    assert len(back_mats) == len(mats)


@pytest.mark.slow
@pytest.mark.parametrize("case", [BOOKCASE, TABLE], ids=["bookcase-tile", "table-stretch"])
def test_mesh_route_within_a_voxel_of_the_csdf_route(data, case):
    rel, edit = case
    path = data(rel)
    scene = load_scene(path)
    out, _ = apply_recipe_to_scene(scene, Recipe.parse([edit]))
    c = apply_recipe(ingest.load(path, res=128), Recipe.parse([edit]))
    m = out.to_mesh()
    pts, _ = trimesh.sample.sample_surface_even(m, 20000, seed=1)
    d = np.abs(sample_linear(c.sdf, c.world_to_index(pts))) / c.voxel_size
    # the CSDF route snaps the shift to whole voxels and resolves % on its own surface's box
    assert np.quantile(d, 0.99) <= 1.0, np.quantile(d, [0.5, 0.9, 0.99])


def test_cli_mesh_route_writes_mesh_and_reports(cli, data, tmp_path):
    src = data(TABLE[0])
    out = tmp_path / "t.glb"
    proc = cli("scale", src, "-o", out, "--axis", "x", "--zone", "25%", "75%", "--to", "125%")
    assert proc.returncode == 0, proc.stderr
    assert "mesh route: 120 ->" in proc.stdout + proc.stderr
    m = trimesh.load(out, force="mesh")
    assert m.extents[0] == pytest.approx(1.5 * trimesh.load(src, force="mesh").extents[0], rel=1e-6)


def test_tiled_closed_box_stays_closed_and_exact():
    box = trimesh.creation.box((1.0, 2.0, 3.0))  # 12 triangles, diagonals differ per face
    scene = trimesh.Scene(box)
    recipe = Recipe.parse([{"axis": "x", "zone": ["20%", "60%"], "to": "140%", "mode": "tile"}])
    out, seams = apply_recipe_to_scene(scene, recipe)
    m = out.to_mesh()
    m.merge_vertices()
    assert len(seams) == 2 and all(sm.ok for sm in seams)
    assert m.is_watertight
    assert m.extents == pytest.approx((1.8, 2.0, 3.0), abs=1e-12)
    assert m.volume == pytest.approx(1.8 * 2.0 * 3.0, rel=1e-12)


def test_a_tile_to_its_start_removes_the_zone_from_a_closed_box():
    """A tile with ``to`` at the zone's start (0 copies) cuts the zone out of the mesh: the box
    is shorter by the zone's length, closed (one welded join) and exact; stretch refuses it."""
    box = trimesh.creation.box((1.0, 2.0, 3.0))
    recipe = Recipe.parse([{"axis": "x", "zone": ["20%", "60%"], "to": "20%", "mode": "tile"}])
    out, seams = apply_recipe_to_scene(trimesh.Scene(box), recipe)
    m = out.to_mesh()
    m.merge_vertices()
    assert len(seams) == 1 and seams[0].ok and seams[0].position == pytest.approx(-0.3)
    assert m.is_watertight
    assert m.extents == pytest.approx((0.6, 2.0, 3.0), abs=1e-12)
    assert m.volume == pytest.approx(0.6 * 2.0 * 3.0, rel=1e-12)
    stretch = Recipe.parse([{"axis": "x", "zone": ["20%", "60%"], "to": "20%"}])
    with pytest.raises(InputError, match="mode tile"):
        apply_recipe_to_scene(trimesh.Scene(box), stretch)


def test_unmatched_seam_is_reported():
    # a wedge: its cross-section shrinks along x, so no two planes match
    wedge = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]],
        [[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [0, 3, 5], [0, 5, 2], [1, 2, 5], [1, 5, 4]],
    )
    assert wedge.is_watertight
    recipe = Recipe.parse([{"axis": "x", "zone": ["20%", "60%"], "to": "100%", "mode": "tile"}])
    _, seams = apply_recipe_to_scene(trimesh.Scene(wedge), recipe)
    assert seams and not any(sm.ok for sm in seams)
    assert "--snap" in seams[0].message() and "CSDF route" in seams[0].message()


def test_a_cut_leaves_no_piece_of_no_area():
    """A triangle whose corners lie in a line (modelling leaves some) is met by the plane at
    one point of two edges: no piece with two corners at that point is made (each would leave
    an edge met once: the surface read as open); a corner a rounding error off the plane is
    on it (no sliver)."""
    from partscale.meshedit.cut import Piece, cut

    line = Piece(np.array([[0.0, 0, 0], [2, 0, 0], [1, 0, 0]]), np.array([[0, 1, 2]]))
    near = Piece(np.array([[0.0, 0, 0], [0.5 + 1e-17, 1, 0], [1, 0, 0]]), np.array([[0, 1, 2]]))
    for piece, plane in ((line, 0.5), (near, 0.5)):
        out = cut(piece, 0, plane)
        P = out.vertices[out.faces]
        same = [(P[:, i] == P[:, (i + 1) % 3]).all(axis=1) for i in range(3)]
        assert not np.any(same), out.faces
        area = np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        assert area.sum() == pytest.approx(
            np.linalg.norm(np.cross(*(piece.vertices[1:] - piece.vertices[0]))), abs=1e-12
        )


@pytest.mark.parametrize("zone", [(-0.13, 0.13), (-0.3, -0.05)])
def test_a_two_sided_box_stretched_still_imports_as_a_solid(zone, tmp_path):
    """Every face stored once per winding (Kenney's cabinets and stairs): the pieces of a face
    cut at a zone plane are stored once per winding too, so the result imports as the longer
    solid (it read as a hollow, a third of its volume, where a face's two copies were cut
    along different diagonals)."""
    from partscale.ingest import load as import_file
    from partscale.meshedit import edit_mesh_file

    box = trimesh.creation.box((1.0, 0.6, 0.4))
    two_sided = trimesh.Trimesh(box.vertices, np.concatenate([box.faces, box.faces[:, ::-1]]))
    src, dst = tmp_path / "box.glb", tmp_path / "longer.glb"
    two_sided.export(src)
    recipe = Recipe.parse([{"axis": "x", "zone": list(zone), "to": zone[1] + 0.25}])
    edit_mesh_file(src, dst, recipe)
    c = import_file(dst, res=64)
    assert c.meta["history"][0].get("two_sided_copies_dropped", 0) > 0
    # the box 1.25 m long, one-sided, imported alike
    plain = tmp_path / "plain.glb"
    trimesh.creation.box((1.25, 0.6, 0.4)).export(plain)
    p = import_file(plain, res=64)
    volume, expected = ((x.sdf < 0).sum() * x.voxel_size**3 for x in (c, p))
    assert abs(volume - expected) <= 0.02 * expected, (volume, expected)


def test_a_real_two_sided_cabinet_stretched_still_imports_as_a_solid(tmp_path):
    """Kenney's kitchenCabinetUpperDouble (two-sided walls, a one-sided back) 17.5 cm wider on
    the mesh route: the strips its walls are cut into along the back's edge read a part of a
    whole winding number at their probes; they follow the rest of their walls, and the result
    imports as the wider cabinet (it read as a hollow shell, under half the source's volume)."""
    from conftest import data_path

    from partscale.ingest import load as import_file
    from partscale.meshedit import edit_mesh_file

    src, dst = data_path("kenney/kitchenCabinetUpperDouble.glb"), tmp_path / "wider.glb"
    recipe = Recipe.parse([{"axis": "x", "zone": ["28.15%", "42.98%"], "to": "57.02%"}])
    edit_mesh_file(src, dst, recipe)
    before, after = (import_file(p, res=96) for p in (src, dst))
    assert after.meta["history"][0].get("two_sided_copies_dropped", 0) > 0
    v0, v1 = ((c.sdf < 0).sum() * c.voxel_size**3 for c in (before, after))
    assert v0 <= v1 <= 1.25 * v0, (v0, v1)  # wider, by under a quarter (17.5 of 125 cm)


def test_welded_only_writes_nothing_where_a_seam_cannot_be_welded(tmp_path):
    """welded_only (what fit asks for its own zones): a wedge tiled, whose seams cannot be
    welded, writes no file and says which seams; a box tiled the same way is written."""
    from partscale.meshedit import edit_mesh_file

    wedge = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]],
        [[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [0, 3, 5], [0, 5, 2], [1, 2, 5], [1, 5, 4]],
    )
    recipe = Recipe.parse([{"axis": "x", "zone": ["20%", "60%"], "to": "100%", "mode": "tile"}])
    for name, mesh, welds in (("wedge", wedge, False), ("box", trimesh.creation.box(), True)):
        src, dst = tmp_path / f"{name}.glb", tmp_path / f"{name}_tiled.glb"
        mesh.export(src)
        result = edit_mesh_file(src, dst, recipe, welded_only=True)
        assert all(seam.ok for seam in result.seams) is welds
        assert (result.written == [dst]) is welds and dst.exists() is welds


def test_stretch_normals_follow_the_surface(data):
    """Normals inside a stretched zone are the stretched surface's (unit, renormalised)."""
    scene = load_scene(data(TABLE[0]))
    out, _ = apply_recipe_to_scene(scene, Recipe.parse([TABLE[1]]))
    for g in out.geometry.values():
        n = g.vertex_normals
        assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-6)


def _glb_json(path) -> dict:
    import json
    import struct

    blob = path.read_bytes()
    (n,) = struct.unpack_from("<I", blob, 12)
    return json.loads(blob[20 : 20 + n])


def test_textured_result_renders_with_its_texture(data, tmp_path):
    """The Poly Haven bookshelf tiled: its textures travel, and three.js draws them."""
    from conftest import render_glbs

    rel, edit = SHELF
    scene = load_scene(data(rel))
    src = save_scene(scene, tmp_path / "src.glb")[0]
    out, _ = apply_recipe_to_scene(scene, Recipe.parse([edit]))
    dst = save_scene(out, tmp_path / "dst.glb")[0]
    a, b = _glb_json(src), _glb_json(dst)
    assert len(b["images"]) == len(a["images"]) >= 1
    assert len(b["materials"]) == len(a["materials"])
    assert all("TEXCOORD_0" in p["attributes"] for m in b["meshes"] for p in m["primitives"])
    renders = render_glbs(src, dst)

    def unlit(r):
        px = r["unlit"]
        return px[px.sum(axis=2) > 0].astype(float)

    before, after = (unlit(r) for r in renders)
    # textured wood, not a flat material colour: the same palette before and after
    assert after.std(axis=0).max() > 10
    assert np.abs(after.mean(axis=0) - before.mean(axis=0)).max() <= 10


def test_two_edits_on_one_axis_refer_to_the_input(data):
    """As on the CSDF route, the second zone is given on the input and carried through the
    first edit: what lies between the two zones moves by the first edit's change only."""
    scene = load_scene(data(SHELF[0]))
    recipe = Recipe.parse(
        [
            {"axis": "y", "zone": ["10%", "30%"], "to": "40%", "mode": "stretch"},
            {"axis": "y", "zone": ["60%", "80%"], "to": "90%", "mode": "stretch"},
        ]
    )
    out, _ = apply_recipe_to_scene(scene, recipe)
    ext = scene.extents[1]
    # each adds 10% of the input's extent
    assert out.extents[1] == pytest.approx(1.2 * ext, rel=1e-9)
    # the input's 60% plane moved by the first edit's +10% only: vertices there stay put after
    w0 = np.concatenate([w for _, _, w in _world(scene)])
    w1 = np.concatenate([w for _, _, w in _world(out)])[: len(w0)]
    lo = scene.bounds[0, 1]
    mid = (w0[:, 1] > lo + 0.3 * ext) & (w0[:, 1] < lo + 0.6 * ext)
    assert mid.sum() > 100
    assert np.abs(w1[mid, 1] - w0[mid, 1] - 0.1 * ext).max() <= 1e-9 * ext


def test_cli_mesh_route_by_and_fit(cli, data, tmp_path):
    src = data(TABLE[0])
    width = trimesh.load(src, force="mesh").extents[0]
    out = tmp_path / "by.glb"
    proc = cli("scale", src, "-o", out, "--axis", "x", "--zone", "25%", "75%", "--by", "+40cm")
    assert proc.returncode == 0, proc.stderr
    assert trimesh.load(out, force="mesh").extents[0] == pytest.approx(width + 0.4, abs=1e-6)
    out = tmp_path / "fit.obj"
    proc = cli("fit", src, "-o", out, "--size", "3.0", "=", "=")
    assert proc.returncode == 0, proc.stderr
    # fit chooses its zones on the CSDF at 128: the length within a voxel (2.65 m / 128)
    assert abs(trimesh.load(out, force="mesh").extents[0] - 3.0) <= 2.65 / 128


def test_obj_in_obj_out_keeps_its_materials(data, tmp_path):
    """Sweet Home 3D's table (OBJ + MTL colours, no UVs): each material group survives."""
    scene = load_scene(data("sweethome3d/table.obj"))
    edit = {"axis": "x", "zone": ["30%", "70%"], "to": "120%", "mode": "stretch"}
    out, _ = apply_recipe_to_scene(scene, Recipe.parse([edit]))
    _check_edit(scene, out, edit)
    written = save_scene(out, tmp_path / "t.obj")
    assert [p.name for p in written] == ["t.obj", "t.mtl"]
    back = trimesh.load(written[0], force="scene")
    kd = {tuple(g.visual.material.diffuse[:3]) for g in back.geometry.values()}
    source = trimesh.load(data("sweethome3d/table.obj"), force="scene")
    want = {tuple(g.visual.material.diffuse[:3]) for g in source.geometry.values()}
    # Kd written back as read (display values), to within the 8-bit round trip
    assert len(kd) == len(want) >= 2
    for c in want:
        assert min(np.abs(np.subtract(c, k, dtype=int)).max() for k in kd) <= 1, (c, kd)


def _textured_glb(path, rgb, material="material_0"):
    """A box GLB whose one material (named ``material``) is a 4x4 texture of colour ``rgb``."""
    from PIL import Image

    box = trimesh.creation.box((1.0, 2.0, 0.5))
    uv = np.column_stack([box.vertices[:, 0] + 0.5, box.vertices[:, 2] + 0.5]) * 0.5 + 0.25
    image = Image.new("RGB", (4, 4), rgb)
    mat = trimesh.visual.material.SimpleMaterial(image=image, name=material)
    box.visual = trimesh.visual.TextureVisuals(uv=uv, material=mat)
    trimesh.Scene(box).export(path)
    return path


def _texture_colours(obj):
    """The texture colours (RGB) of each material of an OBJ loaded back."""
    back = trimesh.load(obj, force="scene")
    return [
        tuple(np.asarray(g.visual.material.image.convert("RGB"))[0, 0])
        for g in back.geometry.values()
    ]


def test_two_obj_outputs_in_one_folder_keep_their_own_textures(tmp_path):
    """Companions are named after the output: same-named materials do not overwrite."""
    from partscale.meshedit import edit_mesh_file

    recipe = Recipe.parse([{"axis": "y", "zone": ["25%", "75%"], "to": "100%"}])
    red = _textured_glb(tmp_path / "red.glb", (255, 0, 0))
    blue = _textured_glb(tmp_path / "blue.glb", (0, 0, 255))
    out = tmp_path / "out"
    out.mkdir()
    a = edit_mesh_file(red, out / "a.obj", recipe).written
    b = edit_mesh_file(blue, out / "b.obj", recipe).written
    assert [p.name for p in a] == ["a.obj", "a.mtl", "a.png"]
    assert [p.name for p in b] == ["b.obj", "b.mtl", "b.png"]
    assert _texture_colours(out / "a.obj") == [(255, 0, 0)]
    assert _texture_colours(out / "b.obj") == [(0, 0, 255)]
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in a + b)


def test_obj_with_several_textures_numbers_them_after_the_output(tmp_path):
    from partscale.export import save_obj

    scenes = [
        load_scene(_textured_glb(tmp_path / f"{k}.glb", c, f"m{k}"))
        for k, c in enumerate([(255, 0, 0), (0, 255, 0)])
    ]
    (g0,), (g1,) = (list(s.geometry.values()) for s in scenes)
    g1 = g1.copy()
    g1.apply_translation((3.0, 0.0, 0.0))
    written = save_obj(trimesh.Scene([g0, g1]), tmp_path / "two.obj")
    assert [p.name for p in written] == ["two.obj", "two.mtl", "two_0.png", "two_1.png"]
    assert sorted(_texture_colours(written[0])) == [(0, 255, 0), (255, 0, 0)]


def test_obj_write_refused_midway_leaves_nothing(tmp_path):
    """A companion that cannot be written: no OBJ, no other companion, no temporary."""
    from partscale.errors import InputError
    from partscale.export import save_obj

    scene = load_scene(_textured_glb(tmp_path / "src.glb", (255, 0, 0)))
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.png").mkdir()  # a directory where the texture goes
    with pytest.raises(InputError, match=r"a\.png: expected a writable file, got a directory"):
        save_obj(scene, out / "a.obj")
    assert [p.name for p in out.iterdir()] == ["a.png"]


# -- OBJ on the mesh route: colours, groups, UVs, missing files ---------------------------


def _centroid_colours(mesh) -> tuple[np.ndarray, np.ndarray]:
    """(F, 3) face centroids and (F, 3) int sRGB colours there, of a ColoredMesh."""
    n = mesh.n_faces
    colours = mesh.color_at(np.arange(n), np.full((n, 3), 1 / 3)).astype(int)
    return mesh.vertices[mesh.faces].mean(axis=1), colours


def _same_colours_both_routes(obj, tmp_path) -> int:
    """Worst sRGB difference, face by face, between the import of ``obj`` and the import of
    the GLB the mesh route writes of it.
    """
    from scipy.spatial import cKDTree

    glb = tmp_path / "routed.glb"
    save_scene(load_scene(obj), glb)
    pa, ca = _centroid_colours(ingest.load_mesh(obj))
    pb, cb = _centroid_colours(ingest.load_mesh(glb))
    dist, j = cKDTree(pb).query(pa)
    assert dist.max() < 1e-6 * np.ptp(pa, axis=0).max()  # the same triangles (GLB: float32)
    return int(np.abs(ca - cb[j]).max())


def test_obj_kd_is_one_colour_on_both_routes(tmp_path):
    """Kd is a display colour on both routes: a desk top stored as 179,107,56 stays so in the
    GLB (not 218,173,129), and a dark one keeps its level (no 8-bit linear rounding).
    """
    (tmp_path / "a.mtl").write_text(
        "newmtl desk\nKd 0.7 0.42 0.22\nnewmtl dark\nKd 0.05 0.02 0.01\n"
    )
    obj = tmp_path / "a.obj"
    obj.write_text(
        "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 2 1 0\n"
        "usemtl desk\nf 1 2 3\nusemtl dark\nf 4 5 6\n"
    )
    _, colours = _centroid_colours(ingest.load_mesh(obj))
    assert sorted(colours.tolist()) == [[13, 5, 3], [179, 107, 56]]
    assert _same_colours_both_routes(obj, tmp_path) <= 2


@pytest.mark.parametrize("rel", ["sweethome3d/table.obj", "sweethome3d/dresser.obj"])
def test_real_obj_is_one_colour_on_both_routes(data, tmp_path, rel):
    assert _same_colours_both_routes(data(rel), tmp_path) <= 2


def _node_names(glb) -> set[str]:
    import json
    import struct

    raw = glb.read_bytes()
    doc = json.loads(raw[20 : 20 + struct.unpack("<I", raw[12:16])[0]])
    return {n.get("name") for n in doc["nodes"]} | {m.get("name") for m in doc["meshes"]}


def test_obj_groups_survive_obj_to_glb(tmp_path):
    """Each OBJ group is a node named after it (not merged per material), even where two
    groups share a material and one group holds two.
    """
    (tmp_path / "a.mtl").write_text("newmtl wood\nKd 0.6 0.4 0.2\nnewmtl metal\nKd 0.5 0.5 0.5\n")
    obj = tmp_path / "a.obj"
    obj.write_text(
        "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
        "g cabinet_opening_on_hinge_1_door\nusemtl wood\nf 1 2 3\n"
        "g cabinet_frame\nusemtl wood\nf 1 2 4\n"
        "g cabinet_hinge_1\nusemtl metal\nf 1 3 4\n"
    )
    out = tmp_path / "a.glb"
    save_scene(load_scene(obj), out)
    names = _node_names(out)
    for g in ("cabinet_opening_on_hinge_1_door", "cabinet_frame", "cabinet_hinge_1"):
        assert g in names, names


def test_sweet_home_3d_door_groups_survive_an_edit_to_glb(data, tmp_path):
    """The dresser's doors (groups ..._opening_on_hinge_N_door, which Sweet Home 3D animates)
    keep their names through a mesh-route edit to GLB.
    """
    from partscale.meshedit import edit_mesh_file

    src = data("sweethome3d/dresser.obj")
    groups = {
        ln.split(maxsplit=1)[1].strip()
        for ln in src.read_text().splitlines()
        if ln.startswith("g ")
    }
    out = tmp_path / "d.glb"
    edit_mesh_file(src, out, Recipe.parse([{"axis": "y", "zone": ["40%", "60%"], "to": "70%"}]))
    names = _node_names(out)
    assert any("opening_on_hinge" in g for g in groups)
    assert groups <= names, groups - names


def test_partly_uv_mapped_obj_keeps_its_uvs_on_the_mesh_route(tmp_path):
    """Faces with vt keep them through the mesh route (trimesh dropped all UVs of a mesh where
    some faces had none); the faces without get (0, 0).
    """
    from PIL import Image

    Image.new("RGB", (2, 2), (200, 30, 30)).save(tmp_path / "q.png")
    (tmp_path / "a.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd q.png\n")
    obj = tmp_path / "a.obj"
    obj.write_text(
        "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\n"
        "usemtl m\nf 1/1 2/2 3/3\nf 1 2 4\nf 1 3 4\n"
    )
    out = tmp_path / "a.glb"
    edit = {"axis": "x", "zone": ["20%", "60%"], "to": "80%"}
    save_scene(apply_recipe_to_scene(load_scene(obj), Recipe.parse([edit]))[0], out)
    back = trimesh.load(out, force="mesh", process=False)
    uv = np.asarray(back.visual.uv)
    assert uv is not None and len(uv) == len(back.vertices)
    given = {(0.1, 0.2), (0.3, 0.4), (0.5, 0.6)}
    got = {tuple(np.round(u, 6)) for u in uv}
    assert given <= got and (0.0, 0.0) in got, got


def test_missing_mtl_and_texture_are_said_on_the_mesh_route_as_on_import(tmp_path, cli):
    """The mesh route handles a missing material library and a missing texture as import
    does: one line each, exit 0, the material's own colour.
    """
    obj = tmp_path / "t.obj"
    obj.write_text(
        "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl red\n"
        "f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"
    )
    for args in (("import", obj, "-o", tmp_path / "t.csdf.npz", "--res", "16"),
                 ("scale", obj, "-o", tmp_path / "t.glb", "--axis", "x", "--zone", "20%", "60%",
                  "--to", "80%")):  # fmt: skip
        proc = cli(*args)
        assert proc.returncode == 0, proc.stderr
        said = [ln for ln in proc.stderr.splitlines() if "gone.mtl" in ln]
        assert len(said) == 1 and "missing" in said[0], (args[0], proc.stderr)
    m = ingest.load_mesh(tmp_path / "t.glb")  # whole: nothing to say, grey as import made it
    _, colours = _centroid_colours(m)
    assert m.notes == () and np.abs(colours - 102).max() <= 1
    (tmp_path / "a.mtl").write_text("newmtl red\nKd 0.8 0.1 0.1\nmap_Kd none.png\n")
    obj.write_text(obj.read_text().replace("gone.mtl", "a.mtl"))
    with pytest.warns(PartscaleWarning, match=r"none\.png .* missing"):
        scene = load_scene(obj)
    save_scene(scene, tmp_path / "u.glb")
    _, colours = _centroid_colours(ingest.load_mesh(tmp_path / "u.glb"))
    assert np.abs(colours - [204, 26, 26]).max() <= 1


def test_gltf_broken_texture_is_said_on_the_mesh_route(tmp_path):
    glb = _textured_glb(tmp_path / "t.glb", (10, 200, 10))
    raw = bytearray(glb.read_bytes())
    at = raw.find(b"\x89PNG")
    raw[at + 16 : at + 40] = b"\0" * 24  # the image header damaged
    glb.write_bytes(bytes(raw))
    with pytest.warns(PartscaleWarning, match=r"t\.glb: the base-colour texture .*unreadable"):
        load_scene(glb)
    with pytest.warns(PartscaleWarning, match=r"t\.glb: the base-colour texture .*unreadable"):
        ingest.load_mesh(glb)


def test_a_mesh_in_with_a_csdf_out_is_refused_naming_import(cli, tmp_path):
    """A mesh IN writes a mesh OUT; asked for a CSDF instead, scale and fit say so in one line
    and name the import (they used to read the mesh as a CSDF: "expected a .csdf.npz ... got
    File is not a zip file"), writing nothing."""
    from conftest import assert_bad_input

    src = tmp_path / "box.glb"
    trimesh.creation.box((1.0, 0.5, 0.4)).export(src)
    out = tmp_path / "out.csdf.npz"
    for args in (
        ("fit", "--add", "x", "1"),
        ("scale", "--axis", "x", "--zone", "25%", "75%", "--by", "+10cm"),
    ):
        proc = cli(args[0], src, "-o", out, *args[1:])
        assert_bad_input(
            proc, "box.glb is a mesh", "expected a mesh out", "partscale import box.glb"
        )
        assert not out.exists()
