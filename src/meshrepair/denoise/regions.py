"""Per-region decision: where is a crease supported (MC penalty), where is the surface smooth.

The sharp-edge MC penalty keeps every normal jump it is allowed to act on; on a smooth (organic)
surface the jumps it finds are left-over noise or terraces of the robust stage, and it freezes
them in as false creases and flat facets. A crease is *supported* where a first robust result
``N¹`` (the all-edges MC stage, a total-variation smoother of the normals) shows a long chain of
creased edges:

.. math::  C = \\{ e : \\angle(N^1_{f_a(e)}, N^1_{f_b(e)}) > th \\}, \\qquad
           C_L = \\{ e \\in C : |\\text{chain}(e)| \\ge L \\},

(chains = connected components of C through shared vertices). Real creases of CAD parts are
long connected lines (after the robust stage, chains of hundreds of edges); what noise and
terracing leave on organic meshes are short pieces (median chain lengths of 10-16 edges on the
benchmark grid, docs/parameters.md). The supported region is ``C_L`` dilated by
``rings`` vertex rings (a crease moves by a few edges between the noisy input and the result):
an edge is in the region when both its vertices are. Outside it the schedule uses edge-Willmore
only (the smooth prior), inside it the paper's robust + feature stages.

On a coarse mesh a whole crease network has fewer than ``L`` edges (a 12-triangle cube's is one
chain of 12), so the length asked of a chain is ``min(L, ⌈f·n_E⌉)`` with ``f = CHAIN_FRACTION``:
only meshes under ``L / f = 1,500`` edges (about 500 vertices) ask less than ``L``.

Length alone does not tell a short real crease (30-45 edges on a small or coarse part) from
the folds, wrinkles and spikes the probe finds on statues (chains of 32-55 edges). A chain
shorter than
``L_long = LONG_CHAIN`` (60) edges is kept only when it looks like a crease between two flat
sides at a coarser scale (:func:`chain_statistics`): its *persistence ratio* ``p`` (the angle
between the mean normals of the faces within 4 steps on each side, over the angle between the
two faces of the edge, medians along the chain) is within 0.05 of 1 and its *side spread*
``s`` (the mean angle of the faces within 2 steps of a side to their mean) is at most 5.5°:

.. math::  C_L' = \\{ e \\in C_L : |\\text{chain}(e)| \\ge L_{long} \\ \\text{or}\\
           (|p - 1| \\le 0.05 \\ \\text{and}\\ s \\le 5.5°) \\}.

On the benchmark grid (docs/parameters.md) real short creases read p = 0.97-1.03,
s = 2.8-5.2°; the short chains on organic meshes read p = 0.82-1.49 and s = 4.0-11.4°, and
more than 90 % of them fail one of the two tests.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair import _kernels as _k
from meshrepair.mesh.topology import Topology, cached, mask_key

MIN_CHAIN = 30
LONG_CHAIN = 60
PERSIST_RINGS = 4
PERSIST_TOL = 0.05
SIDE_RINGS = 2
SIDE_SPREAD = 5.5
CHAIN_FRACTION = 0.02
RINGS = 2
FLAT_RINGS = 0
FLAT_ANGLE = 5.0
FLAT_SPREAD = 4.0


def creased_edges(topo: Topology, N: np.ndarray, th: float) -> np.ndarray:
    """``(nE,) bool``: interior edges whose face normals ``N`` differ by more than ``th`` deg."""
    return _k.creased_edges(N, topo.edge_faces, float(th))


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


def _unit(X: np.ndarray) -> np.ndarray:
    return X / np.maximum(np.linalg.norm(X, axis=1, keepdims=True), 1e-300)


def _angle(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Row-wise angle in degrees between the (not necessarily unit) rows of A and B."""
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", _unit(A), _unit(B)), -1.0, 1.0)))


def _side_adjacency(topo: Topology, mask: np.ndarray, n_faces: int) -> sp.csr_matrix:
    """``I + A``, A the face adjacency through the interior edges *not* in ``mask``; built once
    per topology and mask (the chain reads of one set of normals share it)."""
    def build():  # the pattern only: the callers read which faces, not the values
        ok = topo.interior & ~mask
        if n_faces == topo.n_faces and int(topo.edge_counts.max(initial=0)) <= 2:
            indptr, indices = _k.face_side_csr(topo.face_edges, topo.edge_faces, ok)
        else:  # (edges of more than two faces: the pairs of edge_faces only)
            indptr, indices = _k.sym_csr(topo.edge_faces[ok, 0], topo.edge_faces[ok, 1],
                                         n_faces, diag=True)
        return sp.csr_matrix((np.ones(len(indices)), indices, indptr),
                             shape=(n_faces, n_faces))

    return cached(topo, ("side_adjacency", n_faces, mask_key(mask)), build)


def _grow(act: np.ndarray, e: np.ndarray) -> np.ndarray:
    """``act`` and the vertices one edge of ``e`` (k, 2) away from it (a ring of dilation)."""
    return _k.grow(act, e)


def chain_statistics(topo: Topology, N: np.ndarray, mask: np.ndarray, edges: np.ndarray, *,
                     persist_rings: int = PERSIST_RINGS, side_rings: int = SIDE_RINGS
                     ) -> tuple[float, float]:
    """Persistence ratio and side spread of one chain of creased edges.

    For a chain edge e with faces a, b, the *sides* S_a^k, S_b^k are the faces reached from a
    (from b) in at most k steps across interior edges not in ``mask`` (the creased edges: a
    side does not cross the chain). With m^k the mean of N over a side,

    .. math::  p = \\operatorname{med}_e \\angle(m_a^K, m_b^K) \\,/\\,
               \\operatorname{med}_e \\angle(N_a, N_b), \\qquad
               s = \\operatorname{med}_e \\tfrac12 \\big(\\operatorname{mean}_{f \\in S_a^k}
               \\angle(N_f, m_a^k) + \\operatorname{mean}_{f \\in S_b^k}
               \\angle(N_f, m_b^k)\\big)

    (K = ``persist_rings``, k = ``side_rings``). A crease between two flat sides keeps its
    angle at the coarse scale (p = 1, s = 0); the fold of a curved surface adds the sides'
    curvature to the angle (p > 1), a narrow wrinkle or spike on a smooth surface loses it
    (p < 1); both have curved sides (s > 0).

    Parameters
    ----------
    topo : Topology
    N : (nF, 3) unit face normals
    mask : (nE,) bool, the creased edges (sides do not cross them)
    edges : (k,) int, the chain's edge indices

    Returns
    -------
    (p, s) : the persistence ratio and the side spread in degrees
    """
    Af = _side_adjacency(topo, mask, len(N))
    e = np.asarray(edges, dtype=np.int64)
    p, s = _chain_stats(Af, N, topo.edge_faces[e, 0], topo.edge_faces[e, 1],
                        np.zeros(len(e), np.int64), 1, int(persist_rings), int(side_rings))
    return float(p[0]), float(s[0])


def _ring(S: sp.csr_matrix, Af: sp.csr_matrix, work: np.ndarray) -> sp.csr_matrix:
    """The 0/1 pattern of ``S @ Af`` (one more ring of faces per row) in the order scipy's
    product stores it (:func:`meshrepair._kernels.product_pattern`; ``work`` is reused)."""
    indptr, indices = _k.product_pattern(S.indptr, S.indices, Af.indptr, Af.indices,
                                         Af.shape[0], work)
    return sp.csr_matrix((np.ones(len(indices)), indices, indptr), shape=S.shape)


def _group_median(x: np.ndarray, g: np.ndarray, n_groups: int) -> np.ndarray:
    """Median of ``x`` within each group ``g`` (``0 <= g < n_groups``, every group non-empty)."""
    o = np.lexsort((x, g))
    xs, gs = x[o], g[o]
    start = np.searchsorted(gs, np.arange(n_groups))
    cnt = np.bincount(gs, minlength=n_groups)
    lo, hi = start + (cnt - 1) // 2, start + cnt // 2
    return 0.5 * (xs[lo] + xs[hi])


def _chain_stats(Af, N, fa, fb, group, n_groups, persist_rings, side_rings):
    """(p, s) per chain, all chains at once (rows = chain edges, ``group`` = their chain)."""
    n, nF = len(fa), len(N)
    d1 = _group_median(_angle(N[fa], N[fb]), group, n_groups)
    S = [sp.csr_matrix((np.ones(n), (np.arange(n), f)), shape=(n, nF)) for f in (fa, fb)]
    spread = np.zeros(n)
    p = np.ones(n_groups)
    work = np.full(nF, -1, np.int64)
    for k in range(1, max(persist_rings, side_rings) + 1):
        for j in range(2):
            S[j] = _ring(S[j], Af, work)
        if k == side_rings:
            for Sj in S:
                r, c = Sj.nonzero()
                dev = _angle(N[c], (Sj @ N)[r])
                spread += 0.5 * np.bincount(r, dev, minlength=n) / np.bincount(r, minlength=n)
        if k == persist_rings:
            p = _group_median(_angle(S[0] @ N, S[1] @ N), group, n_groups) / np.maximum(d1, 1e-12)
    if persist_rings == 0:
        p = np.ones(n_groups)
    return p, _group_median(spread, group, n_groups)


def supported_chains(topo: Topology, N: np.ndarray, creased: np.ndarray, chains: np.ndarray, *,
                     long_chain: int = LONG_CHAIN, persist_tol: float = PERSIST_TOL,
                     side_spread: float = SIDE_SPREAD) -> np.ndarray:
    """``chains`` without its chains shorter than ``long_chain`` edges that do not look like a
    crease between flat sides: ``|p − 1| > persist_tol`` or ``s > side_spread``
    (:func:`chain_statistics`). Chains of at least ``long_chain`` edges are kept as they are.

    Returns
    -------
    (nE,) bool
    """
    idx = np.flatnonzero(chains)
    out = chains.copy()
    if len(idx) == 0:
        return out
    e = topo.edges[idx]
    lab = _k.union_find(topo.n_vertices, e[:, 0], e[:, 1])[e[:, 0]]
    cnt = np.bincount(lab)
    short = np.unique(lab[cnt[lab] < long_chain])
    if len(short) == 0:
        return out
    rows = np.flatnonzero(np.isin(lab, short))
    g = np.searchsorted(short, lab[rows])
    ce = idx[rows]
    p, s = _chain_stats(_side_adjacency(topo, creased, len(N)), N, topo.edge_faces[ce, 0],
                        topo.edge_faces[ce, 1], g, len(short), PERSIST_RINGS, SIDE_RINGS)
    bad = (np.abs(p - 1.0) > persist_tol) | (s > side_spread)
    out[ce[bad[g]]] = False
    return out


def crease_support(topo: Topology, N: np.ndarray, *, th: float = 30.0,
                   min_chain: int = MIN_CHAIN, rings: int = RINGS, flat_rings: int = FLAT_RINGS,
                   flat_angle: float = FLAT_ANGLE, long_chain: int = LONG_CHAIN,
                   persist_tol: float | None = PERSIST_TOL, side_spread: float = SIDE_SPREAD,
                   chain_filter=None) -> np.ndarray:
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
    long_chain : chains of at least this many edges are kept without the test below
    persist_tol, side_spread : the shorter chains are kept only when their persistence ratio
        is within ``persist_tol`` of 1 and their side spread at most ``side_spread`` degrees
        (:func:`supported_chains`); ``persist_tol=None`` keeps every chain of ``L`` edges
    chain_filter : optional ``f(topo, N, creased, chains) -> chains`` applied to the kept chains
        before the dilation (:func:`meshrepair.denoise.crease_network.drop_noise_chains`)

    Returns
    -------
    (nE,) bool
    """
    L = min(int(min_chain), max(1, int(np.ceil(CHAIN_FRACTION * topo.n_edges))))
    cre = creased_edges(topo, N, th)
    chains = long_chains(topo, cre, L)
    if persist_tol is not None and chains.any():
        chains = supported_chains(topo, N, cre, chains, long_chain=max(L, int(long_chain)),
                                  persist_tol=float(persist_tol), side_spread=float(side_spread))
    if chain_filter is not None and chains.any():
        chains = chain_filter(topo, N, cre, chains)
    nV = topo.n_vertices
    act = np.zeros(nV, bool)
    act[topo.edges[chains].ravel()] = True
    if rings > 0 and act.any():
        e = topo.edges
        for _ in range(rings):
            act = _grow(act, e)
        if flat_rings > 0:
            flat = ~creased_edges(topo, N, flat_angle) & topo.interior
            ef = e[flat]
            for _ in range(flat_rings):
                new = _grow(act, ef)
                if new.sum() == act.sum():
                    break
                act = new
    return act[topo.edges[:, 0]] & act[topo.edges[:, 1]]


def normal_spread(F: np.ndarray, N: np.ndarray, n_vertices: int) -> np.ndarray:
    """Per vertex, the largest angle (degrees) between an incident face normal and the mean of
    the incident face normals, shape ``(nV,)``: the arccos of the smallest cosine
    (:func:`meshrepair._kernels.min_corner_cos`, one pass over the faces)."""
    return np.degrees(np.arccos(_k.min_corner_cos(F, N, n_vertices)))


def flat_edges(topo: Topology, N: np.ndarray, support: np.ndarray, *,
               max_spread: float = FLAT_SPREAD) -> np.ndarray:
    """Edges of the crease-supported region whose two vertices see nearly one normal: the
    normal spread (:func:`normal_spread`) of the robust result is below ``max_spread`` degrees
    at both ends. These get the flat-TV prior of :mod:`meshrepair.model.priors`."""
    dev = normal_spread(topo.faces, N, topo.n_vertices)
    ok = dev < max_spread
    return support & ok[topo.edges[:, 0]] & ok[topo.edges[:, 1]]
