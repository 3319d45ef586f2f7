"""Local closest points on a triangle mesh in one pass (the kernel of
:func:`meshrepair.denoise.reproject.closest_points_local` with one ring of candidates).

For each query ``P[i]`` the candidate faces are the union of the faces of vertex ``i`` and of
vertex ``near[i]`` (ascending face index, as the rows of the sparse sum in the numpy twin); each
gets Ericson's exact point-triangle closest point (*Real-Time Collision Detection*, 5.1.5) with
the same operations, in the same order, as
:func:`closest_point_triangles`, and the first face of least squared
distance wins. Strict IEEE arithmetic (no fast-math), the three-term dot products summed as
numpy's ``einsum`` sums them on this machine (``(x0 y0 + x2 y2) + x1 y1``, as
``_kernels/fidelity.py`` does), so the result equals the numpy twin's bit for bit there (the
1.18M-vertex run of docs/performance.md) and to rounding elsewhere
(tests/test_kernels_weighted.py). It replaces ~10 candidate rows of temporaries per vertex by
scalars: at 1.18M vertices one ``closest_points_local`` call took 3.36 s of CPU with the numpy
loop and 1.33 s with this pass (of which 0.32 s the pass, the rest the k-d tree query).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from meshrepair._kernels._jit import HAVE_NUMBA, njit

if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_closest_points_local(V, F, P, indptr, indices, near):  # pragma: no cover
        nV = P.shape[0]
        out = np.empty((nV, 3))
        tiny = 1e-300
        for i in range(nV):
            a0, a1 = indptr[i], indptr[i + 1]
            if a0 == a1:  # no face at vertex i: it stays where it is
                out[i, 0], out[i, 1], out[i, 2] = V[i, 0], V[i, 1], V[i, 2]
                continue
            j = near[i]
            b0, b1 = indptr[j], indptr[j + 1]
            px, py, pz = P[i, 0], P[i, 1], P[i, 2]
            found = False
            has_nan = False
            best = 0.0
            bx, by, bz = px, py, pz
            p, q = a0, b0
            while p < a1 or q < b1:
                if q >= b1 or (p < a1 and indices[p] < indices[q]):
                    f = indices[p]
                    p += 1
                elif p >= a1 or indices[q] < indices[p]:
                    f = indices[q]
                    q += 1
                else:
                    f = indices[p]
                    p += 1
                    q += 1
                ia, ib, ic = F[f, 0], F[f, 1], F[f, 2]
                ax, ay, az = V[ia, 0], V[ia, 1], V[ia, 2]
                bvx, bvy, bvz = V[ib, 0], V[ib, 1], V[ib, 2]
                cx, cy, cz = V[ic, 0], V[ic, 1], V[ic, 2]
                abx, aby, abz = bvx - ax, bvy - ay, bvz - az
                acx, acy, acz = cx - ax, cy - ay, cz - az
                apx, apy, apz = px - ax, py - ay, pz - az
                d1 = (abx * apx + abz * apz) + aby * apy
                d2 = (acx * apx + acz * apz) + acy * apy
                bpx, bpy, bpz = px - bvx, py - bvy, pz - bvz
                d3 = (abx * bpx + abz * bpz) + aby * bpy
                d4 = (acx * bpx + acz * bpz) + acy * bpy
                cpx, cpy, cpz = px - cx, py - cy, pz - cz
                d5 = (abx * cpx + abz * cpz) + aby * cpy
                d6 = (acx * cpx + acz * cpz) + acy * cpy
                va = d3 * d6 - d5 * d4
                vb = d5 * d2 - d1 * d6
                vc = d1 * d4 - d3 * d2
                # the regions in the twin's order of overwriting, last first
                if d1 <= 0 and d2 <= 0:
                    xx, xy, xz = ax, ay, az
                elif d3 >= 0 and d4 <= d3:
                    xx, xy, xz = bvx, bvy, bvz
                elif d6 >= 0 and d5 <= d6:
                    xx, xy, xz = cx, cy, cz
                elif vc <= 0 and d1 >= 0 and d3 <= 0:
                    s = d1 / np.maximum(d1 - d3, tiny)
                    xx, xy, xz = ax + s * abx, ay + s * aby, az + s * abz
                elif vb <= 0 and d2 >= 0 and d6 <= 0:
                    s = d2 / np.maximum(d2 - d6, tiny)
                    xx, xy, xz = ax + s * acx, ay + s * acy, az + s * acz
                elif va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
                    s = (d4 - d3) / np.maximum((d4 - d3) + (d5 - d6), tiny)
                    xx = bvx + s * (cx - bvx)
                    xy = bvy + s * (cy - bvy)
                    xz = bvz + s * (cz - bvz)
                else:
                    den = np.maximum(va + vb + vc, tiny)
                    v, w = vb / den, vc / den
                    xx = ax + v * abx + w * acx
                    xy = ay + v * aby + w * acy
                    xz = az + v * abz + w * acz
                rx, ry, rz = xx - px, xy - py, xz - pz
                d = (rx * rx + rz * rz) + ry * ry
                if d != d:
                    has_nan = True
                elif not found or d < best:
                    found = True
                    best = d
                    bx, by, bz = xx, xy, xz
            if has_nan or not found:  # the twin keeps the query where a distance is NaN
                bx, by, bz = px, py, pz
            out[i, 0], out[i, 1], out[i, 2] = bx, by, bz
        return out


def closest_points_one_ring(V: np.ndarray, F: np.ndarray, P: np.ndarray, indptr: np.ndarray,
                            indices: np.ndarray, near: np.ndarray) -> np.ndarray | None:
    """The compiled pass, or ``None`` without numba (the caller then runs the numpy twin).

    Parameters
    ----------
    V : (nV, 3) float64, the surface; F : (nF, 3) int64
    P : (nV, 3) float64, one query per vertex
    indptr, indices : the CSR vertex-face incidence of ``F`` (ascending faces per row)
    near : (nV,) int64, the vertex of V nearest to each query

    Returns
    -------
    (nV, 3) float64, or None
    """
    if not HAVE_NUMBA:
        return None
    return _nb_closest_points_local(
        np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64),
        np.ascontiguousarray(P, dtype=np.float64), np.asarray(indptr, dtype=np.int64),
        np.asarray(indices, dtype=np.int64), np.asarray(near, dtype=np.int64))


def _np_closest_points_local(V: np.ndarray, F: np.ndarray, P: np.ndarray, *, rings: int = 1,
                             chunk: int = 200_000,
                             search: tuple | None = None) -> np.ndarray:
    """The numpy twin of :func:`meshrepair.denoise.reproject.closest_points_local` (batches of
    ``chunk`` vertices; any ``rings``)."""
    V = np.asarray(V, dtype=np.float64)
    P = np.asarray(P, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    nV = len(V)
    VF, tree = local_search(V, F) if search is None else search
    if rings > 1:
        A = (VF @ VF.T).astype(bool).astype(np.int8)
        R = sp.identity(nV, dtype=np.int8, format="csr")
        for _ in range(rings - 1):
            R = ((R @ A) > 0).astype(np.int8)
        VF = ((R @ VF) > 0).astype(np.int8).tocsr()
    near = tree.query(P)[1]
    out = P.copy()
    for s in range(0, nV, chunk):
        idx = np.arange(s, min(nV, s + chunk))
        C1 = VF[idx]
        C2 = VF[near[idx]]
        Cm = (C1 + C2).tocsr()  # candidate faces per row, rows in order
        counts = np.diff(Cm.indptr)
        f = Cm.indices.astype(np.int64)
        if len(f) == 0:
            continue
        q = np.repeat(np.arange(len(idx)), counts)
        gi = idx[q]
        X = closest_point_triangles(P[gi], V[F[f, 0]], V[F[f, 1]], V[F[f, 2]])
        R = X - P[gi]
        d = np.einsum("ij,ij->i", R, R)
        rows = np.flatnonzero(counts)
        dmin = np.minimum.reduceat(d, Cm.indptr[rows])
        full = np.empty(len(idx))
        full[rows] = dmin
        hit = np.flatnonzero(d == full[q])
        first = np.r_[True, q[hit][1:] != q[hit][:-1]]  # q is sorted: first minimiser per row
        sel = hit[first]
        out[idx[q[sel]]] = X[sel]
    has = np.asarray(VF.sum(axis=1)).ravel() > 0
    out[~has] = V[~has]  # isolated vertices have no surface to project on
    return out


def closest_point_triangles(P: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray
                            ) -> np.ndarray:
    """Closest point of each ``P[k]`` on the triangle ``(A[k], B[k], C[k])``.

    Parameters
    ----------
    P, A, B, C : (n, 3) float64

    Returns
    -------
    (n, 3) float64
    """
    ab, ac, ap = B - A, C - A, P - A
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = P - B
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = P - C
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    tiny = 1e-300
    # interior (default), then the edge and vertex regions overwrite it in reverse priority
    den = np.maximum(va + vb + vc, tiny)
    v, w = vb / den, vc / den
    out = A + v[:, None] * ab + w[:, None] * ac
    # edge BC
    m = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    s = (d4 - d3) / np.maximum((d4 - d3) + (d5 - d6), tiny)
    out[m] = B[m] + s[m, None] * (C - B)[m]
    # edge AC
    m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    s = d2 / np.maximum(d2 - d6, tiny)
    out[m] = A[m] + s[m, None] * ac[m]
    # edge AB
    m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    s = d1 / np.maximum(d1 - d3, tiny)
    out[m] = A[m] + s[m, None] * ab[m]
    # vertices
    m = (d6 >= 0) & (d5 <= d6)
    out[m] = C[m]
    m = (d3 >= 0) & (d4 <= d3)
    out[m] = B[m]
    m = (d1 <= 0) & (d2 <= 0)
    out[m] = A[m]
    return out


def _vertex_faces(F: np.ndarray, n_vertices: int) -> sp.csr_matrix:
    nF = len(F)
    return sp.csr_matrix((np.ones(3 * nF, dtype=np.int8),
                          (F.ravel(), np.repeat(np.arange(nF), 3))), shape=(n_vertices, nF))


def local_search(V: np.ndarray, F: np.ndarray) -> tuple[sp.csr_matrix, cKDTree]:
    """What :func:`closest_points_local` builds on the surface ``(V, F)``: the vertex-face
    incidence (ascending faces per row) and the k-d tree of ``V``; pass it as ``search`` to
    several calls on the same surface."""
    V = np.asarray(V, dtype=np.float64)
    VF = _vertex_faces(np.asarray(F, dtype=np.int64), len(V))
    VF.sort_indices()
    return VF, cKDTree(V)
