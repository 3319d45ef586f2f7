"""Boundary-loop correspondence for context-aware completion (paper Sect. 5).

Completion replaces a region of a mesh, bounded by a loop ``b0``, with a template patch bounded by
a loop ``b_P``. The paper assumes both loops are aligned and have the same number of vertices;
this module provides the pieces that make it so:

* arc-length parametrisation and resampling of polylines (:func:`arc_length_parameters`,
  :func:`resample_polyline`);
* splitting boundary edges of a mesh (and the faces they belong to) at given arc-length
  positions so that the mesh stays valid (:func:`split_boundary_edges`,
  :func:`uniform_split_params`, :func:`subdivide_loop`);
* rigid / similarity alignment of point sets (:func:`umeyama`) and the best cyclic shift and
  direction between two loops with the same vertex count, over all shifts at once with the FFT
  (:func:`best_cyclic_alignment`);
* ICP refinement of a loop against a target polyline (:func:`icp_loop_to_polyline`);
* the optimal monotone (order-preserving) matching of a short loop into a longer one
  (:func:`monotone_loop_match`), which decides where the short loop must be subdivided.

Conventions: points are ``(n, 3)`` float64, 4x4 homogeneous transforms act on column vectors
(``p' = T[:3, :3] @ p + T[:3, 3]``). A loop is *closed*: vertex ``n - 1`` connects back to
vertex 0. Input arrays are never modified.
"""

from __future__ import annotations

import heapq
import logging
from dataclasses import dataclass

import numpy as np

from .errors import MeshRepairError

log = logging.getLogger(__name__)

__all__ = [
    "CyclicAlignment",
    "LoopAlignment",
    "align_loops",
    "apply_transform",
    "arc_length_parameters",
    "best_cyclic_alignment",
    "closest_points_on_loop",
    "closest_points_on_mesh",
    "icp_to_surface",
    "icp_loop_to_polyline",
    "monotone_loop_match",
    "resample_polyline",
    "split_boundary_edges",
    "subdivide_loop",
    "umeyama",
    "uniform_split_params",
]

FITS = ("none", "rigid", "similarity")


# ------------------------------------------------------------------------------------------------
# polylines
# ------------------------------------------------------------------------------------------------

def _points(P, name: str = "points") -> np.ndarray:
    P = np.asarray(P, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3:
        raise MeshRepairError(f"{name} must have shape (n, 3), got {P.shape}")
    if not np.isfinite(P).all():
        raise MeshRepairError(f"{name} contain NaN or infinite coordinates")
    return P


def arc_length_parameters(P: np.ndarray, *, closed: bool = True) -> tuple[np.ndarray, float]:
    """Cumulative arc length at each vertex of a polyline.

    Parameters
    ----------
    P : (n, 3) float
    closed : bool
        Include the closing edge ``P[n-1] -> P[0]`` in the total length.

    Returns
    -------
    s : (n,) float64
        Arc length from ``P[0]`` to each vertex (``s[0] = 0``).
    total : float
        Total length (with the closing edge if ``closed``).
    """
    P = _points(P)
    seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    total = float(s[-1] + (np.linalg.norm(P[0] - P[-1]) if closed else 0.0))
    return s, total


def resample_polyline(P: np.ndarray, n: int, *, closed: bool = True) -> np.ndarray:
    """Resample a polyline to ``n`` points equally spaced in arc length.

    Parameters
    ----------
    P : (m, 3) float
    n : int
        Number of output points (>= 2 open, >= 3 closed).
    closed : bool
        Closed loop: points at arc lengths ``k L / n``, ``k = 0..n-1`` (``P[0]`` kept).
        Open polyline: ``linspace(0, L, n)``, so both endpoints are kept.

    Returns
    -------
    (n, 3) float64
    """
    P = _points(P)
    n = int(n)
    if n < (3 if closed else 2) or len(P) < 2:
        raise MeshRepairError(f"cannot resample a polyline of {len(P)} points to {n} points")
    Q = np.vstack([P, P[:1]]) if closed else P
    s, total = arc_length_parameters(Q, closed=False)
    if not total > 0:
        raise MeshRepairError("the polyline has zero length; its points all coincide")
    t = np.arange(n) * (total / n) if closed else np.linspace(0.0, total, n)
    k = np.clip(np.searchsorted(s, t, side="right") - 1, 0, len(Q) - 2)
    seg = s[k + 1] - s[k]
    w = np.divide(t - s[k], seg, out=np.zeros_like(t), where=seg > 0)
    out = Q[k] + w[:, None] * (Q[k + 1] - Q[k])
    if not closed:
        out[-1] = P[-1]
    return out


def uniform_split_params(P: np.ndarray, n_target: int) -> list[np.ndarray]:
    """Where to split the edges of a closed loop to reach ``n_target`` vertices.

    Greedy: each extra vertex goes to the edge whose current pieces are longest, and an edge
    split ``k`` times is cut into ``k + 1`` equal pieces, so the arc-length spacing becomes as
    uniform as possible while every original vertex is kept.

    Parameters
    ----------
    P : (n, 3) float, loop vertices (edge ``i`` joins ``P[i]`` and ``P[(i+1) % n]``)
    n_target : int >= n

    Returns
    -------
    list of n arrays
        ``params[i]``: sorted fractions in (0, 1) along edge ``i``.
    """
    P = _points(P)
    n = len(P)
    extra = int(n_target) - n
    if extra < 0:
        raise MeshRepairError(f"cannot split a loop of {n} vertices down to {n_target} vertices")
    lengths = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    counts = np.zeros(n, dtype=np.int64)
    heap = [(-float(lengths[i]), i) for i in range(n)]
    heapq.heapify(heap)
    for _ in range(extra):
        _, i = heapq.heappop(heap)
        counts[i] += 1
        heapq.heappush(heap, (-float(lengths[i]) / (counts[i] + 1), i))
    return [np.arange(1, c + 1, dtype=np.float64) / (c + 1) for c in counts]


def split_boundary_edges(V: np.ndarray, F: np.ndarray, loop: np.ndarray,
                         params: list[np.ndarray]
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Insert vertices on the edges of a boundary loop, fanning the faces they belong to.

    Edge ``i`` of the loop is the boundary half-edge ``(loop[i], loop[i+1])`` of a face
    ``(u, v, w)`` (the loop must follow the face orientation, as
    :func:`meshrepair.topology.boundary_loops` returns it). Splitting it at fractions
    ``t_1 < ... < t_k`` adds vertices ``p_j = u + t_j (v - u)`` and replaces the face with the fan
    ``(u, p_1, w), (p_1, p_2, w), ..., (p_k, v, w)``: same orientation, same surface, a valid
    mesh. Faces that own two loop edges are handled (the edges are split one after the other).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    loop : (n,) int, a boundary loop following the face orientation
    params : list of n arrays of fractions in (0, 1) (empty arrays for edges not split)

    Returns
    -------
    V2 : (nV + k, 3) float64, new vertices appended after the old ones
    F2 : (nF + k, 3) int64, the split faces replaced in place, new faces appended
    loop2 : (n + k,) int64, the refined loop (old vertices keep their order)
    new_vertices : (k,) int64, indices of the inserted vertices in loop order
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    loop = np.asarray(loop, dtype=np.int64)
    n = len(loop)
    if len(params) != n:
        raise MeshRepairError(f"need one parameter array per loop edge ({n}), got {len(params)}")
    total = int(sum(len(p) for p in params))
    if total == 0:
        return V.copy(), F.copy(), loop.copy(), np.zeros(0, np.int64)
    he_face: dict[tuple[int, int], int] = {}
    for m, (a, b, c) in enumerate(F.tolist()):
        he_face[(a, b)] = m
        he_face[(b, c)] = m
        he_face[(c, a)] = m
    newV = [V]
    Fl = F.tolist()
    nxt = len(V)
    loop2: list[int] = []
    new_vertices: list[int] = []
    for i in range(n):
        u, v = int(loop[i]), int(loop[(i + 1) % n])
        loop2.append(u)
        t = np.sort(np.asarray(params[i], dtype=np.float64).ravel())
        if t.size == 0:
            continue
        if (t <= 0).any() or (t >= 1).any() or (np.diff(t) <= 0).any():
            raise MeshRepairError(f"split fractions of loop edge {i} must be distinct and in "
                                  f"(0, 1), got {t.tolist()}")
        m = he_face.get((u, v))
        if m is None:
            raise MeshRepairError(f"({u}, {v}) is not a boundary half-edge of the mesh: the loop "
                                  "must follow the face orientation (use topology.boundary_loops)")
        face = Fl[m]
        k = face.index(u)
        w = face[(k + 2) % 3]
        P = V[u] + t[:, None] * (V[v] - V[u])
        idx = list(range(nxt, nxt + len(t)))
        nxt += len(t)
        newV.append(P)
        chain = [u, *idx, v]
        del he_face[(u, v)]
        for j in range(len(chain) - 1):
            tri = [chain[j], chain[j + 1], w]
            if j == 0:
                Fl[m] = tri
                fm = m
            else:
                Fl.append(tri)
                fm = len(Fl) - 1
            he_face[(tri[0], tri[1])] = fm
            he_face[(tri[1], tri[2])] = fm
            he_face[(tri[2], tri[0])] = fm
        loop2.extend(idx)
        new_vertices.extend(idx)
    return (np.vstack(newV), np.asarray(Fl, dtype=np.int64), np.asarray(loop2, np.int64),
            np.asarray(new_vertices, np.int64))


def subdivide_loop(V: np.ndarray, F: np.ndarray, loop: np.ndarray, n_target: int
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Split the edges of a boundary loop until it has ``n_target`` vertices (uniformly).

    Combines :func:`uniform_split_params` and :func:`split_boundary_edges`; see there.
    """
    V = np.asarray(V, dtype=np.float64)
    return split_boundary_edges(V, F, loop, uniform_split_params(V[np.asarray(loop)], n_target))


# ------------------------------------------------------------------------------------------------
# alignment
# ------------------------------------------------------------------------------------------------

def apply_transform(T: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Apply a 4x4 transform to points ``(n, 3)``; returns a new ``(n, 3)`` float64 array."""
    T = np.asarray(T, dtype=np.float64)
    P = np.asarray(P, dtype=np.float64)
    return P @ T[:3, :3].T + T[:3, 3]


def _rotation_from_svd(U: np.ndarray, Vt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Proper rotation(s) ``U diag(1, 1, d) Vt`` and the sign(s) ``d`` (batched)."""
    d = np.sign(np.linalg.det(U) * np.linalg.det(Vt))
    d = np.where(d == 0, 1.0, d)
    D = np.ones(U.shape[:-2] + (3,))
    D[..., 2] = d
    return (U * D[..., None, :]) @ Vt, d


def umeyama(src: np.ndarray, dst: np.ndarray, *, scale: bool = False,
            weights: np.ndarray | None = None) -> np.ndarray:
    """Least-squares rigid or similarity transform mapping ``src`` onto ``dst`` (Umeyama 1991).

    Minimises ``sum_i w_i |c R src_i + t - dst_i|^2`` over rotations ``R`` (det +1), translations
    ``t`` and, with ``scale=True``, a uniform scale ``c > 0`` (else ``c = 1``, Kabsch).

    Parameters
    ----------
    src, dst : (n, 3) float, corresponding points (n >= 3 for a unique rotation)
    scale : bool
    weights : (n,) float >= 0, optional

    Returns
    -------
    T : (4, 4) float64
    """
    src = _points(src, "src")
    dst = _points(dst, "dst")
    if src.shape != dst.shape or len(src) == 0:
        raise MeshRepairError(f"src and dst must have the same shape (n, 3), got {src.shape} "
                              f"and {dst.shape}")
    w = np.ones(len(src)) if weights is None else np.asarray(weights, dtype=np.float64)
    if w.shape != (len(src),) or (w < 0).any() or not w.sum() > 0:
        raise MeshRepairError("weights must be (n,) non-negative with a positive sum")
    w = w / w.sum()
    mu_s = w @ src
    mu_d = w @ dst
    S = src - mu_s
    D = dst - mu_d
    H = (D * w[:, None]).T @ S
    U, sig, Vt = np.linalg.svd(H)
    R, d = _rotation_from_svd(U, Vt)
    c = 1.0
    if scale:
        var = float(w @ np.einsum("ij,ij->i", S, S))
        if not var > 0:
            raise MeshRepairError("src points all coincide: the scale is undefined")
        c = float((sig[0] + sig[1] + d * sig[2]) / var)
    T = np.eye(4)
    T[:3, :3] = c * R
    T[:3, 3] = mu_d - c * R @ mu_s
    return T


@dataclass(frozen=True)
class CyclicAlignment:
    """Result of :func:`best_cyclic_alignment`.

    Attributes
    ----------
    shift : int
    reversed : bool
        Vertex ``i`` of ``A`` corresponds to ``B[(i + shift) % n]`` (not reversed) or to
        ``B[(shift - i) % n]`` (reversed).
    transform : (4, 4) float64, maps ``B`` onto ``A`` (identity for ``fit="none"``).
    rms : float, RMS distance ``|A_i - T B_sigma(i)|`` at the optimum.
    rms_other_direction : float, best RMS with the other direction (inf if not tried).
    """

    shift: int
    reversed: bool
    transform: np.ndarray
    rms: float
    rms_other_direction: float = float("inf")

    def indices(self, n: int) -> np.ndarray:
        """(n,) int64: the index into ``B`` matched with each vertex of ``A``."""
        i = np.arange(n)
        return ((self.shift - i) if self.reversed else (self.shift + i)) % n


def _shift_covariances(A: np.ndarray, B: np.ndarray, reverse: bool) -> np.ndarray:
    """``H[s] = sum_i A_i B_sigma_s(i)^T`` for all shifts ``s`` (``(n, 3, 3)``), via the FFT."""
    n = len(A)
    fa = np.fft.rfft(A, axis=0)
    fb = np.fft.rfft(B, axis=0)
    if reverse:  # sigma(i) = s - i: circular convolution
        prod = fa[:, :, None] * fb[:, None, :]
    else:  # sigma(i) = s + i: circular correlation
        prod = np.conj(fa)[:, :, None] * fb[:, None, :]
    return np.fft.irfft(prod, n=n, axis=0)


def best_cyclic_alignment(A: np.ndarray, B: np.ndarray, *, fit: str = "rigid",
                          directions: tuple[bool, ...] = (False, True)) -> CyclicAlignment:
    """Best cyclic shift and direction between two closed loops with the same vertex count.

    For every shift ``s`` and each direction in ``directions`` (``False`` forward, ``True``
    reversed) the optimal transform of ``fit`` is computed in closed form, and the pair with the
    least sum of squared distances is returned. All ``n`` cross-covariances come from one FFT per
    direction and the 3x3 SVDs are batched: O(n log n + n) work.

    Parameters
    ----------
    A : (n, 3) float, target loop
    B : (n, 3) float, loop to be matched onto ``A``
    fit : ``"none"`` (loops already aligned: plain squared distances), ``"rigid"`` (rotation and
        translation) or ``"similarity"`` (also a uniform scale).
    directions : which directions to try.

    Returns
    -------
    CyclicAlignment
    """
    A = _points(A, "loop A")
    B = _points(B, "loop B")
    if fit not in FITS:
        raise MeshRepairError(f"fit must be one of {FITS}, got {fit!r}")
    if A.shape != B.shape or len(A) < 3:
        raise MeshRepairError(f"both loops need the same number (>= 3) of vertices, got {len(A)} "
                              f"and {len(B)}; resample one first")
    if not directions:
        raise MeshRepairError("at least one direction must be tried")
    n = len(A)
    best: dict[bool, tuple[float, int, np.ndarray]] = {}
    for rev in directions:
        if fit == "none":
            H = _shift_covariances(A, B, rev)
            res = (A * A).sum() + (B * B).sum() - 2.0 * np.trace(H, axis1=1, axis2=2)
            s = int(np.argmin(res))
            best[rev] = (max(float(res[s]), 0.0), s, np.eye(4))
            continue
        muA, muB = A.mean(axis=0), B.mean(axis=0)
        Ac, Bc = A - muA, B - muB
        H = _shift_covariances(Ac, Bc, rev)
        U, sig, Vt = np.linalg.svd(H)
        _, d = _rotation_from_svd(U, Vt)
        tr = sig[:, 0] + sig[:, 1] + d * sig[:, 2]
        sa, sb = float((Ac * Ac).sum()), float((Bc * Bc).sum())
        res = sa - tr**2 / sb if fit == "similarity" else sa + sb - 2.0 * tr
        s = int(np.argmin(res))
        idx = ((s - np.arange(n)) if rev else (s + np.arange(n))) % n
        T = umeyama(B[idx], A, scale=fit == "similarity")
        best[rev] = (max(float(res[s]), 0.0), s, T)
    def exact_rms(rev: bool) -> float:  # the FFT residual loses digits by cancellation
        _, s, T = best[rev]
        idx = ((s - np.arange(n)) if rev else (s + np.arange(n))) % n
        return float(np.sqrt(np.mean(np.sum((apply_transform(T, B[idx]) - A) ** 2, axis=1))))

    rev = min(best, key=lambda r: best[r][0])
    _, s, T = best[rev]
    other = [exact_rms(r) for r in best if r != rev]
    return CyclicAlignment(shift=s, reversed=bool(rev), transform=T, rms=exact_rms(rev),
                           rms_other_direction=other[0] if other else float("inf"))


def closest_points_on_loop(P: np.ndarray, loop: np.ndarray, *, samples_per_edge: int = 8,
                           _cache: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Exact closest points on a closed polyline.

    Candidate edges come from a k-d tree of ``samples_per_edge`` samples per edge; the exact
    projection onto the candidate edge and its two neighbours is kept.

    Parameters
    ----------
    P : (m, 3) float, query points
    loop : (n, 3) float, closed polyline

    Returns
    -------
    Q : (m, 3) float64, closest points
    d : (m,) float64, distances
    """
    from scipy.spatial import cKDTree

    P = _points(P)
    loop = _points(loop, "loop")
    n = len(loop)
    key = id(loop)
    if _cache is not None and key in _cache:
        tree, k = _cache[key]
    else:
        k = max(1, int(samples_per_edge))
        nxt = np.roll(loop, -1, axis=0)
        t = (np.arange(k) + 0.5) / k
        dense = (loop[:, None, :] + t[None, :, None] * (nxt - loop)[:, None, :]).reshape(-1, 3)
        tree = cKDTree(dense)
        if _cache is not None:
            _cache[key] = (tree, k)
    _, s = tree.query(P)
    e0 = s // k
    best_q = np.zeros_like(P)
    best_d = np.full(len(P), np.inf)
    for off in (-1, 0, 1):
        e = (e0 + off) % n
        a, b = loop[e], loop[(e + 1) % n]
        ab = b - a
        den = np.einsum("ij,ij->i", ab, ab)
        t = np.divide(np.einsum("ij,ij->i", P - a, ab), den, out=np.zeros(len(P)),
                      where=den > 0)
        q = a + np.clip(t, 0.0, 1.0)[:, None] * ab
        d = np.linalg.norm(P - q, axis=1)
        better = d < best_d
        best_d[better] = d[better]
        best_q[better] = q[better]
    return best_q, best_d


def icp_loop_to_polyline(P: np.ndarray, target: np.ndarray, *, scale: bool = False,
                         max_iter: int = 30, tol: float = 1e-9
                         ) -> tuple[np.ndarray, float, float]:
    """Refine the placement of points ``P`` onto a closed target polyline (ICP).

    Each iteration pairs every point with its exact closest point on the polyline
    (:func:`closest_points_on_loop`) and fits :func:`umeyama` to the pairs.

    Parameters
    ----------
    P : (m, 3) float, e.g. the (resampled) template boundary after a first alignment
    target : (n, 3) float, closed loop
    scale : bool, also fit a uniform scale
    max_iter : int
    tol : stop when the RMS improves by less than ``tol`` relative

    Returns
    -------
    T : (4, 4) float64, to be applied after the transform that produced ``P``
    rms_before, rms_after : float, RMS closest-point distances before and after (the returned
        ``T`` is the best iterate, so ``rms_after <= rms_before``)
    """
    P = _points(P)
    target = _points(target, "target")
    cache: dict = {}
    T = np.eye(4)
    Q = P.copy()
    C, d = closest_points_on_loop(Q, target, _cache=cache)
    rms0 = rms = float(np.sqrt(np.mean(d**2)))
    best_T, best_rms = T, rms
    for _ in range(int(max_iter)):
        T = umeyama(Q, C, scale=scale) @ T
        Q = apply_transform(T, P)
        C, d = closest_points_on_loop(Q, target, _cache=cache)
        new = float(np.sqrt(np.mean(d**2)))
        if new < best_rms:
            best_T, best_rms = T, new
        if rms - new <= tol * max(rms, 1e-300):
            break
        rms = new
    return best_T, rms0, best_rms


def _closest_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray
                          ) -> np.ndarray:
    """Row-wise closest point to ``p`` on triangle ``abc`` (see metrics)."""
    from .metrics import closest_points_on_triangles

    return closest_points_on_triangles(p, a, b, c)


def closest_points_on_mesh(P: np.ndarray, V: np.ndarray, F: np.ndarray, *, candidates: int = 8,
                           _tree=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest points on a triangle mesh.

    Exact point-triangle projections against the ``candidates`` faces with the nearest
    centroids (a k-d tree), vectorised.

    Parameters
    ----------
    P : (m, 3) float, query points
    V : (nV, 3) float
    F : (nF, 3) int

    Returns
    -------
    Q : (m, 3) float64, closest points found
    d : (m,) float64, distances
    face : (m,) int64, the face each closest point lies on
    """
    from scipy.spatial import cKDTree

    P = _points(P)
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    tree = cKDTree(V[F].mean(axis=1)) if _tree is None else _tree
    k = max(1, min(int(candidates), len(F)))
    _, idx = tree.query(P, k=k)
    idx = np.asarray(idx).reshape(len(P), k)
    best_q = np.zeros_like(P)
    best_d = np.full(len(P), np.inf)
    best_f = np.zeros(len(P), np.int64)
    for j in range(k):
        tri = V[F[idx[:, j]]]
        q = _closest_on_triangles(P, tri[:, 0], tri[:, 1], tri[:, 2])
        d = np.linalg.norm(P - q, axis=1)
        better = d < best_d
        best_d[better] = d[better]
        best_q[better] = q[better]
        best_f[better] = idx[better, j]
    return best_q, best_d, best_f


def _rotation_vector(w: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector ``w`` (Rodrigues)."""
    th = float(np.linalg.norm(w))
    if th < 1e-300:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def icp_to_surface(P: np.ndarray, V: np.ndarray, F: np.ndarray, *, scale: bool = False,
                   max_iter: int = 40, tol: float = 1e-10, trim: float = 3.0,
                   point_weight: float = 1e-3) -> tuple[np.ndarray, float, float]:
    """Refine the placement of points ``P`` onto a triangle mesh (trimmed point-to-plane ICP).

    Each iteration pairs the points with their closest points ``q_i`` on ``(V, F)``
    (:func:`closest_points_on_mesh`, face normal ``n_i``), drops pairs farther than ``trim``
    times the median distance (robust to a damaged or partial target) and takes one
    Gauss-Newton step of ``sum_i (n_i . r_i)^2 + point_weight |r_i|^2`` over a small rotation,
    a translation and (``scale=True``) a scale, ``r_i`` being the residual ``p_i - q_i`` after the
    step. The point-to-plane term converges fast; the small point-to-point term keeps flat parts
    from sliding.

    Parameters
    ----------
    P : (m, 3) float, e.g. the template's vertices near its boundary after a first alignment
    V, F : the target surface
    scale : bool, also fit a uniform scale
    max_iter : int
    tol : stop when the trimmed RMS improves by less than ``tol`` relative
    trim : float > 1
    point_weight : float >= 0

    Returns
    -------
    T : (4, 4) float64, the best iterate (possibly the identity), to be applied after the
        transform that produced ``P``
    rms_before, rms_after : float, trimmed RMS distances of the identity and of ``T``
    """
    from scipy.spatial import cKDTree

    from .geometry import face_normals

    P = _points(P)
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    tree = cKDTree(V[F].mean(axis=1))
    FN = face_normals(V, F)
    ext = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))) or 1.0

    def pairs(Q):
        C, d, f = closest_points_on_mesh(Q, V, F, _tree=tree)
        med = float(np.median(d))
        keep = d <= trim * med if med > 1e-12 * ext else np.ones(len(d), bool)
        return C, FN[f], keep, float(np.sqrt(np.mean(d[keep] ** 2)))

    T = np.eye(4)
    C, N, keep, rms = pairs(P)
    rms0 = best_rms = rms
    best_T = T
    nu = 7 if scale else 6
    for _ in range(int(max_iter)):
        if keep.sum() < nu:
            break
        Q = apply_transform(T, P)[keep]
        c = Q.mean(axis=0)
        X = (Q - c) / ext  # conditioned coordinates
        r0 = (Q - C[keep]) / ext
        n = N[keep]
        m = len(X)
        # J_i (3 x nu): d r_i / d(w, t[, s]) = [-[X_i]x, I, X_i]
        J = np.zeros((m, 3, nu))
        J[:, 0, 1], J[:, 0, 2] = X[:, 2], -X[:, 1]
        J[:, 1, 0], J[:, 1, 2] = -X[:, 2], X[:, 0]
        J[:, 2, 0], J[:, 2, 1] = X[:, 1], -X[:, 0]
        J[:, :, 3:6] = np.eye(3)
        if scale:
            J[:, :, 6] = X
        Jn = np.einsum("ij,ijk->ik", n, J)
        rn = np.einsum("ij,ij->i", n, r0)
        H = Jn.T @ Jn + point_weight * np.einsum("ijk,ijl->kl", J, J)
        g = Jn.T @ rn + point_weight * np.einsum("ijk,ij->k", J, r0)
        try:
            x = -np.linalg.solve(H + 1e-12 * np.eye(nu), g)
        except np.linalg.LinAlgError:
            break
        R = _rotation_vector(x[:3])
        sc = 1.0 + (x[6] if scale else 0.0)
        step = np.eye(4)
        step[:3, :3] = sc * R
        step[:3, 3] = c - sc * R @ c + x[3:6] * ext
        T = step @ T
        C, N, keep, new = pairs(apply_transform(T, P))
        if new < best_rms:
            best_T, best_rms = T, new
        if rms - new <= tol * max(rms, 1e-300):
            break
        rms = new
    return best_T, rms0, best_rms


# ------------------------------------------------------------------------------------------------
# monotone matching of loops with different vertex counts
# ------------------------------------------------------------------------------------------------

def _monotone_dp(C: np.ndarray) -> tuple[float, np.ndarray]:
    """Min-cost strictly increasing ``j_0 = 0 < j_1 < ... < j_{m-1} < n`` for costs ``C (m, n)``."""
    m, n = C.shape
    inf = np.inf
    D = np.full(n, inf)
    D[0] = C[0, 0]
    back = np.zeros((m, n), dtype=np.int32)
    ar = np.arange(n)
    for i in range(1, m):
        pm = np.minimum.accumulate(D)
        am = np.maximum.accumulate(np.where(D == pm, ar, 0))
        Dn = np.full(n, inf)
        Dn[1:] = C[i, 1:] + pm[:-1]
        back[i, 1:] = am[:-1]
        Dn[: i] = inf
        Dn[n - m + i + 1:] = inf
        D = Dn
    j = np.zeros(m, dtype=np.int64)
    j[-1] = int(np.argmin(D))
    cost = float(D[j[-1]])
    for i in range(m - 1, 0, -1):
        j[i - 1] = back[i, j[i]]
    return cost, j


def monotone_loop_match(A: np.ndarray, B: np.ndarray, *, anchors: int = 6
                        ) -> tuple[np.ndarray, float]:
    """Order-preserving matching of a closed loop ``A`` into a longer closed loop ``B``.

    Both loops must run in the same direction and be aligned in space. Every vertex of ``A`` is
    matched with a distinct vertex of ``B`` so that the matched indices increase cyclically and
    the sum of squared distances is least (dynamic programming, O(len(A) len(B)) per anchor); the
    unmatched vertices of ``B`` between two matched ones tell where the edge of ``A`` between them
    has to be split. The anchor ``A[0] <-> B[j_0]`` is tried for the ``anchors`` vertices of
    ``B`` nearest to ``A[0]``.

    Parameters
    ----------
    A : (m, 3) float
    B : (n, 3) float with n >= m
    anchors : int

    Returns
    -------
    j : (m,) int64, cyclically increasing indices into ``B`` (``j[0]`` the anchor)
    rms : float, RMS distance of the matched pairs
    """
    A = _points(A, "loop A")
    B = _points(B, "loop B")
    m, n = len(A), len(B)
    if n < m:
        raise MeshRepairError(f"loop B ({n} vertices) must not be shorter than loop A ({m})")
    C = ((A[:, None, :] - B[None, :, :]) ** 2).sum(axis=2)
    if n == m:  # only the cyclic shift is free
        i = np.arange(m)
        costs = np.array([C[i, (i + s) % n].sum() for s in range(n)])
        s = int(np.argmin(costs))
        return (i + s) % n, float(np.sqrt(costs[s] / m))
    cand = np.argsort(C[0])[: max(1, min(int(anchors), n))]
    best = (np.inf, None)
    for c in cand:
        order = (np.arange(n) + c) % n
        cost, j = _monotone_dp(C[:, order])
        if cost < best[0]:
            best = (cost, order[j])
    return best[1].astype(np.int64), float(np.sqrt(best[0] / m))


# ------------------------------------------------------------------------------------------------
# common refinement of two loops (matches and insertions on both sides)
# ------------------------------------------------------------------------------------------------

@dataclass
class LoopAlignment:
    """Result of :func:`align_loops`: how two closed loops are refined to a common sampling.

    Attributes
    ----------
    params_A : list of len(A) arrays, split fractions per edge ``A[i] -> A[i+1]`` (B vertices
        inserted into A)
    params_B : list of len(B) arrays, split fractions per edge ``B[j] -> B[j+1]``
    anchor : int, the vertex of ``B`` matched with ``A[0]``
    n_matched : int, vertex pairs matched directly
    n_common : int, vertices of the common refinement (``len(A) + len(B) - n_matched``)
    rms : float, RMS distance of the paired points of the refinement (after splitting)
    max_distance : float, the largest such distance
    """

    params_A: list
    params_B: list
    anchor: int
    n_matched: int
    n_common: int
    rms: float
    max_distance: float


def _seg_point(P: np.ndarray, a: np.ndarray, b: np.ndarray, lo: float, hi: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Fraction (clamped to [lo, hi]) and squared distance of ``P`` to segments ``a -> b``.

    Shapes broadcast: P (m, 1, 3) against a, b (1, n, 3) gives (m, n).
    """
    ab = b - a
    den = np.maximum((ab * ab).sum(-1), 1e-300)
    t = np.clip(((P - a) * ab).sum(-1) / den, lo, hi)
    q = a + t[..., None] * ab
    return t, ((P - q) ** 2).sum(-1)


def _align_dp(A: np.ndarray, B: np.ndarray, insert_penalty: float, margin: float):
    """Global alignment of A[0..m) with B[0..n) with A[0] <-> B[0] matched (see align_loops)."""
    m, n = len(A), len(B)
    An, Bn = np.roll(A, -1, axis=0), np.roll(B, -1, axis=0)
    hA = ((An - A) ** 2).sum(1)
    hB = ((Bn - B) ** 2).sum(1)
    cm = ((A[:, None, :] - B[None, :, :]) ** 2).sum(-1)
    tA, ca = _seg_point(A[:, None, :], B[None], Bn[None], margin, 1 - margin)  # A_i into B_j
    ca = ca + insert_penalty * hB[None, :]
    tB, cb = _seg_point(B[None, :, :], A[:, None], An[:, None], margin, 1 - margin)  # B_j in A_i
    cb = cb + insert_penalty * hA[:, None]
    inf = np.inf
    move = np.zeros((m, n), np.int8)  # 0 match, 1 A_i inserted (up), 2 B_j inserted (left)
    D = np.full(n, inf)
    D[0] = cm[0, 0]
    # row 0: A_0 matched with B_0, then B_1.. inserted into edge A_0 -> A_1
    D[1:] = cm[0, 0] + np.cumsum(cb[0, 1:])
    move[0, 1:] = 2
    for i in range(1, m):
        X = np.full(n, inf)
        X[1:] = D[:-1] + cm[i, 1:]  # match (i, j) after (i-1, j-1)
        up = D + ca[i]  # A_i inserted after B_j
        mv = np.where(up < X, 1, 0).astype(np.int8)
        X = np.minimum(X, up)
        c = cb[i].copy()
        c[0] = 0.0
        P = np.cumsum(c)
        Y = X - P
        run = np.minimum.accumulate(Y)
        am = np.maximum.accumulate(np.where(Y == run, np.arange(n), 0))
        D = P + run
        move[i] = np.where(am < np.arange(n), 2, mv)
        D[0] = X[0]
        move[i, 0] = mv[0]
    # backtrack from (m-1, n-1)
    i, j = m - 1, n - 1
    events = []  # (kind, i, j)
    while i > 0 or j > 0:
        k = int(move[i, j])
        events.append((k, i, j))
        if k == 0:
            i, j = i - 1, j - 1
        elif k == 1:
            i -= 1
        else:
            j -= 1
    events.append((0, 0, 0))
    events.reverse()
    return float(D[n - 1]), events, tA, tB


def align_loops(A: np.ndarray, B: np.ndarray, *, anchors: int = 6, insert_penalty: float = 0.03,
                margin: float = 0.15) -> LoopAlignment:
    """Common refinement of two aligned closed loops running in the same direction.

    Sequence alignment (Needleman-Wunsch on the cyclic sequences, anchored at ``A[0]``): each
    vertex is either matched with a vertex of the other loop (cost: squared distance) or
    inserted on the other loop's edge at its projection (cost: squared distance to that point
    plus ``insert_penalty`` times the squared length of the edge split; projections are clamped
    to ``[margin, 1 - margin]`` of the edge so no sliver triangles appear). Splitting both loops
    with ``params_A`` / ``params_B`` (see :func:`split_boundary_edges`) gives two loops with the
    same vertex count whose ``k``-th vertices correspond. Compared with matching vertices only
    (:func:`monotone_loop_match`), paired points are at most about the loops' *normal* offset
    apart, not their tangential sampling offset. Each row of the dynamic programme is vectorised
    (a min-plus prefix scan); O(len(A) len(B)) per anchor candidate.

    Parameters
    ----------
    A, B : (m, 3), (n, 3) float
    anchors : int, number of vertices of ``B`` nearest to ``A[0]`` tried as its partner
    insert_penalty : float >= 0
    margin : float in [0, 0.5)

    Returns
    -------
    LoopAlignment
    """
    A = _points(A, "loop A")
    B = _points(B, "loop B")
    m, n = len(A), len(B)
    if m < 3 or n < 3:
        raise MeshRepairError("loops need at least 3 vertices")
    if not 0 <= margin < 0.5 or insert_penalty < 0:
        raise MeshRepairError("need 0 <= margin < 0.5 and insert_penalty >= 0")
    d0 = ((B - A[0]) ** 2).sum(1)
    best = None
    for c in np.argsort(d0)[: max(1, min(int(anchors), n))]:
        Bc = np.roll(B, -int(c), axis=0)
        cost, events, tA, tB = _align_dp(A, Bc, insert_penalty, margin)
        if best is None or cost < best[0]:
            best = (cost, int(c), events, tA, tB)
    cost, c, events, tA, tB = best
    pA: list[list[float]] = [[] for _ in range(m)]
    pB: list[list[float]] = [[] for _ in range(n)]
    n_match = 0
    d2 = []
    for kind, i, j in events:
        jb, jn = (j + c) % n, (j + 1 + c) % n
        if kind == 0:
            n_match += 1
            d2.append(float(((A[i] - B[jb]) ** 2).sum()))
        elif kind == 1:  # A_i inserted on (rolled) B edge j
            pB[jb].append(float(tA[i, j]))
            q = B[jb] + tA[i, j] * (B[jn] - B[jb])
            d2.append(float(((A[i] - q) ** 2).sum()))
        else:  # B_j inserted on A edge i
            pA[i].append(float(tB[i, j]))
            q = A[i] + tB[i, j] * (A[(i + 1) % m] - A[i])
            d2.append(float(((B[jb] - q) ** 2).sum()))

    def fix(ts: list[float]) -> np.ndarray:
        t = np.asarray(ts, dtype=np.float64)
        if t.size == 0:
            return t
        if t.size > 1 and (np.diff(t) <= 1e-6).any():  # keep sequence order, spread evenly
            t = np.linspace(max(margin, 0.05), min(1 - margin, 0.95), t.size)
        return t

    params_A = [fix(t) for t in pA]
    params_B = [fix(t) for t in pB]
    n_common = m + n - n_match
    d2a = np.asarray(d2)
    return LoopAlignment(params_A=params_A, params_B=params_B, anchor=c, n_matched=n_match,
                         n_common=n_common, rms=float(np.sqrt(d2a.mean())),
                         max_distance=float(np.sqrt(d2a.max())))
