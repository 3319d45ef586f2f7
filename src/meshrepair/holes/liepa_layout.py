"""Planar layouts of a Liepa patch and point location in them, for the refinement of
:mod:`meshrepair.holes.liepa_refine`: the isometric development of a triangulated polygon
along its dual tree (:func:`_unfold`), Floater's mean-value embedding of a disc
(:func:`_mean_value_layout`), and the triangle of a planar triangulation that holds each
point, with its barycentric coordinates (:func:`_locate`)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair.holes._geom2d import _polygon_is_simple


def _tri_angles(P: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Corner angles ``(t, 3)`` of the triangles ``T`` of ``P``."""
    out = np.empty(T.shape)
    for c in range(3):
        u = P[T[:, (c + 1) % 3]] - P[T[:, c]]
        v = P[T[:, (c + 2) % 3]] - P[T[:, c]]
        out[:, c] = np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), np.einsum("ij,ij->i", u, v))
    return out


def _unfold(P: np.ndarray, T: np.ndarray) -> np.ndarray | None:
    """Isometric development of a triangulated polygon (all vertices on the loop) into the plane.

    The triangles are laid out along the dual tree, each reflected across the chord it shares
    with its parent, so every triangle keeps its 3-D shape. Returns the ``(k, 2)`` positions, or
    None when the development overlaps itself (the loop's 2-D image is not simple, or the
    triangles round a loop vertex span 360° or more).
    """
    k = len(P)
    nt = len(T)
    by_edge: dict[tuple[int, int], list[int]] = {}
    for t, tri in enumerate(T.tolist()):
        for c in range(3):
            a, b = tri[c], tri[(c + 1) % 3]
            by_edge.setdefault((min(a, b), max(a, b)), []).append(t)
    X = np.full((k, 2), np.nan)
    i, j, m = T[0]
    e = P[j] - P[i]
    le = float(np.linalg.norm(e))
    if not le > 0:
        return None
    X[i] = 0.0
    X[j] = (le, 0.0)
    f = P[m] - P[i]
    X[m] = (float(f @ e) / le, float(np.linalg.norm(np.cross(e, f))) / le)
    done = np.zeros(nt, bool)
    done[0] = True
    queue = [0]
    while queue:
        t = queue.pop()
        tri = T[t].tolist()
        for c in range(3):
            a, b = tri[c], tri[(c + 1) % 3]
            for u in by_edge[(min(a, b), max(a, b))]:
                if done[u]:
                    continue
                done[u] = True
                nb = T[u].tolist()
                r = nb.index(b)  # the shared edge is traversed b -> a in the neighbour
                p, q, w = nb[r], nb[(r + 1) % 3], nb[(r + 2) % 3]
                e3 = P[q] - P[p]
                le = float(np.linalg.norm(e3))
                if not le > 0:
                    return None
                f3 = P[w] - P[p]
                x = float(f3 @ e3) / le
                y = float(np.linalg.norm(np.cross(e3, f3))) / le
                d2 = (X[q] - X[p]) / le
                X[w] = X[p] + x * d2 + y * np.array([-d2[1], d2[0]])
                queue.append(u)
    if not (done.all() and np.isfinite(X).all()):
        return None
    # every corner angle at a loop vertex must add up to less than a full turn
    ang = _tri_angles(P, T)
    total = np.bincount(T.ravel(), ang.ravel(), minlength=k)
    if (total >= 2 * np.pi - 1e-6).any():
        return None
    d1, d2 = X[T[:, 1]] - X[T[:, 0]], X[T[:, 2]] - X[T[:, 0]]
    area2 = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    if not (area2 > 1e-12 * float(np.ptp(X, axis=0).max()) ** 2).all():
        return None
    if not _polygon_is_simple(X):
        return None
    return X


def _bary(Q: np.ndarray, Tc: np.ndarray, t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Barycentric coordinates ``(n, 3)`` of points ``x (n, 2)`` in triangles ``Tc[t]``."""
    A, B, C = Q[Tc[t, 0]], Q[Tc[t, 1]], Q[Tc[t, 2]]
    u1, u2, w = B - A, C - A, x - A
    det = u1[..., 0] * u2[..., 1] - u1[..., 1] * u2[..., 0]
    det = np.where(det != 0, det, 1.0)
    b1 = (w[..., 0] * u2[..., 1] - w[..., 1] * u2[..., 0]) / det
    b2 = (u1[..., 0] * w[..., 1] - u1[..., 1] * w[..., 0]) / det
    return np.stack([1.0 - b1 - b2, b1, b2], axis=-1)


LOCATE_MAX_PAIRS = 64
"""Average (cell, triangle) incidences per triangle above which :func:`_locate` coarsens its
grid (bounds its memory at O(triangles + points))."""


def _locate(Q: np.ndarray, Tc: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coarse triangle of ``Tc`` (a planar layout ``Q``) containing each point, ``(n,)``, and the
    barycentric coordinates ``(n, 3)`` (clipped to the triangle for points on its border).

    Bucket grid: every triangle is registered in the cells its bounding box covers (cell side
    about the square root of the mean triangle area, coarsened until the incidences are at most
    :data:`LOCATE_MAX_PAIRS` per triangle), every point is tested against the triangles of its
    cell, and keeps the one where its smallest barycentric coordinate is largest. Points whose
    cell holds no containing triangle (round-off on the border) get the best of the 8 triangles
    with the nearest centroids. Time and memory O(triangles + points) for a layout of bounded
    anisotropy; matplotlib's trapezoid-map trifinder takes 100 s and 8 GB on a 2.3 M-triangle
    mean-value layout.
    """
    from scipy.spatial import cKDTree

    n, nt = len(pts), len(Tc)
    if n == 0:
        return np.empty(0, np.int64), np.empty((0, 3))
    T3 = Q[Tc]
    tlo, thi = T3.min(axis=1), T3.max(axis=1)
    lo = np.minimum(tlo.min(axis=0), pts.min(axis=0))
    hi = np.maximum(thi.max(axis=0), pts.max(axis=0))
    ext = np.maximum(hi - lo, 1e-300)
    d1, d2 = T3[:, 1] - T3[:, 0], T3[:, 2] - T3[:, 0]
    mean_area = max(float(np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).mean()) / 2,
                    float(ext[0] * ext[1]) / max(nt, 1) * 1e-6, 1e-300)
    cell = np.sqrt(mean_area) * 1.5
    while True:
        nc = np.maximum(np.ceil(ext / cell).astype(np.int64), 1)
        c0 = np.clip(((tlo - lo) / cell).astype(np.int64), 0, nc - 1)
        c1 = np.clip(((thi - lo) / cell).astype(np.int64), 0, nc - 1)
        span = (c1 - c0 + 1)
        cnt = span[:, 0] * span[:, 1]
        if cnt.sum() <= LOCATE_MAX_PAIRS * nt + 4 * n or nc.max() == 1:
            break
        cell *= 2.0
    # (cell, triangle) incidences
    tri = np.repeat(np.arange(nt), cnt)
    start = np.repeat(np.cumsum(cnt) - cnt, cnt)
    r = np.arange(len(tri)) - start
    sx = span[tri, 0]
    cx = c0[tri, 0] + r % sx
    cy = c0[tri, 1] + r // sx
    code = cx * nc[1] + cy
    order = np.argsort(code, kind="stable")
    code, tri = code[order], tri[order]
    pc = np.clip(((pts - lo) / cell).astype(np.int64), 0, nc - 1)
    pcode = pc[:, 0] * nc[1] + pc[:, 1]
    s0 = np.searchsorted(code, pcode, side="left")
    s1 = np.searchsorted(code, pcode, side="right")
    m = s1 - s0
    owner = np.full(n, -1, np.int64)
    score = np.full(n, -np.inf)
    pid = np.repeat(np.arange(n), m)
    if len(pid):
        off = np.arange(len(pid)) - np.repeat(np.cumsum(m) - m, m)
        cand = tri[np.repeat(s0, m) + off]
        sc = _bary(Q, Tc, cand, pts[pid]).min(axis=1)
        # best candidate per point: sort by (point, -score)
        o = np.lexsort((-sc, pid))
        first = np.r_[True, pid[o][1:] != pid[o][:-1]]
        owner[pid[o][first]] = cand[o][first]
        score[pid[o][first]] = sc[o][first]
    miss = np.flatnonzero(score < -1e-9)
    if len(miss):
        kk = min(8, nt)
        _, near = cKDTree(T3.mean(axis=1)).query(pts[miss], k=kk)
        near = np.asarray(near).reshape(len(miss), kk)
        bc = _bary(Q, Tc, near, pts[miss][:, None, :]).min(axis=2)
        best = np.argmax(bc, axis=1)
        better = bc[np.arange(len(miss)), best] > score[miss]
        owner[miss[better]] = near[np.arange(len(miss)), best][better]
    owner = np.maximum(owner, 0)
    bc = np.clip(_bary(Q, Tc, owner, pts), 0.0, None)
    s_ = bc.sum(axis=1, keepdims=True)
    bc = np.where(s_ > 0, bc / np.where(s_ > 0, s_, 1.0), 1.0 / 3.0)
    return owner, bc


def _mean_value_layout(S: np.ndarray, T: np.ndarray, k: int) -> np.ndarray:
    """Floater's mean-value embedding ``(n, 2)`` of the disc ``(S, T)``, boundary on the unit
    circle by arc length (loop vertex 0 at angle 0; the ``k`` loop vertices first in ``S``).
    Positive weights and a convex boundary make it a valid (fold-free) layout."""
    from scipy.sparse.linalg import spsolve

    from meshrepair.mesh.topology import boundary_loops

    n = len(S)
    bl = boundary_loops(T, n)
    b = max(bl, key=len)
    b = np.roll(b, -int(np.flatnonzero(b == 0)[0]))
    el = np.linalg.norm(S[b] - S[np.roll(b, -1)], axis=1)
    t = np.r_[0.0, np.cumsum(el)[:-1]] / el.sum()
    known = np.zeros(n, bool)
    known[b] = True
    U = np.zeros((n, 2))
    U[b] = np.c_[np.cos(2 * np.pi * t), -np.sin(2 * np.pi * t)]
    ang = _tri_angles(S, T)
    rows, cols, vals = [], [], []
    for c in range(3):
        i, j, m = T[:, c], T[:, (c + 1) % 3], T[:, (c + 2) % 3]
        tn = np.tan(0.5 * ang[:, c])
        for o in (j, m):
            rows.append(i)
            cols.append(o)
            vals.append(tn / np.maximum(np.linalg.norm(S[o] - S[i], axis=1), 1e-300))
    W = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n, n))
    L = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()
    unk = np.flatnonzero(~known)
    if len(unk):
        A = L[unk][:, unk].tocsc()
        rhs = -(L[unk][:, np.flatnonzero(known)] @ U[known])
        U[unk] = np.asarray(spsolve(A, rhs)).reshape(len(unk), 2)
    return U
