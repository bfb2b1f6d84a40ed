"""Pictures of a CSDF made from the SDF itself: sphere tracing on the CPU, no GPU, no mesh.

Orthographic views of a Y-up object (glTF's convention: +y up, +z front, +x right):
``front`` looks along -z, ``side`` along -x (from the right), ``top`` along -y (front at the
bottom of the image), ``iso`` along -(1, 1, 1) (from front-right-above). Every ray is marched at
once by a numba kernel (parallel over rays) through the trilinear SDF in voxel units; shading is
Lambert + ambient in linear light with normals from the SDF gradient, written back as sRGB. The
colour grid's corners are decoded to linear light before they are blended, as a GPU filters an
sRGB texture (the editor's page renders the same way).

The camera fits a world box (``frame``, default the solid's bounds): its projection is centred
and its larger projected extent spans ``size * (1 - 2 * MARGIN)`` pixels, so several objects
rendered with the same ``frame`` share one scale.
"""

from __future__ import annotations

import itertools
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from ._files import atomic_path
from ._kernels import corner_weight, grid_cell, trilinear_point
from ._options import choice, count, keyword_options
from .color import linear_to_srgb, palette_colour, srgb8_to_linear
from .csdf import CSDF
from .errors import InputError
from .progress import ProgressCallback, resolve

VIEWS = ("front", "side", "top", "iso")
MARGIN = 0.05
"""Fraction of the image left empty on each side of the frame."""
MIN_SIZE, MAX_SIZE = 16, 4096
NO_PART_COLOR = (150, 150, 150)
HIT_EPS = 0.01
"""A ray hits when the SDF at its point is below this many voxels."""
MAX_STEPS = 512
"""Steps a ray takes at the fine minimum stride (``HIT_EPS``) before it strides on faster."""
GRAZE_STEP = 0.1
"""Minimum stride in voxels after ``MAX_STEPS`` steps: a ray still marching then runs parallel to
a face just above it (a shelf top seen edge-on), where the SDF stays a few hundredths of a voxel
for the face's whole depth. It marches on to what lies behind, never stopping short of the grid's
far side (ending it there drew such rays as background: 1-pixel cracks along thin boards)."""
AMBIENT = 0.35
SCALE_BAR_BAND = 0.08
"""Fraction of the image height kept free at the bottom for the scale bar."""
#: The 256 sRGB values' linear light: the colour grid is decoded corner by corner, then blended.
_SRGB8_LINEAR = srgb8_to_linear(np.arange(256))

# (towards the camera, screen up) per view, world coordinates
_VIEW_AXES = {
    "front": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "side": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "top": ((0.0, 1.0, 0.0), (0.0, 0.0, -1.0)),
    "iso": ((1.0, 1.0, 1.0), (0.0, 1.0, 0.0)),
}


@dataclass(frozen=True)
class Camera:
    """An orthographic camera, as :func:`camera` fits it to a box.

    Parameters
    ----------
    centre : (3,) float64
        World point at the image centre.
    right, up, back : (3,) float64
        Unit vectors of the image's x, its y and towards the viewer.
    scale : float
        Pixels per world unit.
    size : int
        Image width and height in pixels.
    shift : float
        Pixels ``centre`` appears above the image centre.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.render import camera
    >>> cam = camera("front", shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.05).surface_bounds(), 64)
    >>> cam.right.tolist(), cam.pixel_rays().shape
    ([1.0, 0.0, 0.0], (4096, 3))
    """

    centre: np.ndarray
    right: np.ndarray
    up: np.ndarray
    back: np.ndarray
    scale: float
    size: int

    shift: float = 0.0

    def pixel_rays(self) -> np.ndarray:
        """World points of the pixel centres on the camera plane, row by row from the top.

        Returns
        -------
        (size * size, 3) float64
            One point per pixel; rays leave them along ``-back``.
        """
        s = self.size
        u = (np.arange(s) + 0.5 - s / 2) / self.scale
        v = (s / 2 - self.shift - (np.arange(s) + 0.5)) / self.scale
        return (
            self.centre[None, None, :]
            + u[None, :, None] * self.right[None, None, :]
            + v[:, None, None] * self.up[None, None, :]
        ).reshape(-1, 3)


def camera(view: str, frame: np.ndarray, size: int, *, reserve_bottom: float = 0.0) -> Camera:
    """Fit an orthographic camera for ``view`` to a world box.

    The frame's projection is centred in the image and its larger extent spans
    ``size * (1 - 2 * MARGIN)`` pixels.

    Parameters
    ----------
    view : {"front", "side", "top", "iso"}
        Where the camera looks from.
    frame : (2, 3) array_like of float
        World box (min and max corner) to fit.
    size : int
        Image width and height in pixels.
    reserve_bottom : float
        A band at the bottom kept free (a fraction of ``size``, for the scale bar), shrinking and
        lifting the fit accordingly.

    Returns
    -------
    Camera
        The camera.

    Examples
    --------
    >>> from partscale.render import camera
    >>> cam = camera("top", [[0, 0, 0], [2, 1, 1]], 100)
    >>> cam.up.tolist(), round(cam.scale, 1)
    ([0.0, 0.0, -1.0], 45.0)
    """
    view = choice(view, "view", VIEWS)
    back, up = (np.asarray(a, dtype=np.float64) for a in _VIEW_AXES[view])
    back = back / np.linalg.norm(back)
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    frame = np.asarray(frame, dtype=np.float64)
    corners = np.array(
        [[frame[i, 0], frame[j, 1], frame[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )
    pr, pu = corners @ right, corners @ up
    ext_r, ext_u = pr.max() - pr.min(), pu.max() - pu.min()
    avail = size * (1 - 2 * MARGIN)
    avail_u = avail - reserve_bottom * size
    centre = frame.mean(axis=0)
    centre = centre + right * ((pr.max() + pr.min()) / 2 - centre @ right)
    centre = centre + up * ((pu.max() + pu.min()) / 2 - centre @ up)
    scale = min(avail / max(ext_r, 1e-12), avail_u / max(ext_u, 1e-12))
    return Camera(centre, right, up, back, float(scale), int(size), reserve_bottom * size / 2)


# -- numba kernels (index space: voxel centres at integers, distances in voxels) -------------
@numba.njit(cache=True, parallel=True)
def _trace(sdf, origins, d, eps, max_steps, graze, hits):
    """March every ray ``origins[r] + t d`` through ``sdf`` (voxel units); hits[r] = point or nan.

    Steps are the SDF value, at least ``eps`` for ``max_steps`` steps and at least ``graze``
    after (see :data:`GRAZE_STEP`).
    """
    n = origins.shape[0]
    hi = np.array([sdf.shape[0] - 1.0, sdf.shape[1] - 1.0, sdf.shape[2] - 1.0])
    for r in numba.prange(n):
        t0 = -1e30
        t1 = 1e30
        for a in range(3):
            o = origins[r, a]
            if abs(d[a]) < 1e-12:
                if o < 0.0 or o > hi[a]:
                    t0 = 1e30
            else:
                ta = (0.0 - o) / d[a]
                tb = (hi[a] - o) / d[a]
                t0 = max(t0, min(ta, tb))
                t1 = min(t1, max(ta, tb))
        hits[r, 0] = np.nan
        if t0 > t1:
            continue
        t = t0
        stride = eps
        steps = 0
        # ends: at a hit or past the grid; after max_steps every step is >= graze, so a ray
        # takes at most max_steps + (t1 - t0) / graze steps
        while t <= t1:
            x = origins[r, 0] + t * d[0]
            y = origins[r, 1] + t * d[1]
            z = origins[r, 2] + t * d[2]
            v = trilinear_point(sdf, x, y, z)
            if v < eps:
                hits[r, 0] = x
                hits[r, 1] = y
                hits[r, 2] = z
                break
            steps += 1
            if steps == max_steps:
                stride = graze
            t += max(v, stride)


@numba.njit(cache=True, parallel=True)
def _normals(sdf, pts, out):
    for r in numba.prange(pts.shape[0]):
        x, y, z = pts[r, 0], pts[r, 1], pts[r, 2]
        gx = trilinear_point(sdf, x + 0.5, y, z) - trilinear_point(sdf, x - 0.5, y, z)
        gy = trilinear_point(sdf, x, y + 0.5, z) - trilinear_point(sdf, x, y - 0.5, z)
        gz = trilinear_point(sdf, x, y, z + 0.5) - trilinear_point(sdf, x, y, z - 0.5)
        n = math.sqrt(gx * gx + gy * gy + gz * gz)
        if n < 1e-12:
            out[r, 0], out[r, 1], out[r, 2] = 0.0, 0.0, 0.0
        else:
            out[r, 0], out[r, 1], out[r, 2] = gx / n, gy / n, gz / n


@numba.njit(cache=True, parallel=True)
def _colours(rgb, lut, pts, out):
    """Linear-light colour (``out``, (P, 3) float64) at each point of ``pts`` (P, 3) voxel
    indices: each corner's sRGB ``rgb`` (X, Y, Z, 3) uint8 decoded through ``lut`` (256,) before
    the trilinear blend, as a GPU samples an sRGB texture (the editor's page does).
    """
    nx, ny, nz = rgb.shape[0], rgb.shape[1], rgb.shape[2]
    for r in numba.prange(pts.shape[0]):
        i, fx = grid_cell(pts[r, 0], nx)
        j, fy = grid_cell(pts[r, 1], ny)
        k, fz = grid_cell(pts[r, 2], nz)
        for c in range(3):
            acc = 0.0
            for di in range(2):
                for dj in range(2):
                    for dk in range(2):
                        w = corner_weight(fx, fy, fz, di, dj, dk)
                        acc += w * lut[rgb[i + di, j + dj, k + dk, c]]
            out[r, c] = acc


def part_colors(csdf: CSDF) -> np.ndarray:
    """Display colour of each part of a segmented CSDF.

    Parameters
    ----------
    csdf : CSDF
        A segmented object (``csdf.n_parts`` parts; none gives an empty table).

    Returns
    -------
    (P, 3) uint8
        sRGB colour of part ``i`` in row ``i``: ``meta['parts_info'][i]['color']`` when stored,
        else the colour segmentation would store (:func:`partscale.color.palette_colour`).

    Examples
    --------
    >>> from partscale import data, ingest, segment
    >>> from partscale.render import part_colors
    >>> table = segment.segment(ingest.load(data.table(), res=64))
    >>> colours = part_colors(table)
    >>> colours.shape == (table.n_parts, 3), colours.dtype
    (True, dtype('uint8'))
    """
    n = csdf.n_parts
    info = csdf.meta.get("parts_info")
    out = np.empty((n, 3), np.uint8)
    for i in range(n):
        entry = None
        if isinstance(info, list) and i < len(info):
            entry = info[i]
        elif isinstance(info, dict):
            entry = info.get(str(i))
        colour = entry.get("color") if isinstance(entry, dict) else None
        if colour is not None and len(colour) >= 3:
            out[i] = np.clip(np.asarray(colour[:3], dtype=float), 0, 255)
        else:
            out[i] = palette_colour(i)
    return out


def _nice_length(max_length: float) -> float:
    """The largest 1, 2 or 5 times a power of ten not above ``max_length``."""
    p = 10.0 ** math.floor(math.log10(max_length))
    for m in (5.0, 2.0, 1.0):
        if m * p <= max_length * (1 + 1e-9):
            return m * p
    return p


def scale_bar_label(length: float, units: str) -> str:
    """A short label for a scale bar ``length`` long.

    Parameters
    ----------
    length : float
        The bar's length in ``units``.
    units : str
        The object's units; metres are shown in m, cm or mm, whichever reads as a whole number.

    Returns
    -------
    str
        The label.

    Examples
    --------
    >>> from partscale.render import scale_bar_label
    >>> scale_bar_label(0.5, "m"), scale_bar_label(2.0, "m"), scale_bar_label(5, "in")
    ('50 cm', '2 m', '5 in')
    """
    if units == "m":
        for factor, name in ((1.0, "m"), (100.0, "cm"), (1000.0, "mm")):
            if length * factor >= 1 - 1e-9:
                return f"{length * factor:g} {name}"
        return f"{length * 1e6:g} µm"
    return f"{length:g} {units}"


def _draw_scale_bar(
    image: np.ndarray, cam: Camera, units: str, background, *, max_px: float | None = None
) -> np.ndarray:
    """``image`` with a scale bar at its bottom left, at most ``max_px`` (default a quarter of
    the camera's image) long; sized by the camera's image, placed by ``image``'s height.
    """
    from PIL import Image, ImageDraw, ImageFont

    size = cam.size
    length = _nice_length((0.25 * size if max_px is None else max_px) / cam.scale)
    px = round(length * cam.scale)
    label = scale_bar_label(length, units)
    ink = (0, 0, 0) if sum(background) > 3 * 128 else (255, 255, 255)
    im = Image.fromarray(image)
    draw = ImageDraw.Draw(im)
    font = ImageFont.load_default(size=max(10, size // 32))
    x0 = max(4, size // 25)
    y1 = image.shape[0] - max(4, size // 25)
    thick = max(2, size // 128)
    draw.rectangle([x0, y1 - thick, x0 + px, y1], fill=ink)
    for x in (x0, x0 + px):
        draw.rectangle([x - thick // 2, y1 - 3 * thick, x + (thick - 1) // 2, y1], fill=ink)
    draw.text((x0, y1 - 3 * thick - 2), label, fill=ink, font=font, anchor="ld")
    return np.asarray(im)


@keyword_options
def render(
    csdf: CSDF,
    *,
    view: str = "iso",
    size: int = 512,
    parts: bool = False,
    frame=None,
    scale_bar: bool = False,
    background=(255, 255, 255),
    progress: ProgressCallback | None = None,
) -> np.ndarray:
    """Sphere-trace ``csdf`` into an image.

    Parameters
    ----------
    csdf : CSDF
    view : {"front", "side", "top", "iso"}
    size : int
        Image width and height in pixels (16..4096).
    parts : bool
        Colour by part (``meta['parts_info'][i]['color']`` or the part palette; part -1 grey)
        instead of the CSDF's own colours. Needs a segmented CSDF.
    frame : (2, 3) array_like, optional
        World box the camera fits (default: the solid's bounds), for several objects at one scale.
    scale_bar : bool
        Draw a labelled scale bar (e.g. "50 cm") at the bottom left.
    background : (3,) int
        sRGB colour where no ray hits.

    Returns
    -------
    (size, size, 3) uint8
        sRGB image, row 0 at the top.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale.render import render, save_png
    >>> image = render(ingest.load(data.table(), res=64), view="iso", size=256)
    >>> image.shape, image.dtype
    ((256, 256, 3), dtype('uint8'))
    >>> save_png(image, "table.png")
    PosixPath('table.png')
    """
    report = resolve(progress)
    size = count(size, "size", lo=MIN_SIZE, hi=MAX_SIZE)
    view = choice(view, "view", VIEWS)
    if parts and csdf.n_parts == 0:
        raise InputError("parts: expected a segmented CSDF (segment it first), got no parts")
    bg = np.asarray(background, dtype=np.int64).reshape(-1)
    if bg.shape != (3,) or bg.min() < 0 or bg.max() > 255:
        raise InputError(f"background: expected 3 integers in [0, 255], got {background!r}")
    if frame is None:
        frame = csdf.surface_bounds()
    frame = np.asarray(frame, dtype=np.float64)
    if frame.shape != (2, 3) or not np.isfinite(frame).all() or (frame[1] < frame[0]).any():
        raise InputError(
            f"frame: expected a (2, 3) world box with min <= max, got {frame.tolist()}"
        )
    cam = camera(view, frame, size, reserve_bottom=SCALE_BAR_BAND if scale_bar else 0.0)

    report(0.0, "tracing rays")
    h = csdf.voxel_size
    sdf_vox = np.ascontiguousarray(csdf.sdf / np.float32(h), dtype=np.float32)
    origins = cam.pixel_rays()
    origins = np.ascontiguousarray((origins - csdf.origin) / h)
    d = np.ascontiguousarray(-cam.back)
    hits = np.empty_like(origins)
    _trace(sdf_vox, origins, d, HIT_EPS, MAX_STEPS, GRAZE_STEP, hits)
    hit = ~np.isnan(hits[:, 0])
    pts = np.ascontiguousarray(hits[hit])
    report(0.7, "shading")

    normals = np.empty_like(pts)
    _normals(sdf_vox, pts, normals)
    if parts:
        inner = pts - 0.5 * normals  # half a voxel inside: the part of the solid, not the air
        ijk = np.rint(inner).astype(np.intp)
        for a in range(3):
            np.clip(ijk[:, a], 0, csdf.shape[a] - 1, out=ijk[:, a])
        labels = csdf.parts[ijk[:, 0], ijk[:, 1], ijk[:, 2]]
        table = np.concatenate([part_colors(csdf), np.array([NO_PART_COLOR], np.uint8)])
        base = srgb8_to_linear(table[np.where(labels >= 0, labels, len(table) - 1)])
    else:
        base = np.empty_like(pts)  # linear light: decoded before filtering, as the page does
        _colours(np.ascontiguousarray(csdf.rgb), _SRGB8_LINEAR, pts, base)
    # key light from above, slightly left and in front, so the three faces of a box differ
    light = -0.1 * cam.right + 0.45 * cam.up + 0.9 * cam.back
    light /= np.linalg.norm(light)
    lambert = np.clip(normals @ light, 0.0, 1.0)
    shade = AMBIENT + (1 - AMBIENT) * lambert
    lin = base * shade[:, None]
    colours = np.rint(linear_to_srgb(lin) * 255).astype(np.uint8)

    image: np.ndarray = np.empty((size * size, 3), np.uint8)
    image[:] = bg.astype(np.uint8)
    image[hit] = colours
    image = image.reshape(size, size, 3)
    if scale_bar:
        image = _draw_scale_bar(image, cam, csdf.meta.get("units", "m"), tuple(bg.tolist()))
    report(1.0, "rendered")
    return image


def save_png(image: np.ndarray, path: str | os.PathLike) -> Path:
    """Write an image as PNG, atomically.

    Parameters
    ----------
    image : (H, W, 3) or (H, W, 4) uint8
        sRGB(A) pixels, row 0 at the top, as :func:`render` returns them.
    path : str or os.PathLike
        A file ending in ``.png``.

    Returns
    -------
    pathlib.Path
        ``path``, now holding the PNG.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.render import render, save_png
    >>> save_png(render(shapes.sphere((0, 0, 0), 1.0, voxel_size=0.1), size=64), "ball.png")
    PosixPath('ball.png')
    """
    from PIL import Image

    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InputError(
            f"{path}: expected an image file ending in .png, got {path.suffix or 'no suffix'}"
        )
    img = np.asarray(image)
    if img.dtype != np.uint8 or img.ndim != 3 or img.shape[2] not in (3, 4):
        raise InputError(f"image: expected (H, W, 3|4) uint8, got {img.shape} {img.dtype}")
    with atomic_path(path) as tmp:
        Image.fromarray(img).save(tmp, format="PNG")
    return path


#: Margin (a fraction of the image size) :func:`render_bands` keeps around what it draws.
BAND_MARGIN = 0.025
#: Opacity of the bands :func:`render_bands` fills.
BAND_ALPHA = 0.28
#: How many of the first bands :func:`render_bands` fills; the rest are outlined only, so that
#: overlapping candidates do not wash a light object out.
FILLED_BANDS = 2


def _ticks(lo: float, hi: float) -> np.ndarray:
    span = max(hi - lo, 1e-12)
    step = 10 ** math.floor(math.log10(span / 4))
    for m in (1, 2, 5, 10):
        if span / (m * step) <= 6:
            step *= m
            break
    return np.arange(math.ceil(lo / step) * step, hi + 1e-9 * span, step)


def _label_spots(draw, font, boxes, labels, vertical) -> list[tuple[float, float] | None]:
    """Where each band's label goes: its box's top-left corner, or, where that would overlap
    the label of a band before it (a better one), the first free place further along the band
    (down a vertical band, right along a horizontal one), one label's height or width at a
    time; None (left out) where the band has no free place.
    """
    taken: list[tuple[float, float, float, float]] = []
    out: list[tuple[float, float] | None] = []
    for box, label, down in zip(boxes, labels, vertical, strict=True):
        left, top, right, bottom = draw.textbbox((0, 0), label, font=font)
        step = (bottom - top + 2) if down else (right - left + 6)
        spot = None
        for k in itertools.count():  # ends: each step moves the label further along the band
            x = box[0] + 3 + (0 if down else k * step)
            y = box[1] + 2 + (k * step if down else 0)
            lb = (x + left, y + top, x + right, y + bottom)
            # the first place is the label's whatever the band's size; later ones stay inside
            if k and (lb[3] > box[3] if down else lb[2] > box[2]):
                break
            if not any(
                lb[0] < t[2] and t[0] < lb[2] and lb[1] < t[3] and t[1] < lb[3] for t in taken
            ):
                spot = (x, y)
                taken.append(lb)
                break
        out.append(spot)
    return out


def render_bands(
    csdf: CSDF,
    bands: list[tuple[int, float, float, str, tuple[int, int, int]]],
    *,
    view: str = "front",
    size: int = 640,
) -> np.ndarray:
    """Render ``csdf`` with translucent zone bands, axes with ticks in object units and a scale bar.

    The object's larger side spans ``size`` less :data:`MARGIN`; the picture is cropped to the
    object, its bands and axes with a margin of :data:`BAND_MARGIN` of ``size``, the scale bar
    below it (what ``partscale suggest --png`` draws).

    Parameters
    ----------
    csdf : CSDF
        The object.
    bands : list of (axis, lo, hi, label, colour)
        Axis 0-2, world ``lo`` and ``hi`` along it, a short label and an sRGB colour; the first
        is drawn on top and only the first :data:`FILLED_BANDS` are filled (the rest outlined).
        Bands along an axis the view does not show are skipped
        (:class:`~partscale.errors.InputError` when none is left).
    view : {"front", "side", "top", "iso"}
        Where the camera looks from.
    size : int
        Pixels the object's frame is fitted to.

    Returns
    -------
    (H, W, 3) uint8
        sRGB image, cropped.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.render import render_bands
    >>> bar = shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.05)
    >>> image = render_bands(bar, [(0, 0.2, 0.6, "stretch", (255, 0, 0))], size=128)
    >>> image.ndim, image.dtype
    (3, dtype('uint8'))
    """
    from PIL import Image, ImageDraw, ImageFont

    frame = csdf.surface_bounds()
    white = (255, 255, 255)
    cam = camera(view, frame, size)
    # drawn on a wider canvas (labels beside the frame never fall off it), then cropped
    border = size // 8
    image = render(csdf, view=view, size=size, background=white)
    image = np.pad(image, ((border, border), (border, border), (0, 0)), constant_values=255)
    units = csdf.meta.get("units") or ""

    def pixel(p: np.ndarray) -> tuple[float, float]:
        d = p - cam.centre
        return border + size / 2 + (d @ cam.right) * cam.scale, border + size / 2 - cam.shift - (
            d @ cam.up
        ) * cam.scale

    corner_lo, corner_hi = pixel(frame[0]), pixel(frame[1])
    x0, x1 = sorted((corner_lo[0], corner_hi[0]))
    y0, y1 = sorted((corner_lo[1], corner_hi[1]))
    im = Image.fromarray(image).convert("RGBA")
    over = Image.new("RGBA", im.size, (0, 0, 0, 0))
    draw = ImageDraw.Draw(over)
    font = ImageFont.load_default(size=max(10, size // 48))
    across = next(a for a in range(3) if abs(cam.right[a]) > 0.5)
    up = next(a for a in range(3) if abs(cam.up[a]) > 0.5)
    shown = [b for b in bands if int(b[0]) in (across, up)]
    if not shown:
        raise InputError(f"bands: expected one along an axis the {view} view shows, got none")
    boxes = []
    for a, lo, hi, _, _ in shown:
        p0, p1 = frame[0].copy(), frame[0].copy()
        p0[int(a)], p1[int(a)] = lo, hi
        (u0, v0), (u1, v1) = pixel(p0), pixel(p1)
        if int(a) == across:
            boxes.append([min(u0, u1), y0, max(u0, u1), y1])
        else:
            boxes.append([x0, min(v0, v1), x1, max(v0, v1)])
    spots = _label_spots(
        draw, font, boxes, [b[3] for b in shown], [int(b[0]) == across for b in shown]
    )
    # the first band on top: drawn last; the labels over all bands (a fill would hide them)
    for rank, (_, _, _, _, colour) in reversed(list(enumerate(shown))):
        rgb = tuple(int(v) for v in colour)
        fill = (*rgb, round(255 * BAND_ALPHA)) if rank < FILLED_BANDS else None
        draw.rectangle(boxes[rank], fill=fill, outline=(*rgb, 255), width=2)
    for (_, _, _, label, colour), spot in zip(shown, spots, strict=True):
        if spot is not None:
            draw.text(spot, label, fill=(*(int(v) for v in colour), 255), font=font)
    ink = (0, 0, 0, 255)
    # axes with ticks in object units along the frame's bottom and left edges
    draw.line([x0, y1, x1, y1], fill=ink, width=1)
    draw.line([x0, y0, x0, y1], fill=ink, width=1)
    for a, horizontal in ((across, True), (up, False)):
        sign = 1.0 if (cam.right if horizontal else cam.up)[a] > 0 else -1.0
        for t in _ticks(frame[0, a], frame[1, a]):
            p = frame[0].copy()
            p[a] = t
            u, v = pixel(p)
            if horizontal:
                draw.line([u, y1, u, y1 + 5], fill=ink)
                draw.text((u, y1 + 6), f"{t:g}", fill=ink, font=font, anchor="ma")
            else:
                draw.line([x0 - 5, v, x0, v], fill=ink)
                draw.text((x0 - 7, v), f"{t:g}", fill=ink, font=font, anchor="rm")
        name = "xyz"[a]
        label = f"{name}{'' if sign > 0 else ' (-)'} [{units}]" if units else name
        if horizontal:
            draw.text((x1, y1 + 6 + size // 40), label, fill=ink, font=font, anchor="ra")
        else:
            draw.text((x0 + 4, y0 - 4), label, fill=ink, font=font, anchor="ld")
    # crop to what is drawn (the object lies in the frame) and a margin, the scale bar below
    drawn = over.getbbox() or (x0, y0, x1, y1)
    pad = round(BAND_MARGIN * size)
    left, top = max(0, round(min(drawn[0], x0)) - pad), max(0, round(min(drawn[1], y0)) - pad)
    right = min(im.width, round(max(drawn[2], x1)) + pad)
    bottom = min(im.height, round(max(drawn[3], y1)) + pad)
    out = np.asarray(Image.alpha_composite(im, over).convert("RGB"))[top:bottom, left:right]
    # the bar and its label within the picture's width, cropped to its rows too
    bar = min(0.25 * size, 0.8 * out.shape[1] - max(4, size // 25))
    strip = np.full((size // 4, out.shape[1], 3), 255, np.uint8)
    strip = _draw_scale_bar(strip, cam, csdf.meta.get("units", "m"), white, max_px=bar)
    rows = np.flatnonzero((strip != 255).any(axis=(1, 2)))
    strip = strip[max(0, rows[0] - pad // 2) : rows[-1] + 1 + pad]
    return np.concatenate([out, strip])
