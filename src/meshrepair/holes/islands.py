"""Islands (§5, the initial patch S_D): a hole loop nested inside another hole (a separate surface
piece sitting in it).

The pair is filled together as a planar annulus (:func:`.planar._enclose_annulus`); the island
test is geometric (the inner loop projects inside the outer one in the plane of the outer loop's
vector area, the surface lies outside the outer loop, and the inner loop turns the other way).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from meshrepair.holes._geom2d import _plane_frame, _polygon_is_simple, _vector_area
from meshrepair.holes.detect import Hole


def _loop_side_points(V: np.ndarray, F: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Centroids of the faces bordering the loop edges, shape ``(k, 3)``."""
    sel = np.isin(F, loop).sum(axis=1) >= 2
    Fs = F[sel]
    third = {}
    for f in Fs.tolist():
        for j in range(3):
            third[(f[j], f[(j + 1) % 3])] = f[(j + 2) % 3]
    nxt = np.roll(loop, -1)
    w = np.array([third.get((u, v), -1) for u, v in zip(loop.tolist(), nxt.tolist(),
                                                          strict=True)])
    ok = w >= 0
    return (V[loop[ok]] + V[nxt[ok]] + V[w[ok]]) / 3.0


def _nested_in(V: np.ndarray, F: np.ndarray, outer: Hole, inner: Hole) -> bool:
    """True when loop ``inner`` lies inside the hole bounded by ``outer`` (an island)."""
    Po, Pi = V[outer.vertices], V[inner.vertices]
    lo, hi = Po.min(axis=0), Po.max(axis=0)
    pad = 0.5 * float((hi - lo).max())
    if (Pi < lo - pad).any() or (Pi > hi + pad).any():
        return False
    va = _vector_area(Po)
    if not np.linalg.norm(va) > 0:
        return False
    n = -va / np.linalg.norm(va)
    c = Po.mean(axis=0)
    rad = float(np.linalg.norm(Po - c, axis=1).max())
    if np.abs((Pi - c) @ n).max() > 0.5 * rad:
        return False
    e1, e2 = _plane_frame(n)

    def proj(X):
        return np.c_[(X - c) @ e1, (X - c) @ e2]

    Qo, Qi = proj(Po), proj(Pi)
    if not _polygon_is_simple(Qo):
        return False
    from matplotlib.path import Path as MPath

    poly = MPath(Qo)
    if not poly.contains_points(Qi).all():
        return False
    # a hole has its surface outside the loop (a border of a surface piece has it inside)
    side = _loop_side_points(V, F, outer.vertices)
    if len(side) == 0 or poly.contains_points(proj(side)).mean() > 0.5:
        return False
    # an island boundary turns the other way round than the hole it sits in
    area_i = 0.5 * float(np.sum(Qi[:, 0] * np.roll(Qi[:, 1], -1) - np.roll(Qi[:, 0], -1)
                                * Qi[:, 1]))
    return area_i > 0


def pair_islands(V: np.ndarray, F: np.ndarray, holes: Sequence[Hole]) -> dict[int, int]:
    """Islands among ``holes`` (sorted longest first): ``partner[outer] = inner`` and
    ``partner[inner] = outer`` for each island ``inner`` nested inside hole ``outer``."""
    # islands: a loop nested inside another hole is filled together with it as an annulus
    partner: dict[int, int] = {}
    # candidate pairs from the loops' bounding boxes (the outer box padded by half its size, as
    # in _nested_in), so many small holes do not cost a quadratic number of geometric tests
    blo = np.array([V[h.vertices].min(axis=0) for h in holes]).reshape(-1, 3)
    bhi = np.array([V[h.vertices].max(axis=0) for h in holes]).reshape(-1, 3)
    bpad = 0.5 * (bhi - blo).max(axis=1, initial=0.0) if len(holes) else np.zeros(0)
    order_lo = np.argsort(blo[:, 0]) if len(holes) else np.zeros(0, np.int64)
    for io, ho in enumerate(holes):
        lo_o, hi_o = blo[io] - bpad[io], bhi[io] + bpad[io]
        a = np.searchsorted(blo[order_lo, 0], lo_o[0], side="left")
        cand = order_lo[a:]
        cand = cand[((blo[cand] >= lo_o) & (bhi[cand] <= hi_o)).all(axis=1)]
        for ii in np.sort(cand).tolist():
            hi = holes[ii]
            if hi.index == ho.index or hi.index in partner or ho.index in partner:
                continue
            if hi.length < ho.length and _nested_in(V, F, ho, hi):
                partner[ho.index] = hi.index
                partner[hi.index] = ho.index
    return partner
