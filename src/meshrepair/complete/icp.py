"""Iterative closest point refinement of a placement (loops and surfaces), paper Sect. 5.

* exact closest points on a closed polyline (:func:`closest_points_on_loop`) and on a triangle
  mesh (:func:`closest_points_on_mesh`);
* ICP of points against a closed polyline (:func:`icp_loop_to_polyline`, point-to-point with
  :func:`~meshrepair.complete.rigid.umeyama`);
* trimmed point-to-plane ICP of points against a surface (:func:`icp_to_surface`).

Each returns the best iterate, so a refinement never makes a placement worse by its own measure.
"""

from __future__ import annotations

import numpy as np

from meshrepair.complete.rigid import _points, apply_transform, umeyama

__all__ = ["closest_points_on_loop", "closest_points_on_mesh", "icp_loop_to_polyline",
           "icp_to_surface"]


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
    from meshrepair.metrics import closest_points_on_triangles

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

    from meshrepair.mesh.geometry import face_normals

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
