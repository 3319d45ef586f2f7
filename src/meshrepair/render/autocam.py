"""The default camera: the object's front and up, from its surface alone.

Every quantity is a sum over faces weighted by face area (the vector area ``a = Σ A_f n_f``, the
area-weighted second moments of the face centroids), so the camera depends on the surface, not on
the order of its vertices or faces, and the same mesh always gives the same picture.

*Up* (:func:`object_up`), the first rule that applies:

1. an elongated object (its longest principal axis at least :data:`ELONGATED` times the next)
   whose long axis lies within 45° of the world ``y`` or ``z`` axis stands along that axis (a
   statue, a bust, a bottle); up is the long axis, pointing to ``+y`` / ``+z``;
2. an open scan (``|a| ≥`` :data:`OPEN_RATIO` of its area: its faces look mostly one way, at the
   scanner) is upright along the world axis, ``+y`` or ``+z``, further from its viewing direction
   ``a`` (a y-up scan looking along ``+z``, a z-up scan looking along ``-y``);
3. otherwise ``+y`` (the convention of most model files).

*Front* (:func:`default_view`): an open scan is seen from the side its faces look at (``-a`` is
the view direction), a closed object from the principal direction, orthogonal to up, with the
largest silhouette (the world ``z`` axis, or ``x`` for a z-up object, when the object is about as
wide as deep), from the side with more area facing the camera (ties, as on a closed surface, go
to the side of ``+z``, then ``+x``, then ``+y``).
"""

from __future__ import annotations

import numpy as np

ELONGATED = 1.3
"""Ratio of the longest to the second principal extent above which an object stands on its long
axis."""
DISTINCT = 1.2
"""Ratio of the two second moments orthogonal to up above which the smaller one's direction is
the view direction (below it the world axis is used)."""
OPEN_RATIO = 0.3
"""``|Σ A_f n_f| / Σ A_f`` above which a surface is treated as a one-sided scan."""

_WORLD = np.eye(3)


def _normalised(V: np.ndarray) -> np.ndarray | None:
    """``V`` centred on its bounding box and divided by its largest extent (every rule is
    invariant to both; huge or tiny coordinates then neither overflow nor underflow), or None
    for a mesh without extent."""
    V = np.asarray(V, dtype=np.float64)
    lo, hi = V.min(axis=0), V.max(axis=0)
    ext = float(np.max(hi - lo))
    if not (np.isfinite(ext) and ext > 0):
        return None
    return (V - 0.5 * (lo + hi)) / ext


def _face_data(V: np.ndarray, F: np.ndarray):
    P = V[F]
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]) * 0.5  # area-weighted normals
    A = np.linalg.norm(n, axis=1)
    c = P.mean(axis=1)
    return n, A, c


def _principal_axes(A: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Area-weighted principal axes (rows, longest first) and their extents (std)."""
    w = A / max(float(A.sum()), 1e-300)
    mu = w @ c
    d = c - mu
    C = (d * w[:, None]).T @ d
    if not np.all(np.isfinite(C)):
        return _WORLD.copy(), np.ones(3)
    ev, U = np.linalg.eigh(C)
    order = np.argsort(ev)[::-1]
    return U[:, order].T, np.sqrt(np.maximum(ev[order], 0.0))


def _signed(v: np.ndarray) -> np.ndarray:
    """``v`` with the sign making its first clearly non-zero component of (z, x, y) positive."""
    for k in (2, 0, 1):
        if abs(v[k]) > 1e-9 * max(float(np.abs(v).max()), 1e-300):
            return v if v[k] > 0 else -v
    return v


def object_up(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """The object's up direction (unit, world coordinates); see the module docstring."""
    V = _normalised(V)
    if V is None or len(F) == 0:
        return _WORLD[1].copy()
    n, A, c = _face_data(V, np.asarray(F, dtype=np.int64))
    total = float(A.sum())
    if not total > 0:
        return _WORLD[1].copy()
    axes, ext = _principal_axes(A, c)
    e1 = axes[0]
    if ext[0] >= ELONGATED * max(ext[1], 1e-300):
        for k in (1, 2):  # y, then z
            if abs(e1[k]) >= np.cos(np.radians(45.0)):
                return e1 if e1[k] > 0 else -e1
    a = n.sum(axis=0)
    if np.linalg.norm(a) >= OPEN_RATIO * total:
        ah = a / np.linalg.norm(a)
        return _WORLD[1].copy() if abs(ah[1]) <= abs(ah[2]) else _WORLD[2].copy()
    return _WORLD[1].copy()


def default_view(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(view_dir, up)`` of the default camera (unit vectors, world coordinates): the direction
    the camera looks in and the object's up (see the module docstring)."""
    F = np.asarray(F, dtype=np.int64)
    up = object_up(V, F)
    V = _normalised(V)
    if V is None or len(F) == 0:
        return np.array([0.0, 0.0, -1.0]), up
    n, A, c = _face_data(V, F)
    total = float(A.sum())
    if not total > 0:
        return np.array([0.0, 0.0, -1.0]), up
    a = n.sum(axis=0)
    if np.linalg.norm(a) >= OPEN_RATIO * total:
        d = -a / np.linalg.norm(a)
        d = d - (d @ up) * up  # keep the camera level: up stays vertical in the picture
        if np.linalg.norm(d) > 1e-6:
            return d / np.linalg.norm(d), up
    # in the plane orthogonal to up: the principal direction of smallest extent shows the
    # largest silhouette; when the two extents are within DISTINCT of each other the direction
    # is ill-defined (a sphere, a cube) and the world axis z (x when up is z) is taken instead
    b1 = _WORLD[2] - (_WORLD[2] @ up) * up
    if np.linalg.norm(b1) < 0.5:
        b1 = _WORLD[0] - (_WORLD[0] @ up) * up
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(up, b1)
    w = A / total
    q = np.c_[c @ b1, c @ b2]
    q -= w @ q
    C2 = (q * w[:, None]).T @ q
    s = b1
    ev, U = np.linalg.eigh(C2) if np.all(np.isfinite(C2)) else (np.ones(2), np.eye(2))
    if ev[1] > DISTINCT * max(ev[0], 1e-300):
        s = _signed(U[0, 0] * b1 + U[1, 0] * b2)
    s = s / np.linalg.norm(s)  # the camera sits on the side +s, looking along -s
    front = float(np.maximum(n @ s, 0.0).sum())
    back = float(np.maximum(-(n @ s), 0.0).sum())
    if back > front * (1.0 + 1e-6):
        s = -s
    return -s, up
