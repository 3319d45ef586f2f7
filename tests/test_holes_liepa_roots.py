"""Liepa's programs run from several roots read off the loop's geometry
(:mod:`meshrepair.holes.liepa_roots`): the triangulation does not depend on where the loop's
numbering starts, nor do the alternatives tried where it crosses the mesh."""

from __future__ import annotations

import numpy as np
import pytest

from meshrepair.holes.liepa import delaunay_optima, min_weight_triangulation
from meshrepair.holes.liepa_roots import alternative_roots, canonical_start


def _wavy_loop(k: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed loop waving up and down, with a point on the outer side of each edge (the third
    vertex of the face there)."""
    rng = np.random.default_rng(seed)
    t = 2 * np.pi * np.arange(k) / k
    r = 1.0 + 0.15 * rng.standard_normal(k)
    P = np.c_[r * np.cos(t), r * np.sin(t), 0.3 * np.sin(3 * t) + 0.05 * rng.standard_normal(k)]
    mid = 0.5 * (P + np.roll(P, -1, axis=0))
    O = mid * 1.3 + np.c_[np.zeros((k, 2)), 0.1 * rng.standard_normal(k)]
    return P, O


def _as_set(T: np.ndarray) -> set:
    return set(map(tuple, np.sort(T, axis=1).tolist()))


@pytest.mark.parametrize("search", ["delaunay", "all"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_triangulation_does_not_depend_on_the_loop_start(search, seed):
    k = 40
    P, O = _wavy_loop(k, seed)
    T = min_weight_triangulation(P, opposite=O, search=search)
    for shift in (1, 13, 29):
        T2 = min_weight_triangulation(np.roll(P, -shift, axis=0),
                                      opposite=np.roll(O, -shift, axis=0), search=search)
        assert _as_set((T2 + shift) % k) == _as_set(T)


def _is_triangulation(T: np.ndarray, k: int) -> bool:
    """``k - 2`` triangles of the loop's vertices using every loop edge once, every chord twice."""
    from collections import Counter

    e = Counter(tuple(sorted(p)) for t in T.tolist() for p in ((t[0], t[1]), (t[1], t[2]),
                                                                 (t[2], t[0])))
    loop = {tuple(sorted((i, (i + 1) % k))) for i in range(k)}
    return (len(T) == k - 2 and all(e[x] == 1 for x in loop)
            and all(c == 2 for x, c in e.items() if x not in loop))


def test_alternatives_are_triangulations_and_do_not_depend_on_the_start():
    k = 40
    P, O = _wavy_loop(k, 4)
    s0 = canonical_start(P)
    roots = alternative_roots(P)
    assert len(roots) == 7 and s0 not in roots and len(set(roots)) == 7
    alts = list(delaunay_optima(P, opposite=O))
    assert 0 < len(alts) <= 7 and all(_is_triangulation(T, k) for T in alts)
    assert _is_triangulation(min_weight_triangulation(P, opposite=O), k)
    shift = 11
    alts2 = list(delaunay_optima(np.roll(P, -shift, axis=0), opposite=np.roll(O, -shift, axis=0)))
    assert [_as_set((T + shift) % k) for T in alts2] == [_as_set(T) for T in alts]
