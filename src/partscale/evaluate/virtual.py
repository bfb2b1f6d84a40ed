"""Virtual scans of complete objects: depth and colour frames as a Kinect-like sensor sees them.

The object (Y up, standing on a floor at its lowest point) is ray cast with trimesh (Embree when
installed) from cameras on a circle around it, looking at its centre from ``ELEVATION_DEG`` above.
The sensor model: depth noise growing with the square of the distance, depth rounded to 1 mm,
no reading at grazing angles, along depth discontinuities, and in random blotches.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy import ndimage

from ..complete import Frame
from ..ingest import ColoredMesh

ELEVATION_DEG = 25.0
AZIMUTHS_DEG = {1: (35.0,), 3: (35.0, 155.0, 275.0)}
"""Camera azimuths (degrees from +z, the front, towards +x) for one and three views."""
SIZE = (320, 240)
FOCAL = 280.0
FLOOR_RGB = (150, 150, 150)
MAX_RANGE = 4.5
"""Metres: farther than this the sensor gives no reading (a Kinect's range)."""
MAX_OBJECT_DEPTH = 4.2
"""Metres: how far a camera lets the object's far side be (inside the range, for the noise)."""
FRAME_MARGIN = 0.05
"""Fraction of the image's width and height kept clear of the object's bounding box each side."""


def _look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(4, 4) camera-to-world pose of an x-right, y-down, z-forward camera at ``eye``."""
    z = target - eye
    z /= np.linalg.norm(z)
    down = np.array([0.0, -1.0, 0.0])
    y = down - (down @ z) * z
    y /= np.linalg.norm(y)
    x = np.cross(y, z)
    T = np.eye(4)
    T[:3, :3] = np.stack([x, y, z], axis=1)
    T[:3, 3] = eye
    return T


def camera_poses(
    mesh: ColoredMesh,
    views: int,
    *,
    azimuths: Sequence[float] | None = None,
    elevation: float = ELEVATION_DEG,
    distance: float = 1.0,
) -> list[np.ndarray]:
    """Poses (4, 4) of ``views`` (1 or 3) cameras framing the object.

    ``azimuths`` (degrees, default ``AZIMUTHS_DEG[views]``) and ``elevation`` (degrees above
    the horizontal) place them; ``distance`` scales how far each stands from where it frames
    the object (above 1: farther, the object smaller in the image).

    A camera stands where the object's bounding sphere fills the narrower field of view, or
    closer where the object's far side would otherwise lie beyond ``MAX_OBJECT_DEPTH`` (a sofa:
    framed by its sphere, its far end would be 6 m away), but never so close that a corner of its
    bounding box leaves the image (``FRAME_MARGIN``).
    """
    V = np.asarray(mesh.vertices)[np.unique(mesh.faces)]
    lo, hi = V.min(axis=0), V.max(axis=0)
    centre = (lo + hi) / 2
    r = float(np.linalg.norm(hi - lo)) / 2
    vfov = 2 * np.arctan(SIZE[1] / 2 / FOCAL)
    dist = r / np.sin(vfov / 2) * 1.05
    corners = np.stack(np.meshgrid(*zip(lo, hi, strict=True), indexing="ij"), -1).reshape(-1, 3)
    half = (np.array(SIZE) / 2 - FRAME_MARGIN * np.array(SIZE)) / FOCAL

    def fits(t, d):
        T = _look_at(centre + t * d, centre)
        cam = (corners - T[:3, 3]) @ T[:3, :3]
        return bool((cam[:, 2] > 0).all() and (np.abs(cam[:, :2]) <= half * cam[:, 2:]).all())

    el = np.radians(elevation)
    poses = []
    for az in AZIMUTHS_DEG[views] if azimuths is None else azimuths:
        a = np.radians(az)
        d = np.array([np.cos(el) * np.sin(a), np.sin(el), np.cos(el) * np.cos(a)])
        # depth of a point p seen from centre + t d towards the centre: t - (p - centre) @ d
        in_range = MAX_OBJECT_DEPTH + float(((V - centre) @ d).min())
        t = dist
        if in_range < dist:
            near, far = r, dist  # bisection: the image fits at dist, not inside the sphere
            for _ in range(30):
                mid = (near + far) / 2
                near, far = (near, mid) if fits(mid, d) else (mid, far)
            t = max(in_range, far)
        poses.append(_look_at(centre + distance * t * d, centre))
    return poses


def virtual_scan(
    mesh: ColoredMesh,
    views: int = 1,
    *,
    noise: float = 1.0,
    holes: float = 1.0,
    floor: bool = True,
    seed: int = 0,
    azimuths: Sequence[float] | None = None,
    elevation: float = ELEVATION_DEG,
    distance: float = 1.0,
) -> list[Frame]:
    """Depth and colour frames of ``mesh`` from ``views`` (1 or 3) viewpoints.

    Parameters
    ----------
    mesh : ColoredMesh
        The complete object, Y up, metres (a mesh in other units must be scaled first: the
        sensor's noise and range and the completion's tolerances are metric).
    noise, holes : float
        Scale of the depth noise (sigma = noise * (0.5 mm + 1 mm * z^2), z in metres: 5 mm at 2 m) and of the
        blotch dropout (about 5 % of the pixels at 1).
    floor : bool
        Put a grey floor under the object (what a real scan of furniture has).
    seed : int
        Seed of the noise and holes.
    azimuths, elevation, distance
        Where the cameras stand (:func:`camera_poses`; ``azimuths`` given: one view each,
        ``views`` ignored).

    Returns
    -------
    list of Frame, poses in the mesh's frame (full sensor frames, not cropped).

    Raises
    ------
    ValueError
        When the framed object lies beyond the sensor's range (``MAX_RANGE``) from a camera,
        where the sensor would read nothing of it: an object so large is not in metres (a Sweet
        Home 3D chair 9 units tall, in decimetres).

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale.evaluate import virtual_scan
    >>> (frame,) = virtual_scan(ingest.load_mesh(data.table()), 1)
    >>> frame.shape, frame.cropped
    ((240, 320), False)
    """
    import trimesh

    if azimuths is None and views not in AZIMUTHS_DEG:
        raise ValueError(f"views: expected one of {sorted(AZIMUTHS_DEG)}, got {views}")
    rng = np.random.default_rng(seed)
    V = np.asarray(mesh.vertices, np.float64)
    F = np.asarray(mesh.faces, np.int64)
    used = V[np.unique(F)]
    lo, hi = used.min(axis=0), used.max(axis=0)
    n_obj = len(F)
    poses = camera_poses(mesh, views, azimuths=azimuths, elevation=elevation, distance=distance)
    nearest = max(float(((used - T[:3, 3]) @ T[:3, 2]).min()) for T in poses)
    if nearest >= MAX_RANGE:
        raise ValueError(
            f"virtual_scan: expected an object in metres, within the sensor's range of "
            f"{MAX_RANGE} m from cameras framing it, got one {float(np.linalg.norm(hi - lo)):.3g} "
            f"units across whose nearest point is {nearest:.3g} m away: scale the mesh to metres"
        )
    if floor:
        s = 4 * float(np.linalg.norm(hi - lo))
        c = (lo + hi) / 2
        fv = np.array(
            [
                [c[0] - s, lo[1], c[2] - s],
                [c[0] + s, lo[1], c[2] - s],
                [c[0] + s, lo[1], c[2] + s],
                [c[0] - s, lo[1], c[2] + s],
            ]
        )
        V = np.concatenate([V, fv])
        base = len(mesh.vertices)
        F = np.concatenate([F, [[base, base + 2, base + 1], [base, base + 3, base + 2]]])
    tm = trimesh.Trimesh(V, F, process=False)
    W, H = SIZE
    K = np.array([[FOCAL, 0, (W - 1) / 2], [0, FOCAL, (H - 1) / 2], [0, 0, 1]])
    u, v = np.meshgrid(np.arange(W), np.arange(H))
    d_cam = np.stack([(u - K[0, 2]) / FOCAL, (v - K[1, 2]) / FOCAL, np.ones_like(u, float)], -1)
    d_cam = d_cam.reshape(-1, 3)
    frames = []
    for pose in poses:
        R, t = pose[:3, :3], pose[:3, 3]
        dirs = d_cam @ R.T
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        origins = np.broadcast_to(t, dirs.shape)
        loc, ray, tri = tm.ray.intersects_location(origins, dirs, multiple_hits=False)
        depth: np.ndarray = np.zeros(W * H, np.float32)
        rgb = np.zeros((W * H, 3), np.uint8)
        z = (loc - t) @ R[:, 2]
        normals = tm.face_normals[tri]
        cos = np.abs(np.einsum("nd,nd->n", normals, dirs[ray]))
        sigma = noise * (0.0005 + 0.001 * z**2)
        zn = np.round((z + rng.normal(0, 1, len(z)) * sigma) * 1000) / 1000
        ok = (cos > np.cos(np.radians(80))) & (zn < MAX_RANGE)
        depth[ray[ok]] = zn[ok]
        obj = tri < n_obj
        col = np.empty((len(tri), 3), np.uint8)
        col[~obj] = FLOOR_RGB
        if obj.any():
            bary = trimesh.triangles.points_to_barycentric(V[F[tri[obj]]], loc[obj])
            col[obj] = mesh.color_at(
                tri[obj], np.clip(bary, 0, 1) / np.clip(bary, 0, 1).sum(1, keepdims=True)
            )
        col = np.clip(
            col.astype(np.int64) + rng.normal(0, 3, col.shape).round().astype(np.int64), 0, 255
        )
        rgb[ray] = col.astype(np.uint8)
        depth = depth.reshape(H, W)
        # no reading along depth discontinuities (mixed pixels) ...
        dz = np.maximum(
            np.abs(ndimage.maximum_filter(depth, 3) - depth),
            np.abs(depth - ndimage.minimum_filter(depth, 3)),
        )
        edge = (dz > 0.05 * np.maximum(depth, 1e-3)) & (rng.random(depth.shape) < 0.5)
        # ... and in blotches (IR speckle lost on dark or shiny spots)
        field = ndimage.gaussian_filter(rng.normal(0, 1, depth.shape), 4.0)
        blot = field > np.quantile(field, 1 - 0.05 * holes) if holes > 0 else np.zeros_like(edge)
        depth[edge | blot] = 0
        frames.append(Frame(depth, rgb.reshape(H, W, 3), K.copy(), pose, cropped=False))
    return frames
