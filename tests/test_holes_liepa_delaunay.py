"""Liepa's dynamic program over the Delaunay facets of the loop
(:mod:`meshrepair.holes.liepa_delaunay`): the same recursion as the full program, exactly optimal
in its largest bend over the triangulations it searches, and the default search space of
:func:`meshrepair.holes.min_weight_triangulation`."""

from __future__ import annotations

import itertools
from functools import cache

import numpy as np
import pytest

from meshrepair.errors import MeshRepairError
from meshrepair.holes import liepa as HL
from meshrepair.holes import liepa_delaunay as LD
from meshrepair.holes.liepa import min_weight_triangulation

from .conftest import needs_meshes, shared_mesh


def _wavy_loop(k: int, seed: int, wave: float = 0.6) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, k + 1)[:-1]
    P = np.c_[np.cos(t), np.sin(t), wave * np.cos(3 * t)] + 0.05 * rng.normal(size=(k, 3))
    O = 0.5 * (P + np.roll(P, -1, axis=0)) * 1.3 + [0.0, 0.0, 0.1]
    return P, O


def _all_triangles(k: int) -> np.ndarray:
    tri = np.array(list(itertools.combinations(range(k), 3)), dtype=np.int64)
    order = np.lexsort((tri[:, 1], tri[:, 0], tri[:, 2] - tri[:, 0]))
    return tri[order]


def test_with_every_triangle_it_is_the_full_program():
    P, O = _wavy_loop(24, 1)
    O[4] = np.nan  # a loop edge without a face
    N0, has0 = HL._edge_normals(P, O)
    forbid = np.zeros((24, 24), bool)
    forbid[2, 15] = forbid[7, 19] = True
    tri = _all_triangles(24)
    full = HL._np_liepa_dp(P, N0, has0, forbid, HL._DP_TOL)
    sparse = LD._py_delaunay_dp(P, N0, has0, forbid, tri[:, 0].copy(), tri[:, 1].copy(),
                                tri[:, 2].copy(), HL._DP_TOL)
    assert np.array_equal(full[0], sparse[0])
    fin = np.isfinite(full[1])
    assert np.array_equal(fin, np.isfinite(sparse[1]))
    assert np.allclose(full[1][fin], sparse[1][fin], rtol=1e-12, atol=1e-15)
    assert np.allclose(full[2][fin], sparse[2][fin], rtol=1e-12)


def test_numba_twin_agrees():
    if not LD.HAVE_NUMBA:
        pytest.skip("numba not installed: only the Python path")
    P, O = _wavy_loop(60, 2)
    N0, has0 = HL._edge_normals(P, O)
    forbid = np.zeros((60, 60), bool)
    forbid[5, 40] = True
    tri = LD.delaunay_facets(P)
    args = (P, N0, has0, forbid, tri[:, 0].copy(), tri[:, 1].copy(), tri[:, 2].copy(),
            HL._DP_TOL)
    r_py, r_nb = LD._py_delaunay_dp(*args), LD._nb_delaunay_dp(*args)
    assert np.array_equal(r_py[0], r_nb[0])
    fin = np.isfinite(r_py[1])
    assert fin[0, 59] and np.array_equal(fin, np.isfinite(r_nb[1]))
    assert np.allclose(r_py[1][fin], r_nb[1][fin], rtol=1e-12, atol=1e-15)
    assert np.allclose(r_py[2][fin], r_nb[2][fin], rtol=1e-12)


def _recursive(P, N0, has0, allowed: set, tol: float = HL._DP_TOL):
    """The program's recursion written top-down over a set of allowed triangles: per chord
    ``(i, j)``, ``(bend, area, unit normal or None, apex)`` of its best sub-triangulation."""
    k = len(P)

    @cache
    def sub(i: int, j: int):
        if j - i == 1:
            return 0.0, 0.0, (N0[i] if has0[i] else None), -1
        cands = []
        for m in range(i + 1, j):
            if (i, m, j) not in allowed:
                continue
            left, right = sub(i, m), sub(m, j)
            if left is None or right is None:
                continue
            c = np.cross(P[j] - P[i], P[m] - P[i])
            n = c / np.linalg.norm(c)
            a = max(left[0], right[0])
            for side in (left, right):
                if side[2] is not None:
                    a = max(a, 1.0 - n @ side[2])
            if j - i == k - 1 and has0[k - 1]:
                a = max(a, 1.0 - n @ N0[k - 1])
            cands.append((a, 0.5 * np.linalg.norm(c) + left[1] + right[1], n, m))
        if not cands:
            return None
        best = min(c[0] for c in cands)
        return min((c for c in cands if c[0] <= best + tol), key=lambda c: c[1])

    return sub


@pytest.mark.parametrize("seed", range(6))
def test_same_as_the_recursion_over_the_delaunay_facets(seed):
    rng = np.random.default_rng(seed)
    k = 14
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    P = np.c_[np.cos(t), np.sin(t), 0.8 * rng.normal(size=k)]
    O = 0.5 * (P + np.roll(P, -1, axis=0)) * 1.4 + 0.3 * rng.normal(size=(k, 3))
    N0, has0 = HL._edge_normals(P, O)
    tri = LD.delaunay_facets(P)
    allowed = set(map(tuple, tri.tolist()))
    opt, bend, area = LD._py_delaunay_dp(P, N0, has0, np.zeros((k, k), bool), tri[:, 0].copy(),
                                         tri[:, 1].copy(), tri[:, 2].copy(), HL._DP_TOL)
    rec = _recursive(P, N0, has0, allowed)
    n_feasible = 0
    for i in range(k):
        for j in range(i + 2, k):
            want = rec(i, j)
            if want is None:
                assert not np.isfinite(bend[i, j])
                continue
            n_feasible += 1
            assert bend[i, j] == pytest.approx(want[0], rel=1e-12, abs=1e-15)
            assert area[i, j] == pytest.approx(want[1], rel=1e-12)
            assert opt[i, j] == want[3]
    assert n_feasible > k
    if np.isfinite(bend[0, k - 1]):
        T = min_weight_triangulation(P, opposite=O)
        assert all(tuple(sorted(r)) in allowed for r in T.tolist())


def test_falls_back_to_every_triangle():
    # a planar loop has no tetrahedralisation: the full search, same result
    t = np.linspace(0, 2 * np.pi, 13)[:-1]
    P = np.c_[2 * np.cos(t), np.sin(t), np.zeros(12)]
    assert LD.delaunay_facets(P) is None
    assert np.array_equal(min_weight_triangulation(P), min_weight_triangulation(P, search="all"))
    assert HL.delaunay_optimum(P) is None
    # a random loop with an edge that is no Delaunay edge: no triangulation by facets, the full
    # search runs and still triangulates
    for seed in range(40):
        rng = np.random.default_rng(seed)
        P = rng.normal(size=(10, 3))
        tri = LD.delaunay_facets(P)
        N0, has0 = HL._edge_normals(P, None)
        r = LD._py_delaunay_dp(P, N0, has0, np.zeros((10, 10), bool), tri[:, 0].copy(),
                               tri[:, 1].copy(), tri[:, 2].copy(), HL._DP_TOL)
        if not np.isfinite(r[1][0, 9]):
            break
    else:
        pytest.fail("no random loop without a Delaunay triangulation found")
    assert HL.delaunay_optimum(P) is None
    T = min_weight_triangulation(P)
    assert np.array_equal(T, min_weight_triangulation(P, search="all"))
    assert T.shape == (8, 3)


def test_bad_search_space():
    with pytest.raises(MeshRepairError, match="search must be one of"):
        min_weight_triangulation(_wavy_loop(8, 0)[0], search="greedy")


@needs_meshes
def test_a_long_merged_loop_is_filled_without_crossing_the_surface():
    # three 24 l̄ cuts of nicolo merged with its open base: one 415-edge loop winding through
    # space. The unrestricted optimum of Liepa's weight passes through the statue; the
    # triangulation by Delaunay facets (CGAL's) does not, and the faired patch stays clean
    import meshrepair as mr
    from meshrepair.holes.enclose import _opposite_points
    from meshrepair.holes.intersect import self_intersections
    from meshrepair.mesh.topology import boundary_loops
    from meshrepair.synthetic import cut_holes

    V, F = shared_mesh("nicolo.ply")
    Vc, Fc, _, _ = cut_holes(V, F, 24.0, seed=2)
    (loop,) = boundary_loops(Fc)
    P, O = Vc[loop], _opposite_points(Vc, Fc, loop)

    def crossings(T):
        Fn = np.r_[Fc, loop[T]]
        return len(self_intersections(Vc, Fn, faces=np.arange(len(Fc), len(Fn))))

    assert crossings(min_weight_triangulation(P, opposite=O, search="all")) > 100
    # the Delaunay-facet optima of the eight roots share the largest angle; the first root's
    # crosses the statue in 12 face pairs, some other roots' in none
    from meshrepair.holes.liepa import delaunay_optima

    per_root = [crossings(T) for T in delaunay_optima(P, opposite=O)]
    assert per_root[0] > 0 and min(per_root) == 0
    assert crossings(min_weight_triangulation(P, opposite=O)) == per_root[0]
    # enclose_holes refines the first that crosses no face
    from meshrepair.holes.enclose import _liepa_coarse, _loop_chords
    from meshrepair.holes.refuse import _LocalFaces

    T = _liepa_coarse(loop, O, _loop_chords(Fc, loop), _LocalFaces(Vc, Fc), [], [], len(Vc))
    assert crossings(T) == 0
    r = mr.fill_holes(Vc, Fc)
    (h,) = r.holes
    assert h.status == "filled" and h.n_intersections == 0
    assert h.quality["seam_deg"] < 2 * h.quality["surround_deg"]


def test_enclose_keeps_the_full_optimum_where_it_crosses_nothing():
    from pathlib import Path

    from meshrepair.holes.detect import find_holes
    from meshrepair.holes.enclose import _liepa_coarse, _loop_chords, _opposite_points
    from meshrepair.holes.refuse import _LocalFaces
    from meshrepair.io import read_mesh
    from meshrepair.synthetic import cut_holes

    m = read_mesh(Path(__file__).parent / "data" / "spot.ply")
    Vc, Fc, _, _ = cut_holes(m.V, m.F, 6.0, seed=1)
    n_full = 0
    for h in find_holes(Vc, Fc):
        lp = h.vertices
        opp, forb = _opposite_points(Vc, Fc, lp), _loop_chords(Fc, lp)
        full = min_weight_triangulation(Vc[lp], opposite=opp, forbidden=forb, search="all")
        dela = min_weight_triangulation(Vc[lp], opposite=opp, forbidden=forb)
        T = _liepa_coarse(lp, opp, forb, _LocalFaces(Vc, Fc), [], [], len(Vc))
        assert np.array_equal(T, full) or np.array_equal(T, dela)
        n_full += np.array_equal(T, full) and not np.array_equal(full, dela)
    assert n_full >= 1  # a loop whose two optima differ keeps the full one (it crosses nothing)


def test_enclose_loop_refines_the_given_coarse_triangulation():
    from meshrepair.holes import enclose_loop

    P, O = _wavy_loop(30, 3)
    full = min_weight_triangulation(P, opposite=O, search="all")
    dela = min_weight_triangulation(P, opposite=O)
    assert {tuple(sorted(r)) for r in full.tolist()} != {tuple(sorted(r)) for r in dela.tolist()}
    a = enclose_loop(P, method="liepa", opposite=O, coarse=full)
    b = enclose_loop(P, method="liepa", opposite=O)  # the default: the Delaunay optimum
    assert np.array_equal(b.X, enclose_loop(P, method="liepa", opposite=O, coarse=dela).X)
    assert a.X.shape != b.X.shape or not np.allclose(a.X, b.X)
    with pytest.raises(MeshRepairError, match="coarse must be a"):
        enclose_loop(P, method="liepa", coarse=full[:-1])
