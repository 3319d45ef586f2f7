"""Roots of Liepa's dynamic programs: where the recursion starts, and the alternatives.

The programs of :mod:`meshrepair.holes.liepa` triangulate the sub-polygons ``i, ..., j`` of a
loop numbered ``0, ..., k-1`` and return the triangulation of ``[0, k-1]``: the recursion is
rooted at the loop edge from the last vertex to the first. The weight is lexicographic (largest
bend ``1 - cos`` of a dihedral angle, then total area), and a (largest, then sum) weight has no
optimal substructure: a sub-polygon's best triangulation by its own weight need not be part of
the whole loop's best, so the result depends on the root. Rooted wherever the mesh's numbering
starts the loop, the triangulation changed with the vertex order of the mesh.

The programs therefore start from a vertex read off the geometry, the loop vertex farthest from
the loop's centroid (:func:`canonical_start`): the same for every numbering, rotation, scale and
translation. :func:`alternative_roots` are :data:`ROOTS` - 1 more, spread evenly along the loop
from it, whose optima :func:`meshrepair.holes.enclose_holes` tries when the first crosses the
mesh. The weight does not choose between roots: over the 144 runs of the cut protocol, keeping
the root of least largest bend moved 31 runs (mean distance +0.3 %, normals +0.5 %), the root of
least weight (bend, then area) 65 runs (+1.3 %, +1.5 %): a patch of less area cuts across the
hole.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from meshrepair.mesh.geometry import order_free_centroid
from meshrepair.mesh.topology import least_first, row_order

ROOTS = 8
"""Roots spread along a loop: the canonical one and the alternatives (fewer on loops of fewer
vertices)."""


def canonical_start(P: np.ndarray) -> int:
    """The loop vertex farthest from the loop's centroid (the centroid summed over sorted
    coordinates: the same bits whatever the loop's first vertex)."""
    c = order_free_centroid(P)
    return int(np.argmax(((P - c) ** 2).sum(axis=1)))


def alternative_roots(P: np.ndarray) -> list[int]:
    """The roots after :func:`canonical_start` of the loop ``P`` (k, 3): with it, :data:`ROOTS`
    of them spread evenly along the loop."""
    k = len(P)
    r = min(ROOTS, k)
    s = canonical_start(P)
    return [(s + (j * k) // r) % k for j in range(1, r)]


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
    T = least_first((T + s) % k)
    return T[row_order(T)]


def optimum_from(run: Callable, P: np.ndarray, N0: np.ndarray, has0: np.ndarray,
                 fb: np.ndarray, s: int) -> np.ndarray | None:
    """A program's triangulation of the loop rooted at ``s``.

    Parameters
    ----------
    run : callable
        ``run(P, N0, has0, forbid, s) -> (opt, bend, area)``: a program on the loop rolled to
        start at ``s`` (``forbid`` the ``(k, k)`` flags of its forbidden chords).
    P, N0, has0 : (k, 3), (k, 3), (k,)
        Loop positions, normals of the faces on the loop edges, which exist (caller's order).
    fb : (q, 2) int
        Forbidden chords in the caller's local indices.
    s : int
        The root.

    Returns
    -------
    (k - 2, 3) int64 or None
        Triangles ``(i, j, m)``, ``i < m < j``, rows sorted; None when every triangulation
        uses a forbidden chord.
    """
    k = len(P)
    Pr, N0r, has0r = (np.roll(x, -s, axis=0) for x in (P, N0, has0))
    opt, bend, _ = run(Pr, N0r, has0r, _forbid_matrix(fb, s, k), s)
    if not np.isfinite(bend[0, k - 1]):
        return None
    return _unrolled(triangles(opt, k), s, k)
