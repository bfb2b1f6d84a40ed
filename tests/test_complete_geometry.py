"""partscale.complete: mirror planes of a one-sided scan, and the solid between opposite surfaces."""

from __future__ import annotations

import numpy as np


def _box_faces(lo, hi, faces, n_per_face, rng):
    """Points (N, 3) and outward normals on the given faces ('+x', '+y', '+z') of a box."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    P, N = [], []
    for f in faces:
        a = "xyz".index(f[1])
        u = rng.uniform(lo, hi, (n_per_face, 3))
        u[:, a] = hi[a] if f[0] == "+" else lo[a]
        n = np.zeros(3)
        n[a] = 1.0 if f[0] == "+" else -1.0
        P.append(u)
        N.append(np.broadcast_to(n, u.shape))
    return np.concatenate(P), np.concatenate(N)


def test_mirror_plane_of_a_one_sided_scan_maps_points_within_a_quarter_cell():
    # a table seen from the front right (+x, +y, +z faces): four legs and a top, symmetric
    # about the vertical plane x = c; the right side of each leg has no counterpart in the scan
    from partscale.complete import symmetry

    rng = np.random.default_rng(0)
    c, cell = 0.0137, 0.012
    parts = []
    for x0 in (-0.30, 0.22):
        for z0 in (-0.15, 0.07):
            parts.append(
                _box_faces([x0, 0, z0], [x0 + 0.08, 0.5, z0 + 0.08], ["+x", "+z"], 300, rng)
            )
    parts.append(_box_faces([-0.30, 0.5, -0.15], [0.30, 0.56, 0.15], ["+y", "+z", "+x"], 2500, rng))
    P = np.concatenate([p for p, _ in parts])
    N = np.concatenate([n for _, n in parts])
    P[:, 0] += c
    colors = np.full((len(P), 3), 128, np.uint8)
    none_free = lambda p: np.zeros(len(p), bool)  # noqa: E731
    planes = symmetry.mirror_planes(P, colors, none_free, cell, max_planes=1, normals=N)
    assert planes, "expected the left-right plane"
    true = P * [-1, 1, 1] + [2 * c, 0, 0]
    # every mirrored point within a quarter of a cell of where the true plane puts it
    assert np.abs(planes[0].apply(P) - true).max() <= 0.25 * cell


def test_a_block_seen_on_its_sides_completes_solid_down_to_its_unseen_bottom():
    # a chest-like block scanned from three views above: its top and sides are seen, its
    # bottom never; the solid between opposite sides fills it, not a hollow shell open below
    import trimesh

    from partscale.complete import api, virtual
    from partscale.ingest import from_trimesh

    box = trimesh.creation.box([0.6, 0.3, 0.4])
    box.apply_translation([0, 0.15, 0])
    c = api.complete(virtual.virtual_scan(from_trimesh(box), 3), res=48)
    inside = np.asarray(c.sdf) < 0
    volume = inside.sum() * c.voxel_size**3
    assert volume >= 0.85 * (0.6 * 0.3 * 0.4)
    assert volume <= 1.15 * (0.6 * 0.3 * 0.4)
