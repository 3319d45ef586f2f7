"""Matching two closed loops with different vertex counts (completion's suitable subdivision).

* the optimal monotone (order-preserving) matching of a short loop into a longer one
  (:func:`monotone_loop_match`), which decides where the short loop must be subdivided;
* the common refinement of two aligned loops (:func:`align_loops`): matches and insertions on
  both sides, a cyclic Needleman-Wunsch alignment.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from meshrepair.complete.rigid import _points
from meshrepair.errors import MeshRepairError

__all__ = ["LoopAlignment", "align_loops", "monotone_loop_match"]


# ------------------------------------------------------------------------------------------------
# monotone matching of loops with different vertex counts
# ------------------------------------------------------------------------------------------------

def _monotone_dp(C: np.ndarray) -> tuple[float, np.ndarray]:
    """Min-cost strictly increasing ``j_0 = 0 < j_1 < ... < j_{m-1} < n`` for costs ``C (m, n)``."""
    m, n = C.shape
    inf = np.inf
    D = np.full(n, inf)
    D[0] = C[0, 0]
    back = np.zeros((m, n), dtype=np.int32)
    ar = np.arange(n)
    for i in range(1, m):
        pm = np.minimum.accumulate(D)
        am = np.maximum.accumulate(np.where(D == pm, ar, 0))
        Dn = np.full(n, inf)
        Dn[1:] = C[i, 1:] + pm[:-1]
        back[i, 1:] = am[:-1]
        Dn[: i] = inf
        Dn[n - m + i + 1:] = inf
        D = Dn
    j = np.zeros(m, dtype=np.int64)
    j[-1] = int(np.argmin(D))
    cost = float(D[j[-1]])
    for i in range(m - 1, 0, -1):
        j[i - 1] = back[i, j[i]]
    return cost, j


def monotone_loop_match(A: np.ndarray, B: np.ndarray, *, anchors: int = 6
                        ) -> tuple[np.ndarray, float]:
    """Order-preserving matching of a closed loop ``A`` into a longer closed loop ``B``.

    Both loops must run in the same direction and be aligned in space. Every vertex of ``A`` is
    matched with a distinct vertex of ``B`` so that the matched indices increase cyclically and
    the sum of squared distances is least (dynamic programming, O(len(A) len(B)) per anchor); the
    unmatched vertices of ``B`` between two matched ones tell where the edge of ``A`` between them
    has to be split. The anchor ``A[0] <-> B[j_0]`` is tried for the ``anchors`` vertices of
    ``B`` nearest to ``A[0]``.

    Parameters
    ----------
    A : (m, 3) float
    B : (n, 3) float with n >= m
    anchors : int

    Returns
    -------
    j : (m,) int64, cyclically increasing indices into ``B`` (``j[0]`` the anchor)
    rms : float, RMS distance of the matched pairs
    """
    A = _points(A, "loop A")
    B = _points(B, "loop B")
    m, n = len(A), len(B)
    if n < m:
        raise MeshRepairError(f"loop B ({n} vertices) must not be shorter than loop A ({m})")
    C = ((A[:, None, :] - B[None, :, :]) ** 2).sum(axis=2)
    if n == m:  # only the cyclic shift is free
        i = np.arange(m)
        costs = np.array([C[i, (i + s) % n].sum() for s in range(n)])
        s = int(np.argmin(costs))
        return (i + s) % n, float(np.sqrt(costs[s] / m))
    cand = np.argsort(C[0])[: max(1, min(int(anchors), n))]
    best = (np.inf, None)
    for c in cand:
        order = (np.arange(n) + c) % n
        cost, j = _monotone_dp(C[:, order])
        if cost < best[0]:
            best = (cost, order[j])
    return best[1].astype(np.int64), float(np.sqrt(best[0] / m))


# ------------------------------------------------------------------------------------------------
# common refinement of two loops (matches and insertions on both sides)
# ------------------------------------------------------------------------------------------------

@dataclass
class LoopAlignment:
    """Result of :func:`align_loops`: how two closed loops are refined to a common sampling.

    Attributes
    ----------
    params_A : list of len(A) arrays, split fractions per edge ``A[i] -> A[i+1]`` (B vertices
        inserted into A)
    params_B : list of len(B) arrays, split fractions per edge ``B[j] -> B[j+1]``
    anchor : int, the vertex of ``B`` matched with ``A[0]``
    n_matched : int, vertex pairs matched directly
    n_common : int, vertices of the common refinement (``len(A) + len(B) - n_matched``)
    rms : float, RMS distance of the paired points of the refinement (after splitting)
    max_distance : float, the largest such distance
    """

    params_A: list
    params_B: list
    anchor: int
    n_matched: int
    n_common: int
    rms: float
    max_distance: float


def _seg_point(P: np.ndarray, a: np.ndarray, b: np.ndarray, lo: float, hi: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Fraction (clamped to [lo, hi]) and squared distance of ``P`` to segments ``a -> b``.

    Shapes broadcast: P (m, 1, 3) against a, b (1, n, 3) gives (m, n).
    """
    ab = b - a
    den = np.maximum((ab * ab).sum(-1), 1e-300)
    t = np.clip(((P - a) * ab).sum(-1) / den, lo, hi)
    q = a + t[..., None] * ab
    return t, ((P - q) ** 2).sum(-1)


def _align_dp(A: np.ndarray, B: np.ndarray, insert_penalty: float, margin: float):
    """Global alignment of A[0..m) with B[0..n) with A[0] <-> B[0] matched (see align_loops)."""
    m, n = len(A), len(B)
    An, Bn = np.roll(A, -1, axis=0), np.roll(B, -1, axis=0)
    hA = ((An - A) ** 2).sum(1)
    hB = ((Bn - B) ** 2).sum(1)
    cm = ((A[:, None, :] - B[None, :, :]) ** 2).sum(-1)
    tA, ca = _seg_point(A[:, None, :], B[None], Bn[None], margin, 1 - margin)  # A_i into B_j
    ca = ca + insert_penalty * hB[None, :]
    tB, cb = _seg_point(B[None, :, :], A[:, None], An[:, None], margin, 1 - margin)  # B_j in A_i
    cb = cb + insert_penalty * hA[:, None]
    inf = np.inf
    move = np.zeros((m, n), np.int8)  # 0 match, 1 A_i inserted (up), 2 B_j inserted (left)
    D = np.full(n, inf)
    D[0] = cm[0, 0]
    # row 0: A_0 matched with B_0, then B_1.. inserted into edge A_0 -> A_1
    D[1:] = cm[0, 0] + np.cumsum(cb[0, 1:])
    move[0, 1:] = 2
    for i in range(1, m):
        X = np.full(n, inf)
        X[1:] = D[:-1] + cm[i, 1:]  # match (i, j) after (i-1, j-1)
        up = D + ca[i]  # A_i inserted after B_j
        mv = np.where(up < X, 1, 0).astype(np.int8)
        X = np.minimum(X, up)
        c = cb[i].copy()
        c[0] = 0.0
        P = np.cumsum(c)
        Y = X - P
        run = np.minimum.accumulate(Y)
        am = np.maximum.accumulate(np.where(Y == run, np.arange(n), 0))
        D = P + run
        move[i] = np.where(am < np.arange(n), 2, mv)
        D[0] = X[0]
        move[i, 0] = mv[0]
    # backtrack from (m-1, n-1)
    i, j = m - 1, n - 1
    events = []  # (kind, i, j)
    while i > 0 or j > 0:
        k = int(move[i, j])
        events.append((k, i, j))
        if k == 0:
            i, j = i - 1, j - 1
        elif k == 1:
            i -= 1
        else:
            j -= 1
    events.append((0, 0, 0))
    events.reverse()
    return float(D[n - 1]), events, tA, tB


def align_loops(A: np.ndarray, B: np.ndarray, *, anchors: int = 6, insert_penalty: float = 0.03,
                margin: float = 0.15) -> LoopAlignment:
    """Common refinement of two aligned closed loops running in the same direction.

    Sequence alignment (Needleman-Wunsch on the cyclic sequences, anchored at ``A[0]``): each
    vertex is either matched with a vertex of the other loop (cost: squared distance) or
    inserted on the other loop's edge at its projection (cost: squared distance to that point
    plus ``insert_penalty`` times the squared length of the edge split; projections are clamped
    to ``[margin, 1 - margin]`` of the edge so no sliver triangles appear). Splitting both loops
    with ``params_A`` / ``params_B`` (see :func:`split_boundary_edges`) gives two loops with the
    same vertex count whose ``k``-th vertices correspond. Compared with matching vertices only
    (:func:`monotone_loop_match`), paired points are at most about the loops' *normal* offset
    apart, not their tangential sampling offset. Each row of the dynamic programme is vectorised
    (a min-plus prefix scan); O(len(A) len(B)) per anchor candidate.

    Parameters
    ----------
    A, B : (m, 3), (n, 3) float
    anchors : int, number of vertices of ``B`` nearest to ``A[0]`` tried as its partner
    insert_penalty : float >= 0
    margin : float in [0, 0.5)

    Returns
    -------
    LoopAlignment
    """
    A = _points(A, "loop A")
    B = _points(B, "loop B")
    m, n = len(A), len(B)
    if m < 3 or n < 3:
        raise MeshRepairError("loops need at least 3 vertices")
    if not 0 <= margin < 0.5 or insert_penalty < 0:
        raise MeshRepairError("need 0 <= margin < 0.5 and insert_penalty >= 0")
    d0 = ((B - A[0]) ** 2).sum(1)
    best = None
    for c in np.argsort(d0)[: max(1, min(int(anchors), n))]:
        Bc = np.roll(B, -int(c), axis=0)
        cost, events, tA, tB = _align_dp(A, Bc, insert_penalty, margin)
        if best is None or cost < best[0]:
            best = (cost, int(c), events, tA, tB)
    cost, c, events, tA, tB = best
    pA: list[list[float]] = [[] for _ in range(m)]
    pB: list[list[float]] = [[] for _ in range(n)]
    n_match = 0
    d2 = []
    for kind, i, j in events:
        jb, jn = (j + c) % n, (j + 1 + c) % n
        if kind == 0:
            n_match += 1
            d2.append(float(((A[i] - B[jb]) ** 2).sum()))
        elif kind == 1:  # A_i inserted on (rolled) B edge j
            pB[jb].append(float(tA[i, j]))
            q = B[jb] + tA[i, j] * (B[jn] - B[jb])
            d2.append(float(((A[i] - q) ** 2).sum()))
        else:  # B_j inserted on A edge i
            pA[i].append(float(tB[i, j]))
            q = A[i] + tB[i, j] * (A[(i + 1) % m] - A[i])
            d2.append(float(((B[jb] - q) ** 2).sum()))

    def fix(ts: list[float]) -> np.ndarray:
        t = np.asarray(ts, dtype=np.float64)
        if t.size == 0:
            return t
        if t.size > 1 and (np.diff(t) <= 1e-6).any():  # keep sequence order, spread evenly
            t = np.linspace(max(margin, 0.05), min(1 - margin, 0.95), t.size)
        return t

    params_A = [fix(t) for t in pA]
    params_B = [fix(t) for t in pB]
    n_common = m + n - n_match
    d2a = np.asarray(d2)
    return LoopAlignment(params_A=params_A, params_B=params_B, anchor=c, n_matched=n_match,
                         n_common=n_common, rms=float(np.sqrt(d2a.mean())),
                         max_distance=float(np.sqrt(d2a.max())))

