"""Seeded random probe fields attached to the vertices, not to their indices.

Several readings of the input measure an operator through random probes: the white-noise model
profiles of the noise reading (``c_k(m)``, the MAD of ``(I - W^k) W^m Z``), Hutchinson traces
in the risk estimates, a synthetic noise field subtracted from a roughness. Drawn in index
order, a relabelled copy of a mesh gets another realisation of ``Z``, and the reading moves by
its Monte-Carlo error (about 1 % with a few thousand vertices) — enough to move a decision
across its threshold, so the result of a relabelled mesh is not the relabelled result.

The draws are therefore made in a *canonical order* of the vertices: by their squared distance
to the centroid of the vertices in use (those on an edge), ties by index, the vertices no face
uses last (so adding one changes no other vertex's draw). The centroid is summed from each
coordinate column sorted, so it has the same bits in every vertex order; the order is exactly
invariant to relabelling (up to vertices at exactly equal distance, which keep their index
order), and invariant to rotation, translation and scale up to the rounding of the distances
(two distances within about 1e-15 of each other may swap).
"""

from __future__ import annotations

import numpy as np

from meshrepair.mesh.geometry import order_free_centroid

PROBE_SEED = 0


def canonical_order(V: np.ndarray, used: np.ndarray | None = None) -> np.ndarray:
    """The vertices sorted by squared distance to the centroid of the ``used`` ones (ties by
    index), the others last in index order.

    Parameters
    ----------
    V : (nV, 3) float, vertex positions
    used : (nV,) bool, optional, the vertices in use (default: all)

    Returns
    -------
    (nV,) int64, ``order[r]`` is the vertex of rank ``r``
    """
    V = np.asarray(V, dtype=np.float64)
    used = np.ones(len(V), bool) if used is None else np.asarray(used, bool)
    if not used.any():
        return np.arange(len(V), dtype=np.int64)
    c = order_free_centroid(V[used])
    d = V - c
    d = np.where(used, np.einsum("ij,ij->i", d, d), np.inf)
    return np.argsort(d, kind="stable").astype(np.int64)


def probe_field(V: np.ndarray, columns: int | None = None, *, seed: int = PROBE_SEED,
                kind: str = "normal", order: np.ndarray | None = None,
                used: np.ndarray | None = None) -> np.ndarray:
    """A seeded i.i.d. field on the vertices of ``V``, drawn in :func:`canonical_order`.

    Parameters
    ----------
    V : (nV, 3) float, vertex positions (only their order is read)
    columns : the field's columns, or None for a vector
    seed : the generator's seed
    kind : ``"normal"`` (standard normal) or ``"rademacher"`` (±1 with equal probability)
    order : (nV,) int, the canonical order when already computed
    used : (nV,) bool, optional, the vertices in use (:func:`canonical_order`)

    Returns
    -------
    (nV,) or (nV, columns) float64; vertex ``order[r]`` gets the ``r``-th draw
    """
    if order is None:
        order = canonical_order(V, used)
    n = len(order)
    shape = (n,) if columns is None else (n, int(columns))
    rng = np.random.default_rng(seed)
    if kind == "normal":
        draws = rng.normal(size=shape)
    elif kind == "rademacher":
        draws = rng.choice([-1.0, 1.0], size=shape)
    else:
        raise ValueError(f"unknown probe kind {kind!r}")
    Z = np.empty_like(draws)
    Z[order] = draws
    return Z
