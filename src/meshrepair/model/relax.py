"""Feature-constrained tangential vertex relaxation.

The V-update of the paper is driven by face normals only, so it cannot see a vertex sliding within
its tangent plane: the tangential part of random-direction noise survives ADMM and leaves
irregular triangles. After each V-update we move every vertex a fraction ``w`` of the way towards
the centroid of its neighbours, keeping only the component that does not change the shape:

* a smooth vertex moves in its tangent plane (the displacement minus its normal component);
* a crease vertex (exactly two incident sharp or boundary edges) moves along the crease;
* a corner (one, or three or more, such edges) and a fixed vertex stays.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair.mesh.geometry import vertex_normals
from meshrepair.mesh.topology import Topology, adjacency, cached, umbrella_operator


class TangentialRelaxer:
    """Precomputed umbrella operator for :meth:`step`.

    Parameters
    ----------
    topo : Topology
    fixed : (nV,) bool, optional
    """

    def __init__(self, topo: Topology, fixed: np.ndarray | None = None):
        self.topo = topo
        nV = topo.n_vertices
        e = topo.edges
        A = sp.coo_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                          shape=(nV, nV)).tocsr()
        deg = np.asarray(A.sum(axis=1)).ravel()
        self.W = sp.diags(1.0 / np.maximum(deg, 1.0)) @ A
        self.fixed = np.zeros(nV, bool) if fixed is None else np.asarray(fixed, bool)
        self.isolated = deg == 0

    def step(self, V: np.ndarray, sharp: np.ndarray, w: float) -> np.ndarray:
        """One relaxation step; returns new vertices ``(nV, 3)``.

        Parameters
        ----------
        V : (nV, 3)
        sharp : (nE,) bool, the current sharp-edge mask (boundary edges are added)
        w : float in (0, 1], fraction of the tangential move
        """
        topo = self.topo
        nV = topo.n_vertices
        disp = self.W @ V - V
        n = vertex_normals(V, topo.faces)
        disp -= np.einsum("ij,ij->i", disp, n)[:, None] * n

        feat = np.asarray(sharp, bool) | topo.boundary
        fe = topo.edges[feat]
        cnt = np.bincount(fe.ravel(), minlength=nV)
        move_along = cnt == 2
        frozen = (cnt == 1) | (cnt >= 3) | self.fixed | self.isolated
        if move_along.any():
            # unit directions of the feature half-edges leaving each vertex
            src = np.r_[fe[:, 0], fe[:, 1]]
            dst = np.r_[fe[:, 1], fe[:, 0]]
            u = V[dst] - V[src]
            u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300)
            order = np.argsort(src, kind="stable")
            src_s, u_s = src[order], u[order]
            first = np.r_[True, src_s[1:] != src_s[:-1]]
            ref = np.zeros((nV, 3))
            ref[src_s[first]] = u_s[first]
            sgn = np.sign(np.einsum("ij,ij->i", u_s, ref[src_s]))
            tan = np.zeros((nV, 3))
            np.add.at(tan, src_s, sgn[:, None] * u_s)
            tn = np.linalg.norm(tan, axis=1, keepdims=True)
            tan = np.divide(tan, tn, out=np.zeros_like(tan), where=tn > 0)
            full = self.W @ V - V
            along = np.einsum("ij,ij->i", full, tan)[:, None] * tan
            disp[move_along] = along[move_along]
        disp[frozen] = 0.0
        return V + w * disp


def locally_flipped_faces(V: np.ndarray, topo: Topology, cos_max: float = 0.0) -> np.ndarray:
    """Faces whose normal points against the sum of their edge-neighbours' normals.

    A face counts as folded when the angle between its normal and the mean normal of its
    neighbours exceeds ``arccos(cos_max)`` (90° by default). A stricter 120° caught fewer
    fold-overs and left random-noise results 1.5x worse (benchmarks/ablation.py). Most fold-overs
    come from noise with a tangential part (random directions); a clean surface can have a few
    too (tiny sliver faces folded back against a neighbour, at 2-14° interior angles and 0.2-8 %
    of the mean face area: ``benchmarks/input_folds.py`` counts them, 0-113 per clean shared
    mesh). The normal-driven
    V-update cannot unfold them (a face exactly opposite its target normal is a stationary point of
    (26)), and each one costs up to 180° of angular error.

    Returns
    -------
    (nF,) bool
    """
    from meshrepair import _kernels as _k

    N = _k.face_normals(np.ascontiguousarray(V, dtype=np.float64), topo.faces)
    a, b = cached(topo, ("interior_faces",), lambda: _interior_faces(topo))
    return _k.folded(N, _k.neighbor_sum(N, a, b), cos_max)


def _interior_faces(topo: Topology) -> tuple[np.ndarray, np.ndarray]:
    """The two faces of every interior edge, contiguous."""
    from meshrepair._kernels import interior_edges

    return interior_edges(topo.edges, topo.edge_faces)[2:]


def untangle(V: np.ndarray, topo: Topology, *, max_iter: int = 50,
             fixed: np.ndarray | None = None, patience: int = 3,
             flipped: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Unfold locally flipped faces by umbrella smoothing of their vertices and 1-ring only.

    Repeats until no face is locally flipped (usually 1-3 rounds) or ``max_iter``; boundary and
    fixed vertices do not move. Vertices away from fold-overs are untouched.

    The iterate with the fewest flipped faces is returned (the earliest among equals), and the
    rounds stop after ``patience`` rounds without fewer flipped faces. On a tiny closed mesh
    whose faces all meet at more than 90° (a tetrahedron: every face "flipped" against its
    neighbours, which are convex creases, not fold-overs) smoothing every vertex only shrinks
    the mesh towards its centroid (by 1/3 per round on a tetrahedron, to 1e-24 after 50 rounds)
    and never lowers the count, so the input is returned unchanged.

    ``flipped``: :func:`locally_flipped_faces` of ``V`` when the caller has it already.

    Returns
    -------
    V : (nV, 3) new array
    n_left : number of flipped faces left
    """
    nV = topo.n_vertices
    e = topo.edges
    A, W = adjacency(topo), umbrella_operator(topo)
    frozen = np.zeros(nV, bool)
    frozen[e[topo.boundary].ravel()] = True
    if fixed is not None:
        frozen |= np.asarray(fixed, bool)
    V = np.array(V, dtype=np.float64, copy=True)
    fl = locally_flipped_faces(V, topo) if flipped is None else np.asarray(flipped, bool)
    best_V, best_n, stall = V.copy(), int(fl.sum()), 0
    for _ in range(max_iter):
        if not fl.any():
            break
        act = np.zeros(nV, bool)
        act[topo.faces[fl].ravel()] = True
        act |= (A @ act.astype(np.float64)) > 0
        act &= ~frozen
        if not act.any():
            break
        V[act] = (W @ V)[act]
        fl = locally_flipped_faces(V, topo)
        n = int(fl.sum())
        if n < best_n:
            best_V, best_n, stall = V.copy(), n, 0
        else:
            stall += 1
            if stall >= patience:
                break
    return best_V, best_n
