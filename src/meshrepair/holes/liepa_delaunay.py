"""Liepa's dynamic program over the facets of the loop's 3-D Delaunay tetrahedralisation: the
search space of CGAL's ``triangulate_hole`` (``use_delaunay_triangulation``, its default).

The unrestricted program of :func:`meshrepair.holes.min_weight_triangulation` minimises the
largest dihedral angle over every triangulation of the loop, O(k³) candidate triangles. On a long
loop that winds through space (a cut merged with an open border, a loop round a thin part) its
optimum may pass through the surrounding surface: the weight sees only the loop and the faces on
its edges, nothing of the surface further away. A triangle that is a facet of the Delaunay
tetrahedralisation of the loop vertices has a circumscribing sphere empty of loop vertices, so
these triangles span the loop's own "hull" rather than reaching across it, and a triangulation
made of them rarely crosses the rest of the surface; there are O(k) of them for points spread
along a curve (5,675 for a 415-vertex loop, against 1.2·10⁷ triangles of the full space), so the
restricted program costs O(number of facets) instead of O(k³).

The program is the same recursion as the full one, restricted: a triangle ``(a, b, c)`` with
``a < b < c`` (local loop indices) is the apex ``b`` of the chord ``(a, c)``, so each facet is
tried exactly once, chords in order of their span ``c - a``. A chord whose sub-polygon has no
triangulation by facets stays infeasible, and so does the loop when a loop edge is no Delaunay
edge; the caller then searches the full space
(:func:`meshrepair.holes.liepa.min_weight_triangulation`).
"""

from __future__ import annotations

import numpy as np

from meshrepair._kernels import HAVE_NUMBA

if HAVE_NUMBA:
    from meshrepair._kernels import njit


def delaunay_facets(P: np.ndarray) -> np.ndarray | None:
    """Triangles of the 3-D Delaunay tetrahedralisation of the points ``P``.

    Parameters
    ----------
    P : (k, 3) float64

    Returns
    -------
    (t, 3) int64, or None
        Every triangle face of the tetrahedra, each row sorted ascending, rows sorted by the span
        ``c - a`` of their first and last index, then by ``a``, then by ``b`` (the order of
        :func:`_py_delaunay_dp`). None when Qhull cannot tetrahedralise the points (fewer than 5,
        all coplanar, or otherwise degenerate).
    """
    from scipy.spatial import Delaunay, QhullError

    P = np.asarray(P, dtype=np.float64)
    if len(P) < 5:
        return None
    try:
        S = Delaunay(P).simplices
    except (QhullError, ValueError):
        return None
    if len(S) == 0:
        return None
    tri = np.r_[S[:, [0, 1, 2]], S[:, [0, 1, 3]], S[:, [0, 2, 3]], S[:, [1, 2, 3]]]
    tri = np.unique(np.sort(tri, axis=1), axis=0).astype(np.int64)
    order = np.lexsort((tri[:, 1], tri[:, 0], tri[:, 2] - tri[:, 0]))
    return tri[order]


def _py_delaunay_dp(P, N0, has0, forbid, A, B, C, tol):
    """Liepa's dynamic program restricted to the triangles ``(A, B, C)`` (see the module).

    Written in scalar loops so that numba compiles the same function (:func:`_nb_delaunay_dp`);
    with every triangle ``i < m < j`` given it computes exactly what the full program
    :func:`meshrepair.holes.liepa._np_liepa_dp` does (tests/test_holes_liepa_delaunay.py).

    Parameters
    ----------
    P, N0, has0, forbid, tol
        As for the full program (:func:`meshrepair.holes.liepa._np_liepa_dp`): loop positions,
        the normals of the faces on the loop edges and which exist, the forbidden chords, the
        tolerance of equal bends.
    A, B, C : (t,) int64
        The allowed triangles, ``A < B < C``, grouped by chord ``(A, C)`` in order of increasing
        span ``C - A`` (:func:`delaunay_facets`).

    Returns
    -------
    opt, bend, area : (k, k)
        As for the full program: the best apex of each sub-polygon ``[i, j]`` (-1 where
        infeasible) and its weight (``inf`` where infeasible).

    The weight of a candidate apex repeats the inner loop of the full program's numba kernel
    (:func:`meshrepair.holes.liepa._nb_liepa_dp`) instead of calling a shared compiled helper:
    such a call in the full program's O(k³) loop doubles its time (0.23 → 0.48 s at k = 500).
    """
    k = P.shape[0]
    bend = np.full((k, k), np.inf)
    area = np.full((k, k), np.inf)
    opt = np.full((k, k), -1, np.int64)
    nrm = np.zeros((k, k, 3))
    hasn = np.zeros((k, k), np.bool_)
    for i in range(k - 1):
        bend[i, i + 1] = 0.0
        area[i, i + 1] = 0.0
        hasn[i, i + 1] = has0[i]
        for c in range(3):
            nrm[i, i + 1, c] = N0[i, c]
    lmax = 0.0
    for c in range(3):
        lmax = max(lmax, P[:, c].max() - P[:, c].min())
    deg = 1e-12 * lmax * lmax
    # the candidates of one chord: bend, area, apex, unit normal, non-degenerate
    ca = np.empty(k)
    cs = np.empty(k)
    cm = np.empty(k, np.int64)
    cn = np.empty((k, 3))
    cg = np.empty(k, np.bool_)
    t = len(A)
    s = 0
    while s < t:
        i = A[s]
        j = C[s]
        e = s
        while e < t and A[e] == i and C[e] == j:
            e += 1
        if not forbid[i, j]:
            ex = P[j, 0] - P[i, 0]
            ey = P[j, 1] - P[i, 1]
            ez = P[j, 2] - P[i, 2]
            best = np.inf
            nc = 0
            for r in range(s, e):
                m = B[r]
                b1 = bend[i, m]
                b2 = bend[m, j]
                if b1 == np.inf or b2 == np.inf:
                    continue
                fx = P[m, 0] - P[i, 0]
                fy = P[m, 1] - P[i, 1]
                fz = P[m, 2] - P[i, 2]
                nx = ey * fz - ez * fy
                ny = ez * fx - ex * fz
                nz = ex * fy - ey * fx
                q = np.sqrt(nx * nx + ny * ny + nz * nz)
                if q > deg:
                    nx /= q
                    ny /= q
                    nz /= q
                    a = max(b1, b2)
                    if hasn[i, m]:
                        a = max(a, 1.0 - (nx * nrm[i, m, 0] + ny * nrm[i, m, 1]
                                          + nz * nrm[i, m, 2]))
                    if hasn[m, j]:
                        a = max(a, 1.0 - (nx * nrm[m, j, 0] + ny * nrm[m, j, 1]
                                          + nz * nrm[m, j, 2]))
                    if j - i == k - 1 and has0[k - 1]:
                        a = max(a, 1.0 - (nx * N0[k - 1, 0] + ny * N0[k - 1, 1]
                                          + nz * N0[k - 1, 2]))
                else:
                    nx = ny = nz = 0.0
                    a = 2.0
                ca[nc] = a
                cs[nc] = 0.5 * q + area[i, m] + area[m, j]
                cm[nc] = m
                cn[nc, 0] = nx
                cn[nc, 1] = ny
                cn[nc, 2] = nz
                cg[nc] = q > deg
                nc += 1
                if a < best:
                    best = a
            # the lexicographic weight: the least area among the bends within tol of the least;
            # apices come in increasing m, so "<" keeps the full program's choice on ties
            bt = -1
            bs = np.inf
            for r in range(nc):
                if ca[r] <= best + tol and cs[r] < bs:
                    bs = cs[r]
                    bt = r
            if bt >= 0:
                bend[i, j] = best
                area[i, j] = bs
                opt[i, j] = cm[bt]
                for c in range(3):
                    nrm[i, j, c] = cn[bt, c]
                hasn[i, j] = cg[bt]
        s = e
    return opt, bend, area


if HAVE_NUMBA:
    _nb_delaunay_dp = njit(cache=True)(_py_delaunay_dp)
