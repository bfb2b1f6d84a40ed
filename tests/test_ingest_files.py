"""Reading mesh and grid files: glTF texture details, OBJ+MTL textures, damaged files.

Every file is built by hand in ``tmp_path`` so the expected colour (or refusal) is known exactly.
"""

from __future__ import annotations

import base64
import io
import json

import numpy as np
import pytest
from conftest import assert_bad_input
from PIL import Image

import partscale
from partscale import ingest
from partscale.errors import InputError, PartscaleWarning

# 2x2 texture: top-left red, top-right green, bottom-left blue, bottom-right white. In trimesh's
# v-up UVs the texel centres are red (.25, .75), green (.75, .75), blue (.25, .25), white (.75, .25).
QUAD = np.array([[[255, 0, 0], [0, 255, 0]], [[0, 0, 255], [255, 255, 255]]], np.uint8)
RED, GREEN, BLUE, WHITE = ([255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255])


def _png(arr) -> bytes:
    b = io.BytesIO()
    Image.fromarray(arr).save(b, format="PNG")
    return b.getvalue()


def _gltf(path, prims, materials, image=QUAD):
    """A .gltf with one mesh per primitive (one node each) and ``image`` as texture 0.

    prims: dicts with ``uv0``/``uv1`` (glTF v-down UVs, one per vertex) and ``material``.
    Each primitive is a triangle at its own x offset so faces can be told apart.
    """
    blob = bytearray()
    views, accs, meshes = [], [], []

    def add(arr, comp, typ):
        arr = np.ascontiguousarray(arr)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": arr.nbytes})
        blob.extend(arr.tobytes())
        blob.extend(b"\0" * (-len(blob) % 4))
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": len(arr), "type": typ}
        if typ == "VEC3":
            acc["min"], acc["max"] = arr.min(0).tolist(), arr.max(0).tolist()
        accs.append(acc)
        return len(accs) - 1

    for i, p in enumerate(prims):
        pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "<f4")
        pos[:, 0] += 2.0 * i
        attr = {"POSITION": add(pos, 5126, "VEC3")}
        for k in (0, 1):
            if p.get(f"uv{k}") is not None:
                attr[f"TEXCOORD_{k}"] = add(np.asarray(p[f"uv{k}"], "<f4"), 5126, "VEC2")
        prim = {"attributes": attr, "indices": add(np.arange(3, dtype="<u4"), 5125, "SCALAR")}
        if p.get("material") is not None:
            prim["material"] = p["material"]
        meshes.append({"primitives": [prim]})
    png = _png(image)
    views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(png)})
    blob.extend(png)
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(meshes)))}],
        "nodes": [{"mesh": i} for i in range(len(meshes))],
        "meshes": meshes,
        "accessors": accs,
        "bufferViews": views,
        "buffers": [
            {
                "byteLength": len(blob),
                "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode(),
            }
        ],
        "materials": materials,
        "images": [{"bufferView": len(views) - 1, "mimeType": "image/png"}],
        "textures": [{"source": 0}],
        "extensionsUsed": ["KHR_texture_transform"],
    }
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def _face_colours(mesh) -> list[list[int]]:
    """sRGB colour at the centroid of each face, ordered by the face's x position."""
    order = np.argsort(mesh.vertices[mesh.faces].mean(axis=1)[:, 0])
    return mesh.color_at(order, np.full((len(order), 3), 1 / 3)).tolist()


def _textured(offset=None, tex_coord=None, name=None, ext_tex_coord=None) -> dict:
    tex: dict = {"index": 0}
    if tex_coord is not None:
        tex["texCoord"] = tex_coord
    if offset is not None or ext_tex_coord is not None:
        tt: dict = {"offset": offset or [0, 0]}
        if ext_tex_coord is not None:
            tt["texCoord"] = ext_tex_coord
        tex["extensions"] = {"KHR_texture_transform": tt}
    mat: dict = {"pbrMetallicRoughness": {"baseColorTexture": tex}}
    if name is not None:
        mat["name"] = name
    return mat


# glTF UV (.25, .25) (v down) is the red texel; (.75, .75) the white one.
UV_RED = [[0.25, 0.25]] * 3
UV_WHITE = [[0.75, 0.75]] * 3


def test_gltf_texture_transform_follows_the_material_index_not_its_name(tmp_path):
    """Unnamed materials and two materials of one name each keep their own transform."""
    mats = [
        _textured(offset=[0.5, 0]),  # unnamed: u + .5 -> green
        _textured(name="m"),  # named "m", no transform -> red
        _textured(offset=[0, 0.5], name="m"),  # also "m": v + .5 -> blue
        _textured(),  # unnamed, none -> red
    ]
    prims = [{"uv0": UV_RED, "material": i} for i in range(4)]
    m = ingest.load_mesh(_gltf(tmp_path / "t.gltf", prims, mats))
    assert _face_colours(m) == [GREEN, RED, BLUE, RED]


def test_gltf_base_colour_texture_reads_the_uv_set_it_names(tmp_path):
    """texCoord 1 (on the texture or as the transform's override) samples TEXCOORD_1."""
    mats = [_textured(tex_coord=1), _textured(ext_tex_coord=1), _textured(tex_coord=0)]
    prims = [{"uv0": UV_RED, "uv1": UV_WHITE, "material": i} for i in range(3)]
    m = ingest.load_mesh(_gltf(tmp_path / "t.gltf", prims, mats))
    assert _face_colours(m) == [WHITE, WHITE, RED]


def test_gltf_missing_uv_set_is_refused_naming_the_material(tmp_path):
    mats = [_textured(tex_coord=1, name="fabric")]
    path = _gltf(tmp_path / "t.gltf", [{"uv0": UV_RED, "material": 0}], mats)
    with pytest.raises(InputError, match=r"t\.gltf: expected TEXCOORD_1 .*'fabric'"):
        ingest.load_mesh(path)


# -- OBJ + MTL ---------------------------------------------------------------------------


def _obj(folder, mtl_rel, mtl_text, vt="0.25 0.75"):
    """One triangle at UV ``vt`` (v up; the red texel by default) using material ``m``."""
    (folder / mtl_rel).parent.mkdir(parents=True, exist_ok=True)
    (folder / mtl_rel).write_text(mtl_text, encoding="utf-8")
    obj = folder / "a.obj"
    obj.write_text(
        f"mtllib {mtl_rel}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt {vt}\nusemtl m\nf 1/1 2/1 3/1\n",
        encoding="utf-8",
    )
    return obj


@pytest.mark.parametrize(
    ("mtl_rel", "tex_rel", "map_kd", "want"),
    [
        # options before the name: -o shifts u by .5 (red -> green); the others are skipped
        ("a.mtl", "tex/q.png", "-s 1 1 1 -o 0.5 0 0 -bm 1 -mm 0 1 -clamp off tex/q.png", GREEN),
        ("a.mtl", "tex/q.png", "-o 0 0.5 tex/q.png", BLUE),  # -o with u, v only
        ("a.mtl", "my tex.png", "-blendu on my tex.png", RED),  # a name with a space
        ("mats/a.mtl", "mats/q.png", "q.png", RED),  # relative to the MTL's folder
    ],
)
def test_obj_map_kd_options_and_paths(tmp_path, mtl_rel, tex_rel, map_kd, want):
    (tmp_path / tex_rel).parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(QUAD).save(tmp_path / tex_rel)
    m = ingest.load_mesh(_obj(tmp_path, mtl_rel, f"newmtl m\nKd 1 1 1\nmap_Kd {map_kd}\n"))
    assert _face_colours(m) == [want]


def test_obj_map_kd_without_kd_is_the_texture_unscaled(tmp_path):
    """No Kd beside map_Kd: the texel itself (not trimesh's default diffuse of 0.4)."""
    Image.fromarray(QUAD).save(tmp_path / "q.png")
    m = ingest.load_mesh(_obj(tmp_path, "a.mtl", "newmtl m\nmap_Kd q.png\n"))
    assert _face_colours(m) == [RED]
    m = ingest.load_mesh(_obj(tmp_path, "a.mtl", "newmtl m\nKd 0.5 0.5 0.5\nmap_Kd q.png\n"))
    assert _face_colours(m) == [[128, 0, 0]]  # Kd (display 0.5) multiplies the texel


def test_obj_material_without_kd_or_texture_is_grey(tmp_path):
    """Neither Kd nor map_Kd (or a Kd given as a spectrum): display grey 0.4, sRGB 102."""
    m = ingest.load_mesh(_obj(tmp_path, "a.mtl", "newmtl m\nNs 10\n"))
    assert _face_colours(m) == [[102, 102, 102]]
    m = ingest.load_mesh(_obj(tmp_path, "a.mtl", "newmtl m\nKd spectral s.rfl\n"))
    assert _face_colours(m) == [[102, 102, 102]]


@pytest.mark.parametrize("kd", ["nan 0 inf", "1e400 0 0", "-inf"])
def test_obj_non_finite_kd_is_refused(tmp_path, kd):
    """A Kd that is not finite gives no colour at all (trimesh would make it black)."""
    obj = _obj(tmp_path, "a.mtl", f"newmtl m\nKd {kd}\n")
    with pytest.raises(
        InputError, match=rf"a\.obj: expected Kd of material 'm' in a\.mtl .*got {kd}"
    ):
        ingest.load_mesh(obj)


def test_obj_missing_texture_is_said_and_its_kd_used(tmp_path, cli):
    """A texture the MTL names but that is missing: one line, and the material's Kd."""
    obj = _obj(tmp_path, "a.mtl", "newmtl m\nKd 0.2 0.4 0.6\nmap_Kd tex/none.png\n")
    with pytest.warns(PartscaleWarning, match=r"a\.obj: the texture .*none\.png .* missing"):
        m = ingest.load_mesh(obj)
    assert _face_colours(m) == [[51, 102, 153]]
    assert len(m.notes) == 1 and "none.png" in m.notes[0]
    out = tmp_path / "o.csdf.npz"
    proc = cli("import", obj, "-o", out, "--res", "16")
    assert proc.returncode == 0, proc.stderr
    said = [ln for ln in proc.stderr.splitlines() if "none.png" in ln]
    assert len(said) == 1 and "missing" in said[0], proc.stderr
    assert "none.png" in partscale.load(out).meta["history"][0]["notes"][0]


def test_obj_unreadable_texture_without_kd_is_grey(tmp_path):
    """A texture that is not an image: said, and the material grey (no Kd to show)."""
    (tmp_path / "q.png").write_bytes(b"not a png")
    with pytest.warns(PartscaleWarning, match=r"q\.png .* unreadable"):
        m = ingest.load_mesh(_obj(tmp_path, "a.mtl", "newmtl m\nmap_Kd q.png\n"))
    assert _face_colours(m) == [[102, 102, 102]]


def test_obj_missing_material_library_is_said_and_grey(tmp_path):
    obj = tmp_path / "a.obj"
    obj.write_text("mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n")
    with pytest.warns(PartscaleWarning, match=r"a\.obj: its material library gone\.mtl is missing"):
        m = ingest.load_mesh(obj)
    assert _face_colours(m) == [[102, 102, 102]]


def _gltf_image(path, image: dict):
    """Point the (single) image of the .gltf at ``path`` elsewhere: ``image`` replaces it."""
    doc = json.loads(path.read_text(encoding="utf-8"))
    doc["images"] = [image]
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = [0.2, 0.4, 0.6, 1.0]
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("image", "fragment"),
    [
        ({"uri": "gone.png"}, "'gone.png' is missing"),
        ({"uri": "broken.png"}, "'broken.png' is unreadable"),
        ({"uri": "data:image/png;base64," + base64.b64encode(b"junk").decode()}, "unreadable"),
    ],
)
def test_gltf_missing_or_broken_texture_is_said_and_its_factor_used(tmp_path, image, fragment):
    """trimesh drops such a texture with no word: one line names it, the factor is the colour."""
    (tmp_path / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n broken")
    path = _gltf(tmp_path / "t.gltf", [{"uv0": UV_RED, "material": 0}], [_textured(name="oak")])
    _gltf_image(path, image)
    with pytest.warns(PartscaleWarning, match=rf"t\.gltf: .*'oak'.*{fragment}") as said:
        m = ingest.load_mesh(path)
    assert len(said) == 1 and len(m.notes) == 1
    # factor (0.2, 0.4, 0.6) linear, in sRGB
    assert np.abs(np.array(_face_colours(m)) - [124, 170, 203]).max() <= 1


# -- OBJ groups and partial UVs -----------------------------------------------------------


def test_obj_faces_without_vt_beside_faces_with_keep_the_uvs(tmp_path):
    """One material, one triangle with vt (the red texel) and one without: both routes read
    the texture at the UVs given, and the corners without one at (0, 0): the image's corner,
    where the repeat-wrapped bilinear lookup mixes all four texels (linear mean 0.5: sRGB 188).
    """
    Image.fromarray(QUAD).save(tmp_path / "q.png")
    (tmp_path / "a.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd q.png\n")
    obj = tmp_path / "a.obj"
    obj.write_text(
        "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 2 1 0\nvt 0.25 0.75\n"
        "usemtl m\nf 1/1 2/1 3/1\nf 4 5 6\n"
    )
    m = ingest.load_mesh(obj)
    assert _face_colours(m) == [RED, [188, 188, 188]]
    scene = ingest.load_mesh_scene(obj)
    (geom,) = scene.geometry.values()
    assert geom.visual.uv is not None and len(geom.visual.uv) == len(geom.vertices)
    uv = np.asarray(geom.visual.uv)[np.asarray(geom.faces)]
    assert uv[0].tolist() == [[0.25, 0.75]] * 3 and uv[1].tolist() == [[0.0, 0.0]] * 3


# -- damaged or unusual mesh files --------------------------------------------------------

PLY_BAD_INDEX = (
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"
)


@pytest.mark.parametrize(
    ("name", "content", "fragment"),
    [
        ("bad.ply", PLY_BAD_INDEX.encode(), r"face indices in \[0, 3\).*got \[0, 7\]"),
        ("bad.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "index past its list"),
        # a GLB whose JSON chunk is not UTF-8 (trimesh wants charset_normalizer for it)
        (
            "bad.glb",
            b"glTF\x02\0\0\0\x24\0\0\0\x0c\0\0\0JSON{\xff\xfe\xe9\x80\x81\x82\x83}   ",
            "glb",
        ),
        # glTF documents of the wrong shape: (primitives, materials) for _gltf
        ("bad.gltf", ([{"uv0": UV_RED, "material": 0}], [{"pbrMetallicRoughness": "x"}]), "gltf"),
        ("bad.gltf", ([{"uv0": UV_RED, "material": [0]}], [_textured()]), "gltf"),
    ],
)
def test_damaged_mesh_is_an_input_error(tmp_path, cli, name, content, fragment):
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        _gltf(path, *content)
    with pytest.raises(InputError, match=rf"{name}: expected .*{fragment}"):
        ingest.load_mesh(path)
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(cli("import", path, "-o", out), name, "expected")
    assert not out.exists()


def test_latin1_obj_and_mtl_load(tmp_path):
    """OBJ/MTL declare no encoding: text that is not UTF-8 is read as Latin-1, not refused."""
    (tmp_path / "a.mtl").write_bytes("newmtl café\nKd 0.2 0.4 0.6\n".encode("latin-1"))
    (tmp_path / "a.obj").write_bytes(
        "# chaise en hêtre\nmtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl café\nf 1 2 3\n".encode(
            "latin-1"
        )
    )
    m = ingest.load_mesh(tmp_path / "a.obj")
    assert _face_colours(m) == [[51, 102, 153]]


def test_16_bit_greyscale_texture_keeps_its_grey(tmp_path):
    """A 16-bit grey texel of 0x8080 (sRGB 50.2 %) reads as grey 128, not clipped to white."""
    Image.fromarray(np.full((2, 2), 0x8080, np.uint16)).save(tmp_path / "g.png")
    with Image.open(tmp_path / "g.png") as img:
        assert img.mode.startswith("I")
    m = ingest.load_mesh(_obj(tmp_path, "a.mtl", "newmtl m\nmap_Kd g.png\n"))
    assert _face_colours(m) == [[128, 128, 128]]


# -- SDF grids -----------------------------------------------------------------------------


def _ball_volume(n=20) -> np.ndarray:
    ax = np.linspace(-1, 1, n)
    p = np.stack(np.meshgrid(ax, ax, ax, indexing="ij"), -1)
    return (np.linalg.norm(p, axis=-1) - 0.5).astype(np.float32)


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        ({"origin": np.zeros(2)}, r"grid origin: expected 3 finite numbers, got \[0\.0, 0\.0\]"),
        ({"origin": np.array([np.nan, 0, 0])}, "grid origin: expected 3 finite numbers, got .nan"),
        ({"origin": np.array(["a", "b", "c"])}, "grid origin: expected 3 finite numbers"),
        ({"voxel_size": np.array(0.0)}, "grid voxel_size: expected a finite number > 0, got 0.0"),
        (
            {"voxel_size": np.array(np.nan)},
            "grid voxel_size: expected a finite number > 0, got nan",
        ),
        ({"voxel_size": np.array([0.1, 0.2])}, "grid voxel_size: expected one number"),
        ({"iso": np.array([0.0, 1.0])}, "iso: expected one finite number"),
    ],
)
def test_npz_grid_origin_voxel_size_and_iso_are_checked(tmp_path, extra, fragment):
    path = tmp_path / "g.npz"
    np.savez(path, sdf=_ball_volume(), **extra)
    with pytest.raises(InputError, match=rf"g\.npz: {fragment}"):
        ingest.load(path, res=16)


@pytest.mark.parametrize(
    ("col", "want"),
    [
        (np.full(3, 200, np.int32), [200, 200, 200]),  # integers 0..255 as they are
        (np.array([1.0, 0.5, 0.0]), [255, 128, 0]),  # floats with max <= 1: [0, 1]
        (np.array([1.0005, 0.5, -0.0005]), [255, 128, 0]),  # within tolerance, clipped
        (np.array([200.0, 100.0, 2.5]), [200, 100, 2]),  # floats with max > 2: 0..255
    ],
)
def test_colour_volume_scale_rule(col, want):
    vol = _ball_volume(8)
    c = ingest.from_grid(vol, colors=np.broadcast_to(col, (*vol.shape, 3)))
    assert (c.rgb == np.asarray(want, np.uint8)).all()


@pytest.mark.parametrize(
    ("col", "fragment"),
    [
        (np.array([300, 0, 0], np.int32), r"integer colours in 0\.\.255, got \[0, 300\]"),
        (np.array([-1, 0, 0], np.int16), r"integer colours in 0\.\.255, got \[-1, 0\]"),
        (np.array([1.5, 0.2, 0.0]), r"colours as integers in 0\.\..*got floats in \[0, 1\.5\]"),
        (np.array([256.0, 0.0, 0.0]), r"colours as .*got floats in \[0, 256\]"),
        (np.array([0.5, -0.2, 0.0]), r"colours as .*got floats in \[-0\.2, 0\.5\]"),
        (np.array([True, False, True]), r"colours as integers in 0\.\.255.*got dtype bool"),
    ],
)
def test_colour_volume_out_of_range_is_refused(col, fragment):
    vol = _ball_volume(8)
    with pytest.raises(InputError, match=f"grid: expected {fragment}"):
        ingest.from_grid(vol, colors=np.broadcast_to(col, (*vol.shape, 3)))
