"""Render: sphere tracing of the SDF, views, frames, part colours, scale bar, CLI and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_bad_input
from PIL import Image

import partscale
from partscale import render, shapes
from partscale.errors import InputError

WHITE = np.array([255, 255, 255])
CENTRE, RADIUS, H = np.array([0.1, 0.2, -0.1]), 0.3, 0.02


def to_linear(u8):
    c = np.asarray(u8, float) / 255
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def chromaticity(u8):
    lin = to_linear(u8)
    return lin / lin.sum(axis=-1, keepdims=True)


def foreground(image, background=WHITE):
    return (image != background).any(axis=-1)


@pytest.fixture(scope="module")
def sphere():
    return shapes.sphere(CENTRE, RADIUS, voxel_size=H, color=(200, 90, 40))


def test_sphere_front_is_a_disc_of_the_expected_radius(sphere):
    size = 256
    frame = np.array([CENTRE - RADIUS, CENTRE + RADIUS])
    image = render.render(sphere, view="front", size=size, frame=frame)
    assert image.shape == (size, size, 3) and image.dtype == np.uint8
    fg = foreground(image)
    expected_r = RADIUS * size * (1 - 2 * render.MARGIN) / (2 * RADIUS)
    r_area = np.sqrt(fg.sum() / np.pi)
    assert abs(r_area - expected_r) <= 1.0, (r_area, expected_r)
    rows, cols = np.nonzero(fg)
    assert abs(rows.mean() + 0.5 - size / 2) <= 0.5 and abs(cols.mean() + 0.5 - size / 2) <= 0.5
    # every foreground pixel lies within the disc (+1 px), none of the disc is missing (-1 px)
    d = np.hypot(*np.meshgrid(np.arange(size) + 0.5 - size / 2, np.arange(size) + 0.5 - size / 2))
    assert not fg[d > expected_r + 1].any() and fg[d < expected_r - 1].all()


def test_sphere_shows_its_colour_with_shading(sphere):
    image = render.render(sphere, view="front", size=128)
    fg = foreground(image)
    pixels = image[fg]
    # shading scales linear light, so chromaticity stays the CSDF colour's
    err = np.abs(chromaticity(pixels) - chromaticity(np.array([200, 90, 40]))).max()
    assert err <= 0.02, err
    # Lambert: some parts lit, some in shade
    lum = to_linear(pixels).sum(axis=1)
    assert lum.max() > 1.5 * lum.min()


def test_colours_are_decoded_before_they_are_blended_as_the_page_does():
    # black voxels left of x = 0, white from it: a ray between the two voxel centres sees half of
    # each corner. Decoded first (as a GPU filters an sRGB texture) that is half the white's
    # linear light; blending the sRGB codes first would give sRGB 128, a fifth of it.
    h = 0.02
    c = shapes.box((-0.2, -0.2, -0.2), (0.2, 0.2, 0.2), voxel_size=h)
    x = c.origin[0] + np.arange(c.shape[0]) * h
    rgb = np.where((x >= h / 4)[:, None, None, None], 255, 0).astype(np.uint8)
    c = c.replace(rgb=np.ascontiguousarray(np.broadcast_to(rgb, c.rgb.shape)))
    size = 400
    frame = np.array([[-0.2, -0.2, -0.2], [0.2, 0.2, 0.2]])
    image = render.render(c, view="front", size=size, frame=frame)
    row = image[size // 2]
    lit = to_linear(row[row.sum(axis=1) == row.sum(axis=1).max()][0])[0]  # white, shaded
    mid = size / 2 - 0.5 + (float(x[x >= h / 4][0]) - h / 2) * size * (1 - 2 * render.MARGIN) / 0.4
    between = to_linear(row[round(mid)])[0]
    assert abs(between / lit - 0.5) <= 0.1, (between, lit)


def test_same_frame_same_scale():
    frame = np.array([[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]])
    big = shapes.sphere((0, 0, 0), 0.4, voxel_size=H)
    small = shapes.sphere((0, 0, 0), 0.2, voxel_size=H)
    a = foreground(render.render(big, view="front", size=200, frame=frame)).sum()
    b = foreground(render.render(small, view="front", size=200, frame=frame)).sum()
    assert abs(np.sqrt(a / b) - 2.0) <= 0.03


@pytest.mark.parametrize(
    ("view", "ratio"),
    [("front", 0.6 / 0.4), ("side", 0.2 / 0.4), ("top", 0.6 / 0.2)],
)
def test_views_look_along_the_stated_axes(view, ratio):
    # box x 0.6, y 0.4, z 0.2: front shows x by y, side z by y, top x by z
    c = shapes.box((0, 0, 0), (0.6, 0.4, 0.2), voxel_size=H)
    fg = foreground(render.render(c, view=view, size=200))
    rows, cols = np.nonzero(fg)
    w, h = np.ptp(cols) + 1, np.ptp(rows) + 1
    assert abs(w / h - ratio) <= 0.03 * ratio, (w, h)


# a ball coloured by the direction of its outward normal: which colour shows where tells the view
FACE_COLOURS = {
    "+x": (255, 0, 0),
    "-x": (0, 255, 255),
    "+y": (0, 255, 0),
    "-y": (255, 0, 255),
    "+z": (0, 0, 255),
    "-z": (255, 255, 0),
}


def _direction_ball():
    c = shapes.sphere((0, 0, 0), 0.3, voxel_size=H)
    p = np.stack(np.meshgrid(*(c.axis_coords(a) for a in range(3)), indexing="ij"), -1)
    axis = np.abs(p).argmax(axis=-1)
    sign = np.take_along_axis(p, axis[..., None], -1)[..., 0] > 0
    rgb = np.zeros((*c.shape, 3), np.uint8)
    for a, name in enumerate("xyz"):
        rgb[(axis == a) & sign] = FACE_COLOURS[f"+{name}"]
        rgb[(axis == a) & ~sign] = FACE_COLOURS[f"-{name}"]
    return c.replace(rgb=rgb)


def _face_at(image, disc, a, b):
    """Name of the face colour at (a, b) disc radii right of and above the disc's centre."""
    rows, cols = np.nonzero(disc)
    r = (np.ptp(cols) + 1) / 2
    px = image[int(np.rint(rows.mean() - b * r)), int(np.rint(cols.mean() + a * r))].astype(float)
    px /= max(px.max(), 1.0)  # shading scales the colour, the hue stays
    return min(FACE_COLOURS, key=lambda k: np.abs(np.array(FACE_COLOURS[k]) / 255 - px).sum())


@pytest.mark.parametrize(
    ("view", "centre", "up", "down", "left", "right"),
    [
        # +y up, +z towards the viewer, +x right
        ("front", "+z", "+y", "-y", "-x", "+x"),
        # from the right (+x): -z is on the image's right
        ("side", "+x", "+y", "-y", "+z", "-z"),
        # from above: the front (+z) at the bottom, +x right
        ("top", "+y", "-z", "+z", "-x", "+x"),
    ],
)
def test_views_face_the_stated_directions(view, centre, up, down, left, right):
    """A flipped or opposite view shows other faces where these are expected."""
    image = render.render(_direction_ball(), view=view, size=96)
    disc = image.max(axis=-1).astype(int) - image.min(axis=-1) > 60  # saturated: the ball
    got = [
        _face_at(image, disc, a, b) for a, b in ((0, 0), (0, 0.8), (0, -0.8), (-0.8, 0), (0.8, 0))
    ]
    assert got == [centre, up, down, left, right]


def test_iso_view_is_from_front_right_above():
    """Looking along -(1, 1, 1): +y on top, +z lower left, +x lower right."""
    image = render.render(_direction_ball(), view="iso", size=96)
    disc = image.max(axis=-1).astype(int) - image.min(axis=-1) > 60
    got = [_face_at(image, disc, a, b) for a, b in ((0, 0.6), (-0.5, -0.3), (0.5, -0.3))]
    assert got == ["+y", "+z", "+x"]


def test_iso_view_shows_three_shaded_faces():
    c = shapes.box((0, 0, 0), (0.4, 0.4, 0.4), voxel_size=H, color=(180, 180, 180))
    image = render.render(c, view="iso", size=128)
    lum = np.round(to_linear(image[foreground(image)]).sum(axis=1), 2)
    values, counts = np.unique(lum, return_counts=True)
    faces = values[counts > 0.1 * counts.sum()]
    assert len(faces) == 3


def two_part_boxes(parts_info=None):
    boxes = [((0.0, 0.0, 0.0), (0.3, 0.3, 0.3)), ((0.5, 0.0, 0.0), (0.8, 0.3, 0.3))]
    c = shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes), ((0, 0, 0), (0.8, 0.3, 0.3)), voxel_size=H
    )
    x = c.axis_coords(0)
    parts = np.broadcast_to(np.where(x < 0.4, 0, 1)[:, None, None], c.shape)
    meta = dict(c.meta)
    if parts_info is not None:
        meta["parts_info"] = parts_info
    return c.replace(parts=parts, meta=meta)


def test_parts_take_stored_colours():
    info = [{"color": [220, 30, 30]}, {"color": [30, 30, 220]}]
    c = two_part_boxes(info)
    image = render.render(c, view="front", size=160, parts=True)
    fg = foreground(image)
    cols = np.nonzero(fg.any(axis=0))[0]
    left = image[:, : cols.mean().astype(int)][fg[:, : cols.mean().astype(int)]]
    right = image[:, cols.mean().astype(int) :][fg[:, cols.mean().astype(int) :]]
    assert np.abs(chromaticity(left) - chromaticity(np.array(info[0]["color"]))).max() <= 0.02
    assert np.abs(chromaticity(right) - chromaticity(np.array(info[1]["color"]))).max() <= 0.02


def test_parts_without_stored_colours_are_distinct_and_none_is_grey():
    c = two_part_boxes()
    image = render.render(c, view="front", size=160, parts=True)
    fg = foreground(image)
    chroma = np.round(chromaticity(image[fg]), 1)
    assert len(np.unique(chroma, axis=0)) >= 2
    # unsegmented voxels (-1) render grey: equal channels
    grey = c.replace(parts=np.where(c.parts == 1, -1, c.parts))
    image = render.render(grey, view="front", size=160, parts=True)
    right = image[:, 100:][foreground(image[:, 100:])]
    assert len(right) > 100
    assert (np.ptp(right.astype(int), axis=1) <= 1).all()


def bar_px(image: np.ndarray) -> int:
    """Length in pixels of the scale bar: the longest dark row in the bottom tenth."""
    dark = (image < 60).all(axis=-1)
    bottom = dark[int(len(image) * 0.9) :]
    return int(bottom.sum(axis=1).max())


@pytest.mark.parametrize(("width", "bar"), [(1.5, 0.2), (2.0, 0.5)])
def test_scale_bar_is_the_round_length_below_a_quarter_of_the_image(width, bar):
    # a quarter of a 256 px image framing `width` metres: 0.457 m (bar 20 cm), 0.610 m (50 cm)
    c = shapes.sphere((0, 0, 0), 0.3, voxel_size=H)
    frame = np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]) * width / 2
    image = render.render(c, view="front", size=256, frame=frame, scale_bar=True)
    assert abs(bar_px(image) - bar * 256 * 0.82 / width) <= 3


def test_scale_bar_is_labelled_and_to_scale():
    assert render.scale_bar_label(0.5, "m") == "50 cm"
    assert render.scale_bar_label(2.0, "m") == "2 m"
    assert render.scale_bar_label(0.005, "m") == "5 mm"
    c = shapes.sphere((0, 0, 0), 0.3, voxel_size=H)  # centre on a voxel: 0.6 m across exactly
    size = 256
    image = render.render(c, view="front", size=size, scale_bar=True)
    # worked out by hand: the 0.6 m frame fills the image less 5% margins on each side and the
    # bar's 8% band, 256 * (1 - 0.1 - 0.08) px, so 349.9 px/m; a quarter of the width (64 px) is
    # 0.183 m, the bar the round length below it, 10 cm: 35.0 px (+1 for the end pixel)
    assert abs(bar_px(image) - 0.1 * 256 * 0.82 / 0.6) <= 3
    # the (blue) object stays clear of the bar's band: only grey ink there
    band = image[int(size * (1 - render.SCALE_BAR_BAND)) :]
    ink = band[foreground(band)].astype(int)
    assert len(ink) > 100 and (np.ptp(ink, axis=1) <= 2).all()


def test_render_refuses_bad_options(sphere):
    with pytest.raises(InputError, match="segmented"):
        render.render(sphere, parts=True)
    with pytest.raises(InputError, match="front, side, top, iso"):
        render.render(sphere, view="back")
    with pytest.raises(InputError) as err:
        render.render(sphere, size=8)
    assert str(err.value) == (
        f"size: expected an integer in [{render.MIN_SIZE}, {render.MAX_SIZE}], got 8"
    )
    # a view is read as batch manifests read it: without case or surrounding blanks
    frame = [[0, 0, 0], [2, 1, 1]]
    given, top = render.camera(" Top", frame, 100), render.camera("top", frame, 100)
    assert given.up.tolist() == top.up.tolist() and given.back.tolist() == top.back.tolist()
    with pytest.raises(InputError, match=r"^view: expected one of front, side, top, iso, got 5$"):
        render.camera(5, frame, 100)
    with pytest.raises(TypeError, match="options are"):
        render.render(sphere, colour=True)
    with pytest.raises(InputError, match="frame"):
        render.render(sphere, frame=[[1, 1, 1], [0, 0, 0]])
    empty = sphere.replace(sdf=np.abs(sphere.sdf) + 0.01)
    with pytest.raises(InputError, match="surface"):
        render.render(empty)


# -- CLI -------------------------------------------------------------------------------------
@pytest.fixture
def sphere_file(sphere, tmp_path):
    return partscale.save(sphere, tmp_path / "s.csdf.npz")


def test_cli_render_writes_a_png_of_the_asked_size(cli, sphere_file, tmp_path):
    out = tmp_path / "s.png"
    proc = cli("render", sphere_file, "-o", out, "--view", "top", "--pixels", "96")
    assert proc.returncode == 0, proc.stderr
    with Image.open(out) as im:
        assert im.format == "PNG" and im.size == (96, 96) and im.mode == "RGB"
        assert foreground(np.asarray(im)).sum() > 1000


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["--view", "back"], ["--view", "front, side, top, iso", "back"]),
        (["--parts"], ["--parts", "segmented"]),
        (["--pixels", "4"], ["--pixels", "4"]),
    ],
)
def test_cli_render_bad_options(cli, sphere_file, tmp_path, args, fragments):
    out = tmp_path / "out"
    out.mkdir()
    proc = cli("render", sphere_file, "-o", out / "s.png", *args)
    assert_bad_input(proc, *fragments)
    assert list(out.iterdir()) == []


def test_cli_render_bad_files(cli, sphere_file, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    proc = cli("render", sphere_file, "-o", out / "s.jpg")
    assert_bad_input(proc, "s.jpg", ".png")
    proc = cli("render", tmp_path / "missing.csdf.npz", "-o", out / "s.png")
    assert_bad_input(proc, "missing.csdf.npz", "no such file")
    bad = tmp_path / "bad.csdf.npz"
    bad.write_text("not a zip")
    proc = cli("render", bad, "-o", out / "s.png")
    assert_bad_input(proc, "bad.csdf.npz")
    assert list(out.iterdir()) == []


def test_cli_render_onto_a_directory_is_refused(cli, sphere_file, tmp_path):
    out = tmp_path / "out"
    (out / "blocked.png").mkdir(parents=True)
    proc = cli("render", sphere_file, "-o", out / "blocked.png")
    assert_bad_input(proc, str(out / "blocked.png"), "expected a writable file")
    assert [p.name for p in out.iterdir()] == ["blocked.png"]  # no temporary file left
    assert not any((out / "blocked.png").iterdir())


def test_real_chair_silhouette_matches_its_bounds():
    from conftest import data_path

    ingest = pytest.importorskip("partscale.ingest", reason="import stage not on this branch")
    c = ingest.load(data_path("kenney/chair.glb"), res=64)
    b = c.surface_bounds()
    size = 200
    for view, (ax_w, ax_h) in {"front": (0, 1), "side": (2, 1), "top": (0, 2)}.items():
        image = render.render(c, view=view, size=size)
        rows, cols = np.nonzero(foreground(image))
        scale = render.camera(view, b, size).scale
        # the silhouette spans the solid's extent (one pixel of rounding at each edge)
        assert abs(np.ptp(cols) + 1 - (b[1, ax_w] - b[0, ax_w]) * scale) <= 2, view
        assert abs(np.ptp(rows) + 1 - (b[1, ax_h] - b[0, ax_h]) * scale) <= 2, view
    # its own colours: the rendered pixels' chromaticities come from the grid's surface colours
    image = render.render(c, view="iso", size=size)
    near = np.abs(c.sdf) < c.voxel_size
    surface = chromaticity(c.rgb[near].reshape(-1, 3).astype(float) + 1)
    seen = chromaticity(image[foreground(image)].astype(float) + 1)
    assert np.abs(np.median(seen, axis=0) - np.median(surface, axis=0)).max() <= 0.05


def test_cli_render_parts_uses_part_colours(cli, tmp_path):
    info = [{"index": 0, "color": [20, 200, 40]}, {"index": 1, "color": [200, 20, 160]}]
    path = partscale.save(two_part_boxes(info), tmp_path / "two.csdf.npz")
    out = tmp_path / "parts.png"
    proc = cli("render", path, "-o", out, "--parts", "--view", "front", "--pixels", "120")
    assert proc.returncode == 0, proc.stderr
    image = np.asarray(Image.open(out).convert("RGB"))
    chroma = chromaticity(image[foreground(image)])
    for colour in info:
        close = np.abs(chroma - chromaticity(np.array(colour["color"]))).max(axis=1) <= 0.02
        assert close.mean() > 0.3, colour


@pytest.mark.parametrize("view", ["front", "side"])
def test_rays_grazing_thin_shelves_reach_the_back_panel(view):
    """A shelf unit seen edge-on: rays just above a shelf top run parallel to it for the
    shelf's whole depth (the SDF a few hundredths of a voxel all along) and must go on to the
    back panel, not stop and show the background as a 1-pixel crack along the shelf."""
    back = ((0, 0, 0), (1, 1, 0.05)) if view == "front" else ((0, 0, 0), (0.05, 1, 1))
    depth = (1, 0.8) if view == "front" else (0.8, 1)
    boxes = [back] + [((0, y, 0), (depth[0], y + 0.03, depth[1])) for y in (0.1, 0.4, 0.7)]
    c = shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), ((0, 0, 0), (1, 1, 1)), voxel_size=1 / 64)
    magenta = (255, 0, 255)
    image = render.render(c, view=view, size=512, background=magenta)
    bg = ~foreground(image, np.array(magenta))
    # the back panel fills the whole silhouette: every pixel between a row's first and last
    # hit is a hit
    rows = np.nonzero((~bg).any(axis=1))[0]
    holes = 0
    for r in rows:
        hit = np.nonzero(~bg[r])[0]
        holes += int(bg[r, hit[0] : hit[-1] + 1].sum())
    assert holes == 0
    # and the silhouette is the panel's full square, no row of it missing
    assert rows[-1] - rows[0] + 1 == len(rows)


@pytest.mark.parametrize("shape", [(2.0, 0.5, 0.4), (0.4, 2.0, 0.4)])
def test_bands_picture_is_cropped_to_the_object(shape):
    """No empty bands: the picture is the object, its bands and axes, a margin, the scale bar."""
    lo, hi = np.zeros(3), np.array(shape)
    c = shapes.grid(lambda p: shapes.box_sdf(p, lo, hi), [lo, hi], voxel_size=0.02)
    size = 400
    a = 0 if shape[0] > shape[1] else 1
    image = render.render_bands(c, [(a, 0.5, 1.5, "1 stretch", (0, 158, 115))], size=size)
    fg = foreground(image)
    rows, cols = np.flatnonzero(fg.any(axis=1)), np.flatnonzero(fg.any(axis=0))
    margin = render.BAND_MARGIN * size + 1  # one pixel of rounding
    assert rows[0] <= margin and len(image) - 1 - rows[-1] <= margin
    assert cols[0] <= margin and image.shape[1] - 1 - cols[-1] <= margin
    # the object spans the view's larger side less the render margins: most of the picture
    obj = (np.ptp(image.astype(int), axis=-1) > 20).any(axis=a)  # coloured, not grey ink
    assert obj.sum() >= size * (1 - 2 * render.MARGIN) - 2
    assert obj.sum() >= 0.7 * image.shape[1 - a]
    # the other side is not padded to a square
    assert image.shape[a] <= 0.6 * size
    # and there is no empty band of rows anywhere (between the object and the scale bar either)
    blank = ~fg.any(axis=1)
    runs = np.diff(np.flatnonzero(np.concatenate([[True], ~blank, [True]]))) - 1
    assert runs.max() <= 2 * margin


@pytest.mark.parametrize("shape", [(2.0, 0.5, 0.4), (0.4, 2.0, 0.4)])
def test_band_labels_do_not_overlap(shape, monkeypatch):
    """Labels of bands starting close together are moved along their band or left out, the
    best band's staying at its corner: no two overlap."""
    from PIL import ImageDraw

    drawn = []
    text = ImageDraw.ImageDraw.text

    def spy(self, xy, label, *args, **kwargs):
        box = self.textbbox(xy, label, font=kwargs.get("font"), anchor=kwargs.get("anchor"))
        drawn.append((label, box))
        return text(self, xy, label, *args, **kwargs)

    monkeypatch.setattr(ImageDraw.ImageDraw, "text", spy)
    lo, hi = np.zeros(3), np.array(shape)
    c = shapes.grid(lambda p: shapes.box_sdf(p, lo, hi), [lo, hi], voxel_size=0.02)
    a = 0 if shape[0] > shape[1] else 1
    labels = [f"{k + 1} stretch" for k in range(6)]
    bands = [(a, 0.5 + 0.02 * k, 1.5 - 0.02 * k, labels[k], (0, 158, 115)) for k in range(6)]
    render.render_bands(c, bands, size=400)
    boxes = {label: box for label, box in drawn if label in labels}
    assert "1 stretch" in boxes and len(boxes) >= 2, sorted(boxes)
    listed = list(boxes.values())
    for i, p in enumerate(listed):
        for q in listed[i + 1 :]:
            assert not (p[0] < q[2] and q[0] < p[2] and p[1] < q[3] and q[1] < p[3]), (p, q)


def test_bands_beyond_the_first_few_are_outlined_not_filled():
    """Many overlapping candidates do not wash a light object out: only the first few tint it."""
    lo, hi = np.zeros(3), np.array([2.0, 0.5, 0.4])
    c = shapes.grid(lambda p: shapes.box_sdf(p, lo, hi), [lo, hi], voxel_size=0.02)
    c = c.replace(rgb=np.full_like(c.rgb, 240))
    first = [(0, 0.5, 1.5, str(k), (0, 158, 115)) for k in range(render.FILLED_BANDS)]
    more = [(0, 0.2, 1.8, str(k), (200, 0, 0)) for k in range(4)]
    one = render.render_bands(c, first, size=300)
    many = render.render_bands(c, first + more, size=300)
    assert one.shape == many.shape
    # x in (0.25, 0.45) is covered by the later bands only: the object there is as without them
    w = one.shape[1]
    fg = foreground(one)
    rows = np.flatnonzero(fg[:, w // 2])
    cols = np.flatnonzero(fg[rows[len(rows) // 2]])
    x0, x1 = cols[0], cols[-1]  # the object's extent in x on a middle row
    band = slice(x0 + int(0.3 / 2 * (x1 - x0)), x0 + int(0.4 / 2 * (x1 - x0)))
    middle = slice(rows[0] + len(rows) // 4, rows[0] + len(rows) // 2)
    assert np.abs(one[middle, band].astype(int) - many[middle, band].astype(int)).max() <= 2


# -- meshes: what the mesh route writes can be looked at --------------------------------------


def _png(path):
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB")).astype(np.int64)


def _compare(a, b):
    """(silhouette IoU, mean |difference| over pixels both draw, (3,) mean colour difference)."""
    fa, fb = foreground(a), foreground(b)
    both = fa & fb
    iou = both.sum() / (fa | fb).sum()
    return iou, np.abs(a[both] - b[both]).mean(), a[fa].mean(0) - b[fb].mean(0)


def test_render_draws_each_mesh_the_mesh_route_writes_in_its_colours(cli, tmp_path):
    """The shipped table made 20 inches longer by the mesh route, written as GLB, OBJ and PLY:
    ``render`` draws each, the three pictures alike (glTF's linear colour factor reaches the
    OBJ's Kd and the PLY's vertex colours as the same display colour), and like the CSDF
    route's picture of the same edit."""
    from partscale import data

    edit = ("--axis", "x", "--zone", "35%", "65%", "--by", "20in")
    pics = {}
    for fmt in ("glb", "obj", "ply"):
        mesh = tmp_path / f"longer.{fmt}"
        cli("scale", data.table(), "-o", mesh, *edit, check=True)
        pics[fmt] = tmp_path / f"{fmt}.png"
        proc = cli("render", mesh, "-o", pics[fmt], "--pixels", "160", check=True)
        assert "160 x 160" in proc.stderr
    csdf = tmp_path / "t.csdf.npz"
    cli("import", data.table(), "-o", csdf, check=True)
    cli("scale", csdf, "-o", tmp_path / "l.csdf.npz", *edit, check=True)
    cli(
        "render",
        tmp_path / "l.csdf.npz",
        "-o",
        tmp_path / "csdf.png",
        "--pixels",
        "160",
        check=True,
    )
    glb = _png(pics["glb"])
    assert foreground(glb).mean() > 0.15  # the table, not an empty picture
    for fmt in ("obj", "ply"):
        iou, diff, mean = _compare(_png(pics[fmt]), glb)
        assert iou >= 0.99 and diff <= 2 and np.abs(mean).max() <= 2, (fmt, iou, diff, mean)
    iou, diff, mean = _compare(_png(tmp_path / "csdf.png"), glb)
    assert iou >= 0.95 and np.abs(mean).max() <= 3, (iou, diff, mean)


def test_render_draws_a_textured_mesh_route_output_with_its_texture(cli, tmp_path, data):
    """A textured glTF (Poly Haven stool) through the mesh route: the OBJ keeps the texture (its
    picture matches the GLB's texel for texel, near enough); the PLY, which has no textures,
    carries it as vertex colours (the same mean colour)."""
    src = data("polyhaven/painted_wooden_stool/painted_wooden_stool_1k.gltf")
    edit = ("--axis", "y", "--zone", "30%", "60%", "--by", "10cm")
    pics = {}
    for fmt in ("glb", "obj", "ply"):
        cli("scale", src, "-o", tmp_path / f"s.{fmt}", *edit, check=True)
        pics[fmt] = _png_of(cli, tmp_path / f"s.{fmt}", tmp_path / f"{fmt}.png")
    iou, diff, mean = _compare(pics["obj"], pics["glb"])
    assert iou >= 0.99 and diff <= 3 and np.abs(mean).max() <= 2, (iou, diff, mean)
    iou, diff, mean = _compare(pics["ply"], pics["glb"])
    assert iou >= 0.99 and np.abs(mean).max() <= 12, (iou, diff, mean)


def _png_of(cli, mesh, out):
    cli("render", mesh, "-o", out, "--pixels", "200", check=True)
    return _png(out)


def test_render_refuses_a_file_that_is_neither_csdf_nor_mesh(cli, tmp_path):
    bad = tmp_path / "notes.txt"
    bad.write_text("hello")
    assert_bad_input(cli("render", bad, "-o", tmp_path / "x.png"), "notes.txt", ".csdf.npz", ".glb")
    assert not (tmp_path / "x.png").exists()
