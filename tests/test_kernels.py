"""The compiled kernels agree with their numpy twins (the fallback without numba)."""

import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp
import trimesh

from meshrepair import _kernels as K
from meshrepair.mesh.topology import edge_topology
from meshrepair.model.linear import NormalSystem, block_pcg

pytestmark = pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed: only numpy path")


@pytest.fixture
def mesh(rng):
    m = trimesh.creation.icosphere(3)
    V = np.asarray(m.vertices) + 0.05 * rng.normal(size=m.vertices.shape)
    return V, np.asarray(m.faces, dtype=np.int64)


def test_energy_gradient_kernels_agree(mesh, rng):
    V, F = mesh
    z = rng.normal(size=(len(F), 3))
    V0 = V + 0.1 * rng.normal(size=V.shape)
    w = rng.random(len(V))
    S = sp.csr_matrix((np.ones(3 * len(F)), (F.T.ravel(), np.arange(3 * len(F)))),
                      shape=(len(V), 3 * len(F)))
    e1 = K._nb_venergy(V, F, z, V0, w)
    e2 = K._np_venergy(V, F, z, V0, w)
    g1 = np.empty_like(V)
    e3 = K._nb_venergy_grad(V, F, z, V0, w, g1)
    e4, g2 = K._np_venergy_grad(V, F, z, V0, w, S)
    assert e1 == pytest.approx(e2, rel=1e-12) and e3 == pytest.approx(e4, rel=1e-12)
    assert np.allclose(g1, g2, rtol=1e-10, atol=1e-12)


def test_edge_kernels_agree(mesh, rng):
    V, F = mesh
    t = edge_topology(F, len(V))
    fa, fb = t.edge_faces[:, 0].copy(), t.edge_faces[:, 1].copy()
    N = K._np_face_normals(V, F)
    assert np.allclose(K._nb_face_normals(V, F), N)
    l = K._np_edge_lengths(V, t.edges)
    assert np.allclose(K._nb_edge_lengths(V, t.edges), l)
    assert np.allclose(K._nb_grad_edges(N, l, fa, fb), K._np_grad_edges(N, l, fa, fb))
    X = rng.normal(size=(len(fa), 3))
    assert np.allclose(K._nb_grad_edges_T(X, l, fa, fb, len(F)),
                       K._np_grad_edges_T(X, l, fa, fb, len(F)))


def test_fused_pcg_matches_sparse_pcg(mesh, rng):
    V, F = mesh
    t = edge_topology(F, len(V))
    fa, fb = t.edge_faces[:, 0].copy(), t.edge_faces[:, 1].copy()
    ns = NormalSystem(fa, fb, len(F))
    w = rng.random(len(fa)) + 0.5
    B = rng.normal(size=(len(F), 3))
    X1, _ = ns.solve_cg(w, 1.7, B, np.zeros_like(B), rtol=1e-10)
    X2, _ = block_pcg(ns.matrix(w, 1.7), B, rtol=1e-10)
    assert np.abs(X1 - X2).max() < 1e-7


def test_numpy_fallback_runs_and_agrees(tmp_path):
    code = (
        "import numpy as np, trimesh, meshrepair._kernels as K\n"
        "assert not K.HAVE_NUMBA\n"
        "from meshrepair import denoise, add_noise\n"
        "m = trimesh.creation.icosphere(2)\n"
        "V = add_noise(np.asarray(m.vertices), m.faces, 0.2, seed=1)\n"
        "r = denoise(V, m.faces, robust_iters=5, feature_iters=5)\n"
        f"np.save({str(tmp_path / 'np.npy')!r}, r.V)\n"
    )
    env = dict(os.environ, MESHREPAIR_NO_NUMBA="1")
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
    from meshrepair import add_noise, denoise

    m = trimesh.creation.icosphere(2)
    V = add_noise(np.asarray(m.vertices), m.faces, 0.2, seed=1)
    r = denoise(V, m.faces, robust_iters=5, feature_iters=5)
    assert np.abs(np.load(tmp_path / "np.npy") - r.V).max() < 1e-6


def test_connectivity_kernels_agree_with_numpy(rng):
    """Half-edge grouping equals the stable argsort, union-find the scipy labels, Morton codes
    the numpy twin; including a high-valence vertex (the merge-sort bucket) and a pinched mesh."""
    m = trimesh.creation.icosphere(3)
    V = np.asarray(m.vertices)
    F = np.asarray(m.faces, dtype=np.int64)
    # a 100-triangle fan around one new vertex (valence > 64) plus a second sphere touching it
    n = len(V)
    ring = n + 1 + np.arange(100)
    fan = np.c_[np.full(100, n), ring, np.roll(ring, -1)]
    F2 = np.r_[F, fan, F + len(V) + 101]
    F2 = F2[rng.permutation(len(F2))]
    nV = 2 * len(V) + 101
    assert np.array_equal(K._nb_group_halfedges(F2, nV), K._np_group_halfedges(F2, nV))
    a = rng.integers(0, 500, 300)
    b = rng.integers(0, 500, 300)
    assert np.array_equal(K._nb_union_find(500, a, b), K._np_union_find(500, a, b))
    P = rng.normal(size=(1000, 3))
    assert np.array_equal(K._nb_morton(P, 16), K._np_morton(P, 16))
    with pytest.raises(ValueError, match="out of range"):
        K.group_halfedges(F, len(V) - 1)
    with pytest.raises(ValueError, match="out of range"):
        K.union_find(10, [0, 10], [1, 2])


def test_face_shape_kernel_agrees(mesh):
    V, F = mesh
    a1, l1 = K._nb_face_area2_lmax2(V, F)
    a2, l2 = K._np_face_area2_lmax2(V, F)
    assert np.allclose(a1, a2, rtol=1e-12) and np.allclose(l1, l2, rtol=1e-12)


def test_edge_table_kernel_agrees(mesh, rng):
    V, F = mesh
    F = F[rng.permutation(len(F))]
    order = K._np_group_halfedges(F, len(V))
    for x, y in zip(K._nb_edges_from_groups(F, order), K._np_edges_from_groups(F, order),
                    strict=True):
        assert np.array_equal(x, y)


def test_vertex_normal_and_umbrella_kernels_agree(mesh):
    V, F = mesh
    V = np.r_[V, [[9.0, 9.0, 9.0]]]  # an unreferenced vertex gets a zero normal
    assert np.allclose(K._nb_vertex_normals(V, F), K._np_vertex_normals(V, F), atol=1e-13)
    assert not K._nb_vertex_normals(V, F)[-1].any()
    E = edge_topology(F, len(V)).edges
    for x, y in zip(K._nb_umbrella(V, E), K._np_umbrella(V, E), strict=True):
        assert np.allclose(x, y, rtol=1e-13)


def test_min_corner_cos_kernel_agrees(mesh):
    """The normal spread's per-vertex smallest cosine: the compiled pass equals the sparse
    twin bit for bit (same summation orders); an unreferenced vertex reads 1."""
    V, F = mesh
    N = K.face_normals(V, F)
    a = K._nb_min_corner_cos(F, N, len(V) + 1)
    b = K._np_min_corner_cos(F, N, len(V) + 1)
    assert np.array_equal(a, b)
    assert a[-1] == 1.0 and np.all(a[:-1] <= 1.0)


def test_folded_test_kernel_agrees(mesh, rng):
    """The fold-over test ``N·S <= cos_max |S|``: the compiled pass equals numpy's norm and
    einsum bit for bit, on a mesh with folded faces."""
    V, F = mesh
    V = V + 0.3 * rng.normal(size=V.shape)
    N = K.face_normals(V, F)
    ef = edge_topology(F, len(V)).edge_faces
    inner = ef[:, 1] >= 0
    S = K.neighbor_sum(N, np.ascontiguousarray(ef[inner, 0]), np.ascontiguousarray(ef[inner, 1]))
    for c in (0.0, -0.5):
        a = K._nb_folded(N, S, c)
        assert a.any() and np.array_equal(a, K._np_folded(N, S, c))


def test_symmetric_csr_kernel_agrees(mesh, rng):
    """The symmetric pattern built in one pass equals scipy's canonical CSR of the same
    entries (rows sorted, duplicates merged), with and without the diagonal."""
    V, F = mesh
    ef = edge_topology(F, len(V)).edge_faces
    a, b = ef[:, 0], ef[:, 1]
    a, b = np.r_[a, a[:7]], np.r_[b, b[:7]]  # repeated pairs are merged
    for diag in (False, True):
        for x, y in zip(K._nb_sym_csr(a, b, len(F), diag), K._np_sym_csr(a, b, len(F), diag),
                        strict=True):
            assert np.array_equal(x, y)


def test_topology_operators_equal_scipy_products(mesh):
    """The cached vertex adjacency and umbrella operator store the entries of
    ``coo -> csr`` and ``diags(1/deg) @ A`` in the same order, so products are bit-equal."""
    from meshrepair.mesh.topology import adjacency, umbrella_operator, vertex_adjacency

    V, F = mesh
    topo = edge_topology(F[3:], len(V) + 1)  # a boundary and an unreferenced vertex
    A0 = vertex_adjacency(topo.edges, topo.n_vertices)
    W0 = (sp.diags(1.0 / np.maximum(np.asarray(A0.sum(axis=1)).ravel(), 1.0)) @ A0).tocsr()
    for M0, M in ((A0, adjacency(topo)), (W0, umbrella_operator(topo))):
        for k in ("indptr", "indices", "data"):
            assert np.array_equal(getattr(M0, k), getattr(M, k))
    X = np.random.default_rng(0).normal(size=(topo.n_vertices, 3))
    assert np.array_equal(W0 @ X, umbrella_operator(topo) @ X)
    assert umbrella_operator(topo) is umbrella_operator(topo)  # built once per topology


def test_face_neighbour_table_kernel_agrees(mesh):
    V, F = mesh
    topo = edge_topology(F, len(V))
    fa, fb = topo.edge_faces[topo.interior].T
    fa, fb = np.ascontiguousarray(fa), np.ascontiguousarray(fb)
    for x, y in zip(K._nb_face_neighbour_table(fa, fb, len(F)),
                    K._np_face_neighbour_table(fa, fb, len(F)), strict=True):
        assert np.array_equal(x, y)


def test_creased_edges_match_dihedral_threshold(mesh):
    from meshrepair.mesh.geometry import dihedral_angles, face_normals

    V, F = mesh
    topo = edge_topology(F, len(V))
    N = face_normals(V, F)
    fa, fb = (np.ascontiguousarray(c) for c in topo.edge_faces[topo.interior].T)
    ang = dihedral_angles(N, topo)[topo.interior]
    for th in (5.0, 10.0, 20.0):
        want = ang > th
        assert want.any() and not want.all()
        assert np.array_equal(K.creased(N, fa, fb, th), want)
        assert np.array_equal(K._nb_creased(N, fa, fb, np.cos(np.radians(th))), want)


def test_fused_armijo_kernels_agree_with_numpy(mesh, rng):
    """The fused V-descent passes (energy + gradient + Jacobi scale, direction, trial point)
    equal their numpy twins and the unfused kernels."""
    import meshrepair.model._fused as FU

    V, F = mesh
    z = rng.normal(size=(len(F), 3))
    V0 = V + 0.1 * rng.normal(size=V.shape)
    w = rng.random(len(V))
    w[::7] = 0.0  # vertices outside the fidelity region
    S = sp.csr_matrix((np.ones(3 * len(F)), (F.T.ravel(), np.arange(3 * len(F)))),
                      shape=(len(V), 3 * len(F)))
    g1, h1 = np.empty_like(V), np.empty(len(V))
    e1 = FU._nb_venergy_grad_hdiag(V, F, z, V0, w, g1, h1)
    e2, g2, h2 = FU._np_venergy_grad_hdiag(V, F, z, V0, w, S)
    assert e1 == pytest.approx(e2, rel=1e-12)
    assert np.allclose(g1, g2, rtol=1e-10, atol=1e-12) and np.allclose(h1, h2, rtol=1e-12)
    assert np.allclose(h1, K._nb_vhess_diag(V, F, z, w), rtol=1e-13)
    g3 = np.empty_like(V)
    assert e1 == pytest.approx(K._nb_venergy_grad(V, F, z, V0, w, g3), rel=1e-13)
    assert np.allclose(g1, g3, rtol=1e-12, atol=1e-13)
    hmin = float(np.median(h1))
    d1, d2 = np.empty_like(V), np.empty_like(V)
    s1 = FU._nb_descent_direction(g1, h1, hmin, d1)
    s2 = FU._np_descent_direction(g1, h1, hmin, d2)
    assert np.allclose(d1, d2, rtol=1e-15) and s1 == pytest.approx(s2, rel=1e-12) and s1 > 0
    o1, o2 = np.empty_like(V), np.empty_like(V)
    t1 = FU._nb_venergy_trial(V, d1, 0.3, o1, F, z, V0, w)
    t2 = FU._np_venergy_trial(V, d1, 0.3, o2, F, z, V0, w)
    assert np.allclose(o1, V + 0.3 * d1, rtol=1e-15, atol=1e-15) and np.allclose(o1, o2)
    assert t1 == pytest.approx(t2, rel=1e-12)
    assert t1 == pytest.approx(K._nb_venergy(V + 0.3 * d1, F, z, V0, w), rel=1e-14)
    # trial point with the gradient: the values of the trial kernel + the gradient kernel there
    o3, g4 = np.empty_like(V), np.empty_like(V)
    e5 = FU._nb_venergy_grad_trial(V, d1, 0.3, o3, F, z, V0, w, g4)
    g5 = np.empty_like(V)
    e6 = K._nb_venergy_grad(o1, F, z, V0, w, g5)
    assert np.array_equal(o3, o1) and np.array_equal(g4, g5) and e5 == e6
    e7, g7 = FU.venergy_grad_trial(V, d1, 0.3, np.empty_like(V), F, z, V0, w)
    assert e7 == e5 and np.array_equal(g7, g4)
    o4 = np.empty_like(V)
    np.add(V, 0.3 * d1, out=o4)
    e8, g8 = FU._np_venergy_grad(o4, F, z, V0, w, S)
    assert e8 == pytest.approx(e5, rel=1e-12) and np.allclose(g8, g4, rtol=1e-10, atol=1e-12)


def test_rel_change_kernel_agrees(mesh, rng):
    import meshrepair.model._fused as FU

    V, _ = mesh
    W = V + 1e-3 * rng.normal(size=V.shape)
    want = np.linalg.norm(W - V) / np.linalg.norm(V)
    assert FU._nb_rel_change(W, V) == pytest.approx(want, rel=1e-12)
    assert FU._np_rel_change(W, V) == pytest.approx(want, rel=1e-12)
    assert FU.rel_change(V, V) == 0.0


def test_kernels_compile_without_a_writable_numba_cache():
    """Where numba finds no writable cache location it refuses cache=True at decoration time;
    the package then still imports and runs, compiling its kernels in the process."""
    code = (
        "import numba.core.caching as c\n"
        "c.CacheImpl._locator_classes = []\n"  # as if no cache directory were writable
        "import numpy as np, meshrepair._kernels as K\n"
        "assert K.CACHE_DISABLED, 'expected the no-cache fallback'\n"
        "V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])\n"
        "assert np.allclose(K.face_normals(V, F), [[0, 0, 1]])\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_fused_multiplier_and_history_kernels_agree(mesh, rng):
    """Normals + (21) in one face pass, lengths + regulariser of (6) in one edge pass: equal to
    the separate kernels (and so to their numpy twins)."""
    import meshrepair.model._fused as FU

    V, F = mesh
    V = V.copy()
    V[F[0, 1]] = V[F[0, 0]]  # a degenerate face gets a zero normal
    topo = edge_topology(F, len(V))
    ie = np.flatnonzero(topo.interior)
    E = np.ascontiguousarray(topo.edges[ie])
    fa, fb = (np.ascontiguousarray(c) for c in topo.edge_faces[ie].T)
    N = K._np_face_normals(V + 0.01 * rng.normal(size=V.shape), F)
    r1, r2 = rng.normal(size=N.shape), None
    r2 = r1.copy()
    Nv1, s1 = FU._nb_normals_update_rho2(V, F, N, r1, 3.0)
    Nv2 = K._np_face_normals(V, F)
    s2 = K._np_update_rho2(N, Nv2, r2, 3.0)
    assert np.allclose(Nv1, Nv2, atol=1e-15) and not Nv1[0].any()
    assert np.allclose(r1, r2, atol=1e-14) and s1 == pytest.approx(s2, rel=1e-12)
    sharp = rng.random(len(ie)) < 0.3
    l1, e1 = FU._nb_lengths_reg_energy(V, E, Nv2, fa, fb, sharp, 10.0, 1.0)
    l2 = K._np_edge_lengths(V, E)
    assert np.allclose(l1, l2, rtol=1e-15)
    assert e1 == pytest.approx(K._np_reg_energy(Nv2, l2, fa, fb, sharp, 10.0, 1.0), rel=1e-12)


@pytest.mark.parametrize("a,a_flat,beta1,w", [(10.0, 0.5, 12.0, 1.0), (0.5, 0.5, 1.0, 3.0),
                                              (0.25, 0.0, 0.5, 16.0)])
@pytest.mark.parametrize("with_flat", [False, True])
def test_fused_t_update_matches_separate_kernels(mesh, rng, a, a_flat, beta1, w, with_flat):
    from meshrepair._kernels.tstep import _np_t_from_normals, t_from_normals
    from meshrepair.model.penalties import t_update
    from meshrepair.model.priors import t_update_mixed

    V, F = mesh
    topo = edge_topology(F, len(V))
    fa, fb = topo.edge_faces[:, 0].copy(), topo.edge_faces[:, 1].copy()
    N = K._np_face_normals(V, F)
    l = 3.0 * K._np_edge_lengths(V, topo.edges)
    rho1 = 0.3 * rng.normal(size=(len(fa), 3))
    sharp = rng.random(len(fa)) < 0.3
    flat = (rng.random(len(fa)) < 0.4) if with_flat else None
    bt = max(beta1, 1.01 * a_flat)
    DN = K._nb_grad_edges(N, l, fa, fb)
    if with_flat:
        t0 = t_update_mixed(DN, rho1, sharp, flat, a=a, a_flat=a_flat, beta1=bt,
                            willmore_weight=w)
    else:
        t0 = t_update(DN, rho1, sharp, a=a, beta1=bt, willmore_weight=w)
    t1 = t_from_normals(N, l, fa, fb, rho1, sharp, flat, a=a, a_flat=a_flat, beta1=bt, w=w)
    t2 = _np_t_from_normals(N, l, fa, fb, rho1, sharp, flat, a, a_flat, bt, w)
    # equal to rounding (bit for bit on the machine measured: the same IEEE operations)
    assert np.allclose(t1, t0, rtol=1e-14, atol=1e-15)
    assert np.allclose(t2, t0, rtol=1e-14, atol=1e-15)
    # every class is exercised: shrunk to zero, partly shrunk, Willmore
    n = np.linalg.norm(t1, axis=1)
    willmore = ~sharp if flat is None else ~sharp & ~flat
    assert (n[sharp] == 0).any() and (n[sharp] > 0).any() and (n[willmore] > 0).all()
    with pytest.raises(ValueError, match="rule \\(24\\)"):
        t_from_normals(N, l, fa, fb, rho1, sharp, flat, a=a, a_flat=a_flat, beta1=0.5 * a, w=w)


def test_anchor_with_unit_weight_projects_onto_the_normal_lines(mesh, rng):
    from meshrepair.model.fidelity import tangential_anchor

    V, F = mesh
    V0 = V + 0.1 * rng.normal(size=V.shape)
    n = K._np_vertex_normals(V, F)
    # w = 1 projects onto the normal line through V0: the tangential part of V - V0 vanishes
    one = tangential_anchor(V, V0, F, np.ones(len(V)))
    d = one - V0
    assert np.abs(d - np.einsum("ij,ij->i", d, n)[:, None] * n).max() < 1e-12


def test_signed_volume_kernel_agrees(mesh):
    from meshrepair._kernels.faces import _nb_signed_volume, _np_signed_volume

    V, F = mesh
    c = V.mean(axis=0)
    v1, v2 = _nb_signed_volume(V, F, c), _np_signed_volume(V, F, c)
    assert v1 == pytest.approx(v2, rel=1e-12)
    # a closed mesh: the volume does not depend on the centre; the unit icosphere ≈ 4π/3
    assert _nb_signed_volume(V, F, c + 5.0) == pytest.approx(v1, rel=1e-9)
    m = trimesh.creation.icosphere(3)
    Vs, Fs = np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int64)
    assert _nb_signed_volume(Vs, Fs, np.zeros(3)) == pytest.approx(m.volume, rel=1e-12)


def _open_pinched_mesh(rng):
    """An icosphere with a hole, a second one touching it at a vertex (pinched), an
    unreferenced vertex and the faces shuffled."""
    m = trimesh.creation.icosphere(3)
    V = np.asarray(m.vertices)
    F = np.asarray(m.faces, dtype=np.int64)[5:]
    F2 = F + len(V) - 1
    F2[F2 == len(V) - 1 + 7] = F[0, 0]  # vertex 7 of the copy is vertex F[0, 0]: pinched
    F2 = np.r_[F, F2]
    F2 = F2[rng.permutation(len(F2))]
    V2 = np.r_[V, V + 2.0, [[9.0, 9.0, 9.0]]]
    return V2, F2


def test_setup_kernels_agree_with_numpy(rng):
    """Face centroids, exact edge lengths, pair order, fan counts, duplicate rows, the face
    side pattern and the permuted edge tables: the compiled pass equals its numpy twin."""
    V, F = _open_pinched_mesh(rng)
    nV = len(V)
    assert np.array_equal(K._nb_face_centroids(V, F), K._np_face_centroids(V, F))
    topo = edge_topology(F, nV)
    E = topo.edges
    assert np.array_equal(K._nb_edge_lengths_exact(V, E), K._np_edge_lengths_exact(V, E))
    lo = rng.integers(0, 50, 3000)
    hi = rng.integers(0, 8, 3000)
    lo[:100] = 3  # a long bucket (merge sort)
    assert np.array_equal(K._nb_pair_order(lo, hi, 50), K._np_pair_order(lo, hi, 50))
    inner = topo.edge_counts == 2
    order = K.group_halfedges(F, nV)
    _, edge_he, _, _ = K.edges_from_groups(F, order)
    h1, h2 = edge_he[inner, 0], edge_he[inner, 1]
    fans = K._nb_fan_counts(F, h1, h2, nV)
    assert np.array_equal(fans, K._np_fan_counts(F, h1, h2, nV))
    assert fans.max() == 2 and fans[-1] == 0
    W = np.r_[V, V[[3, 5]], [[-0.0, 1.0, 2.0], [0.0, 1.0, 2.0]]] + 0.0
    bits = W.view(np.uint64).reshape(-1, 3)
    d = K._nb_duplicate_rows(bits)
    assert np.array_equal(d, K._np_duplicate_rows(bits))
    assert d.tolist() == [len(V), len(V) + 1, len(V) + 3]
    ok = topo.interior & (rng.random(topo.n_edges) < 0.8)
    for x, y in zip(K._nb_face_side_csr(topo.face_edges, topo.edge_faces, ok),
                    K._np_face_side_csr(topo.face_edges, topo.edge_faces, ok), strict=True):
        assert np.array_equal(x, y)


def test_permuted_topology_equals_a_new_build(rng):
    """The topology of a renumbered, reordered mesh permuted from the first one equals the one
    built from the new faces (compiled and numpy), boundary and pinched vertex included."""
    from meshrepair.mesh.topology import permuted_topology

    V, F = _open_pinched_mesh(rng)
    nV = len(V)
    topo = edge_topology(F, nV)
    pv = rng.permutation(nV)
    pf = rng.permutation(len(F))
    inv = np.empty_like(pv)
    inv[pv] = np.arange(nV)
    Fw = inv[F][pf]
    ref = edge_topology(Fw, nV)
    new = permuted_topology(topo, inv, pf, Fw)
    args = (topo.edges, topo.edge_faces, topo.face_edges, topo.edge_counts, inv, pf)
    for name, x, y in zip(("edges", "edge_faces", "face_edges", "edge_counts"),
                          K._np_permuted_edges(*args), K._nb_permuted_edges(*args), strict=True):
        assert np.array_equal(x, getattr(ref, name)) and np.array_equal(y, x), name
    for name in ("edges", "edge_faces", "face_edges", "edge_counts", "faces"):
        assert np.array_equal(getattr(new, name), getattr(ref, name)), name
    assert new.n_vertices == ref.n_vertices


def test_more_setup_kernels_agree_with_numpy(rng):
    """The one-pass edge tables, creased edges, ring growth, umbrella entries and interior
    edges equal their numpy twins (and the two-step grouping)."""
    from meshrepair.mesh.topology import adjacency

    V, F = _open_pinched_mesh(rng)
    nV = len(V)
    ref = K.edges_from_groups(F, K.group_halfedges(F, nV))
    for x, y, z in zip(K._nb_edge_tables(F, nV), K._np_edge_tables(F, nV), ref, strict=True):
        assert np.array_equal(x, y) and np.array_equal(x, z)
    # a high-valence vertex (the merge-sort bucket)
    n = len(V)
    ring = n + 1 + np.arange(100)
    F2 = np.r_[F, np.c_[np.full(100, n), ring, np.roll(ring, -1)]]
    for x, y in zip(K._nb_edge_tables(F2, n + 101), K._np_edge_tables(F2, n + 101), strict=True):
        assert np.array_equal(x, y)
    topo = edge_topology(F, nV)
    N = K.face_normals(V + 0.05 * rng.normal(size=V.shape), F)
    c = K._nb_creased_edges(N, topo.edge_faces, np.cos(np.radians(20.0)))
    assert c.any() and np.array_equal(c, K._np_creased_edges(N, topo.edge_faces,
                                                             np.cos(np.radians(20.0))))
    act = rng.random(nV) < 0.05
    assert np.array_equal(K._nb_grow(act, topo.edges), K._np_grow(act, topo.edges))
    A = adjacency(topo)
    for x, y in zip(K._nb_umbrella_entries(A.indptr, A.indices),
                    K._np_umbrella_entries(A.indptr, A.indices), strict=True):
        assert np.array_equal(x, y) and x.dtype == y.dtype
    for x, y in zip(K._nb_interior_edges(topo.edges, topo.edge_faces),
                    K._np_interior_edges(topo.edges, topo.edge_faces), strict=True):
        assert np.array_equal(x, y)


def test_adjacency_and_renumbering_kernels(rng):
    """The adjacency of a topology's sorted edges equals sym_csr's (and other edges go to
    sym_csr); the renumbered faces equal ``inv[F][pf]``."""
    V, F = _open_pinched_mesh(rng)
    topo = edge_topology(F, len(V))
    for x, y in zip(K.edge_csr(topo.edges, len(V)), K.sym_csr(topo.edges[:, 0], topo.edges[:, 1],
                                                               len(V)), strict=True):
        assert np.array_equal(x, y)
    assert K._nb_sorted_edge_csr(topo.edges, len(V))[2]
    shuffled = topo.edges[rng.permutation(topo.n_edges)]
    assert not K._nb_sorted_edge_csr(shuffled, len(V))[2]
    for x, y in zip(K.edge_csr(shuffled, len(V)), K.sym_csr(shuffled[:, 0], shuffled[:, 1],
                                                             len(V)), strict=True):
        assert np.array_equal(x, y)
    inv = rng.permutation(len(V))
    pf = rng.permutation(len(F))
    assert np.array_equal(K._nb_renumbered_faces(F, inv, pf), K._np_renumbered_faces(F, inv, pf))


def test_face_neighbours_per_face_equal_the_table(rng):
    """The face-neighbour table gathered per face equals the two-pass table of the interior
    edges (compiled and numpy)."""
    V, F = _open_pinched_mesh(rng)
    topo = edge_topology(F, len(V))
    _, _, fa, fb = K.interior_edges(topo.edges, topo.edge_faces)
    ref = K.face_neighbour_table(fa, fb, topo.n_faces)
    for x, y, z in zip(K._nb_face_neighbours(topo.face_edges, topo.edge_faces),
                       K._np_face_neighbours(topo.face_edges, topo.edge_faces), ref, strict=True):
        assert np.array_equal(x, z) and np.array_equal(y, z)


def test_product_pattern_is_scipys(rng):
    """Rings of faces grown by the compiled product pattern equal scipy's ``(S @ Af)`` pattern
    entry for entry (the order of its stored columns included), ring after ring."""
    from meshrepair.denoise.regions import _ring, _side_adjacency

    V, F = _open_pinched_mesh(rng)
    topo = edge_topology(F, len(V))
    mask = rng.random(topo.n_edges) < 0.1
    Af = _side_adjacency(topo, mask, len(F))
    n = 40
    f = rng.integers(0, len(F), n)
    S0 = sp.csr_matrix((np.ones(n), (np.arange(n), f)), shape=(n, len(F)))
    S1 = S0
    work = np.full(len(F), -1, np.int64)
    for _ in range(4):
        S0 = (S0 @ Af).tocsr()
        S0.data[:] = 1.0
        S1 = _ring(S1, Af, work)
        assert np.array_equal(S0.indptr, S1.indptr) and np.array_equal(S0.indices, S1.indices)
        assert (work == -1).all()
    args = (S0.indptr, S0.indices, Af.indptr, Af.indices)
    a = K._nb_product_pattern(*[np.asarray(x, np.int64) for x in args], len(F), work)
    b = K._np_product_pattern(*args, len(F), work)
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(x, y)
