"""Corners and kinks of crease continuation (:mod:`meshrepair.holes.creases`, steps 3-4):
where three or more crease ends meet inside a hole (the least-squares meeting point of their
lines, exact corners of a box, twin corners), and the leftover ends of one crease that bends at
the loop (kinked pairs). Pure geometry on the ends' positions ``P`` and directions.
"""

from __future__ import annotations

import numpy as np

from meshrepair.holes.crease_ends import (
    CHAIN_PER_GAP,
    CORNER_TOL,
    MIN_CORNER,
    PAIR_MAX_ANGLE_GAP,
    PAIR_MAX_TILT,
    PAIR_MAX_TURN,
    CreaseEnd,
    log,
)


def _corner_point(P: np.ndarray, D: np.ndarray, chain: np.ndarray) -> np.ndarray | None:
    """Least-squares meeting point of the lines ``P_i + t D_i`` in front of all of them."""
    A = np.zeros((3, 3))
    b = np.zeros(3)
    for p, d in zip(P, D, strict=True):
        M = np.eye(3) - np.outer(d, d)
        A += M
        b += M @ p
    w = np.linalg.eigvalsh(A)
    if w[0] < 1e-3 * w[-1]:
        return None  # (nearly) parallel lines: no corner
    c = np.linalg.solve(A, b)
    for p, d, cl in zip(P, D, chain, strict=True):
        t = float((c - p) @ d)
        if not t > 0 or cl < CHAIN_PER_GAP * t:
            return None
        off = float(np.linalg.norm((c - p) - t * d))
        if off > CORNER_TOL * t:
            return None
    return c


EXACT_CORNER_TOL = 0.05
"""Two crease lines *meet* (for :func:`_exact_corner`) when their closest points are within this
fraction of the distance along them."""

EXACT_CORNER_ARM = 45.0
"""Largest angle (degrees) between a further crease end's direction and the chord to an exact
corner for it to join the corner as a curved arm."""


def _arc_to(p: np.ndarray, d: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Hermite data of the cubic nearest the circular arc from ``p`` with tangent ``d`` to
    ``c`` (straight when ``d`` points at ``c``)."""
    s = c - p
    L = float(np.linalg.norm(s))
    sh = s / max(L, 1e-300)
    half = float(np.arccos(np.clip(d @ sh, -1.0, 1.0)))  # half the turn of the arc
    theta = 2 * half
    m = L * (2 * np.tan(theta / 4) / np.sin(theta / 2) if theta > 1e-6 else 1.0)
    d1 = 2 * float(d @ sh) * sh - d  # the tangent at c: d mirrored about the chord
    return np.stack([p, m * d, c, m * d1])


def _collinear_pair(P: np.ndarray, ea: CreaseEnd, eb: CreaseEnd, cos_par: float) -> bool:
    """Two ends pointing at each other along one straight line (within :data:`CORNER_TOL`)."""
    s = P[eb.pos] - P[ea.pos]
    L = float(np.linalg.norm(s))
    if not L > 0 or float(ea.direction @ eb.direction) > -cos_par:
        return False
    return float(np.linalg.norm(np.cross(s, ea.direction))) <= CORNER_TOL * L


def _exact_corner(P: np.ndarray, ends: list[CreaseEnd], within=None):
    """A corner of three or more creases inside the hole, two of which arrive straight: two
    non-parallel ends whose lines meet in front of both (closest points within
    :data:`EXACT_CORNER_TOL` of the distance), and every other end whose direction points at
    that point within :data:`EXACT_CORNER_ARM` (a curved crease reaching the corner).
    Returns (end indices, corner point) for the group with the most ends (then the
    tightest meeting), or None when no group has three ends. Two tangent lines of one circular
    crease also meet, which is why two ends alone never make a corner here.

    ``within`` (a predicate on a 3-D point, optional): the corner must pass it, lying within the
    hole's extent. The crease lines of a polyhedron meet beyond its corners too (the edges of a
    dodecahedron, extended, meet exactly at the vertices of its stellation), and such a meeting
    point outside the hole is no corner of the patch."""
    best = None
    cos_par = np.cos(np.radians(PAIR_MAX_TURN))
    cos_arm = np.cos(np.radians(EXACT_CORNER_ARM))
    for a in range(len(ends)):
        for b in range(a + 1, len(ends)):
            ea, eb = ends[a], ends[b]
            da, db = ea.direction, eb.direction
            if ea.pos == eb.pos or abs(float(da @ db)) > cos_par:
                continue
            pa, pb = P[ea.pos], P[eb.pos]
            w = pa - pb
            A = np.array([[da @ da, -(da @ db)], [da @ db, -(db @ db)]])
            try:
                t, u = np.linalg.solve(A, [-(w @ da), -(w @ db)])
            except np.linalg.LinAlgError:
                continue
            if not (t > 0 and u > 0):
                continue
            qa, qb = pa + t * da, pb + u * db
            gap = float(np.linalg.norm(qa - qb))
            if gap > EXACT_CORNER_TOL * min(t, u):
                continue
            if min(ea.chain_length / t, eb.chain_length / u) < CHAIN_PER_GAP:
                continue
            c = 0.5 * (qa + qb)
            if within is not None and not within(c):
                continue
            grp = [a, b]
            spread = 0.0  # how far the further arms turn to reach c
            for i, e in enumerate(ends):
                if i in grp or e.pos in (ea.pos, eb.pos):
                    continue
                s = c - P[e.pos]
                L = float(np.linalg.norm(s))
                if L > 0 and float(e.direction @ s) > cos_arm * L and (
                        e.chain_length >= CHAIN_PER_GAP * L):
                    grp.append(i)
                    spread += 1.0 - float(e.direction @ s) / L
            if len(grp) < MIN_CORNER:
                continue
            if any(_collinear_pair(P, ends[i], ends[j], cos_par)
                   for i in grp for j in grp if i < j):
                continue  # a straight crease through the hole: a pair (T-junction), not here
            log.debug("exact corner %s at %s: spread %.3f", grp, c, spread)
            # the two lines that meet must be straight chains, reliable that far into the hole
            # (a curved crease's tangent line also meets a straight one near the corner);
            # then the arms that turn least
            reach = min(1.0, ea.straight_length / t, eb.straight_length / u)
            key = (len(grp), round(reach, 1), -spread)
            if best is None or key > best[0]:
                best = (key, grp, c)
    if best is None:
        return None
    return best[1], best[2]


def _twin_corners(P: np.ndarray, ends: list[CreaseEnd]):
    """Four leftover ends that meet two by two at two corners inside the hole (two corners of
    a polyhedron, the crease joining them wholly inside): the split into two pairs whose lines
    meet in front of both (:func:`_corner_point`) with the smallest spread, and the two corner
    points; None when no split works. Both corners must be at least one loop edge apart and
    no end's corner may lie behind the other corner (the pairs would cross)."""
    best = None
    le = float(np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean())
    for a, b in (((0, 1), (2, 3)), ((0, 2), (1, 3)), ((0, 3), (1, 2))):
        cs, cost = [], 0.0
        for grp in (a, b):
            es = [ends[i] for i in grp]
            if es[0].convex != es[1].convex or abs(es[0].angle - es[1].angle) > PAIR_MAX_ANGLE_GAP:
                break
            D = np.array([e.direction for e in es])
            if float(D[0] @ D[1]) > np.cos(np.radians(PAIR_MAX_TURN)):
                break  # (nearly) parallel: not a corner
            c = _corner_point(np.array([P[e.pos] for e in es]), D,
                              np.array([e.chain_length for e in es]))
            if c is None:
                break
            cs.append(c)
            cost += sum(float(np.linalg.norm(c - P[e.pos])) for e in es)
        else:
            if float(np.linalg.norm(cs[0] - cs[1])) >= le and (best is None or cost < best[0]):
                best = (cost, ([ends[i] for i in a], [ends[i] for i in b]), np.array(cs))
    if best is None:
        return None
    return best[1], best[2]


KINKED_PAIR_TURN = 60.0
"""Largest angle (degrees) between a leftover crease end's direction and the chord to its
partner for a *kinked pair* (:func:`_kinked_pairs`)."""


def _lines_meet_ahead(pa: np.ndarray, da: np.ndarray, pb: np.ndarray, db: np.ndarray) -> bool:
    """The lines ``pa + t da`` and ``pb + u db`` pass within :data:`CORNER_TOL` of the
    distance of each other at ``t, u > 0`` (in front of both ends)."""
    w = pa - pb
    A = np.array([[da @ da, -(da @ db)], [da @ db, -(db @ db)]])
    try:
        t, u = np.linalg.solve(A, [-(w @ da), -(w @ db)])
    except np.linalg.LinAlgError:
        return False
    if not (t > 0 and u > 0):
        return False
    return float(np.linalg.norm(pa + t * da - pb - u * db)) <= CORNER_TOL * min(t, u)


def _kinked_pairs(P: np.ndarray, ends: list[CreaseEnd]) -> list[tuple[int, int]]:
    """Pairs of crease ends left over by the pairs, corners and T-junctions that are one crease
    kinking where it meets the loop: same convexity, dihedral angles within
    :data:`PAIR_MAX_ANGLE_GAP`, both directions within :data:`KINKED_PAIR_TURN` of the chord,
    chains at least :data:`CHAIN_PER_GAP` of the chord long, and the chord (not the kinked
    directions) within :data:`PAIR_MAX_TILT` of the plane the hole spans. Greedy by alignment;
    the chord inside the loop seen through its vector area (a chord passing over the surround
    joins two different creases); two ends of one chain (the loop cutting a crease at two
    neighbouring vertices, :attr:`CreaseEnd.chain_id`) are never both used; two ends whose
    lines meet in front of both (:func:`_lines_meet_ahead`) are two creases of a corner whose
    third crease was not found, not one crease. Routed straight: a crease arriving at an end
    can bend by 50-60° there (its chain outside zigzags by 15-30° per edge) while inside the
    hole it turns by a few tens of degrees in all."""
    from meshrepair.holes._geom2d import _vector_area

    va = _vector_area(P)
    nva = float(np.linalg.norm(va))
    nh = va / nva if nva > 0 else None
    cos_turn = np.cos(np.radians(KINKED_PAIR_TURN))
    sin_tilt = np.sin(np.radians(PAIR_MAX_TILT))
    poly = None
    if nh is not None:
        from meshrepair.holes._geom2d import loop_seen_through_plane

        poly, project = loop_seen_through_plane(P, nh)
        Q = project(P)
    t_in = np.linspace(0.02, 0.98, 25)[:, None]
    cand = []
    for a in range(len(ends)):
        for b in range(a + 1, len(ends)):
            ea, eb = ends[a], ends[b]
            if ea.pos == eb.pos or ea.convex != eb.convex or (
                    ea.chain_id >= 0 and ea.chain_id == eb.chain_id):
                continue
            if abs(ea.angle - eb.angle) > PAIR_MAX_ANGLE_GAP:
                continue
            s = P[eb.pos] - P[ea.pos]
            L = float(np.linalg.norm(s))
            if not L > 0 or min(ea.chain_length, eb.chain_length) < CHAIN_PER_GAP * L:
                continue
            if nh is not None and abs(float(s @ nh)) > sin_tilt * L:
                continue
            ca, cb = float(ea.direction @ s) / L, float(-eb.direction @ s) / L
            if not min(ca, cb) > cos_turn:
                continue
            if poly is not None and not poly.contains_points(
                    Q[ea.pos] + t_in * (Q[eb.pos] - Q[ea.pos])).all():
                continue  # the chord passes over the surround: not one crease across the hole
            if _lines_meet_ahead(P[ea.pos], ea.direction, P[eb.pos], eb.direction):
                continue  # two creases meeting at a corner whose third crease was not found
            cand.append((ca + cb, a, b))
    cand.sort(reverse=True)
    used: set[int] = set()
    out = []
    for _, a, b in cand:
        if a in used or b in used:
            continue
        out.append((a, b))
        for i in (a, b):
            used.update(j for j, e in enumerate(ends)
                        if j == i or (e.chain_id >= 0 and e.chain_id == ends[i].chain_id))
    return out
