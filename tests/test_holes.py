"""Tests of meshrepair.holes: detection, selection, enclosing, fairing, intersection checks."""

from __future__ import annotations

import numpy as np
import pytest

from meshrepair import holes as H
from meshrepair.errors import MeshRepairError
from meshrepair.holes import (
    enclose_holes,
    enclose_loop,
    fair_vertices,
    find_holes,
    min_weight_triangulation,
    select_holes,
    self_intersections,
)
from meshrepair.holes import liepa as HL
from meshrepair.mesh.topology import boundary_loops, edge_topology
from meshrepair.mesh.validate import check_mesh

from .conftest import SHARED, grid, needs_meshes

MESHES = SHARED


# ------------------------------------------------------------------------------------------------
# synthetic loops and meshes
# ------------------------------------------------------------------------------------------------


def _polyline(corners: np.ndarray, per_side: int | list[int]) -> np.ndarray:
    """Closed polyline through ``corners`` with ``per_side`` points per side (corner first)."""
    k = len(corners)
    n = [per_side] * k if isinstance(per_side, int) else per_side
    pts = []
    for i in range(k):
        a, b = corners[i], corners[(i + 1) % k]
        t = np.arange(n[i])[:, None] / n[i]
        pts.append(a + t * (b - a))
    return np.concatenate(pts)


def square_loop() -> np.ndarray:
    c = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    return _polyline(c, 10)


def saddle_loop() -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, 61)[:-1]
    return np.c_[np.cos(t), np.sin(t), 0.5 * np.cos(2 * t)]


def thin_loop() -> np.ndarray:
    c = np.array([[0, 0, 0], [20, 0, 0], [20, 1, 0], [0, 1, 0]], float)
    return _polyline(c, [200, 10, 200, 10])


def big_loop() -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, 401)[:-1]
    return np.c_[np.cos(t), np.sin(t), 0.1 * np.sin(3 * t)]


def corner_loop() -> np.ndarray:
    """A loop on the surface of the unit cube around its corner (1, 1, 1)."""
    c = np.array([(1, .5, 1), (1, .5, .5), (1, 1, .5), (.5, 1, .5), (.5, 1, 1), (.5, .5, 1)])
    return _polyline(c, 10)


def wrap_loop() -> np.ndarray:
    """Boundary of a band covering 300 degrees of a cylinder (no planar view is simple)."""
    a = np.linspace(0, np.radians(300), 61)
    z = np.linspace(0, 1, 11)
    return np.r_[np.c_[np.cos(a), np.sin(a), np.zeros(61)][:-1],
                 np.c_[np.full(10, np.cos(a[-1])), np.full(10, np.sin(a[-1])), z[:-1]],
                 np.c_[np.cos(a[::-1]), np.sin(a[::-1]), np.ones(61)][:-1],
                 np.c_[np.ones(10), np.zeros(10), z[::-1][:-1]]]


def drop_faces(V: np.ndarray, F: np.ndarray, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    F = F[keep]
    used = np.unique(F)
    m = -np.ones(len(V), np.int64)
    m[used] = np.arange(len(used))
    return V[used], m[F]


LOOPS = {"square": square_loop, "saddle": saddle_loop, "thin": thin_loop, "400": big_loop,
         "corner": corner_loop}


def _edges(T: np.ndarray) -> np.ndarray:
    return np.unique(np.sort(np.r_[T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]], axis=1), axis=0)


# ------------------------------------------------------------------------------------------------
# enclose_loop
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["auto", "liepa"])
@pytest.mark.parametrize("name", list(LOOPS))
def test_enclose_loop_boundary_orientation_quality(name, method):
    P = LOOPS[name]()
    k = len(P)
    patch = enclose_loop(P, method=method)
    X, T = patch.X, patch.T
    assert np.array_equal(X[:k], P)  # loop positions untouched
    # the patch is a valid, consistently oriented, manifold disc...
    rep = check_mesh(X, T, name=name)
    assert rep.n_components == 1 and rep.n_pinched_vertices == 0 and rep.n_boundary_loops == 1
    # ...whose only boundary is exactly the loop, traversed backwards
    loops = boundary_loops(T, len(X))
    assert len(loops) == 1 and sorted(loops[0].tolist()) == list(range(k))
    he = set(map(tuple, np.stack([T, np.roll(T, -1, axis=1)], axis=2).reshape(-1, 2).tolist()))
    for i in range(k):
        assert ((i + 1) % k, i) in he and (i, (i + 1) % k) not in he
    # no two patch faces intersect
    assert len(self_intersections(X, T)) == 0
    # interior edges match the loop's mean edge length within a factor 2
    h = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean()
    e = _edges(T)
    e = e[~((e[:, 0] < k) & (e[:, 1] < k))]
    ratio = np.linalg.norm(X[e[:, 0]] - X[e[:, 1]], axis=1) / h
    assert 0.75 < ratio.mean() < 1.35, ratio.mean()
    # (liepa keeps the folds of its coarse surface as edges: a few short ones where they fan out)
    share = np.mean((ratio > 0.5) & (ratio < 2.0))
    assert share > (0.98 if method == "auto" else 0.95), (share, ratio.min(), ratio.max())
    assert patch.method in (("plane", "pca-plane") if method == "auto" else ("liepa",))


def test_enclose_planar_loop_stays_planar():
    patch = enclose_loop(square_loop())
    assert np.abs(patch.X[:, 2]).max() < 1e-12
    assert (patch.X[:, :2] >= -1e-12).all() and (patch.X[:, :2] <= 1 + 1e-12).all()


def test_enclose_loop_disc_fallback_for_wrapped_loop():
    P = wrap_loop()
    patch = enclose_loop(P)
    assert patch.method == "disc"
    X, T = patch.X, patch.T
    check_mesh(X, T)
    loops = boundary_loops(T, len(X))
    assert len(loops) == 1 and sorted(loops[0].tolist()) == list(range(len(P)))
    assert len(self_intersections(X, T)) == 0
    h = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean()
    e = _edges(T)
    ratio = np.linalg.norm(X[e[:, 0]] - X[e[:, 1]], axis=1) / h
    assert 0.6 < np.median(ratio) < 1.6


def test_enclose_loop_edge_length_option_and_triangle():
    P = square_loop()
    coarse = enclose_loop(P, edge_length=0.3)
    fine = enclose_loop(P)
    assert len(coarse.X) < len(fine.X)
    tri = enclose_loop(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float))
    assert tri.method == "triangle" and tri.T.tolist() == [[0, 2, 1]]


@pytest.mark.parametrize("P, msg", [
    (np.zeros((2, 3)), "at least 3"),
    (np.array([[0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 1, 0]], float), "same position"),
    (np.array([[0, 0, 0], [np.nan, 0, 0], [1, 0, 0]]), "non-finite"),
    (np.zeros((5, 2)), "at least 3"),
])
def test_enclose_loop_bad_input(P, msg):
    with pytest.raises(MeshRepairError, match=msg):
        enclose_loop(P)
    with pytest.raises(MeshRepairError, match=msg):
        enclose_loop(P, method="liepa")


def test_enclose_loop_bad_method_and_opposite():
    with pytest.raises(MeshRepairError, match="method must be one of"):
        enclose_loop(square_loop(), method="ear")
    with pytest.raises(MeshRepairError, match="opposite must have shape"):
        enclose_loop(square_loop(), method="liepa", opposite=np.zeros((3, 3)))
    with pytest.raises(MeshRepairError, match="forbidden chords"):
        min_weight_triangulation(square_loop(), forbidden=[[0, 99]])


def test_enclose_loop_does_not_modify_input():
    P = saddle_loop()
    P0 = P.copy()
    enclose_loop(P)
    assert np.array_equal(P, P0)


# ------------------------------------------------------------------------------------------------
# Liepa: minimum-weight triangulation and its refinement
# ------------------------------------------------------------------------------------------------


def _half_edges(T: np.ndarray) -> set[tuple[int, int]]:
    return set(map(tuple, np.stack([T, np.roll(T, -1, axis=1)], axis=2).reshape(-1, 2).tolist()))


def test_min_weight_triangulation_of_a_planar_convex_polygon():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 2 * np.pi, 17))
    Q = np.c_[2.0 * np.cos(t), np.sin(t)]  # convex (points on an ellipse), irregular spacing
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]  # in a tilted plane
    P = np.c_[Q, np.zeros(len(Q))] @ R.T + [1.0, -2.0, 0.5]
    k = len(P)
    T = min_weight_triangulation(P)
    assert T.shape == (k - 2, 3) and T.dtype == np.int64
    assert len(np.unique(T)) == k
    # the triangles cover the polygon exactly once: areas add up to the polygon's area...
    area_poly = 0.5 * abs(np.sum(Q[:, 0] * np.roll(Q[:, 1], -1) - np.roll(Q[:, 0], -1) * Q[:, 1]))
    c = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    assert 0.5 * np.linalg.norm(c, axis=1).sum() == pytest.approx(area_poly, rel=1e-12)
    # ...and all face the same way, opposite to the loop's own orientation (Q turns
    # counter-clockwise about the plane normal R[:, 2])
    n = R[:, 2]
    assert (c @ n < 0).all()
    he = _half_edges(T)
    for i in range(k):
        assert ((i + 1) % k, i) in he and (i, (i + 1) % k) not in he
    rep = check_mesh(P, T)
    assert rep.n_boundary_loops == 1 and rep.n_components == 1


def _folded_loop(fold_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Boundary of two unit squares hinged along (0,0,0)-(0,1,0) at ``fold_deg``, and the third
    vertex of a face continuing each square outwards on every loop edge."""
    a = np.radians(fold_deg)
    q = np.array([-np.cos(a), 0, np.sin(a)])
    c = np.array([[1, 0, 0], [1, 1, 0], [0, 1, 0], q + [0, 1, 0], q, [0, 0, 0]], float)
    P = _polyline(c, 4)
    k = len(P)
    mid = 0.5 * (P + np.roll(P, -1, axis=0))
    first = ((np.arange(k) < 8) | (np.arange(k) >= 20))[:, None]
    cen = np.where(first, [0.5, 0.5, 0.0], 0.5 * q + [0.0, 0.5, 0.0])
    return P, mid + 0.5 * (mid - cen)


def test_min_weight_triangulation_avoids_an_existing_edge_as_chord():
    P, O = _folded_loop(30.0)
    k = len(P)
    hinge = (8, 20)  # (0, 1, 0) and (0, 0, 0)
    assert np.allclose(P[8], [0, 1, 0]) and np.allclose(P[20], 0)

    def edges(T):
        return set(map(tuple, np.sort(np.r_[T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]],
                                      axis=1).tolist()))

    # folded 30 degrees, the best triangulation folds along the hinge...
    assert hinge in edges(min_weight_triangulation(P, opposite=O))
    # ...but when the hinge is already an edge of the mesh it is never used
    T = min_weight_triangulation(P, opposite=O, forbidden=np.array([hinge[::-1]]))
    assert hinge not in edges(T) and T.shape == (k - 2, 3)
    check_mesh(P, T)
    # with every chord forbidden there is no alternative: they are allowed again
    allc = np.array([(i, j) for i in range(k) for j in range(i + 2, k)])
    assert min_weight_triangulation(P, forbidden=allc).shape == (k - 2, 3)


def test_min_weight_triangulation_numpy_twin_agrees(monkeypatch):
    rng = np.random.default_rng(7)
    t = np.linspace(0, 2 * np.pi, 41)[:-1]
    P = np.c_[np.cos(t), np.sin(t), 0.4 * np.cos(2 * t)] + 0.02 * rng.normal(size=(40, 3))
    O = 0.5 * (P + np.roll(P, -1, axis=0)) * 1.2 + [0, 0, 0.1]
    O[5] = np.nan  # an edge without a face
    N0, has0 = HL._edge_normals(P, O)
    forbid = np.zeros((40, 40), bool)
    forbid[3, 20] = forbid[10, 30] = True
    r_np = HL._np_liepa_dp(P, N0, has0, forbid, HL._DP_TOL)
    with monkeypatch.context() as m:
        m.setattr(HL, "HAVE_NUMBA", False)
        T_np = min_weight_triangulation(P, opposite=O, forbidden=[[3, 20], [30, 10]])
    assert T_np.shape == (38, 3)
    if not HL.HAVE_NUMBA:
        pytest.skip("numba not installed: only the numpy path")
    r_nb = HL._nb_liepa_dp(P, N0, has0, forbid, HL._DP_TOL)
    assert np.array_equal(r_np[0], r_nb[0])
    fin = np.isfinite(r_np[1])
    assert np.array_equal(fin, np.isfinite(r_nb[1]))
    assert np.allclose(r_np[1][fin], r_nb[1][fin], rtol=1e-12, atol=1e-15)
    assert np.allclose(r_np[2][fin], r_nb[2][fin], rtol=1e-12)
    T_nb = min_weight_triangulation(P, opposite=O, forbidden=[[3, 20], [30, 10]])
    assert np.array_equal(np.sort(T_np, axis=0), np.sort(T_nb, axis=0))


def _cube(levels: int = 4) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    m = trimesh.creation.box(extents=(2, 2, 2))
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    for _ in range(levels):
        V, F = trimesh.remesh.subdivide(V, F)
    return np.asarray(V, float), np.asarray(F, np.int64)


def test_liepa_follows_the_faces_round_a_cube_corner():
    V, F = _cube()
    c = V[F].mean(axis=1)
    Vc, Fc = drop_faces(V, F, np.linalg.norm(c - 1.0, axis=1) >= 0.9)  # corner (1, 1, 1) cut
    holes = find_holes(Vc, Fc)
    assert len(holes) == 1
    lp = holes[0].vertices
    assert all(np.isclose(Vc[lp, j], 1.0).any() for j in range(3))  # on all three faces

    def off_cube(X):  # distance of points inside the cube to its surface
        return 1.0 - np.abs(X).max(axis=1)

    # the coarse triangulation continues the three faces: its triangles lie almost on the cube
    P = Vc[lp]
    T = min_weight_triangulation(P, opposite=H._opposite_points(Vc, Fc, lp))
    T_blind = min_weight_triangulation(P)
    d = off_cube(P[T].mean(axis=1)).mean()
    d_blind = off_cube(P[T_blind].mean(axis=1)).mean()
    assert d < 0.02 and d < 0.25 * d_blind, (d, d_blind)
    # the refined patch: on that surface, closed, oriented, no intersections
    V1, F1, reps = enclose_holes(Vc, Fc, holes, method="liepa")
    assert reps[0].status == "filled" and reps[0].reason == "liepa"
    new = np.arange(len(Vc), len(V1))
    Vp, _, _ = enclose_holes(Vc, Fc, holes, method="auto")
    d_liepa = off_cube(V1[new]).mean()
    d_plane = off_cube(Vp[len(Vc):]).mean()
    assert d_liepa < 0.5 * d_plane, (d_liepa, d_plane)
    rep = check_mesh(V1, F1)
    assert rep.is_closed and rep.n_pinched_vertices == 0
    assert len(self_intersections(V1, F1, np.arange(len(Fc), len(F1)))) == 0
    V2 = fair_vertices(V1, F1, new, order=2, iterations=3)
    assert len(self_intersections(V2, F1, np.arange(len(Fc), len(F1)))) == 0


def test_liepa_developed_and_mean_value_layouts(monkeypatch):
    # a saddle is developed isometrically: the 2-D layout keeps the loop's edge lengths
    P = saddle_loop()
    k = len(P)
    patch = enclose_loop(P, method="liepa")
    el3 = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1)
    el2 = np.linalg.norm(patch.uv[:k] - np.roll(patch.uv[:k], -1, axis=0), axis=1)
    assert np.allclose(el2, el3, rtol=1e-9)
    # a loop waving 2 up and down four times, triangulated over all triangles (its
    # triangulation by Delaunay facets develops): the development overlaps itself, so the
    # subdivided surface is laid out on the unit disc by mean-value coordinates
    from functools import partial

    from meshrepair.holes import liepa_refine as LR
    from meshrepair.holes.liepa_layout import _unfold

    monkeypatch.setattr(LR, "min_weight_triangulation",
                        partial(min_weight_triangulation, search="all"))
    t = np.linspace(0, 2 * np.pi, 121)[:-1]
    P = np.c_[np.cos(t), np.sin(t), 2.0 * np.cos(4 * t)]
    k = len(P)
    assert _unfold(P, LR._orient_patch(min_weight_triangulation(P), k)) is not None
    patch = enclose_loop(P, method="liepa")
    assert np.allclose(np.linalg.norm(patch.uv[:k], axis=1), 1.0)
    X, T = patch.X, patch.T
    assert np.array_equal(X[:k], P)
    rep = check_mesh(X, T)
    assert rep.n_boundary_loops == 1 and rep.n_components == 1 and rep.n_pinched_vertices == 0
    assert sorted(boundary_loops(T, len(X))[0].tolist()) == list(range(k))
    he = _half_edges(T)
    assert all(((i + 1) % k, i) in he for i in range(k))
    assert len(self_intersections(X, T)) == 0
    # anisotropic, but the edge lengths stay near the target
    h = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean()
    e = _edges(T)
    ratio = np.linalg.norm(X[e[:, 0]] - X[e[:, 1]], axis=1) / h
    assert 0.6 < np.median(ratio) < 1.5, np.median(ratio)


# ------------------------------------------------------------------------------------------------
# enclose_holes on meshes
# ------------------------------------------------------------------------------------------------


def test_enclose_holes_orientation_consistent_with_mesh():
    V, F = grid(15, lambda x, y: 0.05 * (x - 7) ** 2 - 0.03 * (y - 7) ** 2)
    c = V[F].mean(axis=1)
    hole = (np.abs(c[:, 0] - 7) < 3) & (np.abs(c[:, 1] - 7) < 3)
    Vh, Fh = drop_faces(V, F, ~hole)
    holes = find_holes(Vh, Fh)
    assert [h.n_boundary for h in holes] == [56, 24]
    skip = select_holes(holes, keep_border=True)
    V1, F1, reps = enclose_holes(Vh, Fh, holes, skip)
    assert [r.status for r in reps] == ["skipped", "filled"]
    assert np.array_equal(V1[: len(Vh)], Vh) and np.array_equal(F1[: len(Fh)], Fh)
    rep = check_mesh(V1, F1)  # raises on inconsistent orientation / non-manifold edges
    assert rep.n_boundary_loops == 1 and rep.n_pinched_vertices == 0
    # new faces point the same way as the surface (+z here)
    Fn = F1[len(Fh):]
    nf = np.cross(V1[Fn[:, 1]] - V1[Fn[:, 0]], V1[Fn[:, 2]] - V1[Fn[:, 0]])
    assert (nf[:, 2] > 0).all()
    assert reps[1].n_new_faces == len(F1) - len(Fh)
    assert reps[1].n_new_vertices == len(V1) - len(Vh)


@pytest.mark.parametrize("method", ["auto", "liepa"])
def test_chords_never_duplicate_an_existing_edge(method):
    # open pyramid: square hole 0-1-2-3; two flaps make both diagonals (0, 2) and (1, 3) existing
    # edges, so any 2-triangle fill of the square would give an edge 3 faces
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, -1],
                  [0.5, 0.5, 2], [0.6, 0.6, 3], [0.5, 0.5, 4], [0.4, 0.6, 5]], float)
    F = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4],
                  [0, 2, 5], [2, 0, 6], [1, 3, 7], [3, 1, 8]])
    holes = find_holes(V, F)
    square = [h for h in holes if sorted(h.vertices.tolist()) == [0, 1, 2, 3]]
    assert len(square) == 1
    skip = {h.index: "not this one" for h in holes if h is not square[0]}
    V1, F1, reps = enclose_holes(V, F, holes, skip, edge_length=2.0, check=False, method=method)
    assert reps[square[0].index].status == "filled"
    assert reps[square[0].index].reason == ("plane" if method == "auto" else "liepa")
    assert edge_topology(F1, len(V1)).edge_counts.max() == 2
    assert len(V1) > len(V)  # a chord was split at its midpoint


def test_pinched_loops_are_split_and_filled_manifold():
    V, F = grid(15, lambda x, y: 0.01 * x * y)
    c = V[F].mean(axis=1)
    h1 = (c[:, 0] > 3) & (c[:, 0] < 7) & (c[:, 1] > 3) & (c[:, 1] < 7)
    h2 = (c[:, 0] > 7) & (c[:, 0] < 11) & (c[:, 1] > 7) & (c[:, 1] < 11)
    Vp, Fp = drop_faces(V, F, ~(h1 | h2))
    assert check_mesh(Vp, Fp).n_pinched_vertices == 1
    holes = find_holes(Vp, Fp)
    assert [(h.n_boundary, h.pinched) for h in holes] == [(56, False), (16, True), (16, True)]
    for h in holes:  # simple loops
        assert len(np.unique(h.vertices)) == h.n_boundary
    V1, F1, reps = enclose_holes(Vp, Fp, holes, select_holes(holes, keep_border=True))
    assert [r.status for r in reps] == ["skipped", "filled", "filled"]
    rep = check_mesh(V1, F1)
    assert rep.n_pinched_vertices == 0 and rep.n_boundary_loops == 1


def test_island_inside_hole_is_filled_as_annulus():
    V, F = grid(21, lambda x, y: 0.02 * (x - 10) ** 2)
    r = np.abs(V[F].mean(axis=1)[:, :2] - 10).max(axis=1)
    Vi, Fi = drop_faces(V, F, (r > 6) | (r < 3))  # a ring removed: an island in the hole
    holes = find_holes(Vi, Fi)
    assert [h.n_boundary for h in holes] == [80, 48, 24]
    assert holes[2].component != holes[1].component
    V1, F1, reps = enclose_holes(Vi, Fi, holes, select_holes(holes, keep_border=True))
    assert reps[1].status == "filled" and "annulus" in reps[1].reason
    assert reps[2].status == "filled" and "island" in reps[2].reason
    rep = check_mesh(V1, F1)
    assert rep.n_components == 1 and rep.n_boundary_loops == 1
    assert len(self_intersections(V1, F1, np.arange(len(Fi), len(F1)))) == 0
    # the island is not filled on its own when its outer hole is excluded
    V1, F1, reps = enclose_holes(Vi, Fi, holes, select_holes(holes, keep_border=True,
                                                             exclude=[1]))
    assert reps[2].status == "skipped" and "island inside hole 1" in reps[2].reason
    assert len(F1) == len(Fi)


def test_whole_border_of_a_disc_is_not_filled():
    V, F = grid(11)
    holes = find_holes(V, F)
    assert len(holes) == 1
    _, F1, reps = enclose_holes(V, F, holes)
    assert reps[0].status == "skipped" and "lie on the existing surface" in reps[0].reason
    assert len(F1) == len(F)
    skip = select_holes(holes, keep_border=True)
    assert "keep_border" in skip[0]


def test_isolated_triangle_is_not_doubled():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    F = np.array([[0, 1, 2]])
    holes = find_holes(V, F)
    _, F1, reps = enclose_holes(V, F, holes)
    assert reps[0].status == "skipped" and "isolated triangle" in reps[0].reason
    assert len(F1) == 1


# ------------------------------------------------------------------------------------------------
# detection and selection on real meshes
# ------------------------------------------------------------------------------------------------


@needs_meshes
def test_find_holes_bunny():
    from meshrepair.io import read_mesh

    m = read_mesh(MESHES / "bunny.ply")
    holes = find_holes(m.V, m.F)
    assert sorted(h.n_boundary for h in holes) == [22, 39, 40, 42, 80]
    lengths = [h.length for h in holes]
    assert lengths == sorted(lengths, reverse=True)
    assert [h.index for h in holes] == list(range(5))
    h = holes[0]
    assert np.isclose(h.length, np.linalg.norm(m.V[h.vertices] - m.V[np.roll(h.vertices, -1)],
                                               axis=1).sum())
    assert not any(h.pinched for h in holes)


@needs_meshes
def test_find_holes_kinect_pinched_loops_split():
    from meshrepair.io import read_mesh

    m = read_mesh(MESHES / "kinect_pyramid.ply")
    holes = find_holes(m.V, m.F)
    topo = edge_topology(m.F, len(m.V))
    assert sum(h.n_boundary for h in holes) == int(topo.boundary.sum())  # every edge once
    for h in holes:
        assert len(np.unique(h.vertices)) == h.n_boundary  # simple
    assert any(h.pinched for h in holes)
    assert holes[0].n_boundary > 500  # the scan border is the longest loop
    assert holes[0].length > 10 * holes[1].length


def test_select_holes_options_and_errors():
    from meshrepair.holes import Hole

    holes = [Hole(index=i, vertices=np.arange(n), length=float(n))
             for i, n in enumerate([100, 40, 10, 3])]
    assert select_holes(holes) == {}
    s = select_holes(holes, keep_border=True, max_hole_size=20, exclude=[2])
    assert set(s) == {0, 1, 2} and "max_hole_size" in s[1] and s[2] == "excluded"
    s = select_holes(holes, indices=[1, 3])
    assert set(s) == {0, 2} and s[0] == "not selected"
    with pytest.raises(MeshRepairError, match="hole index 7 does not exist.*4 boundary loops"):
        select_holes(holes, exclude=[7])
    with pytest.raises(MeshRepairError, match="hole index -1"):
        select_holes(holes, indices=[-1])
    with pytest.raises(MeshRepairError, match="max_hole_size"):
        select_holes(holes, max_hole_size=2)
    with pytest.raises(MeshRepairError, match="no boundary loops"):
        select_holes([], exclude=[0])


def test_find_holes_rejects_bad_mesh():
    V, F = grid(4)
    with pytest.raises(MeshRepairError, match="non-manifold"):
        find_holes(V, np.r_[F, F[:1]])
    assert find_holes(*grid(3))[0].n_boundary == 8


# ------------------------------------------------------------------------------------------------
# fairing
# ------------------------------------------------------------------------------------------------


def test_bilaplacian_fairing_reproduces_a_paraboloid_better_than_membrane():
    f = lambda x, y: 0.03 * ((x - 10) ** 2 + (y - 10) ** 2)  # noqa: E731
    V, F = grid(21, f)
    c = V[F].mean(axis=1)
    hole = np.hypot(c[:, 0] - 10, c[:, 1] - 10) < 5
    Vh, Fh = drop_faces(V, F, ~hole)
    holes = find_holes(Vh, Fh)
    V1, F1, _ = enclose_holes(Vh, Fh, holes, select_holes(holes, keep_border=True))
    new = np.arange(len(Vh), len(V1))
    err_membrane = np.abs(V1[new, 2] - f(V1[new, 0], V1[new, 1])).max()
    V2 = fair_vertices(V1, F1, new, order=2, weights="cotan", iterations=3)
    err_fair = np.abs(V2[new, 2] - f(V2[new, 0], V2[new, 1])).max()
    assert np.array_equal(V2[: len(Vh)], Vh)
    assert err_membrane > 0.3 and err_fair < 0.1 * err_membrane, (err_membrane, err_fair)
    V3 = fair_vertices(V1, F1, new, order=2, weights="uniform")
    assert np.abs(V3[new, 2] - f(V3[new, 0], V3[new, 1])).max() < 0.2 * err_membrane
    V4 = fair_vertices(V1, F1, new, order=1)
    assert np.abs(V4[new, 2] - f(V4[new, 0], V4[new, 1])).max() > 0.5 * err_membrane
    with pytest.raises(MeshRepairError, match="order"):
        fair_vertices(V1, F1, new, order=3)


# ------------------------------------------------------------------------------------------------
# self_intersections
# ------------------------------------------------------------------------------------------------


def test_self_intersections_detects_crossing_and_touching_cases():
    V = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0],  # triangle 0 in z = 0
                  [0.5, 0.5, -1], [0.5, 0.5, 1], [1.5, 1.5, 1],  # crosses triangle 0
                  [5, 5, -1], [5, 5, 1], [6, 6, 1]], float)  # far away
    F = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8]])
    assert self_intersections(V, F).tolist() == [[0, 1]]
    assert self_intersections(V, F, faces=[2]).shape == (0, 2)
    # sharing one vertex: the opposite edge pierces the other triangle
    V = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [1, 0.2, -1], [0.2, 1, 1]], float)
    F = np.array([[0, 1, 2], [0, 3, 4]])
    assert len(self_intersections(V, F)) == 1
    # sharing one vertex, not crossing
    V2 = V.copy()
    V2[4] = [-1, -1, 1]
    V2[3] = [-1, -0.5, -1]
    assert len(self_intersections(V2, F)) == 0
    # sharing an edge: a flat or a 90-degree hinge is fine
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0]], float)
    assert len(self_intersections(V, np.array([[0, 1, 2], [1, 0, 3]]))) == 0
    V[3] = [0.5, 0, 1]
    assert len(self_intersections(V, np.array([[0, 1, 2], [1, 0, 3]]))) == 0


def test_self_intersections_folded_pair():
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 0.8, 0]], float)
    # both faces on the same side of their shared edge: folded (dihedral 180 degrees)
    assert len(self_intersections(V, np.array([[0, 1, 2], [1, 0, 3]]))) == 1


@needs_meshes
def test_self_intersections_clean_mesh_has_none():
    from meshrepair.io import read_mesh

    m = read_mesh(MESHES / "spot.ply")
    assert len(self_intersections(m.V, m.F)) == 0
    # pull one vertex through the opposite side of the body: now there are intersections
    V = m.V.copy()
    c = V.mean(axis=0)
    V[0] = c - 1.5 * (V[0] - c)
    assert len(self_intersections(V, m.F)) > 0


def test_self_intersections_candidates_complete_with_mixed_face_sizes():
    """The radius-class candidate search finds every pair a brute-force pairwise test finds, on a
    soup of triangles whose sizes span 100x (a few huge faces among many small ones)."""
    rng = np.random.default_rng(5)
    n = 70
    centers = rng.random((n, 3))
    size = np.where(rng.random(n) < 0.1, 0.5, 0.005 * (1 + 4 * rng.random(n)))
    V = (centers[:, None, :] + size[:, None, None] * rng.normal(size=(n, 3, 3))).reshape(-1, 3)
    F = np.arange(3 * n).reshape(n, 3)
    got = {tuple(p) for p in self_intersections(V, F).tolist()}
    want = set()
    for i in range(n):
        for j in range(i + 1, n):
            if len(self_intersections(V, F[[i, j]])):
                want.add((i, j))
    assert want and got == want
    sub = {tuple(p) for p in self_intersections(V, F, faces=[0, 1, 2]).tolist()}
    assert sub == {p for p in want if p[0] in (0, 1, 2) or p[1] in (0, 1, 2)}


def test_self_intersections_in_blocks_equal_one_block(monkeypatch):
    """Query faces and candidate pairs processed in small blocks give the pairs of one block
    (pairs between two query faces found once, across blocks too)."""
    from meshrepair.holes import intersect as HI

    rng = np.random.default_rng(11)
    n = 200
    centers = rng.random((n, 3))
    V = (centers[:, None, :] + 0.08 * rng.normal(size=(n, 3, 3))).reshape(-1, 3)
    F = np.arange(3 * n).reshape(n, 3)
    q = rng.choice(n, 60, replace=False)
    whole = self_intersections(V, F), self_intersections(V, F, faces=q)
    assert len(whole[0]) > 30 and len(whole[1]) > 10
    for qb, pb in ((1, 1), (7, 5), (33, 1000)):
        monkeypatch.setattr(HI, "QUERY_BLOCK", qb)
        monkeypatch.setattr(HI, "PAIR_BLOCK", pb)
        assert np.array_equal(self_intersections(V, F), whole[0])
        assert np.array_equal(self_intersections(V, F, faces=q), whole[1])
