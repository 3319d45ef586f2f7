"""Crease continuation across a hole: find the sharp-edge chains that end on a loop, pair them
across the hole, and route each pair (or each crease of a corner) through the patch.

The paper's model rebuilds a crease where the MC penalty is on (``M_E = 1``); inside the hole
there is no crease to detect, so ``S_D`` gets ``M_E = 0`` everywhere and a crease entering the
hole is smoothed away. Here the crease is continued explicitly:

1. *Ends.* A loop vertex ``v`` is a crease end when a chain of at least :data:`MIN_CHAIN` sharp
   edges (dihedral angle above ``th``, not on the loop; the chain may turn at a corner of the
   surround) at least :data:`MIN_CHAIN_EDGES` loop edges long arrives at it. Its direction into
   the hole is ``d = (v - w) / |v - w|`` with ``w`` the vertex up to :data:`TANGENT_EDGES` edges
   back along the chain, before it first turns; its angle is the mean dihedral angle of those
   edges, its sign convex or concave.
2. *Pairs.* Two ends ``i, j`` with ``s = p_j - p_i`` are compatible when both point along the
   chord (``d_i · ŝ`` and ``-d_j · ŝ`` above ``cos`` :data:`PAIR_MAX_TURN`), have the same
   convexity, dihedral angles within :data:`PAIR_MAX_ANGLE_GAP` and chains outside the hole at
   least :data:`CHAIN_PER_GAP` ``|s|`` long (short folds are not extended across a large
   hole), and directions within :data:`PAIR_MAX_TILT` of the plane the hole spans (or, where
   one end tilts past it, a mean direction within it and a route inside the loop seen through
   that plane); pairs are taken greedily
   by ``d_i · ŝ - d_j · ŝ``. A pair is routed as the cubic Hermite curve from ``p_i`` with
   tangent ``|s| d_i`` to ``p_j`` with tangent ``-|s| d_j`` (a straight crease stays straight,
   a circular one is followed closely: end tangents from a one-sided quadratic difference, tangent
   length ``|s| · 2 tan(θ/4) / sin(θ/2)`` for a turn ``θ``, the cubic nearest to an arc).
3. *Corners.* :data:`MIN_CORNER` or more ends left unpaired whose lines nearly meet in front of
   all of them
   (the least-squares point ``c`` of the lines ``p_i + t d_i``, ``t > 0``, within
   :data:`CORNER_TOL` of every line relative to its distance) are routed as straight segments to
   ``c``: the corner where three creases of a box meet is rebuilt at the lines' intersection.
   An exact corner (two straight lines that meet, :func:`.crease_corners._exact_corner`) must
   lie within the hole's extent, no farther from the loop's centroid than its farthest vertex
   (:func:`meshrepair.holes._geom2d.within_reach`): the extended edges of a polyhedron also
   meet beyond its corners.
   A single leftover end whose line meets a paired crease ends there (a T-junction: the pair is
   split at the meeting point).

The routes are constrained segments of the planar triangulation (:func:`.planar.enclose_loop`);
the patch vertices on them are placed on the curves and kept as Dirichlet data of the fairing
(their Laplacian rows dropped, so each side is faired on its own), and the patch edges on them get
the MC penalty (``edge_force = 1``) in the ADMM solve.

Step 1 and the tunables live in :mod:`.crease_ends`, the corner and kink geometry of steps 3-4
in :mod:`.crease_corners`; this module routes (:func:`route_creases`) and runs them per hole
(:func:`find_crease_routes`), and re-exports their names.
"""

from __future__ import annotations

import logging

import numpy as np

from meshrepair.holes.crease_corners import (  # noqa: F401  (re-exported)
    EXACT_CORNER_ARM,
    EXACT_CORNER_TOL,
    KINKED_PAIR_TURN,
    _arc_to,
    _collinear_pair,
    _corner_point,
    _exact_corner,
    _kinked_pairs,
    _lines_meet_ahead,
    _twin_corners,
)
from meshrepair.holes.crease_ends import (  # noqa: F401  (re-exported)
    CHAIN_PER_GAP,
    CORNER_TOL,
    MAX_CHAIN,
    MIN_CHAIN,
    MIN_CHAIN_EDGES,
    MIN_CORNER,
    PAIR_MAX_ANGLE_GAP,
    PAIR_MAX_TILT,
    PAIR_MAX_TURN,
    STRAIGHT_TOL,
    TANGENT_EDGES,
    CreaseEnd,
    CreaseRoute,
    SharpGraph,
    crease_ends,
)

log = logging.getLogger(__name__)


def _pair_curve(p0: np.ndarray, d0: np.ndarray, p1: np.ndarray, d1: np.ndarray) -> np.ndarray:
    """Hermite data of a pair's route from ``p0`` (direction ``d0`` into the hole) to ``p1``
    (direction ``d1`` into the hole): tangent length of the cubic closest to a circular arc
    turning by ``θ``, ``|s| · 2 tan(θ/4) / sin(θ/2)``."""
    L = float(np.linalg.norm(p1 - p0))
    theta = float(np.arccos(np.clip(-d0 @ d1, -1.0, 1.0)))
    m = L * (2 * np.tan(theta / 4) / np.sin(theta / 2) if theta > 1e-6 else 1.0)
    return np.stack([p0, m * d0, p1, -m * d1])


def _route_inside(poly, p0: np.ndarray, d0: np.ndarray, p1: np.ndarray, d1: np.ndarray) -> bool:
    """Whether a pair's route (:func:`_pair_curve`) stays inside the loop seen through the hole's
    plane (``poly``: :func:`meshrepair.holes._geom2d.loop_seen_through_plane`) between 5 % and
    95 % of its length: a route passing over the surround joins two different creases."""
    path, project = poly
    Q = CreaseRoute(curves=[_pair_curve(p0, d0, p1, d1)]).evaluate(0, np.linspace(0.05, 0.95, 19))
    return bool(path.contains_points(project(Q)).all())


def route_creases(V: np.ndarray, loop: np.ndarray, ends: list[CreaseEnd]) -> CreaseRoute | None:
    """Pair the crease ends of a loop and route them (None when there is nothing to route)."""
    P = V[loop]
    le = float(np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean())
    ends = [e for e in ends if e.chain_length >= MIN_CHAIN_EDGES * le]
    if len(ends) < 2:
        return None
    k = len(loop)
    segs, curves, kinds = [], [], []
    points_t: list[np.ndarray] = []
    view = np.zeros(3)
    from meshrepair.holes._geom2d import within_reach

    corner = _exact_corner(P, ends, within=within_reach(P))
    if corner is not None:
        grp, c = corner
        points_t.append(c)
        view = np.sum([ends[i].direction for i in grp], axis=0)
        for i in grp:
            segs.append((ends[i].pos, k))
            curves.append(_arc_to(P[ends[i].pos], ends[i].direction, c))
            kinds.append("corner")
        ends = [e for i, e in enumerate(ends) if i not in grp]
    cos_turn = np.cos(np.radians(PAIR_MAX_TURN))
    cand = []
    for a in range(len(ends)):
        for b in range(a + 1, len(ends)):
            ea, eb = ends[a], ends[b]
            if ea.pos == eb.pos or ea.convex != eb.convex:
                continue
            if abs(ea.angle - eb.angle) > PAIR_MAX_ANGLE_GAP:
                continue
            s = P[eb.pos] - P[ea.pos]
            L = float(np.linalg.norm(s))
            if not L > 0:
                continue
            ca, cb = float(ea.direction @ s) / L, float(-eb.direction @ s) / L
            if min(ea.chain_length, eb.chain_length) < CHAIN_PER_GAP * L:
                continue
            if min(ca, cb) > cos_turn:
                cand.append((ca + cb, a, b))
    from meshrepair.holes._geom2d import _vector_area

    va = _vector_area(P)
    nva = float(np.linalg.norm(va))
    if nva > 0:
        nh = va / nva
        sin_tilt = np.sin(np.radians(PAIR_MAX_TILT))
        poly = None
        kept = []
        for c in cand:
            da, db = ends[c[1]].direction, ends[c[2]].direction
            if max(abs(float(da @ nh)), abs(float(db @ nh))) <= sin_tilt:
                kept.append(c)
                continue
            # one end tilts past the bound (a loop folding over the crease): the pair's mean
            # direction within it, and its route inside the loop seen through the hole's plane
            if abs(float((da + db) @ nh)) > 2 * sin_tilt:
                continue
            if poly is None:
                from meshrepair.holes._geom2d import loop_seen_through_plane

                poly = loop_seen_through_plane(P, nh)
            if _route_inside(poly, P[ends[c[1]].pos], da, P[ends[c[2]].pos], db):
                kept.append(c)
        cand = kept
    cand.sort(reverse=True)
    used: set[int] = set()
    for _, a, b in cand:
        if a in used or b in used:
            continue
        used.update((a, b))
        ea, eb = ends[a], ends[b]
        p0, p1 = P[ea.pos], P[eb.pos]
        segs.append((ea.pos, eb.pos))
        curves.append(_pair_curve(p0, ea.direction, p1, eb.direction))
        kinds.append("pair")
    rest = [e for i, e in enumerate(ends) if i not in used]
    # T-junctions: a leftover crease whose line meets a paired crease ends on it (e.g. a
    # concave crease meeting a straight convex one); the pair is split at the junction
    left = []
    for e in rest:
        best = None
        for j, kind in enumerate(kinds):
            if kind != "pair":
                continue
            tt = np.linspace(0.05, 0.95, 91)
            Q = CreaseRoute(curves=[curves[j]]).evaluate(0, tt)
            rel = Q - P[e.pos]
            s_ = rel @ e.direction
            off = np.linalg.norm(rel - s_[:, None] * e.direction, axis=1)
            ok = (s_ > 0) & (off <= CORNER_TOL * s_) & (e.chain_length >= CHAIN_PER_GAP * s_)
            if ok.any():
                i = int(np.flatnonzero(ok)[np.argmin(off[ok])])
                if best is None or off[i] < best[0]:
                    best = (off[i], j, float(tt[i]), Q[i])
        if best is None:
            left.append(e)
            continue
        _, j, t0, J = best
        a, b = segs[j]
        p0, m0, p1, m1 = curves[j]

        def dH(t, p0=p0, m0=m0, p1=p1, m1=m1):
            return ((6 * t * t - 6 * t) * p0 + (3 * t * t - 4 * t + 1) * m0
                    + (-6 * t * t + 6 * t) * p1 + (3 * t * t - 2 * t) * m1)

        jidx = k + len(points_t)
        points_t.append(J)
        segs[j] = (a, jidx)
        curves[j] = np.stack([p0, m0 * t0, J, dH(t0) * t0])
        kinds[j] = "junction"
        segs.append((b, jidx))
        curves.append(np.stack([p1, -m1 * (1 - t0), J, -dH(t0) * (1 - t0)]))
        kinds.append("junction")
        segs.append((e.pos, jidx))
        curves.append(np.stack([P[e.pos], J - P[e.pos], J, J - P[e.pos]]))
        kinds.append("junction")
    rest = left
    # one end per loop vertex (two chains from the same vertex cannot both reach a corner)
    seen: set[int] = set()
    rest = [e for e in rest if not (e.pos in seen or seen.add(e.pos))]
    points = np.asarray(points_t, float).reshape(-1, 3)
    n_before_rest = len(kinds)
    if len(rest) >= MIN_CORNER:
        c = _corner_point(np.array([P[e.pos] for e in rest]),
                          np.array([e.direction for e in rest]),
                          np.array([e.chain_length for e in rest]))
        if c is not None:
            kc = k + len(points)
            points = np.r_[points, c[None]]
            view = np.sum([e.direction for e in rest], axis=0)
            for e in rest:
                p0 = P[e.pos]
                segs.append((e.pos, kc))
                curves.append(np.stack([p0, c - p0, c, c - p0]))  # straight
                kinds.append("corner")
        elif len(rest) == 4:
            twin = _twin_corners(P, rest)
            if twin is not None:
                groups, cs = twin
                kc = k + len(points)
                points = np.r_[points, cs]
                view = np.sum([e.direction for e in rest], axis=0)
                for g, grp in enumerate(groups):
                    c = cs[g]
                    for e in grp:
                        p0 = P[e.pos]
                        segs.append((e.pos, kc + g))
                        curves.append(np.stack([p0, c - p0, c, c - p0]))
                        kinds.append("corner")
                segs.append((kc, kc + 1))  # the crease joining the two corners
                curves.append(np.stack([cs[0], cs[1] - cs[0], cs[1], cs[1] - cs[0]]))
                kinds.append("corner")
    if not any(kd == "corner" for kd in kinds[n_before_rest:]):
        # leftover ends of one crease that bends where it meets the loop
        for a, b in _kinked_pairs(P, rest):
            p0, p1 = P[rest[a].pos], P[rest[b].pos]
            segs.append((rest[a].pos, rest[b].pos))
            curves.append(np.stack([p0, p1 - p0, p1, p1 - p0]))  # straight
            kinds.append("kinked")
    if not segs:
        return None
    return CreaseRoute(points=points, segments=np.asarray(segs, np.int64).reshape(-1, 2),
                       curves=curves, kinds=kinds, view=view)


def find_crease_routes(V: np.ndarray, F: np.ndarray, holes, skip: dict[int, str],
                       th: float) -> dict[int, CreaseRoute]:
    """Crease routes of every selected hole (hole index -> route), for :func:`enclose_holes`."""
    todo = [h for h in holes if h.index not in skip]
    if not todo:
        return {}
    G = SharpGraph(V, F, th)
    if len(G.edges) == 0:
        return {}
    has = np.zeros(len(V), bool)
    has[G.edges.ravel()] = True
    out: dict[int, CreaseRoute] = {}
    for h in todo:
        if not has[h.vertices].any():
            continue
        r = route_creases(V, h.vertices, crease_ends(G, h.vertices))
        if r is not None:
            out[h.index] = r
            log.info("hole %d: %d crease segment(s) routed through the patch (%s)", h.index,
                     r.n_creases, ", ".join(r.kinds))
    return out
