"""Liepa's minimum-weight triangulation of a loop (Liepa 2003, as in CGAL's ``triangulate_hole``):
an O(k³) dynamic program (numba kernel, numpy twin) minimising the largest dihedral angle, then
the area."""

from __future__ import annotations

import logging

import numpy as np

from meshrepair._kernels import HAVE_NUMBA
from meshrepair.errors import MeshRepairError
from meshrepair.holes._geom2d import _loop_positions
from meshrepair.holes.liepa_delaunay import _py_delaunay_dp, delaunay_facets
from meshrepair.holes.liepa_roots import alternative_roots, canonical_start, optimum_from

if HAVE_NUMBA:
    from meshrepair._kernels import (
        njit,  # numba.njit, without the disk cache where none is writable
    )
    from meshrepair.holes.liepa_delaunay import _nb_delaunay_dp

log = logging.getLogger(__name__)


LIEPA_MAX_LOOP = 1000
"""Largest loop (boundary vertices) :func:`meshrepair.fill.fill_holes` encloses with the O(k³)
dynamic program of :func:`min_weight_triangulation` (about 2 s and 90 MB at this size)."""

SEARCH_SPACES = ("delaunay", "all")
"""Search spaces of :func:`min_weight_triangulation`: the facets of the loop's Delaunay
tetrahedralisation (:mod:`meshrepair.holes.liepa_delaunay`), falling back to all triangles when
they hold no triangulation of the loop, or all triangles."""

_DP_TOL = 1e-12
"""Bends ``1 - cos(dihedral angle)`` closer than this count as equal in the lexicographic
weight (angles of about 1e-6 rad and below are not told apart: the area decides)."""


def _np_liepa_dp(P: np.ndarray, N0: np.ndarray, has0: np.ndarray, forbid: np.ndarray,
                 tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Liepa's dynamic program (numpy twin of ``_nb_liepa_dp``, vectorised over each diagonal).

    For ``i < j`` the sub-polygon ``i, i+1, ..., j`` closed by the chord ``(i, j)`` is
    triangulated with the triangle ``(i, j, m)`` (patch orientation) on that chord and the best
    triangulations of ``[i, m]`` and ``[m, j]``. Its weight is (largest bend, total area), where
    the bend of two consistently oriented adjacent triangles is ``1 - cos`` of their dihedral
    angle (monotone in the angle, cheaper than ``arccos``); the triangle on ``(i, j)`` is compared
    with the triangles of the sub-solutions on ``(i, m)`` and ``(m, j)`` or, for a loop edge,
    with the existing face there. Candidates are compared by bend (within ``tol``), then area.

    Parameters
    ----------
    P : (k, 3) float64
        Loop positions.
    N0 : (k, 3) float64
        Unit normal of the existing face on loop edge ``(i, i+1)`` (edge ``k-1`` closes the loop).
    has0 : (k,) bool
        Which loop edges have such a face.
    forbid : (k, k) bool
        ``forbid[i, j]`` (``i < j``): the chord ``(i, j)`` must not be used.
    tol : float
        Bends closer than this are equal.

    Returns
    -------
    opt : (k, k) int64
        Best apex ``m`` of the sub-polygon ``[i, j]`` (-1 where infeasible or unused).
    bend, area : (k, k) float64
        Its weight (``inf`` where infeasible); ``[0, k-1]`` is the whole loop.
    """
    k = len(P)
    bend = np.full((k, k), np.inf)
    area = np.full((k, k), np.inf)
    opt = np.full((k, k), -1, np.int64)
    nrm = np.zeros((k, k, 3))
    hasn = np.zeros((k, k), bool)
    i1 = np.arange(k - 1)
    bend[i1, i1 + 1] = 0.0
    area[i1, i1 + 1] = 0.0
    nrm[i1, i1 + 1] = N0[:-1]
    hasn[i1, i1 + 1] = has0[:-1]
    deg = 1e-12 * float(np.ptp(P, axis=0).max()) ** 2
    for d in range(2, k):
        ii = np.arange(k - d)
        jj = ii + d
        mm = ii[:, None] + np.arange(1, d)[None, :]  # (n, d-1)
        I = np.broadcast_to(ii[:, None], mm.shape)
        J = np.broadcast_to(jj[:, None], mm.shape)
        e, f = P[J] - P[I], P[mm] - P[I]
        n = np.stack([e[..., 1] * f[..., 2] - e[..., 2] * f[..., 1],
                      e[..., 2] * f[..., 0] - e[..., 0] * f[..., 2],
                      e[..., 0] * f[..., 1] - e[..., 1] * f[..., 0]], axis=-1)
        q = np.sqrt(n[..., 0] * n[..., 0] + n[..., 1] * n[..., 1] + n[..., 2] * n[..., 2])
        good = q > deg
        nu = np.where(good[..., None], n / np.where(good, q, 1.0)[..., None], 0.0)
        c1 = np.where(hasn[I, mm], 1.0 - np.einsum("...i,...i->...", nu, nrm[I, mm]), 0.0)
        c2 = np.where(hasn[mm, J], 1.0 - np.einsum("...i,...i->...", nu, nrm[mm, J]), 0.0)
        a = np.maximum(np.maximum(bend[I, mm], bend[mm, J]), np.maximum(c1, c2))
        if d == k - 1 and has0[k - 1]:
            a = np.maximum(a, 1.0 - nu @ N0[k - 1])
        a = np.where(good, a, 2.0)
        a = np.where(np.isfinite(bend[I, mm]) & np.isfinite(bend[mm, J]), a, np.inf)
        s = 0.5 * q + area[I, mm] + area[mm, J]
        best = a.min(axis=1)
        s = np.where(a <= best[:, None] + tol, s, np.inf)
        b = np.argmin(s, axis=1)
        r = np.arange(len(ii))
        ok = np.isfinite(best) & ~forbid[ii, jj]
        ii, jj, b, r = ii[ok], jj[ok], b[ok], r[ok]
        bend[ii, jj] = best[ok]
        area[ii, jj] = s[r, b]
        opt[ii, jj] = mm[r, b]
        nrm[ii, jj] = nu[r, b]
        hasn[ii, jj] = good[r, b]
    return opt, bend, area


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_liepa_dp(P, N0, has0, forbid, tol):  # pragma: no cover - compiled
        """Liepa's dynamic program, O(k³): see :func:`_np_liepa_dp` (same results)."""
        k = P.shape[0]
        # row i of bend/area/nrm holds the sub-polygons [i, j]; row j of the transposed copies
        # (bendT, areaT, nrmT) the sub-polygons [m, j], so the inner loop reads contiguously
        bend = np.full((k, k), np.inf)
        area = np.full((k, k), np.inf)
        bendT = np.full((k, k), np.inf)
        areaT = np.full((k, k), np.inf)
        opt = np.full((k, k), -1, np.int64)
        nrm = np.zeros((k, k, 3))
        nrmT = np.zeros((k, k, 3))
        hasn = np.zeros((k, k), np.bool_)
        hasnT = np.zeros((k, k), np.bool_)
        for i in range(k - 1):
            hasn[i, i + 1] = has0[i]
            hasnT[i + 1, i] = has0[i]
            bend[i, i + 1] = 0.0
            area[i, i + 1] = 0.0
            bendT[i + 1, i] = 0.0
            areaT[i + 1, i] = 0.0
            for c in range(3):
                nrm[i, i + 1, c] = N0[i, c]
                nrmT[i + 1, i, c] = N0[i, c]
        lmax = 0.0
        for c in range(3):
            lmax = max(lmax, P[:, c].max() - P[:, c].min())
        deg = 1e-12 * lmax * lmax
        ca = np.empty(k)
        cs = np.empty(k)
        cn = np.empty((k, 3))
        cg = np.empty(k, np.bool_)
        for d in range(2, k):
            for i in range(k - d):
                j = i + d
                if forbid[i, j]:
                    continue
                ex = P[j, 0] - P[i, 0]
                ey = P[j, 1] - P[i, 1]
                ez = P[j, 2] - P[i, 2]
                best = np.inf
                for t in range(d - 1):
                    m = i + 1 + t
                    b1 = bend[i, m]
                    b2 = bendT[j, m]
                    ca[t] = np.inf
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
                        if hasnT[j, m]:
                            a = max(a, 1.0 - (nx * nrmT[j, m, 0] + ny * nrmT[j, m, 1]
                                              + nz * nrmT[j, m, 2]))
                        if d == k - 1 and has0[k - 1]:
                            a = max(a, 1.0 - (nx * N0[k - 1, 0] + ny * N0[k - 1, 1]
                                              + nz * N0[k - 1, 2]))
                    else:
                        nx = ny = nz = 0.0
                        a = 2.0
                    ca[t] = a
                    cs[t] = 0.5 * q + area[i, m] + areaT[j, m]
                    cn[t, 0] = nx
                    cn[t, 1] = ny
                    cn[t, 2] = nz
                    cg[t] = q > deg
                    if a < best:
                        best = a
                if best == np.inf:
                    continue
                bt = -1
                bs = np.inf
                for t in range(d - 1):
                    if ca[t] <= best + tol and cs[t] < bs:
                        bs = cs[t]
                        bt = t
                bend[i, j] = best
                bendT[j, i] = best
                area[i, j] = bs
                areaT[j, i] = bs
                opt[i, j] = i + 1 + bt
                for c in range(3):
                    nrm[i, j, c] = cn[bt, c]
                    nrmT[j, i, c] = cn[bt, c]
                hasn[i, j] = cg[bt]
                hasnT[j, i] = cg[bt]
        return opt, bend, area


def _edge_normals(P: np.ndarray, opposite: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals of the existing faces ``(P_i, P_i+1, O_i)`` on the loop edges, ``(k, 3)``,
    and which of them exist (finite, non-degenerate)."""
    k = len(P)
    if opposite is None:
        return np.zeros((k, 3)), np.zeros(k, bool)
    O = np.asarray(opposite, dtype=np.float64)
    if O.shape != (k, 3):
        raise MeshRepairError(f"opposite must have shape ({k}, 3) (one point per loop edge), got "
                              f"{O.shape}")
    Pn = np.roll(P, -1, axis=0)
    n = np.cross(Pn - P, O - P)
    q = np.linalg.norm(n, axis=1)
    lmax = float(np.ptp(P, axis=0).max())
    ok = np.isfinite(q) & (q > 1e-12 * lmax * lmax)
    N = np.zeros((k, 3))
    N[ok] = n[ok] / q[ok, None]
    return N, ok


def min_weight_triangulation(P: np.ndarray, *, opposite: np.ndarray | None = None,
                             forbidden: np.ndarray | None = None,
                             search: str = "delaunay") -> np.ndarray:
    """Liepa's minimum-weight triangulation of a closed 3-D polygon (no new vertices).

    Dynamic program over the sub-polygons ``i, i+1, ..., j`` (O(k³) time, O(k²) memory; a numba
    kernel, or numpy vectorised over each diagonal when numba is unavailable or
    ``MESHREPAIR_NO_NUMBA=1``). The weight of a triangle set is lexicographic: first the largest
    dihedral angle between adjacent triangles, including the existing face on each loop edge
    (``opposite``), then the total area (Liepa 2003, "Filling holes in meshes"; the weight of
    CGAL's ``triangulate_hole``). It therefore follows the surrounding faces instead of a
    projection plane. As in CGAL, the search first runs over the facets of the Delaunay
    tetrahedralisation of the loop vertices (:mod:`meshrepair.holes.liepa_delaunay`: O(k)
    triangles for a loop, and a triangulation by them rarely crosses the surrounding surface,
    which the unrestricted optimum of a long loop winding through space can), and over every
    triangle when those hold no triangulation of the loop.

    Parameters
    ----------
    P : (k, 3) float, k >= 3
        Loop positions in the order of :attr:`Hole.vertices`.
    opposite : (k, 3) float, optional
        Third vertex of the existing face ``(P_i, P_i+1, opposite_i)`` on each loop edge (rows
        of NaN where there is none); without it only the angles inside the patch count.
    forbidden : (q, 2) int, optional
        Local index pairs that must not become chords (they are edges of the mesh already and
        would get a third face). Ignored when no triangulation avoids them all.
    search : ``"delaunay"`` or ``"all"``
        The search space (:data:`SEARCH_SPACES`): the Delaunay facets first (falling back to all
        triangles), or all triangles at once.

    Returns
    -------
    (k - 2, 3) int64
        Triangles in local indices, ``(i, j, m)`` with ``i < m < j``: every loop edge ``(i, i+1)``
        is traversed as ``(i+1, i)``, like :attr:`Patch.T`.

    Raises
    ------
    MeshRepairError
        For a loop of fewer than 3 vertices or non-finite positions, or an unknown ``search``.
    """
    if search not in SEARCH_SPACES:
        raise MeshRepairError(f"search must be one of {SEARCH_SPACES}, got {search!r}")
    P, N0, has0, fb = _program_inputs(P, opposite, forbidden)
    k = len(P)
    if search == "delaunay":
        T = _delaunay_optimum(P, N0, has0, fb)
        if T is not None:
            return T
        log.debug("no triangulation of the %d-loop by Delaunay facets; searching all", k)
    dp = _nb_liepa_dp if HAVE_NUMBA else _np_liepa_dp

    def full(Pr, N0r, has0r, forbid, s):
        return dp(Pr, N0r, has0r, forbid, _DP_TOL)

    s = canonical_start(P)
    T = optimum_from(full, P, N0, has0, fb, s)
    if T is None:
        log.info("no triangulation of the %d-loop avoids the existing edges; allowing them", k)
        T = optimum_from(full, P, N0, has0, fb[:0], s)
    return T


def _program_inputs(P, opposite, forbidden):
    """The inputs of the dynamic programs: the loop positions checked, the normals of the faces
    on the loop edges and which exist, and the forbidden chords ``(q, 2)`` in local indices."""
    P = _loop_positions(P)
    k = len(P)
    N0, has0 = _edge_normals(P, opposite)
    fb = np.zeros((0, 2), dtype=np.int64)
    if forbidden is not None and len(forbidden):
        fb = np.asarray(forbidden, dtype=np.int64).reshape(-1, 2)
        if (fb < 0).any() or (fb >= k).any():
            raise MeshRepairError(f"forbidden chords must be local loop indices in [0, {k})")
    return P, N0, has0, fb


def _delaunay_optimum(P, N0, has0, fb, root: int | None = None,
                      tri: np.ndarray | None = None) -> np.ndarray | None:
    """The minimum-weight triangulation by the loop's Delaunay facets ``tri`` (default: computed
    here, :func:`~meshrepair.holes.liepa_delaunay.delaunay_facets`) avoiding the forbidden
    chords, rooted at ``root`` (default:
    :func:`~meshrepair.holes.liepa_roots.canonical_start`), or None where there is none."""
    k = len(P)
    tri = delaunay_facets(P) if tri is None else tri
    if tri is None:
        return None
    ddp = _nb_delaunay_dp if HAVE_NUMBA else _py_delaunay_dp

    def restricted(Pr, N0r, has0r, forbid, s):
        t = np.sort((tri - s) % k, axis=1)
        t = t[np.lexsort((t[:, 1], t[:, 0], t[:, 2] - t[:, 0]))]  # delaunay_facets' order
        return ddp(Pr, N0r, has0r, forbid, t[:, 0].copy(), t[:, 1].copy(), t[:, 2].copy(),
                   _DP_TOL)

    root = canonical_start(P) if root is None else root
    return optimum_from(restricted, P, N0, has0, fb, root)


def delaunay_optimum(P: np.ndarray, *, opposite: np.ndarray | None = None,
                     forbidden: np.ndarray | None = None) -> np.ndarray | None:
    """:func:`min_weight_triangulation` over the loop's Delaunay facets only, avoiding the
    ``forbidden`` chords: the ``(k - 2, 3)`` triangles, or None where the facets hold no such
    triangulation (no fallback to the full search)."""
    return _delaunay_optimum(*_program_inputs(P, opposite, forbidden))


def delaunay_optima(P: np.ndarray, *, opposite: np.ndarray | None = None,
                    forbidden: np.ndarray | None = None):
    """The Delaunay-facet optima rooted at the
    :func:`~meshrepair.holes.liepa_roots.alternative_roots`, in root order (a generator of
    ``(k - 2, 3)`` triangulations; roots without one are left out): what
    :func:`meshrepair.holes.enclose_holes` tries when the optima cross the mesh."""
    args = _program_inputs(P, opposite, forbidden)
    tri = delaunay_facets(args[0])
    if tri is None:
        return
    for s in alternative_roots(args[0]):
        T = _delaunay_optimum(*args, root=s, tri=tri)
        if T is not None:
            yield T
