"""Loops that are two loops touching at a narrow place (meshrepair.fill.split)."""

from __future__ import annotations

import numpy as np

from meshrepair.fill import fill_holes
from meshrepair.fill.split import (
    NECK_RATIO,
    narrowest_place,
    retry_split,
    split_holes,
    split_loop,
)
from meshrepair.holes import _find_holes
from meshrepair.mesh.topology import boundary_loops
from meshrepair.synthetic import grid_plane


def _circle(n: int, r: float = 1.0, c=(0.0, 0.0)) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[c[0] + r * np.cos(t), c[1] + r * np.sin(t), np.zeros(n)]


def _dumbbell():
    """A 40 × 40 grid with two discs of radius 6 cut 15 apart, joined by a channel two units wide:
    one hole loop whose sides come within about one unit of each other twice."""
    V, F = grid_plane(40)
    keep = np.ones(len(F), bool)
    cen = V[F].mean(axis=1)
    for cx in (12.0, 27.0):
        keep &= np.hypot(cen[:, 0] - cx, cen[:, 1] - 20.0) > 6.0
    keep &= ~((np.abs(cen[:, 1] - 20.0) < 1.2) & (cen[:, 0] > 12) & (cen[:, 0] < 27.0))
    F = F[keep]
    used = np.unique(F)
    idx = -np.ones(len(V), np.int64)
    idx[used] = np.arange(len(used))
    return V[used], idx[F]


def test_round_loop_has_no_narrow_place():
    r = narrowest_place(_circle(64))
    assert r is not None and abs(r[0] - 2 / np.pi) < 0.01
    assert r[0] > NECK_RATIO


def test_narrowest_place_in_row_blocks_equals_the_whole_table():
    """The blockwise search (rows of ROW_BLOCK at a time) finds the pair of the whole n × n
    table of chord / shorter arc, on a pinched loop longer than one block."""
    import meshrepair.fill.split as sp

    rng = np.random.default_rng(3)
    n = sp.ROW_BLOCK * 2 + 37
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    P = np.c_[np.cos(t), np.sin(t) * (0.05 + np.abs(np.cos(t))), np.zeros(n)]
    P += 1e-3 * rng.standard_normal(P.shape)
    seg = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1)
    L, cum = seg.sum(), np.r_[0.0, np.cumsum(seg)][:n]
    A = np.abs(cum[:, None] - cum[None, :])
    A = np.minimum(A, L - A)
    D = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2)
    R = np.where(A >= sp.MIN_ARC * L / n, D / np.maximum(A, 1e-300), np.inf)
    i, j = np.unravel_index(int(np.argmin(R)), R.shape)
    got = narrowest_place(P)
    assert got is not None
    assert got[0] == float(R[i, j])
    assert (got[1], got[2]) == (min(i, j), max(i, j))
    assert got[0] < NECK_RATIO  # the waist at t = ±π/2 is narrow


def test_dumbbell_loop_splits_into_two_consistent_loops():
    V, F = _dumbbell()
    holes = _find_holes(V, F)
    hole = [h for h in holes if h.index != 0][0]  # the outer border is the longest loop
    r = narrowest_place(V[hole.vertices])
    assert r is not None and r[0] <= NECK_RATIO
    extra: list[np.ndarray] = []
    parts = split_loop(V, hole.vertices, extra, len(V))
    assert len(parts) >= 2
    # every loop edge is in exactly one part, every chord edge in two parts, opposite ways
    edges = {}
    for p in parts:
        for a, b in zip(p, np.roll(p, -1), strict=True):
            edges[(int(a), int(b))] = edges.get((int(a), int(b)), 0) + 1
    loop_edges = {(int(a), int(b)) for a, b in zip(hole.vertices, np.roll(hole.vertices, -1),
                                                   strict=True)}
    assert all(edges.get(e) == 1 for e in loop_edges)
    chord = [e for e in edges if e not in loop_edges]
    assert chord and all(edges[e] == 1 and (e[1], e[0]) in edges for e in chord)
    # chord vertices lie between the loop's two sides at the narrow place
    Vx = np.concatenate(extra)
    assert np.all((Vx[:, 0] > 12) & (Vx[:, 0] < 27.0)) and np.allclose(Vx[:, 2], 0.0)


def test_split_holes_keeps_the_order_and_the_other_loops():
    V, F = _dumbbell()
    holes = _find_holes(V, F)
    i = [h.index for h in holes if h.index != 0][0]
    V_aug, holes2, parts = split_holes(V, holes, [i])
    assert set(parts) == {i} and len(parts[i]) >= 2
    assert np.array_equal(V_aug[:len(V)], V) and len(V_aug) > len(V)
    assert holes2[0] is holes[0]
    assert [h.index for h in holes2[1:]] == parts[i]


def test_retry_split_fills_the_parts_when_the_whole_patch_intersects():
    V, F = _dumbbell()
    res = fill_holes(V, F)
    holes = _find_holes(V, F)
    i = [h.index for h in holes if h.index != 0][0]
    rep = [r for r in res.holes if r.index == i][0]
    assert rep.status == "filled" and not res.params.get("split")
    # the whole patch of a flat dumbbell is clean; pretend it intersects the surface
    rep.n_intersections = 10**6
    opts = dict(denoise=False, initial="bilaplacian", refine=True, edge_length=None, lam=None,
                th=30.0, a=10.0, max_iter=150, tol=1e-5, rings=3, relax=0.0,
                inner_solver="armijo", inner_iters=3, check=True, callback=None, progress=None,
                creases=True, curvature=True, triharmonic=True, fitted=False)
    skip = {0: "open border"}
    out = retry_split(V, F, holes, skip, res, opts, set(), set(), {})
    assert out is not res and out.params["split"] == {i: len(split_holes(V, holes, [i])[2][i])}
    split_rep = [r for r in out.holes if r.index == i][0]
    assert split_rep.status == "filled" and split_rep.reason.startswith("split at")
    assert split_rep.n_intersections == 0
    # the hole is closed, the outer border stays open, the input comes first unchanged
    loops = boundary_loops(out.F, len(out.V))
    assert len(loops) == 1 and len(loops[0]) == len(holes[0].vertices)
    assert np.array_equal(out.V[:len(V)], V) and np.array_equal(out.F[:len(F)], F)
    assert np.array_equal(out.new_vertices, np.arange(len(V), len(out.V)))
    assert (out.M_V[len(V):] == 0).all() and (out.M_V[:len(V)] == 1).all()
    assert np.abs(out.V[len(V):, 2]).max() < 1e-6  # a flat hole stays flat


def test_retry_split_says_the_loop_note_once():
    V, F = _dumbbell()
    res = fill_holes(V, F)
    holes = _find_holes(V, F)
    i = [h.index for h in holes if h.index != 0][0]
    [r for r in res.holes if r.index == i][0].n_intersections = 10**6
    opts = dict(denoise=False, initial="bilaplacian", refine=True, edge_length=None, lam=None,
                th=30.0, a=10.0, max_iter=150, tol=1e-5, rings=3, relax=0.0,
                inner_solver="armijo", inner_iters=3, check=True, callback=None, progress=None,
                creases=True, curvature=True, triharmonic=True, fitted=False)
    out = retry_split(V, F, holes, {0: "open border"}, res, opts, {i}, set(),
                      {i: "uncertain: check it"})
    rep = [r for r in out.holes if r.index == i][0]
    assert rep.note.count("uncertain: check it") == 1


def test_retry_split_keeps_the_whole_fill_when_the_retry_fails(monkeypatch):
    """The split's second fill is optional: when it raises, the first fill is returned as it
    was (nothing of the user's fill is lost)."""
    import meshrepair.fill.core as core
    from meshrepair.errors import MeshRepairError

    V, F = _dumbbell()
    res = fill_holes(V, F)
    holes = _find_holes(V, F)
    i = [h.index for h in holes if h.index != 0][0]
    rep = [r for r in res.holes if r.index == i][0]
    rep.n_intersections = 10**6
    V_before, F_before = res.V.copy(), res.F.copy()

    def fail(*args, **kwargs):
        raise MeshRepairError("refused")

    monkeypatch.setattr(core, "_fill_core", fail)
    opts = dict(denoise=False, initial="bilaplacian", refine=True, edge_length=None, lam=None,
                th=30.0, a=10.0, max_iter=150, tol=1e-5, rings=3, relax=0.0,
                inner_solver="armijo", inner_iters=3, check=True, callback=None, progress=None,
                creases=True, curvature=True, triharmonic=True, fitted=False)
    out = retry_split(V, F, holes, {0: "open border"}, res, opts, set(), set(), {})
    assert out is res
    assert np.array_equal(out.V, V_before) and np.array_equal(out.F, F_before)
    assert not out.params.get("split")
