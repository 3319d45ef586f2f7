r"""Is a crease chain of the probe a CAD part's crease, or noise?

:func:`meshrepair.denoise.regions.crease_support` keeps every chain of at least ``L_long = 60``
creased edges of the robust probe's normals ``N¹`` as it is. On a CAD part those chains are its
creases. On a coarse smooth organic mesh under heavy normal noise the probe leaves dihedrals
above ``th`` all over the surface, and they join into long chains too: the supported region
then covers a third to a half of the edges, the mesh is read as a CAD part (the outside weight,
the discrepancy test, the CAD finish) and the result loses to a plain Taubin filter. Length
does not tell these apart; the *shape* of a chain does.

For a chain ``c`` (a connected component of the creased edges kept by
:func:`meshrepair.denoise.regions.crease_support`, before its dilation), ``V_c`` its vertices and
``d(v)`` the number of its edges at ``v``, two statistics:

* the **branching** of the chain,

  .. math:: β_c = \frac{|\{v \in V_c : d(v) \ge 3\}|}{|V_c|}.

  A CAD part's creases are polylines that meet at its corners: ``d(v) = 2`` along a crease,
  ``d(v) ≥ 3`` at a corner and where noise makes the crease zigzag across a triangle, so β is
  small (on the benchmark CAD parts at γ 0.1-0.7: mostly 0.00-0.22 per chain, up to 0.41 on
  single chains of a curved part; 0.02-0.18 over each whole network). The edges of a smooth
  surface whose probe dihedral exceeds ``th`` at heavy noise are where the noise happened to be
  large: they form a random network with junctions everywhere (0.19-0.46 per chain, 0.30-0.36
  over the network).

* the **side spread** (the ``s`` of :func:`meshrepair.denoise.regions.chain_statistics`): for a
  chain
  edge with faces ``a``, ``b``, the faces within ``k = 2`` steps of ``a`` (of ``b``) across
  edges that are not creased, ``S_a``, ``S_b``, with mean normals ``m_a``, ``m_b``;

  .. math:: s_c = \operatorname{med}_{e \in c} \tfrac12 \big(
            \operatorname{mean}_{f \in S_a} \angle(N¹_f, m_a) +
            \operatorname{mean}_{f \in S_b} \angle(N¹_f, m_b)\big).

  The probe is a total-variation-like smoother: on a CAD part both sides of a crease come out
  nearly flat (2.0-7.6° per chain, 2.0-5.2° over the network but for parts with curved sides,
  up to 7.6°); beside a noise chain the surface is as rough as anywhere else on the mesh
  (6.0-9.8° per chain, 7.5-8.1° over the network). A face all of whose edges
  are creased has no side at all (``S_a = {a}``) and gives no evidence: an edge is averaged
  over the sides it has, an edge with none is left out of the medians, and a chain (or
  network) with no side at all reads ``s`` = NaN, never noise (a regular tetrahedron: every
  face closed in by its creases, every vertex a junction, β = 1).

The same two statistics over the whole network (``β`` of every kept chain edge together, ``s``
the median over all of them) say whether noise made chains on this mesh at all. A chain is
dropped from the crease support when both levels read noise:

.. math:: \text{drop}(c) \iff \underbrace{β > β_0 \wedge s > s_0}_{\text{the network}}
          \;\wedge\; \underbrace{β_c > β_0 \wedge s_c > s_0}_{\text{the chain}},
          \qquad β_0 = 0.2,\; s_0 = 5.5°.

The network test keeps every chain of a CAD part whose statistics are ordinary (the per-chain
reads alone are noisy on curved CAD sides, where a real crease can read β_c 0.22, s_c 5.9°);
the chain test keeps the real creases of a CAD part whose probe also left noise chains (a
network that reads β 0.24, s 6.4° can hold both).

``s_0`` is the side-spread bound of the short-chain test of :mod:`meshrepair.denoise.regions`
(:data:`meshrepair.denoise.regions.SIDE_SPREAD`); ``β_0`` lies between the CAD networks (≤ 0.18) and
the noise networks (≥ 0.30). Requiring both keeps a CAD part whose sides are curved (network s
up to 7.6°, β ≤ 0.18) or whose network branches (β up to 0.16, s 4.2°).

**The noise is heavy for this mesh** (:func:`heavy_from_network`) when the dropped noise
chains had supported more than ``f_h = 4 %`` of the edges: noise that is large against the
local triangle size makes chains over a sizeable part of the surface, whatever the one-ring level
γ̂ in mean edge lengths reads (5-37 % on coarse organic meshes at γ 0.2-0.4, up to nearly all
edges on a mesh whose triangle sizes vary widely). The sparse terrace chains an unconverged
probe leaves on a finely subdivided mesh are dropped too but do not make the noise heavy
(0.5-1.7 % of the edges). Then the gate of the low-pass of the input
(:func:`meshrepair.denoise.presmooth.presmooth_steps`, ``heavy=True``) does not ask for
``γ_t > 0.32``; its other conditions (an organic mesh, white noise, not impulsive) and its
length ``k`` are unchanged (docs/parameters.md).

Both statistics read angles and the mesh's connectivity only: they are invariant under rigid
motions and uniform scaling.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from meshrepair.mesh.topology import Topology

NOISE_NETWORK = True
BRANCHING = 0.2
SIDE_SPREAD = 5.5
SIDE_RINGS = 2


def branching(edges: np.ndarray, n_vertices: int) -> float:
    """``β`` of the module docstring for the network of ``edges`` ``(k, 2)``: the fraction of its
    vertices where three or more of its edges meet (NaN when empty)."""
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    if len(e) == 0:
        return float("nan")
    d = np.bincount(e.ravel(), minlength=int(n_vertices))
    on = d > 0
    return float((d[on] >= 3).sum() / on.sum())


def side_spreads(topo: Topology, N: np.ndarray, creased: np.ndarray, chain_edges: np.ndarray,
                 rings: int = SIDE_RINGS) -> np.ndarray:
    """Per edge of ``chain_edges`` (edge indices), the side spread of the module docstring in
    degrees: the mean angle of the faces within ``rings`` steps of each side (across interior
    edges not in ``creased``) to the side's mean normal, averaged over the two sides."""
    from meshrepair.denoise.regions import _angle, _ring, _side_adjacency

    ce = np.asarray(chain_edges, dtype=np.int64)
    n, nF = len(ce), len(N)
    if n == 0:
        return np.zeros(0)
    Af = _side_adjacency(topo, creased, nF)
    tot, cnt_sides = np.zeros(n), np.zeros(n)
    work = np.full(nF, -1, np.int64)
    for j in range(2):
        S = sp.csr_matrix((np.ones(n), (np.arange(n), topo.edge_faces[ce, j])), shape=(n, nF))
        for _ in range(int(rings)):
            S = _ring(S, Af, work)
        r, c = S.nonzero()
        dev = _angle(N[c], (S @ N)[r])
        cnt = np.bincount(r, minlength=n)
        # a face every edge of which is creased has no side: no evidence either way
        has = cnt > 1
        tot += np.where(has, np.bincount(r, dev, minlength=n) / np.maximum(cnt, 1), 0.0)
        cnt_sides += has
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(cnt_sides > 0, tot / np.maximum(cnt_sides, 1), np.nan)


def chain_reads(topo: Topology, N: np.ndarray, creased: np.ndarray, chains: np.ndarray,
                per_edge: bool = False):
    """Per chain (connected component of ``chains``, a ``(nE,)`` bool mask), its branching
    ``β_c`` and side spread ``s_c`` (module docstring), with ``creased`` the mask the sides do
    not cross.

    Returns
    -------
    (idx, group, beta, spread) : the chain edges ``(k,)``, their chain index ``(k,)`` and per
    chain ``β_c`` and ``s_c`` in degrees ``(n_chains,)``; with ``per_edge`` also the side
    spread of every chain edge ``(k,)``
    """
    from meshrepair import _kernels as _k
    from meshrepair.denoise.regions import _group_median

    idx = np.flatnonzero(chains)
    if len(idx) == 0:
        z = np.zeros(0)
        return (idx, idx.copy(), z, z, z) if per_edge else (idx, idx.copy(), z, z)
    e = topo.edges[idx]
    lab_v = _k.union_find(topo.n_vertices, e[:, 0], e[:, 1])
    u, g = np.unique(lab_v[e[:, 0]], return_inverse=True)
    d = np.bincount(e.ravel(), minlength=topo.n_vertices)  # chains are vertex-disjoint
    on = np.flatnonzero(d > 0)
    gv = np.searchsorted(u, lab_v[on])
    n_v = np.bincount(gv, minlength=len(u))
    beta = np.bincount(gv, (d[on] >= 3).astype(np.float64), minlength=len(u)) / n_v
    s_e = side_spreads(topo, N, creased, idx)
    spread = np.full(len(u), np.nan)
    ok = np.isfinite(s_e)
    if ok.any():  # median over the edges that have a side; NaN for a chain with none
        has = np.unique(g[ok])
        spread[has] = _group_median(s_e[ok], np.searchsorted(has, g[ok]), len(has))
    return (idx, g, beta, spread, s_e) if per_edge else (idx, g, beta, spread)


def is_noise_chain(beta, spread, *, branching_max: float = BRANCHING,
                   side_spread_max: float = SIDE_SPREAD):
    """``β_c > β_0 ∧ s_c > s_0`` (module docstring), elementwise."""
    return (np.asarray(beta) > branching_max) & (np.asarray(spread) > side_spread_max)


@dataclass
class NetworkRead:
    """What :func:`supported` read: the branching and median side spread over every kept chain
    (NaN when there is none), the chains dropped as noise and the fraction of the edges whose
    support they removed."""

    branching: float = float("nan")
    side_spread: float = float("nan")
    n_chains: int = 0
    dropped: int = 0
    rejected: float = 0.0


def drop_noise_chains(topo: Topology, N: np.ndarray, creased: np.ndarray, chains: np.ndarray,
                      read: NetworkRead | None = None) -> np.ndarray:
    """``chains`` without its noise chains (:func:`is_noise_chain`); the
    ``chain_filter`` of :func:`meshrepair.denoise.regions.crease_support`. ``read`` is filled in."""
    idx, g, beta, spread, s_edges = chain_reads(topo, N, creased, chains, per_edge=True)
    out = chains.copy()
    if len(idx) == 0:
        return out
    fin = s_edges[np.isfinite(s_edges)]
    b_net = branching(topo.edges[idx], topo.n_vertices)
    s_net = float(np.median(fin)) if len(fin) else float("nan")
    bad = np.zeros(len(beta), bool)
    if NOISE_NETWORK and is_noise_chain(b_net, s_net):  # noise made chains here at all
        bad = is_noise_chain(beta, spread)  # and these are they
    out[idx[bad[g]]] = False
    if read is not None:
        read.branching, read.side_spread = b_net, s_net
        read.n_chains, read.dropped = len(beta), int(bad.sum())
    return out


def supported(topo: Topology, N: np.ndarray, th: float = 30.0
              ) -> tuple[np.ndarray, NetworkRead]:
    """The crease-supported region of :func:`meshrepair.denoise.regions.crease_support` without the
    noise chains, and what was read (``rejected``: the fraction of the edges the dropped chains
    supported, 0 when none was dropped)."""
    from meshrepair.denoise.regions import crease_support

    read = NetworkRead()
    sup = crease_support(topo, N, th=th,
                         chain_filter=lambda t, n, c, ch: drop_noise_chains(t, n, c, ch, read))
    if read.dropped:
        read.rejected = float(crease_support(topo, N, th=th).mean() - sup.mean())
    return sup, read


HEAVY_FROM_NETWORK = True
HEAVY_SUPPORT = 0.04


def heavy_from_network(rejected_fraction: float) -> bool:
    """Whether dropped noise chains say the noise is heavy for this mesh (module docstring):
    they had supported more than :data:`HEAVY_SUPPORT` of the edges."""
    return bool(HEAVY_FROM_NETWORK and rejected_fraction > HEAVY_SUPPORT)
