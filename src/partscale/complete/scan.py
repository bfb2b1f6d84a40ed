"""What a scan says: depth frames with intrinsics and poses, read from RGB-D images or point clouds.

Conventions: a camera frame has x right, y down, z forward (metres, OpenCV/TUM); a pose is the
4x4 camera-to-world matrix, identity by default, so the world is the first camera's frame.
A depth of 0 means "no reading".

Two kinds of frame, told apart by :attr:`Frame.cropped`:

- a full sensor frame (an RGB-D image): pixels without a reading say nothing (unknown);
- a frame made from a cropped range mesh or point cloud (the object cut out of its scene): pixels
  outside the object's closed silhouette were seen through to the background, so the rays
  through them are free space at every depth (the visual-hull rule).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import _schema
from ..errors import InputError, one_line, shown

DEPTH_SCALE = 5000.0
#: Working bytes per pixel of a depth or colour frame, from its pixels to its points
#: (the decoded image, metres as float64 then float32, the colour, the masks, the points)
PIXEL_BYTES = 64
"""TUM/Kinect convention: a 16-bit depth PNG holds metres x 5000."""
MIN_DEPTH_SCALE, MAX_DEPTH_SCALE = 1e-3, 1e9
"""Depth units per metre a frame may use (1: metres; 1000: millimetres; beyond: not a depth)."""
MIN_FOCAL, MAX_FOCAL = 1.0, 1e7
"""Focal lengths in pixels a pinhole camera may have (below 1 pixel a frame spans ~180 degrees);
the bound of every intrinsics entry's magnitude too."""
MAX_COORDINATE = 1e6
"""Largest magnitude of a pose entry (metres): beyond it a scan is not an object's."""
MAX_PIXEL = 1_000_000
"""Largest magnitude of a pixel coordinate (a ``box``): beyond any sensor's image."""
MAX_VIEWS = 1000
"""Most views one ``--views`` file may list."""
DENOISE_JUMP = 0.03
"""Relative depth difference beyond which two neighbouring readings lie on different surfaces
(a depth discontinuity; well above the sensor's noise: 5 mm at 2 m is 0.25 %)."""
UPSAMPLE_READINGS = 2
"""Readings among a fine pixel's four nearest coarse pixels that :func:`upsample` blends (a
point cloud's frame leaves about half its pixels without a point)."""


@dataclass(frozen=True, eq=False)
class Frame:
    """One depth view: a depth image, its colours, intrinsics and camera pose.

    Made by :func:`read_frame` (an RGB-D image), :func:`frame_from_points` (a range mesh or point
    cloud) or :func:`read_views` (several registered views).

    Attributes
    ----------
    depth : (H, W) float32
        Metres along the optical axis, 0 where there is no reading.
    color : (H, W, 3) uint8 or None
        sRGB registered to ``depth``.
    K : (3, 3) float64
        Pinhole intrinsics (fx, fy, cx, cy).
    pose : (4, 4) float64
        Camera-to-world transform.
    cropped : bool
        Made from a cropped object scan: pixels outside its silhouette are free space.

    Examples
    --------
    A 2 x 2 image whose right column reads 2 m, seen by a camera at the origin:

    >>> import numpy as np
    >>> from partscale.complete import Frame
    >>> depth = np.array([[0, 2], [0, 2]], np.float32)
    >>> K = np.array([[100.0, 0, 1], [0, 100, 1], [0, 0, 1]])
    >>> frame = Frame(depth, None, K, np.eye(4))
    >>> frame.shape
    (2, 2)
    >>> points, colors, pixels = frame.points()
    >>> points
    array([[ 0.  , -0.02,  2.  ],
           [ 0.  ,  0.  ,  2.  ]])
    >>> colors.tolist(), pixels.tolist()
    ([[160, 160, 160], [160, 160, 160]], [1, 3])
    """

    depth: np.ndarray
    color: np.ndarray | None
    K: np.ndarray
    pose: np.ndarray
    cropped: bool = False

    @property
    def shape(self) -> tuple[int, int]:
        """The image's (H, W)."""
        return tuple(int(s) for s in self.depth.shape)  # type: ignore[return-value]

    def points(self, mask: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Back-projected readings: world points, their colours and pixels.

        Parameters
        ----------
        mask : (H, W) bool, optional
            Only the pixels it holds.

        Returns
        -------
        points : (N, 3) float64
            World points of the pixels with a reading (within ``mask`` when given).
        colors : (N, 3) uint8
            Their sRGB colours (grey where the frame has none).
        pixels : (N,) int64
            Their flat pixel indices, ``v * W + u``.
        """
        valid = self.depth > 0
        if mask is not None:
            valid &= mask
        v, u = np.nonzero(valid)
        z = self.depth[v, u].astype(np.float64)
        fx, fy, cx, cy = self.K[0, 0], self.K[1, 1], self.K[0, 2], self.K[1, 2]
        cam = np.stack([(u - cx) / fx * z, (v - cy) / fy * z, z], axis=1)
        world = cam @ self.pose[:3, :3].T + self.pose[:3, 3]
        rgb = self.color[v, u] if self.color is not None else np.full((len(z), 3), 160, np.uint8)
        return world, rgb, v * self.depth.shape[1] + u


def denoise(frame: Frame, sigma: float = 1.0) -> Frame:
    """The frame with its depth smoothed: a plane fitted (least squares, Gaussian weights of
    ``sigma`` pixels) to the valid pixels around each one on the same side of any depth
    discontinuity (within ``DENOISE_JUMP`` of its own depth), read at the pixel. No reading is
    pulled across an edge, and none along a slope towards the side its neighbours lie on (at an
    edge, a weighted mean of one side would be).
    """
    d = frame.depth.astype(np.float64)
    valid = d > 0
    r = int(np.ceil(4 * sigma))  # scipy's gaussian_filter reach
    H, W = d.shape
    pad_d = np.pad(d, r)
    tol = DENOISE_JUMP * np.maximum(d, 1e-3)
    # weighted moments of (1, dx, dy) and of the depth against them
    m = np.zeros((6, H, W))
    b = np.zeros((3, H, W))
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            g = np.exp(-(dx * dx + dy * dy) / (2 * sigma * sigma))
            nb = pad_d[r + dy : r + dy + H, r + dx : r + dx + W]
            # a neighbour across a jump (the floor behind a seat's edge) is another surface:
            # blending it would hang the edge's readings in the space between the two
            w = g * ((nb > 0) & (np.abs(nb - d) < tol))
            m += w * np.array([1.0, dx, dy, dx * dx, dx * dy, dy * dy])[:, None, None]
            b += w * nb * np.array([1.0, dx, dy])[:, None, None]
    A = np.stack(
        [np.stack([m[i] for i in row], -1) for row in ((0, 1, 2), (1, 3, 4), (2, 4, 5))], -2
    )
    mean = b[0] / np.maximum(m[0], 1e-12)
    det = np.linalg.det(A)
    # a plane needs neighbours spread both ways (not a one-pixel line): else the mean
    ok = valid & (det > 1e-3 * np.maximum(m[0], 1e-12) ** 3)
    fit = mean.copy()
    fit[ok] = np.linalg.solve(A[ok], np.moveaxis(b, 0, -1)[ok][..., None])[:, 0, 0]
    out = np.where(valid, fit, 0.0).astype(np.float32)
    return Frame(out, frame.color, frame.K, frame.pose, frame.cropped)


def upsample(frame: Frame, k: int) -> Frame:
    """The frame at ``k`` times its pixels along each side: the same rays, read between them.

    A pixel's depth is the bilinear blend of the readings among its four nearest pixels where at
    least ``UPSAMPLE_READINGS`` of them read the same surface (within ``DENOISE_JUMP`` of each
    other); elsewhere each reading stays at the middle of its own pixel, once, and the rest read
    nothing: no depth is made across an edge, and none inside a hole wider than a pixel.
    Colours are the nearest pixel's. The intrinsics follow the finer pixels (``fx, fy`` times ``k``, pixel centres kept).

    Parameters
    ----------
    frame : Frame
    k : int
        Pixels along each side per pixel of ``frame`` (>= 1).

    Returns
    -------
    Frame
        (H * k, W * k) depth and colour.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.complete.scan import Frame, upsample
    >>> K = np.array([[100.0, 0, 0.5], [0, 100, 0.5], [0, 0, 1]])
    >>> depth = np.array([[1.0, 1.01], [1.0, 1.01]], np.float32)
    >>> f = upsample(Frame(depth, None, K, np.eye(4)), 2)
    >>> f.shape, [round(float(x), 4) for x in f.depth[0]]
    ((4, 4), [1.0, 1.0025, 1.0075, 1.01])
    """
    if k <= 1:
        return frame
    d = frame.depth.astype(np.float64)
    H, W = d.shape
    # the source position of each fine pixel's centre, and its four neighbours
    ys = np.clip((np.arange(H * k) + 0.5) / k - 0.5, 0, H - 1)
    xs = np.clip((np.arange(W * k) + 0.5) / k - 0.5, 0, W - 1)
    y0 = np.minimum(ys.astype(np.int64), max(H - 2, 0))
    x0 = np.minimum(xs.astype(np.int64), max(W - 2, 0))
    y1, x1 = np.minimum(y0 + 1, H - 1), np.minimum(x0 + 1, W - 1)
    ty, tx = (ys - y0)[:, None], (xs - x0)[None, :]
    corners = [d[np.ix_(y0, x0)], d[np.ix_(y0, x1)], d[np.ix_(y1, x0)], d[np.ix_(y1, x1)]]
    weights = [(1 - ty) * (1 - tx), (1 - ty) * tx, ty * (1 - tx), ty * tx]
    # the blend of the readings among the four (a hole of the sensor, or a point cloud's
    # pixel nobody's point fell in, is left out and the rest weighed up)
    lo = np.full((H * k, W * k), np.inf)
    hi = np.zeros((H * k, W * k))
    n = np.zeros((H * k, W * k), np.int64)
    num = np.zeros((H * k, W * k))
    den = np.zeros((H * k, W * k))
    for c, w in zip(corners, weights, strict=True):
        v = c > 0
        lo = np.where(v, np.minimum(lo, c), lo)
        hi = np.where(v, np.maximum(hi, c), hi)
        n += v
        num += np.where(v, w * c, 0.0)
        den += np.where(v, w, 0.0)
    blend = num / np.maximum(den, 1e-12)
    same = (n >= UPSAMPLE_READINGS) & (hi - lo < DENOISE_JUMP * lo)
    yn = np.minimum((np.arange(H * k) // k), H - 1)
    xn = np.minimum((np.arange(W * k) // k), W - 1)
    # elsewhere each reading once, at its own pixel's middle: copied over the whole pixel it
    # would make a flat tile (a staircase on a slope, and tiles' normals facing the camera)
    middle = ((np.arange(H * k) % k) == k // 2)[:, None] & ((np.arange(W * k) % k) == k // 2)[None]
    nearest = np.where(middle, d[np.ix_(yn, xn)], 0.0)
    depth = np.where(same, blend, nearest).astype(np.float32)
    color = None if frame.color is None else frame.color[np.ix_(yn, xn)]
    K = np.array(frame.K, np.float64)
    K[0, 0] *= k
    K[1, 1] *= k
    K[0, 2] = (K[0, 2] + 0.5) * k - 0.5
    K[1, 2] = (K[1, 2] + 0.5) * k - 0.5
    return Frame(depth, color, K, frame.pose, frame.cropped)


def check_pose(pose, what: str) -> np.ndarray:
    """(4, 4) float64 rigid camera-to-world transform (nested or 16 numbers, row major);
    rotation checked orthonormal.
    """
    a = _schema.matrix(pose, what, (4, 4), lo=-MAX_COORDINATE, hi=MAX_COORDINATE)
    R = a[:3, :3]
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-3) or np.linalg.det(R) < 0:
        raise InputError(
            f"{what}: expected a rigid transform (rotation + translation), got {a[:3, :3].round(3).tolist()}"
        )
    return a


def check_intrinsics(K, what: str) -> np.ndarray:
    """(3, 3) float64 pinhole intrinsics from a 3x3 matrix (nested or 9 numbers, row major):
    focal lengths in [:data:`MIN_FOCAL`, :data:`MAX_FOCAL`] pixels, the rest finite and bounded.
    """
    m = _schema.matrix(K, what, (3, 3), lo=-MAX_FOCAL, hi=MAX_FOCAL)
    for name, v in (("fx", m[0, 0]), ("fy", m[1, 1])):
        _schema.number(v, f"{what}: {name}", lo=MIN_FOCAL, hi=MAX_FOCAL)
    return m


def read_intrinsics(path: str | os.PathLike) -> np.ndarray:
    """(3, 3) float64 pinhole intrinsics read from a JSON file.

    Parameters
    ----------
    path : str or os.PathLike
        A JSON file holding Open3D's ``intrinsic_matrix`` (9 numbers, column major) or
        ``{"fx", "fy", "cx", "cy"}`` (pixels).

    Returns
    -------
    (3, 3) float64
        ``[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]``.

    Raises
    ------
    InputError
        No such file, not JSON, neither form, or focal lengths that are not positive.

    Examples
    --------
    >>> import json
    >>> from partscale.complete import read_intrinsics
    >>> with open("K.json", "w") as f:
    ...     json.dump({"fx": 280, "fy": 280, "cx": 160, "cy": 120}, f)
    >>> read_intrinsics("K.json")
    array([[280.,   0., 160.],
           [  0., 280., 120.],
           [  0.,   0.,   1.]])
    """
    from .._files import read_json

    path = Path(path)
    data = read_json(path, what="an intrinsics JSON file")
    if isinstance(data, dict) and "intrinsic_matrix" in data:
        m = _schema.matrix(data["intrinsic_matrix"], f"{path}: intrinsic_matrix", (3, 3))
        K = m.T  # Open3D writes column major
    elif isinstance(data, dict) and all(k in data for k in ("fx", "fy", "cx", "cy")):
        fx, fy, cx, cy = (
            _schema.number(data[k], f"{path}: {k}", lo=-MAX_FOCAL, hi=MAX_FOCAL)
            for k in ("fx", "fy", "cx", "cy")
        )
        K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1]], np.float64)
    else:
        raise InputError(
            f"{path}: expected intrinsic_matrix or fx, fy, cx, cy, got keys "
            f"{shown(sorted(data)) if isinstance(data, dict) else type(data).__name__}"
        )
    return check_intrinsics(K, str(path))


def _read_image(path: Path, what: str) -> np.ndarray:
    """The pixels of an image file, refused by its size (from its header) before decoding
    where :data:`PIXEL_BYTES` per pixel would not fit in memory.
    """
    from PIL import Image

    from .._memory import check_bytes

    if not path.is_file():
        raise InputError(f"{path}: expected a {what} image, got no such file")
    try:
        with Image.open(path) as im:
            w, h = im.size
            check_bytes(float(w) * h * PIXEL_BYTES, what=f"{path}: a {w}x{h} {what} image")
            return np.asarray(im)
    except InputError:
        raise
    except Exception as exc:  # PIL raises many kinds on damaged files
        raise InputError(f"{path}: expected a {what} image, got {one_line(exc)}") from None


def read_frame(
    depth: str | os.PathLike,
    color: str | os.PathLike | None = None,
    intrinsics: str | os.PathLike | np.ndarray | None = None,
    *,
    depth_scale: float = DEPTH_SCALE,
    pose=None,
) -> Frame:
    """An RGB-D frame from a 16-bit depth PNG, an optional colour image and the intrinsics.

    Parameters
    ----------
    depth : str or os.PathLike
        A single-channel depth image (a 16-bit PNG): value / ``depth_scale`` = metres, 0 = no
        reading.
    color : str or os.PathLike, optional
        An sRGB image of the same size, registered to the depth.
    intrinsics : str, os.PathLike or (3, 3) ndarray
        A JSON file (:func:`read_intrinsics`) or the matrix; required.
    depth_scale : float
        Depth image units per metre (5000: TUM, Kinect; 1000: millimetres).
    pose : (4, 4) array_like, optional
        The camera-to-world transform (default: identity, the world is this camera's frame).

    Returns
    -------
    Frame
        A full sensor frame (not :attr:`Frame.cropped`): pixels without a reading say nothing.

    Raises
    ------
    InputError
        No intrinsics, a missing or unreadable image, colours of another size, a bad pose.

    Examples
    --------
    A frame of the shipped table from a virtual sensor, written as PNGs and read back:

    >>> import json
    >>> import numpy as np
    >>> from PIL import Image
    >>> from partscale import data, ingest
    >>> from partscale.complete import DEPTH_SCALE, read_frame
    >>> from partscale.evaluate import virtual_scan
    >>> (seen,) = virtual_scan(ingest.load_mesh(data.table()), 1)
    >>> depth = np.rint(seen.depth * DEPTH_SCALE).astype(np.uint16)
    >>> Image.fromarray(depth).save("depth.png")
    >>> Image.fromarray(seen.color).save("color.png")
    >>> frame = read_frame("depth.png", "color.png", seen.K)
    >>> frame.shape, frame.depth.dtype, frame.cropped
    ((240, 320), dtype('float32'), False)
    >>> bool(np.abs(frame.depth - seen.depth).max() < 1e-3)
    True
    """
    depth = Path(depth)
    if intrinsics is None:
        raise InputError(
            f"{depth}: expected camera intrinsics (intrinsics, a K.json) with a depth image, got "
            "none",
            params=("intrinsics",),
        )
    K = (
        check_intrinsics(intrinsics, "intrinsics")
        if isinstance(intrinsics, np.ndarray)
        else read_intrinsics(intrinsics)
    )
    d = _read_image(depth, "depth")
    if d.ndim != 2 or d.dtype.kind not in "iuf":
        raise InputError(f"{depth}: expected a single-channel depth image, got shape {d.shape}")
    depth_scale = _schema.number(depth_scale, "depth_scale", lo=MIN_DEPTH_SCALE, hi=MAX_DEPTH_SCALE)
    z = (d.astype(np.float64) / depth_scale).astype(np.float32)
    z[~np.isfinite(z) | (z < 0)] = 0
    rgb = None
    if color is not None:
        color = Path(color)
        rgb = _read_image(color, "colour")
        if rgb.ndim == 2:
            rgb = np.repeat(rgb[..., None], 3, axis=2)
        rgb = np.ascontiguousarray(rgb[..., :3]).astype(np.uint8)
        if rgb.shape[:2] != z.shape:
            raise InputError(
                f"{color}: expected a colour image the size of the depth image "
                f"{z.shape[1]}x{z.shape[0]}, got {rgb.shape[1]}x{rgb.shape[0]}"
            )
    pose = np.eye(4) if pose is None else check_pose(pose, f"{depth}: pose")
    return Frame(z, rgb, K, pose, cropped=False)


def read_points(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (N, 3) float64 and their sRGB colours (N, 3) uint8 of a range mesh or point cloud.

    Parameters
    ----------
    path : str or os.PathLike
        A PLY, OBJ or other file trimesh reads (a point cloud or a mesh, whose vertices are
        the points).

    Returns
    -------
    points : (N, 3) float64
        The finite vertices, in the file's frame.
    colors : (N, 3) uint8
        Their sRGB colours; grey (160) where the file has none.

    Raises
    ------
    InputError
        No such file, one trimesh cannot read, or no points.

    Examples
    --------
    >>> import numpy as np
    >>> import trimesh
    >>> from partscale.complete import read_points
    >>> _ = trimesh.PointCloud(np.eye(3)).export("cloud.ply")
    >>> points, colors = read_points("cloud.ply")
    >>> points.shape, colors[0].tolist()
    ((3, 3), [160, 160, 160])
    """
    import trimesh

    path = Path(path)
    if not path.is_file():
        raise InputError(
            f"{path}: expected a scan (PLY point cloud or range mesh), got no such file"
        )
    try:
        geom: trimesh.parent.Geometry | None = trimesh.load(str(path), process=False)
    except Exception as exc:
        raise InputError(
            f"{path}: expected a PLY point cloud or mesh, got {one_line(exc)}"
        ) from None
    if isinstance(geom, trimesh.Scene):
        geoms = list(geom.dump()) if geom.geometry else []
        geom = trimesh.util.concatenate(geoms) if geoms else None
    verts = np.asarray(getattr(geom, "vertices", np.zeros((0, 3))), dtype=np.float64)
    if len(verts) == 0:
        raise InputError(f"{path}: expected scan points, got none")
    if not np.isfinite(verts).all():
        verts = verts[np.isfinite(verts).all(axis=1)]
    cols = None
    vis = getattr(geom, "visual", None)
    if vis is not None:
        try:
            vc = np.asarray(vis.vertex_colors)
            if vc.shape[0] == len(verts) and getattr(vis, "kind", None) == "vertex":
                cols = vc[:, :3].astype(np.uint8)
        except Exception:  # a visual without per-vertex colours
            cols = None
    if cols is None:
        c = getattr(geom, "colors", None)
        if c is not None and len(c) == len(verts):
            cols = np.asarray(c)[:, :3].astype(np.uint8)
    if cols is None:
        cols = np.full((len(verts), 3), 160, np.uint8)
    return verts, cols


def frame_from_points(points, colors, pose=None) -> Frame:
    """A depth frame that sees ``points`` (world, (N, 3)) as the camera at ``pose`` did.

    The focal length is chosen so that neighbouring scan points fall on neighbouring pixels
    (from the median spacing of the points against their depth), the image just covers them, and
    each pixel keeps its nearest point (a z-buffer). The result is :attr:`Frame.cropped`.

    Parameters
    ----------
    points : (N, 3) array_like of float
        World points of the object alone (a cropped scan), metres.
    colors : (N, 3) uint8
        Their sRGB colours.
    pose : (4, 4) array_like, optional
        The camera-to-world transform of the camera that saw them (default: identity).

    Returns
    -------
    Frame
        A cropped frame: pixels outside the points' silhouette are free space.

    Raises
    ------
    InputError
        Fewer than 3 points in front of the camera, a bad pose, or an image over 4096^2 pixels.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale.complete import frame_from_points
    >>> from partscale.evaluate import virtual_scan
    >>> (seen,) = virtual_scan(ingest.load_mesh(data.table()), 1, floor=False)
    >>> points, colors, _ = seen.points()
    >>> frame = frame_from_points(points, colors, seen.pose)
    >>> frame.cropped, frame.depth.dtype, bool((frame.depth > 0).sum() > 1000)
    (True, dtype('float32'), True)
    """
    from scipy.spatial import cKDTree

    pose = np.eye(4) if pose is None else check_pose(pose, "camera")
    P = np.asarray(points, np.float64)
    cam = (P - pose[:3, 3]) @ pose[:3, :3]
    front = cam[:, 2] > 1e-6
    if front.sum() < 3:
        raise InputError(
            f"scan: expected points in front of the camera (z > 0 in its frame), got {int(front.sum())}"
        )
    cam, cols = cam[front], np.asarray(colors)[front]
    sub = cam[:: max(1, len(cam) // 5000)]
    dist, _ = cKDTree(sub).query(sub, k=2)
    spacing = dist[:, 1] * max(1.0, np.sqrt(len(cam) / max(len(sub), 1)))
    # points per pixel ~1: focal = depth / lateral spacing between neighbouring samples
    ratio = sub[:, 2] / np.maximum(spacing, 1e-9)
    f = float(np.clip(np.median(ratio), 50.0, 5000.0))
    u = cam[:, 0] / cam[:, 2] * f
    v = cam[:, 1] / cam[:, 2] * f
    margin = 8
    u0, v0 = np.floor(u.min()) - margin, np.floor(v.min()) - margin
    W = int(np.ceil(u.max() - u0)) + margin + 1
    H = int(np.ceil(v.max() - v0)) + margin + 1
    if W * H > 4096 * 4096:
        raise InputError(f"scan: expected a range image of at most 4096^2 pixels, got {W}x{H}")
    K = np.array([[f, 0, -u0], [0, f, -v0], [0, 0, 1]], np.float64)
    iu = np.rint(u - u0).astype(np.int64)
    iv = np.rint(v - v0).astype(np.int64)
    flat = iv * W + iu
    order = np.lexsort((cam[:, 2], flat))  # nearest point first in every pixel
    first = np.r_[True, flat[order][1:] != flat[order][:-1]]
    keep = order[first]
    depth = np.zeros(H * W, np.float32)
    rgb = np.zeros((H * W, 3), np.uint8)
    depth[flat[keep]] = cam[keep, 2]
    rgb[flat[keep]] = cols[keep]
    return Frame(depth.reshape(H, W), rgb.reshape(H, W, 3), K, pose, cropped=True)


VIEW_KEYS = ("depth", "color", "intrinsics", "pose", "depth_scale", "points")
"""Keys of a view in a ``--views`` file (others, such as a name, are ignored)."""


def read_views(path: str | os.PathLike) -> list[Frame]:
    """Registered views from a JSON list of RGB-D frames and point clouds.

    Parameters
    ----------
    path : str or os.PathLike
        A JSON file: a list (or ``{"views": [...]}``) of ``{"depth", "color", "intrinsics",
        "pose", "depth_scale"}`` per RGB-D frame or ``{"points", "pose"}`` per scan (points in
        the camera's frame), paths relative to the file; ``pose`` is a 4x4 camera-to-world
        matrix (default identity).

    Returns
    -------
    list of Frame
        One per view: :func:`read_frame` for a depth image, :func:`frame_from_points` for a
        scan.

    Raises
    ------
    InputError
        A list that is empty or not one, a view with neither ``depth`` nor ``points``, or a
        file a view names that cannot be read.

    Examples
    --------
    >>> import json
    >>> import numpy as np
    >>> import trimesh
    >>> from partscale.complete import read_views
    >>> _ = trimesh.PointCloud(np.random.default_rng(0).random((100, 3)) + (0, 0, 2)).export(
    ...     "near.ply"
    ... )
    >>> turn = [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 4], [0, 0, 0, 1]]
    >>> with open("views.json", "w") as f:
    ...     json.dump([{"points": "near.ply"}, {"points": "near.ply", "pose": turn}], f)
    >>> [frame.cropped for frame in read_views("views.json")]
    [True, True]
    """
    path = Path(path)
    from .._files import read_json

    data = read_json(path, what="a list of views")
    views = data.get("views") if isinstance(data, dict) else data
    if not isinstance(views, list) or not views:
        raise InputError(f"{path}: expected a non-empty list of views, got {type(views).__name__}")
    _schema.sequence(views, f"{path}: views", hi=MAX_VIEWS)
    frames = []
    for i, v in enumerate(views):
        where = f"{path}: view {i}"
        v = _schema.mapping(v, where)
        pose = check_pose(v.get("pose", np.eye(4)), f"{where}.pose")
        if "points" in v:
            P, C = read_points(_schema.path(v["points"], f"{where}.points", base=path.parent))
            # points are stored in their camera's frame, like a single scan
            world = P @ pose[:3, :3].T + pose[:3, 3]
            frames.append(frame_from_points(world, C, pose))
        elif "depth" in v:
            if v.get("intrinsics") is None:
                raise InputError(f"{where}: expected intrinsics with the depth image, got none")
            K = v["intrinsics"]
            K = (
                _schema.path(K, f"{where}.intrinsics", base=path.parent)
                if isinstance(K, str)
                else check_intrinsics(K, f"{where}.intrinsics")
            )
            color = v.get("color")
            frames.append(
                read_frame(
                    _schema.path(v["depth"], f"{where}.depth", base=path.parent),
                    None
                    if color is None
                    else _schema.path(color, f"{where}.color", base=path.parent),
                    K,
                    depth_scale=_schema.number(
                        v.get("depth_scale", DEPTH_SCALE),
                        f"{where}.depth_scale",
                        lo=MIN_DEPTH_SCALE,
                        hi=MAX_DEPTH_SCALE,
                    ),
                    pose=pose,
                )
            )
        else:
            raise InputError(f"{where}: expected 'depth' or 'points', got keys {shown(sorted(v))}")
    return frames
