"""Boundary resampling, cyclic correspondence, alignment and ICP
(meshrepair.complete.correspondence)."""

import numpy as np
import pytest
import trimesh

from meshrepair.complete.correspondence import (
    align_loops,
    apply_transform,
    arc_length_parameters,
    best_cyclic_alignment,
    closest_points_on_loop,
    closest_points_on_mesh,
    icp_loop_to_polyline,
    icp_to_surface,
    monotone_loop_match,
    resample_polyline,
    split_boundary_edges,
    subdivide_loop,
    umeyama,
    uniform_split_params,
)
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.geometry import face_normals_areas
from meshrepair.mesh.topology import boundary_loops
from meshrepair.mesh.validate import check_mesh
from meshrepair.metrics import point_to_surface


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    a, b, c, d = q
    return np.array([
        [a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)],
        [2 * (b * c + a * d), a * a - b * b + c * c - d * d, 2 * (c * d - a * b)],
        [2 * (b * d - a * c), 2 * (c * d + a * b), a * a - b * b - c * c + d * d],
    ])


def similarity(rng, scale=1.0, shift=1.0):
    T = np.eye(4)
    T[:3, :3] = scale * random_rotation(rng)
    T[:3, 3] = shift * rng.normal(size=3)
    return T


def irregular_loop(rng, n=40):
    """A non-planar, non-symmetric closed curve (no rigid self-map)."""
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = 1.0 + 0.3 * np.cos(2 * t) + 0.15 * np.sin(3 * t)
    return np.stack([r * np.cos(t), 0.7 * r * np.sin(t), 0.4 * np.sin(t) + 0.2 * np.cos(3 * t)],
                    axis=1)


def square_loop(per_side=3):
    corners = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    pts = []
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        for j in range(per_side):
            pts.append(a + (b - a) * j / per_side)
    return np.array(pts)


def disc_patch(n_ring=3, n_seg=16):
    """A curved disc-like patch (spherical cap) as (V, F) with one boundary loop."""
    m = trimesh.creation.icosphere(subdivisions=3)
    V = np.asarray(m.vertices)
    F = np.asarray(m.faces)
    keep = (V[F][:, :, 2] > 0.45).all(axis=1)
    used = np.unique(F[keep])
    new = -np.ones(len(V), int)
    new[used] = np.arange(len(used))
    return V[used].copy(), new[F[keep]].astype(np.int64)


# ----------------------------------------------------------------------------------------------
# resampling and subdivision


def test_resample_open_polyline_10_to_13_keeps_endpoints_and_spacing(rng):
    P = np.cumsum(rng.normal(size=(10, 3)), axis=0)
    Q = resample_polyline(P, 13, closed=False)
    assert Q.shape == (13, 3)
    np.testing.assert_allclose(Q[0], P[0], atol=1e-12)
    np.testing.assert_allclose(Q[-1], P[-1], atol=1e-12)
    # every output point lies on the polyline, at arc length k L / 12
    s, L = arc_length_parameters(P, closed=False)
    seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
    arcs = []
    for q in Q:
        d = []
        for k in range(9):
            ab = P[k + 1] - P[k]
            t = np.clip((q - P[k]) @ ab / (ab @ ab), 0, 1)
            d.append((np.linalg.norm(P[k] + t * ab - q), s[k] + t * seg[k]))
        dist, arc = min(d)
        assert dist < 1e-9
        arcs.append(arc)
    np.testing.assert_allclose(arcs, np.linspace(0, L, 13), atol=1e-9)


def test_resample_closed_loop_uniform_and_keeps_first(rng):
    P = irregular_loop(rng, 25)
    Q = resample_polyline(P, 60)
    np.testing.assert_allclose(Q[0], P[0])
    _, L = arc_length_parameters(P)
    _, LQ = arc_length_parameters(Q)
    assert LQ <= L + 1e-12 and LQ > 0.99 * L  # chords of the same curve
    step = np.linalg.norm(np.diff(np.vstack([Q, Q[:1]]), axis=0), axis=1)
    assert step.max() <= L / 60 + 1e-12


def test_uniform_split_params_keeps_vertices_and_evens_spacing():
    P = square_loop(per_side=2).astype(float)  # 8 points, edges of length 0.5
    P[1] = [0.8, 0, 0]  # edges 0 and 1 now of length 0.8 and 0.2
    params = uniform_split_params(P, 13)
    assert sum(len(p) for p in params) == 5
    # the longest edge gets the most splits, at equal fractions
    assert len(params[0]) >= max(len(p) for p in params[1:])
    for p in params:
        np.testing.assert_allclose(p, np.arange(1, len(p) + 1) / (len(p) + 1))
    with pytest.raises(MeshRepairError):
        uniform_split_params(P, 5)


def test_split_boundary_edges_keeps_mesh_valid_and_surface():
    V, F = disc_patch()
    loop = boundary_loops(F, len(V))[0]
    n = len(loop)
    params = [np.zeros(0)] * n
    params[0] = np.array([0.5])
    params[3] = np.array([0.2, 0.7])
    params[n - 1] = np.array([0.4])  # the closing edge
    V0, F0 = V.copy(), F.copy()
    V2, F2, loop2, new = split_boundary_edges(V, F, loop, params)
    np.testing.assert_array_equal(V, V0)
    np.testing.assert_array_equal(F, F0)
    assert len(new) == 4 and len(loop2) == n + 4 and len(F2) == len(F) + 4
    rep = check_mesh(V2, F2)  # manifold, consistently oriented, no zero-area face
    assert rep.n_boundary_loops == 1
    loops = boundary_loops(F2, len(V2))
    assert len(loops) == 1
    k = int(np.flatnonzero(loops[0] == loop2[0])[0])
    np.testing.assert_array_equal(np.roll(loops[0], -k), loop2)  # same order and orientation
    # the surface is unchanged: same area, new vertices on the old edges
    _, A0 = face_normals_areas(V, F)
    _, A2 = face_normals_areas(V2, F2)
    assert A2.sum() == pytest.approx(A0.sum(), rel=1e-12)
    np.testing.assert_allclose(V2[new[0]], 0.5 * (V[loop[0]] + V[loop[1]]))
    np.testing.assert_allclose(V2[new[-1]], 0.6 * V[loop[-1]] + 0.4 * V[loop[0]])


def test_subdivide_loop_to_target_count():
    V, F = disc_patch()
    loop = boundary_loops(F, len(V))[0]
    V2, F2, loop2, new = subdivide_loop(V, F, loop, len(loop) + 7)
    assert len(loop2) == len(loop) + 7
    check_mesh(V2, F2)


def test_split_rejects_wrong_orientation_and_bad_fractions():
    V, F = disc_patch()
    loop = boundary_loops(F, len(V))[0]
    params = [np.zeros(0)] * len(loop)
    params[0] = np.array([0.5])
    with pytest.raises(MeshRepairError, match="orientation"):
        split_boundary_edges(V, F, loop[::-1], params)
    params[0] = np.array([1.2])
    with pytest.raises(MeshRepairError, match="fractions"):
        split_boundary_edges(V, F, loop, params)


# ----------------------------------------------------------------------------------------------
# alignment and cyclic correspondence


def test_umeyama_recovers_known_similarity(rng):
    X = rng.normal(size=(30, 3))
    T = similarity(rng, scale=1.7, shift=3.0)
    Y = apply_transform(T, X)
    np.testing.assert_allclose(umeyama(X, Y, scale=True), T, atol=1e-10)
    # rigid fit of a rigid motion, and with noise the fit stays close
    R = similarity(rng, scale=1.0)
    np.testing.assert_allclose(umeyama(X, apply_transform(R, X)), R, atol=1e-10)
    Tn = umeyama(X, Y + 1e-3 * rng.normal(size=Y.shape), scale=True)
    assert np.abs(Tn - T).max() < 1e-2


def test_umeyama_returns_proper_rotation_for_mirrored_data(rng):
    X = rng.normal(size=(20, 3))
    Y = X * np.array([1, 1, -1])
    T = umeyama(X, Y)
    assert np.linalg.det(T[:3, :3]) == pytest.approx(1.0)


def test_square_loop_known_shift_and_reversal():
    A = square_loop(per_side=3)  # 12 points, already aligned: fit="none"
    n = len(A)
    for shift in (0, 5, 11):
        i = np.arange(n)
        B = np.empty_like(A)
        B[(shift - i) % n] = A  # A[i] = B[(shift - i) % n]: reversed
        ca = best_cyclic_alignment(A, B, fit="none")
        assert ca.reversed and ca.shift == shift and ca.rms < 1e-12
        np.testing.assert_allclose(B[ca.indices(n)], A)
        B2 = np.roll(A, shift, axis=0)  # A[i] = B2[(i + shift) % n]: forward
        ca = best_cyclic_alignment(A, B2, fit="none")
        assert not ca.reversed and ca.shift == shift and ca.rms < 1e-12


def test_rigid_cyclic_alignment_of_moved_reversed_loop(rng):
    A = irregular_loop(rng, 50)
    T = similarity(rng, shift=5.0)
    shift = 17
    i = np.arange(50)
    B = np.empty_like(A)
    B[(shift - i) % 50] = apply_transform(T, A)
    ca = best_cyclic_alignment(A, B, fit="rigid")
    assert ca.reversed and ca.shift == shift and ca.rms < 1e-9
    np.testing.assert_allclose(ca.transform, np.linalg.inv(T), atol=1e-9)
    assert ca.rms_other_direction > 0.05  # the other direction does not fit
    # with a scale, only the similarity fit explains it
    S = similarity(rng, scale=0.6)
    cs = best_cyclic_alignment(A, apply_transform(S, A), fit="similarity")
    assert cs.shift == 0 and not cs.reversed and cs.rms < 1e-9
    assert best_cyclic_alignment(A, apply_transform(S, A), fit="rigid").rms > 0.01


def test_fft_costs_match_brute_force(rng):
    A = irregular_loop(rng, 23)
    B = irregular_loop(rng, 23) + 0.1
    for rev in (False, True):
        ca = best_cyclic_alignment(A, B, fit="rigid", directions=(rev,))
        best = np.inf
        for s in range(23):
            idx = ((s - np.arange(23)) if rev else (s + np.arange(23))) % 23
            T = umeyama(B[idx], A)
            best = min(best, np.sqrt(np.mean(np.sum((apply_transform(T, B[idx]) - A) ** 2, 1))))
        assert ca.rms == pytest.approx(best, rel=1e-9, abs=1e-12)


def test_alignment_input_errors(rng):
    A = irregular_loop(rng, 10)
    with pytest.raises(MeshRepairError, match="same number"):
        best_cyclic_alignment(A, A[:9])
    with pytest.raises(MeshRepairError, match="fit"):
        best_cyclic_alignment(A, A, fit="affine")
    with pytest.raises(MeshRepairError):
        umeyama(A, A[:5])


# ----------------------------------------------------------------------------------------------
# matching loops with different vertex counts


def test_monotone_match_recovers_the_original_vertices(rng):
    A = irregular_loop(rng, 30)
    # B: A with 9 extra points inserted on some edges, rolled by 7
    params = [np.zeros(0)] * 30
    for k in (0, 4, 5, 17, 29):
        params[k] = np.sort(rng.uniform(0.1, 0.9, size=1 + (k % 2)))
    pts, orig_pos = [], []
    for i in range(30):
        orig_pos.append(len(pts))
        pts.append(A[i])
        for t in params[i]:
            pts.append(A[i] + t * (A[(i + 1) % 30] - A[i]))
    B = np.roll(np.array(pts), 7, axis=0)
    j, rms = monotone_loop_match(A, B)
    np.testing.assert_array_equal(j, (np.array(orig_pos) + 7) % len(B))
    assert rms < 1e-12


def test_align_loops_common_refinement_of_two_samplings():
    t1 = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    t2 = np.linspace(0, 2 * np.pi, 17, endpoint=False) + 0.13
    A = np.stack([np.cos(t1), np.sin(t1), 0 * t1], 1)
    B = np.stack([np.cos(t2), np.sin(t2), 0 * t2], 1)
    la = align_loops(A, B)
    nA = sum(len(p) for p in la.params_A)
    nB = sum(len(p) for p in la.params_B)
    assert 12 + nA == 17 + nB == la.n_common
    # the paired points are closer than when vertices are only matched with vertices
    j, rms_vertices = monotone_loop_match(A, B)
    assert la.rms < 0.6 * rms_vertices
    assert la.max_distance < 0.8 * np.linalg.norm(A - B[j], axis=1).max()
    for p in la.params_A + la.params_B:
        assert ((p > 0) & (p < 1)).all() and (np.diff(p) > 0).all()


def test_align_loops_identical_loops_need_no_insertion(rng):
    A = irregular_loop(rng, 20)
    la = align_loops(A, np.roll(A, 5, axis=0))  # A[0] is B[5]
    assert la.anchor == 5 and la.n_matched == 20 and la.rms < 1e-12


# ----------------------------------------------------------------------------------------------
# ICP


def test_icp_loop_to_polyline_recovers_small_motion(rng):
    A = irregular_loop(rng, 60)
    T = similarity(rng, scale=1.0, shift=0.0)
    # a small motion: interpolate the rotation towards identity
    w = 0.03 * rng.normal(size=3)
    from meshrepair.complete.correspondence import _rotation_vector

    M = np.eye(4)
    M[:3, :3] = _rotation_vector(w)
    M[:3, 3] = 0.02 * rng.normal(size=3)
    P = apply_transform(M, resample_polyline(A, 90))
    dT, r0, r1 = icp_loop_to_polyline(P, A)
    assert r1 < 0.05 * r0
    assert T.shape == (4, 4)


def test_closest_points_match_metrics_distance(rng):
    m = trimesh.creation.icosphere(subdivisions=2)
    V, F = np.asarray(m.vertices), np.asarray(m.faces)
    P = rng.normal(size=(200, 3)) * 1.3
    Q, d, f = closest_points_on_mesh(P, V, F)
    np.testing.assert_allclose(d, point_to_surface(P, V, F), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(P - Q, axis=1), d)
    loop = irregular_loop(rng, 30)
    Q2, d2 = closest_points_on_loop(loop + 0.0, loop)
    assert d2.max() < 1e-12


def bumpy_patch():
    """A generic curved grid patch (no continuous symmetry)."""
    n = 15
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    z = 0.3 * np.sin(2 * x + 0.5) * np.cos(1.5 * y) + 0.2 * x * y + 0.1 * x**2
    V = np.stack([x.ravel(), y.ravel(), z.ravel()], 1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    F = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3),
                        np.stack([a, d, c], -1).reshape(-1, 3)])
    return V, F


def test_point_to_plane_icp_recovers_rigid_motion_exactly(rng):
    V, F = bumpy_patch()
    from meshrepair.complete.correspondence import _rotation_vector

    M = np.eye(4)
    M[:3, :3] = _rotation_vector(np.array([0.05, -0.03, 0.04]))
    M[:3, 3] = [0.02, -0.01, 0.03]
    P = apply_transform(M, V[::3])
    dT, r0, r1 = icp_to_surface(P, V, F)
    assert r0 > 1e-2 and r1 < 1e-8
    np.testing.assert_allclose(dT @ M, np.eye(4), atol=1e-7)
