"""Is the probe's crease network a CAD part's creases, or noise? (issue 12, round 11c).

:func:`meshrepair.regions.crease_support` keeps every chain of at least ``L_long = 60`` creased
edges of the robust probe's normals ``N¹`` as it is. On a CAD part those chains are its
creases. On a smooth organic mesh under heavy normal noise (spot γ0.4, ≈ 3k vertices) the probe
leaves dihedrals above ``th`` all over the surface, and they join into long chains too: the
supported region then covers 36-50 % of the edges, the mesh is read as a CAD part (the outside
weight, the discrepancy test, the CAD finish) and the result loses to a plain Taubin filter.
Length does not tell these apart; the *shape* of the network does.

Let ``C_L`` be the creased edges of ``N¹`` (dihedral > ``th``) in chains of at least ``L``
edges (the chains :func:`meshrepair.regions.long_chains` returns), ``V_C`` their vertices and
``d(v)`` the number of edges of ``C_L`` at ``v``. Two statistics:

* the **branching** of the network,

  .. math:: β = \\frac{|\\{v \\in V_C : d(v) \\ge 3\\}|}{|V_C|}.

  A CAD part's creases are polylines that meet at its corners: ``d(v) = 2`` along a crease,
  ``d(v) ≥ 3`` at a corner and where noise makes the crease zigzag across a triangle, so β is
  small (0.04-0.16 on fandisk, twelve, sharp_sphere, trim_star and screwdriver at γ 0.1-0.7).
  The edges of a smooth surface whose probe dihedral exceeds ``th`` at heavy noise are where
  the noise happened to be large: they form a random network with junctions everywhere
  (spot γ0.4 normal: β = 0.29-0.33).

* the **side spread** (the ``s`` of :func:`meshrepair.regions.chain_statistics`, here the
  median over every edge of ``C_L``, not per chain): for a chain edge with faces ``a``, ``b``,
  the faces within ``k = 2`` steps of ``a`` (of ``b``) across edges that are not creased,
  ``S_a``, ``S_b``, with mean normals ``m_a``, ``m_b``;

  .. math:: s = \\operatorname{med}_{e \\in C_L} \\tfrac12 \\big(
            \\operatorname{mean}_{f \\in S_a} \\angle(N¹_f, m_a) +
            \\operatorname{mean}_{f \\in S_b} \\angle(N¹_f, m_b)\\big).

  The probe is a total-variation-like smoother: on a CAD part both sides of a crease come out
  nearly flat (s = 2.0-5.7°); beside a noise chain the surface is as rough as anywhere else on
  the mesh (spot: 6.3-9.1°). A face all of whose edges are creased has no side at all (``S_a =
  {a}``): its edge reads ``s = ∞`` (no flat side), so a network so dense that it isolates the
  faces reads as rough, not as flat.

The network is called **noise** when both read so:

.. math:: \\text{noise} \\iff β > β_0 \\;\\wedge\\; s > s_0, \\qquad β_0 = 0.2,\\; s_0 = 5.5°,

and then no crease is supported: the region ``C`` is empty, and the mesh follows the schedule of
a smooth surface (:mod:`meshrepair.lowpass`, :mod:`meshrepair.presmooth`, the organic finish).
``s_0`` is the side-spread bound of the short-chain test of :mod:`meshrepair.regions`
(:data:`meshrepair.regions.SIDE_SPREAD`), ``β_0`` lies between the CAD parts' largest reading
(0.16, sharp_sphere γ0.7) and the organic networks' smallest where the region covers ≥ 20 %
(0.29). Requiring both keeps a CAD part whose sides are curved (screwdriver γ0.4: s 5.7°, β
0.07) or whose network branches (sharp_sphere γ0.7: β 0.16, s 4.2°). Measured in
docs/parameters.md (round 11c).

Both statistics read angles and the mesh's connectivity only: they are invariant under rigid
motions and uniform scaling.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .topology import Topology

NOISE_NETWORK = True
BRANCHING = 0.2
SIDE_SPREAD = 5.5
SIDE_RINGS = 2


@dataclass(frozen=True)
class NetworkStatistics:
    """Branching ``β`` and median side spread ``s`` (degrees) of a crease network; ``n_edges``
    its size (NaN statistics for an empty network)."""

    branching: float
    side_spread: float
    n_edges: int


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
    from .regions import _angle, _side_adjacency

    ce = np.asarray(chain_edges, dtype=np.int64)
    n, nF = len(ce), len(N)
    if n == 0:
        return np.zeros(0)
    Af = _side_adjacency(topo, creased, nF)
    out = np.zeros(n)
    for j in range(2):
        S = sp.csr_matrix((np.ones(n), (np.arange(n), topo.edge_faces[ce, j])), shape=(n, nF))
        for _ in range(int(rings)):
            S = (S @ Af).tocsr()
            S.data[:] = 1.0
        r, c = S.nonzero()
        dev = _angle(N[c], (S @ N)[r])
        cnt = np.bincount(r, minlength=n)
        # a face every edge of which is creased has no side to be flat: no bound on its spread
        out += np.where(cnt > 1, 0.5 * np.bincount(r, dev, minlength=n) / np.maximum(cnt, 1),
                        np.inf)
    return out


def network_statistics(topo: Topology, N: np.ndarray, th: float = 30.0) -> NetworkStatistics:
    """The statistics of the module docstring for the long chains (``L`` of
    :func:`meshrepair.regions.crease_support`) of edges creased by more than ``th`` degrees in
    the face normals ``N`` ``(nF, 3)``."""
    from .regions import CHAIN_FRACTION, MIN_CHAIN, creased_edges, long_chains

    L = min(MIN_CHAIN, max(1, int(np.ceil(CHAIN_FRACTION * topo.n_edges))))
    cre = creased_edges(topo, N, th)
    idx = np.flatnonzero(long_chains(topo, cre, L))
    if len(idx) == 0:
        return NetworkStatistics(float("nan"), float("nan"), 0)
    s = float(np.median(side_spreads(topo, N, cre, idx)))
    return NetworkStatistics(branching(topo.edges[idx], topo.n_vertices), s, len(idx))


def is_noise_network(stats: NetworkStatistics, *, branching_max: float = BRANCHING,
                     side_spread_max: float = SIDE_SPREAD) -> bool:
    """``β > β_0 ∧ s > s_0`` (module docstring); an empty network is not noise."""
    return bool(NOISE_NETWORK and stats.n_edges > 0 and stats.branching > branching_max
                and stats.side_spread > side_spread_max)


def supported(topo: Topology, N: np.ndarray, support: np.ndarray, th: float = 30.0
              ) -> tuple[np.ndarray, NetworkStatistics]:
    """``support`` (the region of :func:`meshrepair.regions.crease_support`), emptied when the
    network of creased chains reads as noise; with the statistics read."""
    stats = network_statistics(topo, N, th)
    if support.any() and is_noise_network(stats):
        return np.zeros_like(support), stats
    return support, stats


HEAVY_FROM_NETWORK = True
HEAVY_SUPPORT = 0.0


def heavy_from_network(rejected_fraction: float) -> bool:
    """Whether a rejected noise network says the noise is heavy for this mesh: it would have
    covered more than :data:`HEAVY_SUPPORT` of the edges."""
    return bool(HEAVY_FROM_NETWORK and rejected_fraction > HEAVY_SUPPORT)
