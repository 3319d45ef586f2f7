"""Per-region decision: where is a crease supported (MC penalty), where is the surface smooth.

The sharp-edge MC penalty keeps every normal jump it is allowed to act on; on a smooth (organic)
surface the jumps it finds are left-over noise or terraces of the robust stage, and it freezes
them in as false creases and flat facets. A crease is *supported* where a first robust result
``N¹`` (the all-edges MC stage, a total-variation smoother of the normals) shows a long chain of
creased edges:

.. math::  C = \\{ e : \\angle(N^1_{f_a(e)}, N^1_{f_b(e)}) > th \\}, \\qquad
           C_L = \\{ e \\in C : |\\text{chain}(e)| \\ge L \\},

(chains = connected components of C through shared vertices). Real creases of CAD parts are
long connected lines (after the robust stage the crease network of fandisk is one chain of ~720
edges, twelve's 8 chains of 590, sharp_sphere's 34 chains of 1,480); what noise and terracing
leave on organic meshes are short pieces (medians of 10-16 edges on nicolo, igea, pierrot and the
Kinect scan; measured in docs/parameters.md). The supported region is ``C_L`` dilated by
``rings`` vertex rings (a crease moves by a few edges between the noisy input and the result):
an edge is in the region when both its vertices are. Outside it the schedule uses edge-Willmore
only (the smooth prior), inside it the paper's robust + feature stages.

On a coarse mesh a whole crease network has fewer than ``L`` edges (a 12-triangle cube's is one
chain of 12), so the length asked of a chain is ``min(L, ⌈f·n_E⌉)`` with ``f = CHAIN_FRACTION``:
only meshes under ``L / f = 1,500`` edges (about 500 vertices) ask less than ``L``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from . import _kernels as _k
from .topology import Topology

MIN_CHAIN = 30
CHAIN_FRACTION = 0.02
RINGS = 2
FLAT_RINGS = 0
FLAT_ANGLE = 5.0
FLAT_SPREAD = 4.0


def creased_edges(topo: Topology, N: np.ndarray, th: float) -> np.ndarray:
    """``(nE,) bool``: interior edges whose face normals ``N`` differ by more than ``th`` deg."""
    ie = np.flatnonzero(topo.interior)
    m = np.zeros(topo.n_edges, bool)
    m[ie] = _k.creased(np.ascontiguousarray(N, dtype=np.float64),
                       np.ascontiguousarray(topo.edge_faces[ie, 0]),
                       np.ascontiguousarray(topo.edge_faces[ie, 1]), float(th))
    return m


def long_chains(topo: Topology, mask: np.ndarray, min_edges: int) -> np.ndarray:
    """The edges of ``mask`` in connected chains of at least ``min_edges`` edges."""
    idx = np.flatnonzero(mask)
    out = np.zeros(topo.n_edges, bool)
    if len(idx) == 0:
        return out
    e = topo.edges[idx]
    lab = _k.union_find(topo.n_vertices, e[:, 0], e[:, 1])
    cnt = np.bincount(lab[e[:, 0]], minlength=int(lab.max()) + 1)
    out[idx[cnt[lab[e[:, 0]]] >= min_edges]] = True
    return out


def crease_support(topo: Topology, N: np.ndarray, *, th: float = 30.0,
                   min_chain: int = MIN_CHAIN, rings: int = RINGS, flat_rings: int = FLAT_RINGS,
                   flat_angle: float = FLAT_ANGLE) -> np.ndarray:
    """The edges where a crease is supported (see the module docstring).

    Parameters
    ----------
    topo : Topology
    N : (nF, 3) unit face normals of a first robust result
    th : dihedral threshold in degrees
    min_chain : minimum chain length ``L`` in edges
    rings : dilation of the supported chains, in vertex rings
    flat_rings : further growth, only across edges whose dihedral is below ``flat_angle``
    flat_angle : degrees

    Returns
    -------
    (nE,) bool
    """
    L = min(int(min_chain), max(1, int(np.ceil(CHAIN_FRACTION * topo.n_edges))))
    chains = long_chains(topo, creased_edges(topo, N, th), L)
    nV = topo.n_vertices
    act = np.zeros(nV, bool)
    act[topo.edges[chains].ravel()] = True
    if rings > 0 and act.any():
        e = topo.edges
        A = sp.coo_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]],
                                                 np.r_[e[:, 1], e[:, 0]])),
                          shape=(nV, nV)).tocsr()
        for _ in range(rings):
            act |= (A @ act.astype(np.float64)) > 0
        if flat_rings > 0:
            flat = ~creased_edges(topo, N, flat_angle) & topo.interior
            ef = e[flat]
            Af = sp.coo_matrix((np.ones(2 * len(ef)), (np.r_[ef[:, 0], ef[:, 1]],
                                                       np.r_[ef[:, 1], ef[:, 0]])),
                               shape=(nV, nV)).tocsr()
            for _ in range(flat_rings):
                new = act | ((Af @ act.astype(np.float64)) > 0)
                if new.sum() == act.sum():
                    break
                act = new
    return act[topo.edges[:, 0]] & act[topo.edges[:, 1]]


def normal_spread(F: np.ndarray, N: np.ndarray, n_vertices: int) -> np.ndarray:
    """Per vertex, the largest angle (degrees) between an incident face normal and the mean of
    the incident face normals, shape ``(nV,)``."""
    F = np.asarray(F, dtype=np.int64)
    nF = len(F)
    Avf = sp.csr_matrix((np.ones(3 * nF), (F.ravel(), np.repeat(np.arange(nF), 3))),
                        shape=(n_vertices, nF))
    M = Avf @ N
    M /= np.maximum(np.linalg.norm(M, axis=1, keepdims=True), 1e-300)
    dev = np.zeros(n_vertices)
    for k in range(3):
        c = np.clip(np.einsum("ij,ij->i", N, M[F[:, k]]), -1.0, 1.0)
        np.maximum.at(dev, F[:, k], np.degrees(np.arccos(c)))
    return dev


def flat_edges(topo: Topology, N: np.ndarray, support: np.ndarray, *,
               max_spread: float = FLAT_SPREAD) -> np.ndarray:
    """Edges of the crease-supported region whose two vertices see nearly one normal: the
    normal spread (:func:`normal_spread`) of the robust result is below ``max_spread`` degrees
    at both ends. These get the flat-TV prior of :mod:`meshrepair.priors`."""
    dev = normal_spread(topo.faces, N, topo.n_vertices)
    ok = dev < max_spread
    return support & ok[topo.edges[:, 0]] & ok[topo.edges[:, 1]]
