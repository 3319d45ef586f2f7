"""Roots of Liepa's dynamic programs: where the recursion starts, and the best of several.

The programs of :mod:`meshrepair.holes.liepa` triangulate the sub-polygons ``i, ..., j`` of a
loop numbered ``0, ..., k-1`` and return the triangulation of ``[0, k-1]``: the recursion is
rooted at the loop edge from the last vertex to the first. The weight is lexicographic (largest
bend ``1 - cos`` of a dihedral angle, then total area), and a (largest, then sum) weight has no
optimal substructure: a sub-polygon's best triangulation by its own weight need not be part of
the whole loop's best, so the result depends on the root. Rooted wherever the mesh's numbering
starts the loop, the triangulation changed with the vertex order of the mesh.

Here the programs run from ``R`` roots spread evenly along the loop from a start read off the
geometry (the loop vertex farthest from the loop's centroid, :func:`canonical_start`), and the
triangulation of least weight among them is kept (ties: the first root). Each run is exact for
its root, so more roots can only lower the weight found; the roots depend on the loop's
geometry alone, so the result is the same for every numbering, rotation, scale and translation.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

ROOTS = 8
"""Roots each program runs from (fewer on loops of fewer vertices)."""

FULL_WORK = 8 * 200 ** 3
"""Work bound of the unrestricted O(k³) program over all its roots, in units of k³: 8 roots up
to k = 200 vertices (about 10 ms each), 1 from k = 400 (0.1-2 s each up to the largest loop)."""


def canonical_start(P: np.ndarray) -> int:
    """The loop vertex farthest from the loop's centroid (the centroid summed over sorted
    coordinates: the same bits whatever the loop's first vertex)."""
    c = np.sort(P, axis=0).sum(axis=0) / len(P)
    return int(np.argmax(((P - c) ** 2).sum(axis=1)))


def program_roots(P: np.ndarray, *, full: bool) -> list[int]:
    """The roots of a program on the loop ``P`` (k, 3): :data:`ROOTS` of them (the unrestricted
    program: as many as :data:`FULL_WORK` allows) spread evenly from :func:`canonical_start`."""
    k = len(P)
    r = ROOTS if not full else int(max(1, min(ROOTS, FULL_WORK // max(k, 1) ** 3)))
    r = min(r, k)
    s = canonical_start(P)
    return [(s + (j * k) // r) % k for j in range(r)]


def triangles(opt: np.ndarray, k: int) -> np.ndarray:
    """The triangles ``(i, j, m)`` of the best apices ``opt`` of the whole loop ``[0, k-1]``."""
    T = []
    stack = [(0, k - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        m = int(opt[i, j])
        T.append((i, j, m))
        stack += [(i, m), (m, j)]
    return np.asarray(T, dtype=np.int64).reshape(-1, 3)


def _forbid_matrix(fb: np.ndarray, s: int, k: int) -> np.ndarray:
    """``(k, k)`` flags of the forbidden chords ``fb`` (local indices) for the loop rolled to
    start at ``s`` (``forbid[i, j]``, ``i < j``); loop edges are never chords."""
    forbid = np.zeros((k, k), bool)
    if len(fb):
        f = (fb - s) % k
        lo, hi = f.min(axis=1), f.max(axis=1)
        chord = (hi - lo >= 2) & ~((lo == 0) & (hi == k - 1))
        forbid[lo[chord], hi[chord]] = True
    return forbid


def _unrolled(T: np.ndarray, s: int, k: int) -> np.ndarray:
    """Triangles ``(i, j, m)`` of the loop rolled to start at ``s``, in the caller's local
    indices: each listed again from its least index, which keeps ``i < m < j`` (a cyclic shift
    keeps the cyclic order of three loop vertices, so the orientation), rows sorted."""
    T = (T + s) % k
    first = np.argmin(T, axis=1)[:, None]
    T = np.take_along_axis(T, (first + np.arange(3)) % 3, axis=1)
    return T[np.lexsort(T.T[::-1])] if len(T) else T


def best_over_roots(run: Callable, P: np.ndarray, N0: np.ndarray, has0: np.ndarray,
                    fb: np.ndarray, roots: list[int], tol: float) -> np.ndarray | None:
    """The least-weight triangulation of the loop over the ``roots``.

    Parameters
    ----------
    run : callable
        ``run(P, N0, has0, forbid, s) -> (opt, bend, area)``: a program on the loop rolled to
        start at ``s`` (``forbid`` the ``(k, k)`` flags of its forbidden chords).
    P, N0, has0 : (k, 3), (k, 3), (k,)
        Loop positions, normals of the faces on the loop edges, which exist (caller's order).
    fb : (q, 2) int
        Forbidden chords in the caller's local indices.
    roots : list of int
    tol : float
        Bends closer than this are equal (then the smaller area wins).

    Returns
    -------
    (k - 2, 3) int64 or None
        Triangles ``(i, j, m)``, ``i < m < j``, rows sorted; None when no root gives a
        triangulation (every one uses a forbidden chord).
    """
    k = len(P)
    best = None
    for s in roots:
        Pr, N0r, has0r = (np.roll(x, -s, axis=0) for x in (P, N0, has0))
        opt, bend, area = run(Pr, N0r, has0r, _forbid_matrix(fb, s, k), s)
        b, a = float(bend[0, k - 1]), float(area[0, k - 1])
        if not np.isfinite(b):
            continue
        if best is None or b < best[0] - tol or (b <= best[0] + tol and a < best[1]):
            best = (b, a, opt, s)
    return None if best is None else _unrolled(triangles(best[2], k), best[3], k)
