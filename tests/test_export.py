"""Export: meshes (GLB/PLY/OBJ), 3D textures (raw, PNG flipbook, NRRD), resampling, bad input."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import assert_bad_input, gltf_validator_report

import partscale
from partscale import export, shapes
from partscale.surface import to_mesh

BOX_LO, BOX_HI = (0.0, 0.0, 0.0), (0.6, 0.4, 0.3)
CENTRE, RADIUS = (0.1, -0.2, 0.3), 0.3
H = 0.02


def srgb_to_linear_reference(u8):
    """IEC 61966-2-1, written out here so the test does not trust the code under test."""
    c = np.asarray(u8, float) / 255
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def read_glb(path: Path) -> tuple[dict, dict[str, np.ndarray], np.ndarray]:
    """(gltf JSON, attribute arrays of primitive 0, faces) read straight from the GLB bytes."""
    data = path.read_bytes()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert (magic, version, length) == (b"glTF", 2, len(data))
    jlen, jtype = struct.unpack_from("<I4s", data, 12)
    assert jtype == b"JSON"
    gltf = json.loads(data[20 : 20 + jlen])
    blen, btype = struct.unpack_from("<I4s", data, 20 + jlen)
    assert btype == b"BIN\x00"
    blob = data[28 + jlen : 28 + jlen + blen]
    dtypes = {5126: "<f4", 5125: "<u4", 5123: "<u2", 5121: "u1"}
    widths = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}

    def accessor(i: int) -> np.ndarray:
        acc = gltf["accessors"][i]
        view = gltf["bufferViews"][acc["bufferView"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        n = acc["count"] * widths[acc["type"]]
        a = np.frombuffer(blob, dtypes[acc["componentType"]], n, start)
        return a.reshape(acc["count"], -1)

    prim = gltf["meshes"][0]["primitives"][0]
    attrs = {name: accessor(i) for name, i in prim["attributes"].items()}
    faces = accessor(prim["indices"]).reshape(-1, 3)
    return gltf, attrs, faces


@pytest.fixture(scope="module")
def box():
    return shapes.box(BOX_LO, BOX_HI, voxel_size=H, color=(200, 120, 60))


@pytest.fixture(scope="module")
def sphere():
    return shapes.sphere(CENTRE, RADIUS, voxel_size=H, color=(60, 120, 200))


# -- meshes ----------------------------------------------------------------------------------
@pytest.mark.parametrize("shape", ["box", "sphere"])
def test_glb_watertight_outward_volume_and_linear_colours(shape, box, sphere, tmp_path):
    c = box if shape == "box" else sphere
    true_volume = (
        np.prod(np.subtract(BOX_HI, BOX_LO)) if shape == "box" else 4 / 3 * np.pi * RADIUS**3
    )
    srgb = (200, 120, 60) if shape == "box" else (60, 120, 200)
    out = export.export_mesh(c, tmp_path / f"{shape}.glb")
    gltf, attrs, faces = read_glb(out)
    mesh = trimesh.Trimesh(attrs["POSITION"].astype(float), faces, process=True)
    assert mesh.is_watertight
    assert mesh.volume > 0  # outward faces
    # marching cubes cuts the box's edges and flattens the sphere's curvature slightly: 1.5 %
    assert abs(mesh.volume - true_volume) <= 0.015 * true_volume, (mesh.volume, true_volume)
    # world units: the solid's bounds within half a voxel of the analytic ones
    lo, hi = (
        (BOX_LO, BOX_HI)
        if shape == "box"
        else (np.subtract(CENTRE, RADIUS), np.add(CENTRE, RADIUS))
    )
    assert np.abs(mesh.bounds - np.array([lo, hi])).max() <= H / 2
    # COLOR_0: float linear RGB, not the grid's sRGB bytes
    col_acc = gltf["accessors"][gltf["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"]]
    assert col_acc["componentType"] == 5126
    expected = srgb_to_linear_reference(srgb)
    assert np.abs(attrs["COLOR_0"] - expected).max() <= 1e-6
    assert np.abs(attrs["COLOR_0"] - np.asarray(srgb) / 255).max() > 0.1
    normals = attrs["NORMAL"]
    assert np.abs(np.linalg.norm(normals, axis=1) - 1).max() <= 1e-6


def test_glb_colour_gradient_is_linearised_per_vertex(tmp_path):
    def colour(p):
        t = np.clip((p[:, 0] + 0.3) / 0.6, 0, 1)
        return np.stack([t * 255, 255 - t * 255, np.full(len(p), 40)], axis=1)

    c = shapes.sphere((0, 0, 0), 0.3, voxel_size=H, color=colour)
    _, attrs, _ = read_glb(export.export_mesh(c, tmp_path / "g.glb"))
    srgb = to_mesh(c).visual.vertex_colors[:, :3]
    assert np.abs(attrs["COLOR_0"] - srgb_to_linear_reference(srgb)).max() <= 1e-6
    assert np.ptp(attrs["COLOR_0"][:, 0]) > 0.8


def test_mesh_without_attributes_is_the_same_surface(box, sphere):
    """The geometry alone (relief, shape measures) is the surface export writes, wound
    outward; it carries no colours or parts."""
    for c in (box, sphere):
        full, bare = to_mesh(c), to_mesh(c, attributes=False)
        assert np.array_equal(full.vertices, bare.vertices)
        assert np.array_equal(full.faces, bare.faces)
        assert bare.volume > 0 and "parts" not in bare.vertex_attributes
        assert bare.visual.kind is None


def test_glb_passes_khronos_validator(sphere, tmp_path):
    report = gltf_validator_report(export.export_mesh(sphere, tmp_path / "s.glb"))
    assert report["issues"]["numErrors"] == 0, report["issues"]["messages"]
    assert report["info"]["totalTriangleCount"] > 1000


@pytest.mark.parametrize("suffix", [".ply", ".obj"])
def test_ply_obj_watertight_with_srgb_colours(suffix, box, tmp_path):
    out = export.export_mesh(box, tmp_path / f"b{suffix}")
    mesh = trimesh.load(out, force="mesh", process=True)
    assert mesh.is_watertight and mesh.volume > 0
    true_volume = np.prod(np.subtract(BOX_HI, BOX_LO))
    assert abs(mesh.volume - true_volume) <= 0.015 * true_volume
    rgb = np.asarray(mesh.visual.vertex_colors)[:, :3].astype(int)
    assert np.abs(rgb - (200, 120, 60)).max() <= 1


# -- resampling ------------------------------------------------------------------------------
@pytest.mark.parametrize("size", [32, 64])
def test_resample_keeps_radius_and_world_bounds(size):
    c = shapes.sphere(CENTRE, RADIUS, voxel_size=0.01)
    parts = np.where(c.axis_coords(0)[:, None, None] < CENTRE[0], 0, 1) * np.ones(c.shape, int)
    c = c.replace(parts=parts)
    r = export.resize_grid(c, size)
    h = r.voxel_size
    assert max(r.shape) == size
    gb, rb = c.grid_bounds, r.grid_bounds
    longest = int(np.argmax(gb[1] - gb[0]))
    assert np.abs(rb[:, longest] - gb[:, longest]).max() <= 1e-9
    assert np.abs(rb - gb).max() <= h / 2 + 1e-9
    radii = np.linalg.norm(to_mesh(r).vertices - CENTRE, axis=1)
    assert np.abs(radii - RADIUS).max() <= h, np.abs(radii - RADIUS).max() / h
    # parts nearest: still exactly {0, 1}, split at the centre plane within a voxel
    assert set(np.unique(r.parts)) == {0, 1}
    x = r.axis_coords(0)
    assert (r.parts[x < CENTRE[0] - h] == 0).all() and (r.parts[x > CENTRE[0] + h] == 1).all()
    assert r.meta["history"][-1]["op"] == "resample"
    assert r.meta["history"][-1]["size"] == size


# -- textures --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def varied():
    """A non-cubic grid with position-dependent colour: catches axis mix-ups."""

    def colour(p):
        return np.clip(np.stack([p[:, 0] * 400, p[:, 1] * 600, p[:, 2] * 800], axis=1), 0, 255)

    return shapes.box((0, 0, 0), (0.5, 0.3, 0.2), voxel_size=H, color=colour)


def test_raw_half_float_round_trip_and_layout(varied, tmp_path):
    paths = export.export_texture(varied, tmp_path / "t.raw")
    assert [p.name for p in paths] == ["t.raw", "t.raw.json"]
    side = json.loads(paths[1].read_text())
    X, Y, Z = varied.shape
    assert side["size"] == [X, Y, Z]
    assert side["voxel_size"] == varied.voxel_size
    assert side["origin"] == varied.origin.tolist()
    assert side["encoding"]["byte_order"] == "little"
    assert side["color_space"] == "sRGB"
    # x fastest, read straight from the bytes
    raw = np.frombuffer(paths[0].read_bytes(), "<f2").reshape(-1, 4)
    i, j, k = 7, 3, 5
    texel = raw[(k * Y + j) * X + i]
    assert texel[3] == np.float16(varied.sdf[i, j, k])
    assert np.rint(texel[:3].astype(float) * 255).tolist() == varied.rgb[i, j, k].tolist()
    back = export.read_texture(paths[0])
    # IEEE half: relative error <= 2^-11 for normal numbers, <= 2^-25 absolute among subnormals
    err = np.abs(back.sdf.astype(float) - varied.sdf)
    assert (err <= 2.0**-11 * np.abs(varied.sdf) + 2.0**-25).all()
    assert np.array_equal(back.rgb, varied.rgb)
    assert np.array_equal(back.origin, varied.origin) and back.voxel_size == varied.voxel_size


def test_png_flipbook_round_trip_and_layout(varied, tmp_path):
    from PIL import Image

    paths = export.export_texture(varied, tmp_path / "t.png")
    side = json.loads(paths[1].read_text())
    X, Y, Z = varied.shape
    enc = side["encoding"]
    cols, rows = enc["flipbook"]["columns"], enc["flipbook"]["rows"]
    assert cols * rows == side["size"][2] == Z + enc["flipbook"]["padded_slices"]
    atlas = np.asarray(Image.open(paths[0]))
    assert atlas.shape == (rows * Y, cols * X, 4) and atlas.dtype == np.uint8
    # voxel (i, j, k): tile k left-to-right, top-to-bottom; y up inside a tile
    K, h, iso = enc["distance_band_voxels"], side["voxel_size"], enc["iso_level"]
    for i, j, k in [(0, 0, 0), (7, 3, 5), (X - 1, Y - 1, Z - 1)]:
        px = atlas[(k // cols) * Y + (Y - 1 - j), (k % cols) * X + i]
        assert px[:3].tolist() == varied.rgb[i, j, k].tolist()
        a = np.clip(np.rint(iso + varied.sdf[i, j, k] / (K * h) * 127), 0, 255)
        assert px[3] == a
    back = export.read_texture(paths[0])
    back = back.replace(sdf=back.sdf[:, :, :Z], rgb=back.rgb[:, :, :Z], parts=back.parts[:, :, :Z])
    assert np.array_equal(back.rgb, varied.rgb)
    step = K * h / 127
    band = np.abs(varied.sdf) <= K * h
    err = np.abs(back.sdf - varied.sdf)
    assert band.sum() > 1000
    # within the encoded band: half a quantisation step (plus float32 rounding)
    assert err[band].max() <= step / 2 + 1e-6
    # beyond it: clamped, sign kept
    assert (np.sign(back.sdf[~band]) == np.sign(varied.sdf[~band])).all()
    assert (np.abs(back.sdf[~band]) >= K * h * (1 - 1 / 127) - 1e-6).all()
    # the surface is at the stated iso level: inside voxels encode below it, outside above
    alpha = atlas[..., 3]
    assert alpha.min() < iso < alpha.max()


def test_nrrd_origin_spacing_and_values(varied, tmp_path):
    import nrrd

    (path,) = export.export_texture(varied, tmp_path / "t.nrrd")
    data, header = nrrd.read(str(path), index_order="F")
    assert data.shape == varied.shape
    np.testing.assert_array_equal(data, varied.sdf)
    np.testing.assert_allclose(header["space origin"], varied.origin, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        header["space directions"], np.eye(3) * varied.voxel_size, rtol=0, atol=1e-12
    )
    back = export.read_texture(path)
    assert np.array_equal(back.sdf, varied.sdf) and back.voxel_size == varied.voxel_size


def test_texture_size_resamples(sphere, tmp_path):
    paths = export.export_texture(sphere, tmp_path / "t.raw", size=32)
    side = json.loads(paths[1].read_text())
    assert max(side["size"]) == 32
    assert side["history"][-1]["op"] == "resample"


def test_flipbook_layout_fills_the_atlas():
    assert export.flipbook_layout(128) == (16, 8)
    assert export.flipbook_layout(64) == (8, 8)
    assert export.flipbook_layout(37) == (8, 5)  # prime: padded, not a 37-tile strip
    for depth in range(2, 300):
        cols, rows = export.flipbook_layout(depth)
        assert depth <= cols * rows <= depth + cols and rows <= cols <= 2 * rows


def test_png_flipbook_pads_an_awkward_depth(tmp_path):
    # z extent 0.68 + margins -> 41 slices (prime): padded to 42 = 7 x 6 tiles
    c = shapes.box((0, 0, 0), (0.2, 0.2, 0.68), voxel_size=H)
    assert c.shape[2] == 41
    paths = export.export_texture(c, tmp_path / "p.png")
    side = json.loads(paths[1].read_text())
    flip = side["encoding"]["flipbook"]
    assert flip["columns"] * flip["rows"] == side["size"][2] == 41 + flip["padded_slices"]
    back = export.read_texture(paths[0])
    step = side["encoding"]["distance_step"]
    assert np.array_equal(back.origin, c.origin)
    assert np.abs(back.sdf[:, :, :41] - np.clip(c.sdf, -8 * H, 8 * H)).max() <= step / 2 + 1e-6
    # padding is empty space, farther out than the last slice
    assert (back.sdf[:, :, 41:] >= back.sdf[:, :, 40:41] - 1e-6).all()


# -- CLI ---------------------------------------------------------------------------------------
@pytest.fixture
def box_file(box, tmp_path):
    return partscale.save(box, tmp_path / "box.csdf.npz")


def test_cli_export_writes_every_output(cli, box_file, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    proc = cli(
        "export",
        box_file,
        "--mesh",
        out / "b.glb",
        "--texture",
        out / "b.png",
        "--texture",
        out / "b.nrrd",
        "--grid",
        "32",
    )
    assert proc.returncode == 0, proc.stderr
    names = sorted(p.name for p in out.iterdir())
    assert names == ["b.glb", "b.nrrd", "b.png", "b.png.json"]
    assert max(json.loads((out / "b.png.json").read_text())["size"]) == 32


def _listing(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob("*"))


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["--mesh", "{out}/b.stl"], ["b.stl", "expected a mesh file", ".glb"]),
        (["--texture", "{out}/b.jpg"], ["b.jpg", "expected a 3d texture", ".png"]),
        (["--mesh", "{out}/b.glb", "--grid", "100"], ["--grid", "32, 64, 128, 256", "100"]),
        ([], ["expected at least one output"]),
    ],
)
def test_cli_export_bad_options(cli, box_file, tmp_path, args, fragments):
    out = tmp_path / "out"
    out.mkdir()
    proc = cli("export", box_file, *[a.format(out=out) for a in args])
    assert_bad_input(proc, *fragments)
    assert _listing(out) == []


def test_cli_export_missing_and_corrupt_input(cli, box_file, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    proc = cli("export", tmp_path / "nope.csdf.npz", "--mesh", out / "b.glb")
    assert_bad_input(proc, "nope.csdf.npz", "no such file")
    corrupt = tmp_path / "corrupt.csdf.npz"
    corrupt.write_bytes(box_file.read_bytes()[:2000])
    proc = cli("export", corrupt, "--mesh", out / "b.glb", "--texture", out / "b.raw")
    assert_bad_input(proc, "corrupt.csdf.npz")
    assert _listing(out) == []


def test_export_library_refuses_before_writing(box, tmp_path):
    from partscale.errors import InputError

    with pytest.raises(InputError, match="expected one of 32, 64, 128, 256"):
        export.export_texture(box, tmp_path / "t.raw", size=48)
    with pytest.raises(InputError, match=r"\.glb"):
        export.export_mesh(box, tmp_path / "t.fbx")
    with pytest.raises(InputError, match="surface"):
        export.export_mesh(box.replace(sdf=np.abs(box.sdf) + 0.01), tmp_path / "t.glb")
    assert list(tmp_path.iterdir()) == []


# -- a real object ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def chair():
    from conftest import data_path

    ingest = pytest.importorskip("partscale.ingest", reason="import stage not on this branch")
    return ingest.load(data_path("kenney/chair.glb"), res=64)


def test_real_chair_exports_valid_watertight_glb_and_textures(chair, tmp_path):
    out = export.export_mesh(chair, tmp_path / "chair.glb")
    _, attrs, faces = read_glb(out)
    mesh = trimesh.Trimesh(attrs["POSITION"].astype(float), faces, process=True)
    assert mesh.is_watertight and mesh.volume > 0
    ref = to_mesh(chair)
    assert abs(mesh.volume - ref.volume) <= 1e-6 * ref.volume
    srgb = ref.visual.vertex_colors[:, :3]
    assert np.abs(attrs["COLOR_0"] - srgb_to_linear_reference(srgb)).max() <= 1e-6
    report = gltf_validator_report(out, required=False)
    if report is not None:
        assert report["issues"]["numErrors"] == 0, report["issues"]["messages"]
    for suffix in (".raw", ".png"):
        back = export.read_texture(export.export_texture(chair, tmp_path / f"c{suffix}")[0])
        Z = chair.shape[2]  # the flipbook may pad z to fill its atlas
        assert np.array_equal(back.rgb[:, :, :Z], chair.rgb)
        assert np.array_equal(back.origin, chair.origin)
        same_sign = np.sign(back.sdf[:, :, :Z]) == np.sign(chair.sdf)
        assert same_sign[np.abs(chair.sdf) > 1e-4].all()
