"""Error metrics of the paper's Sect. 6 (MSAE (33), E_V (34)) and distances to a reference
surface."""

from __future__ import annotations

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.geometry import face_normals


def _same_shape(V: np.ndarray, V_ref: np.ndarray) -> None:
    if V.shape != V_ref.shape:
        raise MeshRepairError(
            f"the result has {len(V)} vertices but the reference has {len(V_ref)}; MSAE and E_V "
            "compare corresponding vertices, so both meshes must share connectivity "
            "(use distances() for meshes with different connectivity)"
        )


def _points(X, name: str) -> np.ndarray:
    X = np.asarray(X, dtype=np.float64)
    if X.ndim != 2 or X.shape[1] != 3:
        raise MeshRepairError(f"{name} must have shape (n, 3), got {X.shape}")
    bad = ~np.isfinite(X).all(axis=1)
    if bad.any():
        raise MeshRepairError(f"{name} has {int(bad.sum())} non-finite (NaN/inf) points (first: "
                              f"{np.flatnonzero(bad)[:5].tolist()}); metrics need finite "
                              "coordinates")
    return X


def _faces(F, n_vertices: int, name: str) -> np.ndarray:
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3 or len(F) == 0:
        raise MeshRepairError(f"{name} must be a non-empty (nF, 3) face array, got shape "
                              f"{F.shape}")
    if not np.issubdtype(F.dtype, np.integer):
        raise MeshRepairError(f"{name} must hold integer vertex indices, got {F.dtype}")
    if F.min() < 0 or F.max() >= n_vertices:
        raise MeshRepairError(f"{name} has indices outside [0, {n_vertices - 1}]")
    return F.astype(np.int64, copy=False)


def msae(V: np.ndarray, V_ref: np.ndarray, F: np.ndarray, *, degrees: bool = True,
         faces: np.ndarray | None = None) -> float:
    """Mean squared angular error (33) between corresponding face normals.

    Parameters
    ----------
    V, V_ref : (nV, 3) result and ground truth with the same connectivity F
    F : (nF, 3)
    degrees : report in degrees² (default) or radians²
    faces : (nF,) bool, optional: average over these faces only (for example the well-shaped
        ones, ``min_face_angles(V_ref, F) >= 5``; see :func:`min_face_angles`)

    Returns
    -------
    float
    """
    ang = _normal_angles(V, V_ref, F)
    if degrees:
        ang = np.degrees(ang)
    if faces is not None:
        mask = np.asarray(faces)
        if mask.dtype != bool or mask.shape != ang.shape:
            raise MeshRepairError(f"faces must be a boolean mask of shape ({len(ang)},), got "
                                  f"{mask.dtype} {mask.shape}")
        if not mask.any():
            raise MeshRepairError("faces selects no face; MSAE of an empty set is undefined")
        ang = ang[mask]
    return float(np.mean(ang**2))


def min_face_angles(V: np.ndarray, F: np.ndarray, *, degrees: bool = True) -> np.ndarray:
    """The smallest interior angle of every face, ``(nF,)``.

    A face's normal is the direction of ``(v_1 − v_0) × (v_2 − v_0)``; moving one of its
    vertices by ``δ`` off its plane turns it by about ``δ / h``, ``h`` the face's smallest
    height, and ``h ≈ ℓ sin(θ_min)`` for its longest edge ``ℓ``. A sliver (``θ_min`` of a few
    degrees) therefore has a normal that noise of a small fraction of an edge turns by tens of
    degrees, and the MSAE (33), which weighs every face alike, can be dominated by such faces
    (``benchmarks/monotone.py`` reports it with and without them).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    degrees : degrees (default) or radians

    Returns
    -------
    (nF,) float64; 0 for a degenerate face (a zero-length edge)
    """
    V = _points(V, "V")
    F = _faces(F, len(V), "F")
    P = V[F]
    e = P[:, [1, 2, 0]] - P  # e_j = v_{j+1} − v_j
    length = np.linalg.norm(e, axis=2)
    ang = np.empty((len(F), 3))
    for j in range(3):  # the angle at v_j, between e_j and −e_{j−1}
        a, b = e[:, j], -e[:, j - 1]
        den = length[:, j] * length[:, j - 1]
        c = np.einsum("ij,ij->i", a, b) / np.where(den > 0, den, 1.0)
        ang[:, j] = np.where(den > 0, np.arccos(np.clip(c, -1.0, 1.0)), 0.0)
    out = ang.min(axis=1)
    return np.degrees(out) if degrees else out


def mean_angle_error(V: np.ndarray, V_ref: np.ndarray, F: np.ndarray, *,
                     degrees: bool = True) -> float:
    """E_a: mean angle between corresponding face normals (what most denoising papers report
    beside (33)).

    Parameters
    ----------
    V, V_ref : (nV, 3) result and ground truth with the same connectivity F
    F : (nF, 3)
    degrees : report in degrees (default) or radians

    Returns
    -------
    float
    """
    ang = _normal_angles(V, V_ref, F)
    return float(np.mean(np.degrees(ang) if degrees else ang))


def _normal_angles(V, V_ref, F) -> np.ndarray:
    """Angles (radians) between the face normals of ``V`` and ``V_ref`` on ``F``, ``(nF,)``."""
    V, V_ref = _points(V, "V"), _points(V_ref, "V_ref")
    _same_shape(V, V_ref)
    F = _faces(F, len(V), "F")
    a = face_normals(V, F)
    b = face_normals(V_ref, F)
    return np.arccos(np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0))


def vertex_error(V: np.ndarray, V_ref: np.ndarray) -> float:
    """E_V of (34): ``||V - V_ref||_F / nV``."""
    V, V_ref = _points(V, "V"), _points(V_ref, "V_ref")
    _same_shape(V, V_ref)
    if len(V) == 0:
        raise MeshRepairError("E_V needs at least one vertex")
    return float(np.linalg.norm(V - V_ref) / len(V))


def _surface_samples(V: np.ndarray, F: np.ndarray, per_face: int) -> np.ndarray:
    """Vertices plus ``per_face`` fixed barycentric points per face, shape ``(n, 3)``."""
    bary = [(1 / 3, 1 / 3, 1 / 3), (2 / 3, 1 / 6, 1 / 6), (1 / 6, 2 / 3, 1 / 6),
            (1 / 6, 1 / 6, 2 / 3), (0.5, 0.5, 0.0), (0.0, 0.5, 0.5), (0.5, 0.0, 0.5)][:per_face]
    pts = [V]
    for w in bary:
        pts.append(w[0] * V[F[:, 0]] + w[1] * V[F[:, 1]] + w[2] * V[F[:, 2]])
    return np.concatenate(pts)


def point_to_surface(P: np.ndarray, V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Distance from points ``P (n, 3)`` to the triangle mesh ``(V, F)``.

    Exact point-triangle distances against the nearest candidate faces (found with a k-d tree on
    face centroids, 8 candidates per point), vectorised. The nearest face is almost always among
    them on a usual mesh; on a tangled mesh with large, crossing faces it may not be, and the
    distance is then over-estimated (a property test found a self-distance of 4 % of the
    bounding-box diagonal on a 42-vertex sphere with strong random noise).
    """

    V, P = _points(V, "V"), _points(P, "P")
    F = _faces(F, len(V), "F")
    # work in a centred, unit-size frame: huge (1e300) or tiny coordinates neither overflow
    # nor underflow in the squared distances; distances scale back by ``s``
    c = 0.5 * V.min(axis=0) + 0.5 * V.max(axis=0)
    with np.errstate(over="ignore", invalid="ignore"):
        s = float(max(np.abs(V - c).max(initial=0.0), np.abs(P - c).max(initial=0.0)))
    if not np.isfinite(s):
        raise MeshRepairError("coordinates span more than the float64 range; rescale them")
    if s == 0:
        return np.zeros(len(P))
    return s * _point_to_surface_unit((P - c) / s, (V - c) / s, F)


def _point_to_surface_unit(P: np.ndarray, V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """:func:`point_to_surface` on checked arrays of moderate size."""
    from scipy.spatial import cKDTree

    cen = V[F].mean(axis=1)
    k = min(8, len(F))
    _, idx = cKDTree(cen).query(P, k=k)
    idx = np.atleast_2d(idx).reshape(len(P), k)
    best = np.full(len(P), np.inf)
    for c in range(k):
        tri = V[F[idx[:, c]]]
        best = np.minimum(best, _point_triangle_distance(P, tri[:, 0], tri[:, 1], tri[:, 2]))
    return best


def closest_points_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray
                                ) -> np.ndarray:
    """Row-wise closest point to ``p`` on triangle ``abc``, all arrays ``(n, 3)``.

    Ericson, Real-Time Collision Detection, 5.1.5 (Voronoi regions of vertices, edges, face).
    """
    ab, ac, ap = b - a, c - a, p - a
    d1 = np.einsum("ij,ij->i", ab, ap)
    d2 = np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3 = np.einsum("ij,ij->i", ab, bp)
    d4 = np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5 = np.einsum("ij,ij->i", ab, cp)
    d6 = np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
        q = a + v[:, None] * ab + w[:, None] * ac
        # edge regions
        t_ab = np.where(d1 - d3 != 0, d1 / (d1 - d3), 0.0)
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        q = np.where(m[:, None], a + t_ab[:, None] * ab, q)
        t_ac = np.where(d2 - d6 != 0, d2 / (d2 - d6), 0.0)
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        q = np.where(m[:, None], a + t_ac[:, None] * ac, q)
        e1, e2 = d4 - d3, d5 - d6
        t_bc = np.where(e1 + e2 != 0, e1 / (e1 + e2), 0.0)
        m = (va <= 0) & (e1 >= 0) & (e2 >= 0)
        q = np.where(m[:, None], b + t_bc[:, None] * (c - b), q)
    # vertex regions take precedence
    q = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, q)
    q = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, q)
    q = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, q)
    return q


def _point_triangle_distance(p, a, b, c):
    """Row-wise exact distance from p to triangle abc."""
    return np.linalg.norm(p - closest_points_on_triangles(p, a, b, c), axis=1)


def distances(V: np.ndarray, F: np.ndarray, V_ref: np.ndarray, F_ref: np.ndarray, *,
              per_face: int = 4) -> dict[str, float]:
    """Symmetric surface distances between two meshes (any connectivity).

    Points sampled on each surface (vertices plus ``per_face`` barycentric points per face) are
    measured exactly against the other surface.

    Returns
    -------
    dict with ``mean`` (symmetric mean), ``hausdorff`` (symmetric max), ``mean_to_ref``,
    ``max_to_ref``, and ``diag`` (bounding-box diagonal of the reference), all in input units.
    """
    from meshrepair.options import check_int

    per_face = check_int("per_face", per_face, low=0, high=7)
    V, V_ref = _points(V, "V"), _points(V_ref, "V_ref")
    F, F_ref = _faces(F, len(V), "F"), _faces(F_ref, len(V_ref), "F_ref")
    a = point_to_surface(_surface_samples(V, F, per_face), V_ref, F_ref)
    b = point_to_surface(_surface_samples(V_ref, F_ref, per_face), V, F)
    ext = V_ref.max(axis=0) - V_ref.min(axis=0)
    m = float(ext.max())
    diag = m * float(np.linalg.norm(ext / m)) if m > 0 else 0.0
    return {
        "mean": float(0.5 * (a.mean() + b.mean())),
        "hausdorff": float(max(a.max(), b.max())),
        "mean_to_ref": float(a.mean()),
        "max_to_ref": float(a.max()),
        "diag": diag,
    }
