"""Rigid and similarity transforms of point sets (Umeyama 1991), shared by the alignment code.

Conventions: points are ``(n, 3)`` float64, 4x4 homogeneous transforms act on column vectors
(``p' = T[:3, :3] @ p + T[:3, 3]``). Input arrays are never modified.
"""

from __future__ import annotations

import numpy as np

from meshrepair.errors import MeshRepairError

__all__ = ["apply_transform", "reflection", "umeyama"]


def _points(P, name: str = "points") -> np.ndarray:
    P = np.asarray(P, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3:
        raise MeshRepairError(f"{name} must have shape (n, 3), got {P.shape}")
    if not np.isfinite(P).all():
        raise MeshRepairError(f"{name} contain NaN or infinite coordinates")
    return P


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



def reflection(normal, point) -> np.ndarray:
    """4x4 reflection about the plane through ``point`` with normal ``normal``.

    ``x' = x - 2 ((x - p) . n) n`` with ``n`` normalised; an involution with determinant -1.
    """
    n = np.asarray(normal, dtype=np.float64).ravel()
    p = np.asarray(point, dtype=np.float64).ravel()
    if n.shape != (3,) or p.shape != (3,) or not np.isfinite(n).all() or not np.isfinite(p).all():
        raise MeshRepairError("a plane needs a finite 3-vector normal and point")
    nn = float(np.linalg.norm(n))
    if not nn > 0:
        raise MeshRepairError("the plane normal is zero")
    n = n / nn
    T = np.eye(4)
    T[:3, :3] -= 2.0 * np.outer(n, n)
    T[:3, 3] = 2.0 * float(n @ p) * n
    return T
