"""Triangle (Shewchuk's constrained Delaunay mesher) called in a canonical frame.

Triangle's refinement inserts Steiner points in an order set by its input: the order of the
points and segments, and their coordinates to the last bit (an area or angle test near its
bound goes either way). The planar view of a hole is the same polygon, up to rounding, whatever
the mesh's vertex order, rotation, scale or translation, but its coordinates and its first point
are not. So every call meets Triangle in one frame computed from the points themselves:

- translate to the points' centroid ``c`` and divide by their RMS radius ``u`` (both summed over
  sorted values, so the same bits in every order);
- rotate so the point farthest from ``c`` lies on the positive x axis;
- round to a grid of :data:`QUANTUM` (in units of ``u``): coordinates that differ by rounding land
  on the same grid point (unless they straddle a grid line: about 1e-7 per coordinate); points
  closer than that stay unrounded, so Triangle still sees them apart;
- list the points, segments and triangles in lexicographic order of the grid coordinates.

Area bounds are divided by ``u²`` and rounded to single precision for the same reason. The
returned points are the input points, bit for bit and in the caller's order, followed by the
Steiner points mapped back (``X = u · Y R + c``); index arrays are mapped to the caller's order.
"""

from __future__ import annotations

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.geometry import order_free_centroid
from meshrepair.mesh.topology import least_first, row_order

MIN_ANGLE = 28.0
"""Minimum angle (degrees) asked of the 2-D constrained Delaunay triangulation."""

QUANTUM = 2.0 ** -24
"""Grid step of the canonical frame, in units of the points' RMS radius (6e-8): coarse enough that
rounding-level differences (1e-15) seldom cross a grid line, fine enough that no two distinct
points of a hole's planar view share a grid point."""

STEINER_FACTOR = 20
"""Triangle may add at most this many times the vertices a patch needs at its area bound (the
polygon's area over the bound, halved, plus one per loop vertex), and at least
:data:`STEINER_MIN`. Measured patches of real holes add at most 2.25 times that count; a
polygon that needs far more is a long thin one (a loop through a vertex far from the others):
quality triangles along a sliver of width w and length L need about (L / w)² of them."""
STEINER_MIN = 10_000
"""Steiner points Triangle may always add (about 20 ms of its work)."""
STEINER_MAX = 1_000_000
"""Steiner points Triangle never exceeds (about the 2 M new-face budget of hole filling)."""


def _area_switch(max_area: float) -> str:
    """Triangle's ``a`` switch for a maximum triangle area, in positional notation: Triangle
    reads only digits and '.', so ``a6.3e-05`` would mean an area bound of 6.3 (and then the
    switches ``e`` and ``-``), leaving loops of small meshes unrefined."""
    return "a" + np.format_float_positional(float(max_area), precision=12, fractional=False,
                                            trim="-")


def _frame(X: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Centroid ``c``, RMS radius ``u`` and rotation ``R`` (rows: the canonical axes) of the
    points ``X`` (n, 2), independent of their order."""
    n = len(X)
    c = order_free_centroid(X)
    d = X - c
    r2 = (d * d).sum(axis=1)
    u = float(np.sqrt(np.sort(r2).sum() / n))
    if not u > 0:
        return c, 1.0, np.eye(2)
    a = d[int(np.argmax(r2))] / np.sqrt(r2.max())
    return c, u, np.array([[a[0], a[1]], [-a[1], a[0]]])


def _grid(Y: np.ndarray) -> np.ndarray:
    return np.round(Y / QUANTUM) * QUANTUM


def _single(a) -> np.ndarray:
    return np.asarray(a, dtype=np.float64).astype(np.float32).astype(np.float64)


def triangulate(data: dict, opts: str, *, max_area: float | None = None) -> dict:
    """``triangle.triangulate(data, opts)`` in the canonical frame of ``data["vertices"]``.

    Parameters
    ----------
    data : dict
        Triangle's input: ``vertices`` (n, 2) and optionally ``segments`` (m, 2) with
        ``segment_markers`` (m, 1), ``holes`` (h, 2), ``triangles`` (t, 3) with
        ``triangle_max_area`` (t,) (a negative bound: none).
    opts : str
        Triangle's switches, without a numeric area bound.
    max_area : float, optional
        Largest triangle area, in the units of ``data["vertices"]`` (the ``a`` switch).

    Returns
    -------
    dict
        Triangle's output in the caller's frame and numbering: ``vertices`` (the n input points
        unchanged, then the Steiner points), ``triangles``, ``segments`` and ``segment_markers``
        when Triangle returns them.
    """
    import triangle

    X = np.asarray(data["vertices"], dtype=np.float64).reshape(-1, 2)
    n = len(X)
    c, u, R = _frame(X)
    Y = (X - c) @ R.T / u
    G = _grid(Y)
    if len(np.unique(G, axis=0)) == n:  # else two points closer than the grid: keep them apart
        Y = G
    perm = row_order(Y)  # canonical index -> caller's index
    rank = np.empty(n, dtype=np.int64)
    rank[perm] = np.arange(n)
    cd: dict = {"vertices": Y[perm]}
    if "segments" in data:
        S = np.sort(rank[np.asarray(data["segments"], dtype=np.int64).reshape(-1, 2)], axis=1)
        o = row_order(S)
        cd["segments"] = S[o]
        if "segment_markers" in data:
            cd["segment_markers"] = np.asarray(data["segment_markers"]).reshape(len(S), -1)[o]
    if "holes" in data:
        H = _grid((np.asarray(data["holes"], dtype=np.float64).reshape(-1, 2) - c) @ R.T / u)
        cd["holes"] = H[row_order(H)]
    if "triangles" in data:
        T = least_first(rank[np.asarray(data["triangles"], dtype=np.int64).reshape(-1, 3)])
        o = row_order(T)
        cd["triangles"] = T[o]
        if "triangle_max_area" in data:
            b = np.asarray(data["triangle_max_area"], dtype=np.float64).ravel()[o]
            cd["triangle_max_area"] = np.where(b > 0, _single(b / (u * u)), b)
    if max_area is not None:
        opts += _area_switch(_single(max_area / (u * u)))
    out = triangle.triangulate(cd, opts)
    Z = np.asarray(out["vertices"], dtype=np.float64).reshape(-1, 2)
    back = np.r_[perm, np.arange(n, len(Z), dtype=np.int64)]
    res = {"vertices": np.r_[X, (Z[n:] * u) @ R + c]}
    for key in ("triangles", "segments"):
        if key in out:
            res[key] = back[np.asarray(out[key], dtype=np.int64)]
    if "segment_markers" in out:
        res["segment_markers"] = np.asarray(out["segment_markers"])
    return res


def steiner_cap(Q: np.ndarray, n_loop: int, max_area: float | None) -> int:
    """The most Steiner points a quality triangulation of the 2-D points ``Q`` (``n_loop`` of
    them on the boundary) with triangle areas at most ``max_area`` may add
    (:data:`STEINER_FACTOR`; the area is that of ``Q``'s convex hull, a bound of the region's)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        area = float(ConvexHull(np.asarray(Q, dtype=np.float64)).volume)
    except (QhullError, ValueError):  # collinear or too few points: no area
        area = 0.0
    n_tri = area / max_area if max_area else 0.0
    n_tri = n_tri if np.isfinite(n_tri) else float(STEINER_MAX)
    return int(min(STEINER_MAX, STEINER_FACTOR * (n_tri / 2.0 + n_loop) + STEINER_MIN))


def triangulate_capped(data: dict, opts: str, cap: int, *,
                       max_area: float | None = None) -> dict:
    """:func:`triangulate` with at most ``cap`` Steiner points (switch ``S``);
    :class:`MeshRepairError` when the cap is reached (the quality mesh of this polygon would
    need more: refused after bounded work, instead of running for hours)."""
    n_in = len(data["vertices"])
    out = triangulate(data, f"{opts}S{max(int(cap), 0)}", max_area=max_area)
    if len(out["vertices"]) - n_in >= cap:
        X = np.asarray(data["vertices"], dtype=np.float64)
        seg = np.asarray(data["segments"], dtype=np.int64).reshape(-1, 2)
        el = np.linalg.norm(X[seg[:, 0]] - X[seg[:, 1]], axis=1)
        raise MeshRepairError(
            f"the patch of this hole would need more than {cap:,} new vertices for triangles "
            f"with angles of at least {MIN_ANGLE:g}°: in its planar view the constrained edges "
            f"range from {el.min():.3g} to {el.max():.3g} in length, a long thin polygon; check "
            "the mesh for vertices far from the others (outliers), or exclude this hole")
    return out
