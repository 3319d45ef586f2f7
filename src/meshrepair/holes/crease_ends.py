"""Crease ends on a hole's loop (:mod:`meshrepair.holes.creases`, step 1): the sharp-edge graph
of the surround, the chains that arrive at the loop, each end's position, direction into the
hole, dihedral angle and convexity, and the tunables of the pairing (steps 2-4), with the
dataclasses of an end and of a routed crease.
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
meet are too often two unrelated features of an organic surface (docs/holes.md)."""

PAIR_MAX_TILT = 30.0
"""Largest angle (degrees) between a paired crease's directions and the plane the hole spans
(unit normal ``n`` along its vector area): a crease crossing a hole runs within it; folds that
dive into a flat cut (a statue's base) are not paired. Where the loop folds over a curved crease
(a hole over a ridge of a rounded part), one end can tilt past the bound while the crease still
crosses the hole: such a pair is kept when its mean direction is within the bound,
``|(d_i + d_j) · n| <= 2 sin`` of it (the Hermite route's midpoint lies
``|s| (d_i + d_j) · n / 8`` off the chord's midpoint across the plane, so the route stays near
it; a fold tilts both ends the same way), and its route, seen through the plane, stays inside
the loop (a route passing over the surround joins two different creases)."""

MIN_CHAIN_EDGES = 8.0
"""A crease end needs a chain at least this many mean loop edge lengths long: the creases of the
CAD meshes in the peers benchmark run 20-66 edges before turning back, the short features of
an organic surface 4-8 (continuing those across a hole makes the patch worse)."""

MAX_CHAIN = 64
"""Edges walked back along a chain (enough evidence for any gap up to 256 edges)."""


STRAIGHT_TOL = 2.0
"""Degrees: a crease chain is straight as far as its vertices stay this close to the line of its
first edge (:attr:`CreaseEnd.straight_length`)."""


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
        from meshrepair.mesh.geometry import dihedral_angles, face_normals
        from meshrepair.mesh.topology import edge_topology

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
