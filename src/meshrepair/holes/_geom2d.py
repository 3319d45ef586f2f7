"""2-D helpers of the enclosing step: simple-polygon test, cotangent weights, harmonic
extension, Triangle calls, plane frames, and the :class:`Patch` container."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from meshrepair.errors import MeshRepairError
from meshrepair.holes._triangle import MIN_ANGLE, steiner_cap, triangulate_capped


def _polygon_is_simple(Q: np.ndarray) -> bool:
    """True when the closed 2-D polygon ``Q (k, 2)`` does not touch or cross itself."""
    k = len(Q)
    if k < 3:
        return False
    A = Q
    B = np.roll(Q, -1, axis=0)
    seg = B - A
    scale = float(np.abs(Q - Q.mean(axis=0)).max())
    if not scale > 0:
        return False
    lens = np.linalg.norm(seg, axis=1)
    if (lens <= 1e-9 * scale).any():
        return False
    eps = 1e-10 * scale * scale
    # adjacent segments must not fold back onto each other
    nxt = np.roll(seg, -1, axis=0)
    crs = seg[:, 0] * nxt[:, 1] - seg[:, 1] * nxt[:, 0]
    dot = np.einsum("ij,ij->i", seg, nxt)
    if ((np.abs(crs) <= eps) & (dot < 0)).any():
        return False
    lo = np.minimum(A, B) - 1e-9 * scale
    hi = np.maximum(A, B) + 1e-9 * scale

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (
            q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    chunk = max(1, 2_000_000 // k)
    jj = np.arange(k)
    for s in range(0, k, chunk):
        ii = np.arange(s, min(k, s + chunk))
        i = ii[:, None]
        valid = (jj[None, :] > i + 1) & ~((i == 0) & (jj[None, :] == k - 1))
        box = ((lo[i, 0] <= hi[None, :, 0]) & (lo[None, :, 0] <= hi[i, 0])
               & (lo[i, 1] <= hi[None, :, 1]) & (lo[None, :, 1] <= hi[i, 1]) & valid)
        if not box.any():
            continue
        a, b = np.nonzero(box)
        a = ii[a]
        pa, pb, qa, qb = A[a], B[a], A[b], B[b]
        o1, o2 = orient(pa, pb, qa), orient(pa, pb, qb)
        o3, o4 = orient(qa, qb, pa), orient(qa, qb, pb)

        def sgn(o):
            return np.where(np.abs(o) <= eps, 0.0, np.sign(o))

        if ((sgn(o1) * sgn(o2) <= 0) & (sgn(o3) * sgn(o4) <= 0)).any():
            return False
    return True


def _cotan_weights_2d(X: np.ndarray, T: np.ndarray, n: int,
                      cot_range: tuple[float, float] | None = None) -> sp.csr_matrix:
    """Symmetric cotangent weight matrix (positive off-diagonal), shape ``(n, n)``; with
    ``cot_range = (lo, hi)`` every angle's cotangent is clipped to ``[lo, hi]`` first."""
    rows, cols, vals = [], [], []
    P = X if X.shape[1] == 3 else np.c_[X, np.zeros(len(X))]
    c = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    dbl = np.maximum(np.linalg.norm(c, axis=1), 1e-300)
    for k in range(3):
        i, j, o = T[:, (k + 1) % 3], T[:, (k + 2) % 3], T[:, k]
        cot = np.einsum("ij,ij->i", P[i] - P[o], P[j] - P[o]) / dbl
        if cot_range is not None:
            cot = np.clip(cot, cot_range[0], cot_range[1])
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * cot, 0.5 * cot]
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, n))


def _harmonic(W: sp.csr_matrix, known: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Harmonic extension: rows of unknown vertices satisfy ``sum_j w_ij (x_j - x_i) = 0``."""
    from scipy.sparse.linalg import spsolve

    n = W.shape[0]
    out = np.zeros((n, values.shape[1]))
    out[known] = values
    unk = np.flatnonzero(~known)
    if len(unk) == 0:
        return out
    L = sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W
    L = L.tocsr()
    A = L[unk][:, unk].tocsc()
    rhs = -(L[unk][:, np.flatnonzero(known)] @ values)
    sol = spsolve(A, rhs)
    out[unk] = sol.reshape(len(unk), -1)
    return out


def _triangulate(Q: np.ndarray, segments: np.ndarray, max_area: float | None,
                 holes: np.ndarray | None = None, quality: bool = True) -> tuple[np.ndarray,
                                                                                  np.ndarray]:
    data = {"vertices": Q, "segments": segments}
    if holes is not None:
        data["holes"] = holes
    opts = "pYQ"
    if quality:
        opts += f"q{MIN_ANGLE:g}"
    out = triangulate_capped(data, opts, steiner_cap(Q, len(Q), max_area), max_area=max_area)
    X = np.asarray(out["vertices"], dtype=np.float64)
    T = np.asarray(out.get("triangles", np.empty((0, 3))), dtype=np.int64).reshape(-1, 3)
    return X, T


def _plane_frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = n / np.linalg.norm(n)
    a = np.eye(3)[int(np.argmin(np.abs(n)))]
    e1 = np.cross(n, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    return e1, e2


def loop_seen_through_plane(P: np.ndarray, nh: np.ndarray):
    """A loop ``P`` (k, 3) seen through the plane of unit normal ``nh``: the polygon (a
    matplotlib path, for ``contains_points``) and the projection ``X -> (X - c) [e1 e2]`` of
    3-D points into its frame (``c`` the loop's centroid, ``e1, e2`` of :func:`_plane_frame`)."""
    from matplotlib.path import Path as MPath

    e1, e2 = _plane_frame(-nh)
    c0 = P.mean(axis=0)

    def project(X: np.ndarray) -> np.ndarray:
        return np.c_[(X - c0) @ e1, (X - c0) @ e2]

    return MPath(project(P)), project


def within_reach(P: np.ndarray):
    """Predicate on 3-D points ``X`` (n, 3) or one point: within the extent of the hole bounded
    by the loop ``P`` (k, 3), no farther from the loop's centroid than its farthest vertex (a
    patch spanning the loop lies in that ball unless it bulges past its own rim)."""
    c = P.mean(axis=0)
    R = float(np.linalg.norm(P - c, axis=1).max())
    return lambda X: bool(np.all(np.linalg.norm(np.atleast_2d(np.asarray(X, float)) - c,
                                                axis=1) <= R))


def _vector_area(P: np.ndarray) -> np.ndarray:
    c = P.mean(axis=0)
    Q = P - c
    return 0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)


@dataclass
class Patch:
    """Triangulated patch enclosing one loop (local numbering).

    Attributes
    ----------
    X : (k + m, 3) float64
        Positions: the ``k`` loop vertices first (in loop order), then ``m`` interior vertices.
    T : (t, 3) int64
        Triangles in local indices, traversing every loop edge ``(i, i+1)`` as ``(i+1, i)``.
    uv : (k + m, 2) float64
        The 2-D domain the patch was triangulated in.
    method : str
        ``"triangle"`` (3-loop), ``"plane"``, ``"pca-plane"``, ``"disc"``, ``"annulus"`` or
        ``"liepa"``.
    n_loop : int
        Number of loop vertices ``k`` (for an annulus, outer + inner).
    sharp_edges : (q, 2) int64
        Local edges on routed creases (:mod:`.creases`): their interior vertices lie on the
        crease curves and the edges get the MC penalty in the solve.
    n_creases : int
        Crease segments routed through the patch.
    n_folds : int
        ``"liepa"`` only: folds of the coarse triangulation kept as edges (0 with the mean-value
        layout, which keeps none).
    """

    X: np.ndarray
    T: np.ndarray
    uv: np.ndarray
    method: str
    n_loop: int
    sharp_edges: np.ndarray = field(default_factory=lambda: np.empty((0, 2), np.int64))
    n_creases: int = 0
    n_folds: int = 0


def _max_area_for(h2: float) -> float:
    # an equilateral triangle of side h2 has area sqrt(3)/4 h2^2; triangle's refinement keeps
    # the mean area well below the bound, so the bound is set 1.6 times the target
    return 1.6 * np.sqrt(3.0) / 4.0 * h2 * h2


def _orient_patch(T: np.ndarray, k: int) -> np.ndarray:
    """Flip ``T`` if it traverses the loop edge (0, 1) forwards; check all loop edges."""
    he = np.stack([T, np.roll(T, -1, axis=1)], axis=2).reshape(-1, 2)
    loop_fwd = np.c_[np.arange(k), (np.arange(k) + 1) % k]
    code = he[:, 0] * (T.max() + 1) + he[:, 1]
    fwd = np.isin(loop_fwd[:, 0] * (T.max() + 1) + loop_fwd[:, 1], code)
    if fwd.all():
        T = T[:, ::-1].copy()
    elif fwd.any():
        raise MeshRepairError("internal error: the 2-D triangulation of the hole is inconsistently "
                              "oriented along its boundary")
    return T


def _loop_positions(P) -> np.ndarray:
    """``P`` as a C-contiguous ``(k, 3)`` float64 array of finite loop positions, ``k >= 3``."""
    P = np.ascontiguousarray(P, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) < 3:
        raise MeshRepairError(f"a hole loop needs at least 3 vertices of shape (k, 3), got "
                              f"{P.shape}")
    if not np.isfinite(P).all():
        raise MeshRepairError("the hole loop has non-finite vertex positions")
    return P
