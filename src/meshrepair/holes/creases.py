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
   hole), and directions within :data:`PAIR_MAX_TILT` of the plane the hole spans; pairs are
   taken greedily
   by ``d_i · ŝ - d_j · ŝ``. A pair is routed as the cubic Hermite curve from ``p_i`` with
   tangent ``|s| d_i`` to ``p_j`` with tangent ``-|s| d_j`` (a straight crease stays straight,
   a circular one is followed closely: end tangents from a one-sided quadratic difference, tangent
   length ``|s| · 2 tan(θ/4) / sin(θ/2)`` for a turn ``θ``, the cubic nearest to an arc).
3. *Corners.* :data:`MIN_CORNER` or more ends left unpaired whose lines nearly meet in front of
   all of them
   (the least-squares point ``c`` of the lines ``p_i + t d_i``, ``t > 0``, within
   :data:`CORNER_TOL` of every line relative to its distance) are routed as straight segments to
   ``c``: the corner where three creases of a box meet is rebuilt at the lines' intersection.
   A single leftover end whose line meets a paired crease ends there (a T-junction: the pair is
   split at the meeting point).

The routes are constrained segments of the planar triangulation (:func:`.planar.enclose_loop`);
the patch vertices on them are placed on the curves and kept as Dirichlet data of the fairing
(their Laplacian rows dropped, so each side is faired on its own), and the patch edges on them get
the MC penalty (``edge_force = 1``) in the ADMM solve.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

log = logging.getLogger(__name__)

MIN_CHAIN = 3
"""Sharp edges in a row needed for a crease end (isolated noisy sharp edges are not creases)."""

TANGENT_EDGES = 2
"""Edges back along the chain used for the direction of a crease end."""

PAIR_MAX_TURN = 35.0
"""Largest angle (degrees) between a crease end's direction and the chord to its partner."""

PAIR_MAX_ANGLE_GAP = 25.0
"""Largest difference (degrees) of the dihedral angles of two paired crease ends."""

CORNER_TOL = 0.25
"""Largest distance of the corner point from a crease line, relative to the distance along it."""

CHAIN_PER_GAP = 0.25
"""A crease is continued across a gap (to its partner or to the corner) only when its chain
outside the hole is at least this fraction of the gap long: short sharp features (folds of a
statue near a cut base) are not extended across a large hole."""

MIN_CORNER = 3
"""Crease ends needed for a corner: three creases meeting (a box corner); two lines that nearly
meet are too often two unrelated features of an organic surface (measured on nefertiti)."""

PAIR_MAX_TILT = 30.0
"""Largest angle (degrees) between a paired crease's direction and the plane the hole spans
(orthogonal to its vector area): a crease crossing a hole runs within it; folds that dive into a
flat cut (a statue's base) are not paired."""

MIN_CHAIN_EDGES = 8.0
"""A crease end needs a chain at least this many mean loop edge lengths long: the creases of the
CAD meshes in the peers benchmark run 20-66 edges before turning back, the features of
nefertiti that were paired across a hole 4-8 (continuing them made that patch worse: patch
distance 0.500 vs 0.381 ×1e-3)."""

MAX_CHAIN = 64
"""Edges walked back along a chain (enough evidence for any gap up to 256 edges)."""


@dataclass
class CreaseEnd:
    """A sharp-edge chain arriving at a loop vertex.

    Attributes
    ----------
    pos : int
        Position of the vertex in the loop (local index).
    vertex : int
        The mesh vertex.
    direction : (3,) float
        Unit direction of the chain into the hole.
    angle : float
        Mean dihedral angle (degrees) of the chain's last edges.
    convex : bool
    chain_length : float
        Length of the sharp chain walked back from the vertex (at most :data:`MAX_CHAIN`
        edges).
    straight_length : float
        How far back the chain stays on a straight line through the vertex (every chain vertex
        within :data:`STRAIGHT_TOL` degrees of the first edge's direction).
    chain_id : int
        The chain's first vertex off the loop (-1: unknown): two ends with the same id are one
        crease that the loop cuts at two neighbouring vertices.
    """

    pos: int
    vertex: int
    direction: np.ndarray
    angle: float
    convex: bool
    chain_length: float = np.inf
    straight_length: float = np.inf
    chain_id: int = -1


@dataclass
class CreaseRoute:
    """How creases cross one hole (local loop indices).

    Attributes
    ----------
    points : (c, 3) float
        Extra interior points (corners), numbered ``k, k + 1, ...`` after the ``k`` loop vertices.
    segments : (q, 2) int
        Constrained segments between loop vertices and extra points.
    curves : list of (4, 3) float
        Per segment, Hermite data ``(p0, m0, p1, m1)`` of the 3-D curve from its first to its
        second end.
    kinds : list of str
        ``"pair"``, ``"junction"`` or ``"corner"`` per segment.
    view : (3,) float
        A direction to look at a corner from (sum of the directions of its creases), tried as
        a projection plane normal when the loop's own planes cannot hold the routes.
    """

    points: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))
    segments: np.ndarray = field(default_factory=lambda: np.empty((0, 2), np.int64))
    curves: list = field(default_factory=list)
    kinds: list = field(default_factory=list)

    view: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def n_creases(self) -> int:
        return len(self.segments)

    def evaluate(self, seg: int, t: np.ndarray) -> np.ndarray:
        """Points of segment ``seg``'s curve at parameters ``t (n,)`` in [0, 1], ``(n, 3)``."""
        p0, m0, p1, m1 = self.curves[seg]
        t = np.asarray(t, float)[:, None]
        t2, t3 = t * t, t * t * t
        return ((2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * p1
                + (t3 - t2) * m1)


class SharpGraph:
    """Sharp edges of a mesh (dihedral angle above ``th``) as an adjacency structure."""

    def __init__(self, V: np.ndarray, F: np.ndarray, th: float):
        from ..geometry import dihedral_angles, face_normals
        from ..topology import edge_topology

        topo = edge_topology(F, len(V))
        N = face_normals(V, F)
        ang = dihedral_angles(N, topo)
        sharp = (ang > th) & topo.interior
        self.V = V
        self.edges = topo.edges[sharp]
        self.angle = ang[sharp]
        ef = topo.edge_faces[sharp]
        # convex: the second face's far vertex lies below the first face's plane
        fa, fb = ef[:, 0], ef[:, 1]
        Fb = F[fb]
        mask_far = (Fb != self.edges[:, :1]) & (Fb != self.edges[:, 1:])
        w = Fb[np.arange(len(Fb)), np.argmax(mask_far, axis=1)]
        self.convex = np.einsum("ij,ij->i", N[fa], V[w] - V[self.edges[:, 0]]) < 0
        n = len(V)
        e = self.edges
        order = np.argsort(np.r_[e[:, 0], e[:, 1]], kind="stable")
        self.ptr = np.r_[0, np.cumsum(np.bincount(np.r_[e[:, 0], e[:, 1]], minlength=n))]
        self.adj_e = np.r_[np.arange(len(e)), np.arange(len(e))][order]
        self.adj_v = np.r_[e[:, 1], e[:, 0]][order]

    def neighbours(self, v: int) -> tuple[np.ndarray, np.ndarray]:
        s, t = self.ptr[v], self.ptr[v + 1]
        return self.adj_v[s:t], self.adj_e[s:t]


def crease_ends(G: SharpGraph, loop: np.ndarray) -> list[CreaseEnd]:
    """Crease ends on a loop (see the module docstring)."""
    V = G.V
    on_loop = set(loop.tolist())
    ends: list[CreaseEnd] = []
    for pos, v in enumerate(loop.tolist()):
        nb, ne = G.neighbours(v)
        for u, e in zip(nb.tolist(), ne.tolist(), strict=True):
            if u in on_loop:
                continue  # a chord or a crease along the loop, not entering the hole
            chain_v, chain_e = [v, u], [e]
            prev, cur = v, u
            straight = 1  # edges of the chain before it first turns (for the direction)
            while len(chain_e) < MAX_CHAIN:
                nb2, ne2 = G.neighbours(cur)
                cand = [(w, f) for w, f in zip(nb2.tolist(), ne2.tolist(), strict=True)
                        if w != prev and w not in chain_v]
                if not cand:
                    break
                dirv = V[cur] - V[prev]
                dirv = dirv / max(np.linalg.norm(dirv), 1e-300)
                w, f = max(cand, key=lambda c: float(
                    np.dot((V[c[0]] - V[cur]) / max(np.linalg.norm(V[c[0]] - V[cur]), 1e-300),
                           dirv)))
                step = V[w] - V[cur]
                if straight == len(chain_e) and np.dot(step, dirv) > np.cos(np.radians(
                        PAIR_MAX_TURN)) * np.linalg.norm(step):
                    straight += 1
                chain_v.append(w)
                chain_e.append(f)
                prev, cur = cur, w
            if len(chain_e) < MIN_CHAIN:
                continue
            if straight >= 2:  # one-sided quadratic difference: exact tangent of a circle
                l1 = float(np.linalg.norm(V[v] - V[chain_v[1]]))
                l2 = float(np.linalg.norm(V[chain_v[1]] - V[chain_v[2]]))
                d = ((V[v] - V[chain_v[1]]) / max(l1, 1e-300) * (2 * l1 + l2) / (l1 + l2)
                     - (V[chain_v[1]] - V[chain_v[2]]) / max(l2, 1e-300) * l1 / (l1 + l2))
            else:
                d = V[v] - V[chain_v[1]]
            nd = float(np.linalg.norm(d))
            if not nd > 0:
                continue
            ce = np.asarray(chain_e[:min(TANGENT_EDGES, straight)])
            d = d / nd
            # the loop may run along the crease for a few edges (a boundary edge on the crease
            # line has no dihedral angle): the crease enters the hole at the last of them
            p_end, v_end = pos, v
            for _ in range(len(loop)):
                moved = False
                for nbp in ((p_end + 1) % len(loop), (p_end - 1) % len(loop)):
                    step = V[loop[nbp]] - V[v_end]
                    ls = float(np.linalg.norm(step))
                    if ls > 0 and float(step @ d) > np.cos(np.radians(5.0)) * ls:
                        p_end, v_end, moved = nbp, int(loop[nbp]), True
                        break
                if not moved:
                    break
            cl = float(np.linalg.norm(np.diff(V[np.asarray(chain_v)], axis=0), axis=1).sum())
            rel = V[np.asarray(chain_v[1:])] - V[v]
            dist = np.linalg.norm(rel, axis=1)
            d0 = rel[0] / max(dist[0], 1e-300)
            off = (rel @ d0) < np.cos(np.radians(STRAIGHT_TOL)) * dist
            i_off = int(np.argmax(off)) if off.any() else len(dist)
            sl = float(dist[i_off - 1]) if i_off > 0 else 0.0
            ends.append(CreaseEnd(pos=p_end, vertex=v_end, direction=d,
                                  angle=float(G.angle[ce].mean()),
                                  convex=bool(np.mean(G.convex[ce]) >= 0.5), chain_length=cl,
                                  straight_length=sl, chain_id=int(chain_v[1])))
    return ends


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


STRAIGHT_TOL = 2.0
"""Degrees: a crease chain is straight as far as its vertices stay this close to the line of its
first edge (:attr:`CreaseEnd.straight_length`)."""


def _collinear_pair(P: np.ndarray, ea: CreaseEnd, eb: CreaseEnd, cos_par: float) -> bool:
    """Two ends pointing at each other along one straight line (within :data:`CORNER_TOL`)."""
    s = P[eb.pos] - P[ea.pos]
    L = float(np.linalg.norm(s))
    if not L > 0 or float(ea.direction @ eb.direction) > -cos_par:
        return False
    return float(np.linalg.norm(np.cross(s, ea.direction))) <= CORNER_TOL * L


def _exact_corner(P: np.ndarray, ends: list[CreaseEnd]):
    """A corner of three or more creases inside the hole, two of which arrive straight: two
    non-parallel ends whose lines meet in front of both (closest points within
    :data:`EXACT_CORNER_TOL` of the distance), and every other end whose direction points at
    that point within :data:`EXACT_CORNER_ARM` (a curved crease reaching the corner, as on
    fandisk). Returns (end indices, corner point) for the group with the most ends (then the
    tightest meeting), or None when no group has three ends. Two tangent lines of one circular
    crease also meet, which is why two ends alone never make a corner here."""
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
            # (fandisk: a curved crease's tangent line also meets a straight one near the
            # corner); then the arms that turn least
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
    third crease was not found (fandisk creases r=16), not one crease. Routed straight:
    on trim_star crease r=8 the crease arriving at one end bends by 58° there (its chain
    outside zigzags by 15-30° per edge), while inside the hole it turns by 24° in all."""
    from ._geom2d import _vector_area

    va = _vector_area(P)
    nva = float(np.linalg.norm(va))
    nh = va / nva if nva > 0 else None
    cos_turn = np.cos(np.radians(KINKED_PAIR_TURN))
    sin_tilt = np.sin(np.radians(PAIR_MAX_TILT))
    poly = None
    if nh is not None:
        from matplotlib.path import Path as MPath

        from .planar import _plane_frame

        e1, e2 = _plane_frame(-nh)
        Q = np.c_[(P - P.mean(axis=0)) @ e1, (P - P.mean(axis=0)) @ e2]
        poly = MPath(Q)
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
    corner = _exact_corner(P, ends)
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
    from ._geom2d import _vector_area

    va = _vector_area(P)
    nva = float(np.linalg.norm(va))
    if nva > 0:
        nh = va / nva
        sin_tilt = np.sin(np.radians(PAIR_MAX_TILT))
        cand = [c for c in cand if abs(float(ends[c[1]].direction @ nh)) <= sin_tilt
                and abs(float(ends[c[2]].direction @ nh)) <= sin_tilt]
    cand.sort(reverse=True)
    used: set[int] = set()
    for _, a, b in cand:
        if a in used or b in used:
            continue
        used.update((a, b))
        ea, eb = ends[a], ends[b]
        p0, p1 = P[ea.pos], P[eb.pos]
        L = float(np.linalg.norm(p1 - p0))
        # tangent length of the cubic closest to a circular arc turning by theta
        theta = float(np.arccos(np.clip(-ea.direction @ eb.direction, -1.0, 1.0)))
        m = L * (2 * np.tan(theta / 4) / np.sin(theta / 2) if theta > 1e-6 else 1.0)
        segs.append((ea.pos, eb.pos))
        curves.append(np.stack([p0, m * ea.direction, p1, -m * eb.direction]))
        kinds.append("pair")
    rest = [e for i, e in enumerate(ends) if i not in used]
    # T-junctions: a leftover crease whose line meets a paired crease ends on it (fandisk: a
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
