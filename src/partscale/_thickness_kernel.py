"""Numba kernel of :func:`partscale.thickness.thin_features`: one sweep over the grid (kept
apart so that reading :mod:`partscale.thickness`, as every command's start-up does, does not
load numba).
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True, parallel=True, nogil=True)
def thin_pass(s, h, limit, thickness, counts):
    """One sweep over ``s`` (X, Y, Z) float32, slabs of x in parallel: ``thickness`` (X, Y, Z)
    float32 gets each thin voxel's thickness in voxels (inf elsewhere) and ``counts`` (X, 5)
    int64 per slab: thin solid, thin gap, of those below one voxel (solid, gap), and surface
    voxels (a face neighbour across the zero level).

    A voxel's thickness is the least over the axes of its run's: a run of one same-side voxel
    between two of the other side spans ``max(2 - |sdf| before - |sdf| after, 2 |sdf|)``, of
    two ``max(3 - |sdf| before - |sdf| after, 1)`` (``|sdf|`` in voxels; a run reaching the
    border, or longer, is not thin). It is thin below ``limit``, unless it lies on the surface
    (``|sdf| <= 0.01`` voxel) or a voxel of its 3 x 3 x 3 neighbourhood on its side lies at
    least ``limit / 2`` deep (the rim of a thick body).
    """
    # Complexity 49 (radon), kept in one kernel: the sweep's work is per surface voxel, and
    # its runs along each axis, the rim test and the counts read the same neighbourhood while
    # it is in cache; helpers that numba inlines would only move the branches elsewhere, and
    # helpers it calls would pay a call per voxel of the grid's hottest loop.
    nx, ny, nz = s.shape
    dims = (nx, ny, nz)
    on_surface = np.float32(0.01) * h
    deep = np.float32(limit / 2) * h
    one, two, three = np.float32(1.0), np.float32(2.0), np.float32(3.0)
    inf = np.float32(np.inf)
    lim = np.float32(limit)
    for ip in nb.prange(nx):
        i = np.int64(ip)  # signed: neighbours at i - 1 (a prange index may be unsigned)
        for j in range(ny):
            for k in range(nz):
                v = s[i, j, k]
                inside = v <= 0
                # surface voxels: a face neighbour on the other side. Every run of one or two
                # ends at one, so the rest (most of the grid) stop here
                surf = (
                    (i > 0 and (s[i - 1, j, k] <= 0) != inside)
                    or (i < nx - 1 and (s[i + 1, j, k] <= 0) != inside)
                    or (j > 0 and (s[i, j - 1, k] <= 0) != inside)
                    or (j < ny - 1 and (s[i, j + 1, k] <= 0) != inside)
                    or (k > 0 and (s[i, j, k - 1] <= 0) != inside)
                    or (k < nz - 1 and (s[i, j, k + 1] <= 0) != inside)
                )
                if not surf:
                    continue
                counts[i, 4] += 1
                if not abs(v) > on_surface:
                    continue
                t = inf
                x = (i, j, k)
                for ax in range(3):
                    n = dims[ax]
                    pos = x[ax]
                    # runs of one or two holding this voxel: [lo, hi] with lo - 1 and hi + 1
                    # on the other side, both inside the grid
                    for run in range(3):
                        # run 0: [pos, pos]; run 1: [pos - 1, pos]; run 2: [pos, pos + 1]
                        lo = pos - 1 if run == 1 else pos
                        hi = pos + 1 if run == 2 else pos
                        if lo - 1 < 0 or hi + 1 > n - 1:
                            continue
                        ok = True
                        for q in range(lo, hi + 1):
                            if q == pos:
                                continue
                            if ax == 0:
                                w = s[q, j, k]
                            elif ax == 1:
                                w = s[i, q, k]
                            else:
                                w = s[i, j, q]
                            if (w <= 0) != inside:
                                ok = False
                        if not ok:
                            continue
                        if ax == 0:
                            before, after = s[lo - 1, j, k], s[hi + 1, j, k]
                        elif ax == 1:
                            before, after = s[i, lo - 1, k], s[i, hi + 1, k]
                        else:
                            before, after = s[i, j, lo - 1], s[i, j, hi + 1]
                        if ((before <= 0) == inside) or ((after <= 0) == inside):
                            continue
                        ab = np.float32(abs(before)) / h
                        aa = np.float32(abs(after)) / h
                        if run == 0:
                            r = max(two - ab - aa, two * (np.float32(abs(v)) / h))
                        else:
                            r = max(three - ab - aa, one)
                        if r < t:
                            t = r
                if not t < lim:
                    continue
                rim = False
                for ra in range(i - 1 if i > 0 else 0, i + 2 if i + 2 < nx else nx):
                    for rb in range(max(j - 1, 0), min(j + 2, ny)):
                        for rc in range(max(k - 1, 0), min(k + 2, nz)):
                            w = s[ra, rb, rc]
                            if inside:
                                if w <= 0 and -w >= deep:
                                    rim = True
                            elif w > 0 and w >= deep:
                                rim = True
                if rim:
                    continue
                thickness[i, j, k] = t
                side = 0 if inside else 1
                counts[i, side] += 1
                if t < one:
                    counts[i, 2 + side] += 1
