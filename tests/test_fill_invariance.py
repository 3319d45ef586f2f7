"""Hole filling does not depend on how the user's mesh is numbered or placed: the same cut mesh
relabelled (vertices and faces), or rotated, scaled and translated, gets the same patches (the
same counts of new vertices and faces, positions equal up to rounding carried through the
solve)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

import meshrepair as mr
from meshrepair.holes._triangle import triangulate
from meshrepair.io import read_mesh
from meshrepair.synthetic import cut_holes

DATA = Path(__file__).parent / "data"


def _cut(name: str, r: float, seed: int):
    m = read_mesh(DATA / f"{name}.ply")
    return cut_holes(m.V, m.F, r, seed=seed)[:2]


def _new_vertices_apart(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance from a new vertex of one fill to the nearest of the other's."""
    return float(max(cKDTree(a).query(b)[0].max(), cKDTree(b).query(a)[0].max()))


@pytest.mark.parametrize("case", [("fandisk", 8.0, 0), ("spot", 6.0, 1), ("trim_star", 4.0, 0)],
                         ids=lambda c: f"{c[0]}-r{c[1]:g}-s{c[2]}")
def test_fill_is_invariant_to_vertex_order_and_similarity(case):
    V, F = _cut(*case)
    n = len(V)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    a = mr.fill_holes(V, F)
    assert len(a.new_vertices) > 0

    rng = np.random.default_rng(7)
    p = rng.permutation(n)
    inv = np.empty(n, dtype=np.int64)
    inv[p] = np.arange(n)
    b = mr.fill_holes(V[p], inv[F][rng.permutation(len(F))])

    R = Rotation.from_euler("xyz", [0.3, 1.1, -0.7]).as_matrix()
    s, t = 37.3, np.array([5.0, -2.0, 11.0])
    c = mr.fill_holes(s * V @ R.T + t, F)
    Vc = ((c.V - t) @ R) / s

    for other, old in ((b, b.V[inv]), (c, Vc[:n])):
        assert len(other.V) == len(a.V) and len(other.F) == len(a.F)
        assert np.abs(old - a.V[:n]).max() <= 1e-6 * diag
    assert _new_vertices_apart(a.V[n:], b.V[n:]) <= 1e-6 * diag
    assert _new_vertices_apart(a.V[n:], Vc[n:]) <= 1e-6 * diag


def test_triangle_sees_one_frame():
    """The planar mesher gets the same input for a polygon and its rotated, scaled, translated
    and renumbered copy: its Steiner points map onto each other."""
    rng = np.random.default_rng(3)
    k = 40
    ang = np.sort(rng.uniform(0, 2 * np.pi, k))
    Q = np.c_[np.cos(ang), np.sin(ang)] * rng.uniform(0.8, 1.2, k)[:, None]
    segs = np.c_[np.arange(k), (np.arange(k) + 1) % k]
    out = triangulate({"vertices": Q, "segments": segs}, "pYQq28", max_area=0.004)
    assert np.array_equal(out["vertices"][:k], Q)

    th, s, t = 2.1, 13.7, np.array([-4.0, 9.0])
    Rm = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    roll = 17
    Q2 = np.roll(s * Q @ Rm.T + t, -roll, axis=0)
    segs2 = np.c_[np.arange(k), (np.arange(k) + 1) % k][::-1]
    out2 = triangulate({"vertices": Q2, "segments": segs2}, "pYQq28", max_area=0.004 * s * s)
    assert np.array_equal(out2["vertices"][:k], Q2)
    X1, X2 = out["vertices"], ((out2["vertices"] - t) @ Rm) / s
    assert len(X1) == len(X2) and len(out["triangles"]) == len(out2["triangles"])
    assert _new_vertices_apart(X1[k:], X2[k:]) < 1e-12
    # the triangles, in the callers' numbering, are the same set
    back = np.r_[(np.arange(k) - roll) % k, np.arange(k, len(X1))]  # index in 1 -> index in 2
    match = cKDTree(X2[k:]).query(X1[k:])[1] + k
    back[k:] = match
    T1 = np.sort(back[out["triangles"]], axis=1)
    T2 = np.sort(out2["triangles"], axis=1)
    assert set(map(tuple, T1.tolist())) == set(map(tuple, T2.tolist()))


def test_points_closer_than_the_grid_stay_apart():
    k = 30
    a = 2 * np.pi * np.arange(k) / k
    Q = np.c_[np.cos(a), np.sin(a)]
    Q = np.insert(Q, 1, Q[0] + (1e-9, 1e-9), axis=0)  # a loop vertex 1.4e-9 from another
    n = len(Q)
    segs = np.c_[np.arange(n), (np.arange(n) + 1) % n]
    out = triangulate({"vertices": Q, "segments": segs}, "pYQ", max_area=0.01)
    assert np.array_equal(out["vertices"][:n], Q)
    assert set(np.unique(out["triangles"])) >= set(range(n))  # every loop vertex is used
