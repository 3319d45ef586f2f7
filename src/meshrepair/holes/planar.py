"""Planar enclosing of one loop (Sect. 5 of the paper, "trivial enclosing").

The loop is projected onto the plane orthogonal to its vector area (else the least-squares plane,
else the unit disc by arc length), meshed by Triangle (``pYq28a``: no Steiner point on the loop)
and the interior vertices are placed on the harmonic membrane (cotangent weights of the 2-D
triangulation). :func:`enclose_loop` dispatches to :mod:`.liepa` for ``method="liepa"``.
"""

from __future__ import annotations

import logging

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.holes._geom2d import (
    Patch,
    _cotan_weights_2d,
    _harmonic,
    _loop_positions,
    _max_area_for,
    _orient_patch,
    _plane_frame,
    _polygon_is_simple,
    _triangulate,
    _vector_area,
)

log = logging.getLogger(__name__)

ENCLOSE_METHODS = ("auto", "liepa")
"""Ways :func:`enclose_loop` can triangulate a loop."""


def enclose_loop(P: np.ndarray, *, edge_length: float | None = None, method: str = "auto",
                 opposite: np.ndarray | None = None,
                 forbidden: np.ndarray | None = None, creases=None,
                 conforming: bool = False, coarse: np.ndarray | None = None) -> Patch:
    """Triangulate the hole bounded by the closed 3-D polygon ``P``.

    Parameters
    ----------
    P : (k, 3) float array, k >= 3
        Loop positions in the order of :attr:`Hole.vertices`.
    edge_length : float, optional
        Target interior edge length (default: the loop's mean edge length).
    method : ``"auto"`` or ``"liepa"``
        ``"auto"``: a planar view of the loop (vector-area plane, least-squares plane, else the
        unit disc) meshed by Triangle, interior vertices on the harmonic membrane.
        ``"liepa"``: :func:`min_weight_triangulation` of the loop (minimal largest dihedral
        angle, then area, against the faces in ``opposite``), refined to the edge length on that
        surface (see :func:`_enclose_liepa`); follows the surrounding faces where the loop is far
        from planar.
    opposite : (k, 3) float, optional
        ``"liepa"`` only: third vertex of the existing face on each loop edge.
    forbidden : (q, 2) int, optional
        ``"liepa"`` only: local index pairs that are existing edges (not to be used as chords).
    conforming : bool
        ``"liepa"`` only: let Triangle split the folds of the coarse triangulation for its angle
        bound (a patch much finer along them) instead of dividing them into pieces of the edge
        length first (see :func:`_refine_on_triangulation`).
    coarse : (k - 2, 3) int, optional
        ``"liepa"`` only: the triangulation of the loop to refine, in local indices as
        :func:`min_weight_triangulation` returns it (default: that function's, from ``opposite``
        and ``forbidden``).
    creases : CreaseRoute, optional
        ``"auto"`` only: crease segments to route through the patch as constrained edges of the
        planar triangulation (:mod:`.creases`); their vertices are placed on the crease curves
        (``Patch.sharp_edges``). Ignored (logged) when no planar view can hold them.

    Returns
    -------
    Patch
        The first ``k`` rows of ``Patch.X`` are ``P``; ``Patch.T`` traverses every loop edge
        backwards, so the patch is consistently oriented with the faces that border the loop. The
        interior vertices are the harmonic interpolation of ``P`` (a membrane) or lie on the
        minimum-weight triangulation (``"liepa"``); use :func:`fair_vertices` for a curved fill.

    Raises
    ------
    MeshRepairError
        If the loop has fewer than 3 vertices, repeated or non-finite positions, or for an
        unknown ``method``.
    """
    if method not in ENCLOSE_METHODS:
        raise MeshRepairError(f"method must be one of {ENCLOSE_METHODS}, got {method!r}")
    P = _loop_positions(P)
    k = len(P)
    el = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1)
    if (el <= 0).any():
        raise MeshRepairError("the hole loop has two consecutive vertices at the same position "
                              "(zero-length boundary edge); merge or move them first")
    Lp = float(el.sum())
    h = float(el.mean()) if edge_length is None else float(edge_length)
    if not h > 0:
        raise MeshRepairError(f"edge_length must be > 0, got {edge_length}")
    if k == 3:
        return Patch(X=P.copy(), T=np.array([[0, 2, 1]], dtype=np.int64),
                     uv=np.zeros((3, 2)), method="triangle", n_loop=3)
    if method == "liepa":
        from meshrepair.holes.liepa_refine import _enclose_liepa

        return _enclose_liepa(P, h, opposite, forbidden, conforming=conforming, coarse=coarse)
    segs = np.c_[np.arange(k), (np.arange(k) + 1) % k]
    c = P.mean(axis=0)
    candidates: list[tuple[str, np.ndarray]] = []
    va = _vector_area(P)
    if np.linalg.norm(va) > 1e-12 * Lp * Lp:
        candidates.append(("plane", -va))
    _, _, vt = np.linalg.svd(P - c, full_matrices=False)
    n_pca = vt[2] if np.dot(vt[2], -va) >= 0 else -vt[2]
    candidates.append(("pca-plane", n_pca))
    if creases is not None and creases.n_creases:
        # a view where the routes fit inside the loop: the loop's own planes, then the view
        # of the corner (sum of the crease directions, e.g. (1, 1, 1) at a box corner)
        views = list(candidates)
        if len(creases.points):
            vn = creases.view
            if np.linalg.norm(vn) > 0:
                views.append(("plane", vn if np.dot(vn, -va) >= 0 else -vn))
        planar_views = []
        for method, n in views:
            e1, e2 = _plane_frame(n)
            Q = np.c_[(P - c) @ e1, (P - c) @ e2]
            if not _polygon_is_simple(Q):
                continue
            L2 = float(np.linalg.norm(Q - np.roll(Q, -1, axis=0), axis=1).sum())
            planar_views.append((Q, h * L2 / Lp, e1, e2, method))
            patch = _enclose_with_creases(P, Q, segs, h * L2 / Lp, creases, c, e1, e2, method,
                                          allow_drop=False)
            if patch is not None:
                return patch
        # the disc (arc length on the unit circle) is convex: every chord between two ends is
        # inside; a corner goes to the mean of its ends' disc positions
        s_ = np.r_[0.0, np.cumsum(el)[:-1]] / Lp
        Qd = np.c_[np.cos(2 * np.pi * s_), np.sin(2 * np.pi * s_)]
        sg = creases.segments
        Qc = np.array([Qd[sg[(sg[:, 1] == k + j) & (sg[:, 0] < k), 0]].mean(axis=0)
                       for j in range(len(creases.points))]).reshape(-1, 2)
        patch = _enclose_with_creases(P, Qd, segs, h * 2 * np.pi / Lp, creases, c, None, None,
                                      "disc", Qc=Qc, allow_drop=False)
        if patch is not None:
            return patch
        for Q, h2, e1, e2, method in planar_views:  # the routes that fit a planar view
            patch = _enclose_with_creases(P, Q, segs, h2, creases, c, e1, e2, method)
            if patch is not None:
                return patch
        log.info("the creases of a %d-loop could not be routed in a planar view; filling it "
                 "without them", k)
    for method, n in candidates:
        e1, e2 = _plane_frame(n)
        Q = np.c_[(P - c) @ e1, (P - c) @ e2]
        if not _polygon_is_simple(Q):
            continue
        L2 = float(np.linalg.norm(Q - np.roll(Q, -1, axis=0), axis=1).sum())
        h2 = h * L2 / Lp
        X2, T = _triangulate(Q, segs, _max_area_for(h2))
        if len(T) == 0 or len(X2) < k or not np.allclose(X2[:k], Q):
            continue
        if (np.abs(X2[k:, None, :] - Q[None]).sum(axis=2) == 0).any() if len(X2) > k else False:
            continue
        T = _orient_patch(T, k)
        X = _embed(P, X2, T)
        return Patch(X=X, T=T, uv=X2, method=method, n_loop=k)
    # disc: cumulative arc length on the unit circle (always a convex, valid polygon)
    s = np.r_[0.0, np.cumsum(el)[:-1]] / Lp
    Q = np.c_[np.cos(2 * np.pi * s), np.sin(2 * np.pi * s)]
    # number of triangles from the area of a coarse membrane over the loop
    X2c, Tc = _triangulate(Q, segs, None)
    Xc = _embed(P, X2c, Tc)
    area3 = 0.5 * float(np.linalg.norm(np.cross(Xc[Tc[:, 1]] - Xc[Tc[:, 0]],
                                                Xc[Tc[:, 2]] - Xc[Tc[:, 0]]), axis=1).sum())
    n_tri = max(area3 / (np.sqrt(3.0) / 4.0 * h * h), 1.0)
    X2, T = _triangulate(Q, segs, 2.0 * np.pi / n_tri)
    T = _orient_patch(T, k)
    X = _embed(P, X2, T)
    return Patch(X=X, T=T, uv=X2, method="disc", n_loop=k)


def _enclose_with_creases(P, Q, segs, h2, route, c, e1, e2, method, Qc=None,
                          allow_drop: bool = True) -> Patch | None:
    """Planar triangulation of the loop polygon ``Q`` with the crease segments of ``route`` as
    constraints; crease vertices on the Hermite curves, the rest on the membrane spanning loop
    and creases. None when the routes do not fit inside the polygon."""
    from matplotlib.path import Path as MPath

    k = len(P)
    if Qc is None:
        Qc = np.c_[(route.points - c) @ e1, (route.points - c) @ e2] if len(route.points) else \
            np.empty((0, 2))
    Qall = np.r_[Q, Qc]
    cs = route.segments
    poly = MPath(Q)
    # a route must lie inside the polygon (sampled): the others are dropped (a chord of the
    # loop passing over the surround in this view); routes must not cross each other
    t = np.linspace(0.02, 0.98, 25)[:, None]
    inside = [bool(poly.contains_points(Qall[a] + t * (Qall[b] - Qall[a])).all())
              for a, b in cs.tolist()]
    if not any(inside) or (not allow_drop and not all(inside)):
        return None
    if not all(inside):
        keep = np.flatnonzero(inside)
        log.info("%d of %d crease routes leave the loop's planar view; dropped",
                 len(cs) - len(keep), len(cs))
        from meshrepair.holes.crease_ends import CreaseRoute

        route = CreaseRoute(points=route.points, segments=cs[keep],
                            curves=[route.curves[i] for i in keep],
                            kinds=[route.kinds[i] for i in keep], view=route.view)
        cs = route.segments
        used_pts = np.unique(cs[cs >= k]) - k
        if len(used_pts) < len(route.points):
            # renumber the extra points still in use
            remap = -np.ones(len(route.points), np.int64)
            remap[used_pts] = np.arange(len(used_pts))
            cs = np.where(cs >= k, k + remap[np.maximum(cs - k, 0)], cs)
            route = CreaseRoute(points=route.points[used_pts], segments=cs, curves=route.curves,
                                kinds=route.kinds, view=route.view)
            Qc = Qc[used_pts]
            Qall = np.r_[Q, Qc]
    for i in range(len(cs)):
        for j in range(i + 1, len(cs)):
            if len(set(cs[i].tolist()) & set(cs[j].tolist())):
                continue
            if _segments_cross(Qall[cs[i, 0]], Qall[cs[i, 1]], Qall[cs[j, 0]], Qall[cs[j, 1]]):
                return None
    markers = np.r_[np.ones(k, np.int32), 2 + np.arange(len(cs), dtype=np.int32)]
    data = {"vertices": Qall, "segments": np.r_[segs, cs],
            "segment_markers": markers[:, None]}
    from meshrepair.holes._triangle import MIN_ANGLE, steiner_cap, triangulate_capped

    amax = _max_area_for(h2)
    out = triangulate_capped(data, f"pYQq{MIN_ANGLE:g}", steiner_cap(Qall, len(Qall), amax),
                             max_area=amax)
    X2 = np.asarray(out["vertices"], dtype=np.float64)
    T = np.asarray(out.get("triangles", np.empty((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(T) == 0 or len(X2) < len(Qall) or not np.allclose(X2[: len(Qall)], Qall):
        return None
    sub = np.asarray(out["segments"], np.int64).reshape(-1, 2)
    mk = np.asarray(out["segment_markers"]).ravel()
    sharp = sub[mk >= 2]
    seg_of = mk[mk >= 2] - 2
    T = _orient_patch(T, k)
    # 3-D positions of crease vertices: the parameter along their 2-D segment, on the curve
    known = np.zeros(len(X2), bool)
    known[:k] = True
    Xk = np.zeros((len(X2), 3))
    Xk[:k] = P
    for (u, w), j in zip(sharp.tolist(), seg_of.tolist(), strict=True):
        a, b = cs[j]
        d = Qall[b] - Qall[a]
        for x in (u, w):
            if known[x]:
                continue
            tt = float(np.clip((X2[x] - Qall[a]) @ d / max(d @ d, 1e-300), 0.0, 1.0))
            Xk[x] = route.evaluate(j, np.array([tt]))[0]
            known[x] = True
    n = len(X2)
    W = _cotan_weights_2d(X2, T, n)
    W.data = np.maximum(W.data, 1e-8)
    X = _harmonic(W, known, Xk[known]) if (~known).any() else Xk
    # _harmonic keeps known rows in order of the mask: restore them exactly
    X[known] = Xk[known]
    return Patch(X=X, T=T, uv=X2, method=method, n_loop=k, sharp_edges=sharp,
                 n_creases=len(cs))


def _segments_cross(p, q, r, s) -> bool:
    """Proper crossing of 2-D segments pq and rs."""
    def orient(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    d1, d2 = orient(p, q, r), orient(p, q, s)
    d3, d4 = orient(r, s, p), orient(r, s, q)
    return (d1 * d2 < 0) and (d3 * d4 < 0)


def _embed(P: np.ndarray, X2: np.ndarray, T: np.ndarray) -> np.ndarray:
    """3-D positions of a 2-D triangulation whose first ``len(P)`` vertices are ``P``."""
    n = len(X2)
    known = np.zeros(n, bool)
    known[: len(P)] = True
    W = _cotan_weights_2d(X2, T, n)
    # clamp negative weights (obtuse pairs) for a maximum-principle, fold-free embedding
    W.data = np.maximum(W.data, 1e-8)
    return _harmonic(W, known, P)


def _enclose_annulus(Po: np.ndarray, Pi: np.ndarray, h: float) -> Patch | None:
    """Triangulate the region between an outer loop and an island loop (planar view only)."""
    ko, ki = len(Po), len(Pi)
    P = np.r_[Po, Pi]
    n = -_vector_area(Po)
    if not np.linalg.norm(n) > 0:
        return None
    e1, e2 = _plane_frame(n)
    c = Po.mean(axis=0)
    Q = np.c_[(P - c) @ e1, (P - c) @ e2]
    Qo, Qi = Q[:ko], Q[ko:]
    if not (_polygon_is_simple(Qo) and _polygon_is_simple(Qi)):
        return None
    segs = np.r_[np.c_[np.arange(ko), (np.arange(ko) + 1) % ko],
                 ko + np.c_[np.arange(ki), (np.arange(ki) + 1) % ki]]
    # a point strictly inside the island polygon
    Xi, Ti = _triangulate(Qi, segs[ko:] - ko, None, quality=False)
    if len(Ti) == 0:
        return None
    d1, d2 = Xi[Ti[:, 1]] - Xi[Ti[:, 0]], Xi[Ti[:, 2]] - Xi[Ti[:, 0]]
    areas = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    seed = Xi[Ti[int(np.argmax(areas))]].mean(axis=0)
    Lp = float(np.linalg.norm(Po - np.roll(Po, -1, axis=0), axis=1).sum())
    L2 = float(np.linalg.norm(Qo - np.roll(Qo, -1, axis=0), axis=1).sum())
    X2, T = _triangulate(Q, segs, _max_area_for(h * L2 / Lp), holes=seed[None])
    if len(T) == 0 or len(X2) < ko + ki or not np.allclose(X2[: ko + ki], Q):
        return None
    # orientation: outer loop edges must be traversed backwards
    he = np.stack([T, np.roll(T, -1, axis=1)], axis=2).reshape(-1, 2)
    m = int(T.max()) + 1
    code = set((he[:, 0] * m + he[:, 1]).tolist())
    if 1 in code:  # half-edge 0 -> 1 (code 0 * m + 1): the outer loop traversed forwards
        T = T[:, ::-1].copy()
        he = np.stack([T, np.roll(T, -1, axis=1)], axis=2).reshape(-1, 2)
        code = set((he[:, 0] * m + he[:, 1]).tolist())
    inner_back = [((ko + (j + 1) % ki) * m + ko + j) in code for j in range(ki)]
    outer_back = [(((j + 1) % ko) * m + j) in code for j in range(ko)]
    if not (all(inner_back) and all(outer_back)):
        return None
    return Patch(X=_embed(P, X2, T), T=T, uv=X2, method="annulus", n_loop=ko + ki)
