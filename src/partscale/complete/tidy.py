"""The completed grid made fit to mesh: floating specks dropped, diagonal-only contacts filled.

Two rules on the sign of the completed SDF (solid where ``sdf < 0``), applied after the fusion:

- Specks: a solid component (6-connected) smaller than ``SPECK_SHARE`` of the largest one is
  scan noise (flying pixels, a few readings a thin closure turned solid) and becomes outside:
  free-floating, or a bump touching a part only along an edge or at a corner (26-connected
  pieces, which keep those bumps joined by the next rule, scored lower on the bench). Small
  components that touch one another along edges or at corners and together reach the share are
  a thin part lying across the grid's axes, a staircase of voxels (a railing's baluster about a
  voxel thick, seen from three views, fell into hundreds of such pieces), and stay; the next
  rule joins them. The share is of volumes, so it does not change with the resolution.
- Manifold voxels: two solid voxels that touch only along an edge (a 2x2 face whose solid voxels
  are diagonal) or only at a corner (a 2x2x2 cube whose solid, or whose outside, voxels are two
  opposite corners alone) leave marching cubes a choice it makes differently from each side: the
  mesh gets edges shared by four faces. One outside voxel of each such configuration is filled
  until none is left (the standard manifold-voxel fix), so the mesh is watertight.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

SPECK_SHARE = 0.007
"""A solid component under this share of the largest one's voxels is a speck (dropped). On the
four TUM scans at --res 128 the specks reach 0.0045 of the largest, the smallest parts kept
(a caster, a leg's end) 0.0104."""
CORNERS = np.ones((3, 3, 3), bool)
"""Connectivity of voxels touching by a face, along an edge or at a corner (26 neighbours)."""
FILL_VOXELS = 0.1
"""Voxels inside the surface a filled voxel's SDF is set to (the fusion's own nearest value)."""


def drop_specks(sdf: np.ndarray, h: float) -> tuple[np.ndarray, int]:
    """(X, Y, Z) float32 SDF without solid (6-connected) components under ``SPECK_SHARE`` of the
    largest (unless they are links of a thin part: small components touching along edges or at
    corners, together reaching the share), and how many were dropped. A dropped voxel takes
    its distance's magnitude (outside, as near the surface as it was inside).
    """
    lab, n = ndimage.label(sdf < 0)
    if n < 2:
        return sdf, 0
    size = np.bincount(lab.ravel())
    size[0] = 0
    small = size < SPECK_SHARE * size.max()
    small[0] = False
    if not small.any():
        return sdf, 0
    # small pieces touching one another along edges or at corners, together as large as a part
    # kept, are a thin part across the grid's axes (a staircase of voxels), not specks
    chains, _ = ndimage.label(small[lab], structure=CORNERS)
    chain_size = np.bincount(chains.ravel())
    chain_size[0] = 0
    thin_part = chain_size >= SPECK_SHARE * size.max()
    thin_part[0] = False
    small[np.unique(lab[thin_part[chains]])] = False
    if not small.any():
        return sdf, 0
    drop = small[lab]
    tiny = np.float32(1e-3 * h)
    out = np.where(drop, np.maximum(np.abs(sdf), tiny), sdf).astype(np.float32)
    return out, int(small.sum())


def _ambiguous(solid: np.ndarray) -> np.ndarray:
    """(..., X, Y, Z) bool: outside voxels to fill, one per diagonal-only contact of ``solid``
    (each entry of the leading axes a grid of its own: :func:`_ambiguous_near` passes patches).
    """
    fill = np.zeros(solid.shape, bool)
    S = solid
    lead = S.ndim - 3
    # faces: 2x2 squares in each axis-aligned plane with the solid on one diagonal only
    for a, b in ((0, 1), (0, 2), (1, 2)):

        def sl(da, db, a=a + lead, b=b + lead):
            s = [slice(None)] * S.ndim
            s[a] = slice(da, S.shape[a] - 1 + da)
            s[b] = slice(db, S.shape[b] - 1 + db)
            return tuple(s)

        s00, s11, s01, s10 = S[sl(0, 0)], S[sl(1, 1)], S[sl(0, 1)], S[sl(1, 0)]
        # solid on the main diagonal: fill the (0, 1) voxel; on the other: fill the (0, 0) one
        fill[sl(0, 1)] |= s00 & s11 & ~s01 & ~s10
        fill[sl(0, 0)] |= s01 & s10 & ~s00 & ~s11
    # corners: 2x2x2 cubes whose solid (or outside) voxels are two opposite corners alone
    n = tuple(d - 1 for d in S.shape[lead:])

    def c(i, j, k):
        return S[..., i : i + n[0], j : j + n[1], k : k + n[2]]

    corners = [(i, j, k) for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    cube = {q: c(*q) for q in corners}
    count = sum(v.astype(np.int8) for v in cube.values())
    for q in corners[:4]:
        o = (1 - q[0], 1 - q[1], 1 - q[2])
        pair = cube[q] & cube[o]
        # two solid opposite corners, nothing else: fill a neighbour of the first
        nb = (1 - q[0], q[1], q[2])
        hit = pair & (count == 2)
        fill[..., nb[0] : nb[0] + n[0], nb[1] : nb[1] + n[1], nb[2] : nb[2] + n[2]] |= hit
        # two outside opposite corners, the rest solid: fill the first
        hole = ~cube[q] & ~cube[o] & (count == 6)
        fill[..., q[0] : q[0] + n[0], q[1] : q[1] + n[1], q[2] : q[2] + n[2]] |= hole
    return fill & ~S


def _ambiguous_near(solid: np.ndarray, near: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    """Indices (a tuple of three (K,) int64, each voxel once) of :func:`_ambiguous`'s voxels
    whose face or cube holds a voxel of ``near`` (indices too); ``solid``: (X, Y, Z) bool, at
    least 3 voxels along each axis.

    Every face and cube holding a voxel lies in the 3x3x3 patch around it (moved inside the grid
    at its border: never a patch that reaches past it, whose faces and cubes the grid lacks).
    """
    shape = np.array(solid.shape)
    start = np.clip(np.stack(near, axis=1) - 1, 0, shape - 3)  # (K, 3)
    d = np.arange(3)
    patch = solid[
        start[:, 0, None, None, None] + d[:, None, None],
        start[:, 1, None, None, None] + d[None, :, None],
        start[:, 2, None, None, None] + d[None, None, :],
    ]  # (K, 3, 3, 3)
    m, i, j, k = np.nonzero(_ambiguous(patch))
    at = (start[m, 0] + i, start[m, 1] + j, start[m, 2] + k)
    # overlapping patches find a voxel more than once
    flat = np.unique(np.ravel_multi_index(at, solid.shape))
    return np.unravel_index(flat, solid.shape)


def fill_contacts(sdf: np.ndarray, h: float, max_rounds: int = 100) -> tuple[np.ndarray, int]:
    """(X, Y, Z) float32 SDF whose solid has no diagonal-only contacts, and how many voxels were
    filled (set to ``-FILL_VOXELS * h``).

    A fill can make new contacts next to it, so the fills repeat until none is left (at most
    ``max_rounds`` rounds). The first round looks at the whole grid; later ones only around the
    voxels the round before filled: each contact found had one of its own voxels filled, so a
    face or cube with none of them filled was no contact before and is none now.
    """
    out = sdf.astype(np.float32, copy=True)
    inside = np.float32(-FILL_VOXELS * h)
    solid = out < 0
    total = 0
    filled = None  # the whole grid first
    for _ in range(max_rounds):
        if filled is None or min(solid.shape) < 3:
            fill = np.nonzero(_ambiguous(solid))
        else:
            fill = _ambiguous_near(solid, filled)
        k = len(fill[0])
        if k == 0:
            break
        out[fill] = np.minimum(out[fill], inside)
        solid[fill] = out[fill] < 0
        total += k
        filled = fill
    return out, total
