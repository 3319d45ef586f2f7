"""Liepa's programs run from several roots read off the loop's geometry
(:mod:`meshrepair.holes.liepa_roots`): the triangulation does not depend on where the loop's
numbering starts, and its weight is the least over the roots."""

from __future__ import annotations

import numpy as np
import pytest

import meshrepair.holes.liepa as L
from meshrepair.holes.liepa import min_weight_triangulation
from meshrepair.holes.liepa_roots import best_over_roots, program_roots


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


def _weight(P, O, fb, roots, run):
    """(bend, area) of the best triangulation over ``roots``, from the programs' own values."""
    out = []

    def spy(*args):
        res = run(*args)
        out.append((float(res[1][0, len(P) - 1]), float(res[2][0, len(P) - 1])))
        return res

    N0, has0 = L._edge_normals(P, O)
    best_over_roots(spy, P, N0, has0, fb, roots, L._DP_TOL)
    return out


def test_kept_weight_is_the_least_over_the_roots():
    k = 36
    P, O = _wavy_loop(k, 5)
    dp = L._np_liepa_dp

    def full(Pr, N0r, has0r, forbid, s):
        return dp(Pr, N0r, has0r, forbid, L._DP_TOL)

    roots = program_roots(P, full=True)
    assert len(roots) == 8 and len(set(roots)) == 8
    per_root = _weight(P, O, np.zeros((0, 2), np.int64), roots, full)
    T = min_weight_triangulation(P, opposite=O, search="all")
    # the weight of the kept triangulation, recomputed from its triangles
    n = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    area = 0.5 * np.linalg.norm(n, axis=1).sum()
    best = min(per_root, key=lambda w: (round(w[0], 9), w[1]))
    assert area == pytest.approx(best[1], rel=1e-12)
    # the roots do differ here: one root alone would not always have found it
    assert len({round(a, 9) for _, a in per_root}) > 1
