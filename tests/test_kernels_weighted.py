"""Fused passes: the per-edge-weight t-update and lengths + history energy
(:mod:`meshrepair._kernels.weighted`), the one-ring closest points
(:mod:`meshrepair._kernels.closest`), the sort-free unique edges and the shared face geometry of
the CAD finish equal what they replace."""

import numpy as np
import pytest
import trimesh

from meshrepair import _kernels as K
from meshrepair._kernels import priors as KP
from meshrepair._kernels import weighted as KW
from meshrepair.mesh.topology import edge_topology

needs_numba = pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed: only numpy path")


@pytest.fixture
def mesh(rng):
    m = trimesh.creation.icosphere(3)
    V = np.asarray(m.vertices) + 0.03 * rng.normal(size=m.vertices.shape)
    return V, np.asarray(m.faces, dtype=np.int64)


def _interior(V, F):
    topo = edge_topology(F, len(V))
    ie = np.flatnonzero(topo.interior)
    E = np.ascontiguousarray(topo.edges[ie])
    fa, fb = (np.ascontiguousarray(c) for c in topo.edge_faces[ie].T)
    return topo, E, fa, fb


@pytest.mark.parametrize("with_flat", [True, False])
def test_t_from_normals_weighted_is_the_composition(mesh, rng, with_flat):
    V, F = mesh
    _, E, fa, fb = _interior(V, F)
    n = len(fa)
    N = K.face_normals(V, F)
    l = K.edge_lengths(V, E)
    rho1 = 0.05 * rng.normal(size=(n, 3))
    sharp = rng.random(n) < 0.2
    flat = (rng.random(n) < 0.4) if with_flat else None
    w = np.where(rng.random(n) < 0.5, 6.0, 1.0)
    for a, af, b1 in ((10.0, 0.5, 12.0), (0.5, 0.25, 1.0)):
        t = KW.t_from_normals_weighted(N, l, fa, fb, rho1, sharp, flat, a=a, a_flat=af,
                                       beta1=b1, w=w)
        # the two kernels it replaces in the solver, bit for bit (same iterates)
        ref = KP.t_update_mixed(K.grad_edges(N, l, fa, fb), rho1, sharp, flat, a, af, b1, w)
        assert np.array_equal(t, ref)
        tn = KW._np_t_from_normals_weighted(N, l, fa, fb, rho1, sharp, flat, a, af, b1, w)
        assert np.allclose(t, tn, rtol=1e-13, atol=1e-15)


def test_t_from_normals_weighted_refuses_a_weak_beta1(mesh):
    V, F = mesh
    _, E, fa, fb = _interior(V, F)
    n = len(fa)
    N, l = K.face_normals(V, F), K.edge_lengths(V, E)
    with pytest.raises(ValueError, match="rule"):
        KW.t_from_normals_weighted(N, l, fa, fb, np.zeros((n, 3)), np.ones(n, bool), None,
                                   a=10.0, a_flat=0.5, beta1=5.0, w=np.ones(n))


def test_lengths_reg_energy_weighted_is_the_two_passes(mesh, rng):
    import meshrepair.model._fused as _fused

    V, F = mesh
    _, E, fa, fb = _interior(V, F)
    n = len(fa)
    Nv = K.face_normals(V, F)
    sharp = rng.random(n) < 0.2
    flat = rng.random(n) < 0.4
    w_int = np.where(rng.random(n) < 0.5, 6.0, 1.0)
    l, e, s = KW.lengths_reg_energy_weighted(V, E, Nv, fa, fb, sharp, flat, 10.0, 0.5, 1.0,
                                             w_int)
    l0, e0 = KP.lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, 10.0, 0.5, 1.0)
    s0 = _fused.willmore_extra(l0, Nv, fa, fb, w_int, 1.0, sharp | flat)
    assert np.array_equal(l, l0)  # the lengths feed the next iteration: bit for bit
    assert e == pytest.approx(e0, rel=1e-13) and s == pytest.approx(s0, rel=1e-13)
    assert s > 0
    ln, en, sn = KW._np_lengths_reg_energy_weighted(V, E, Nv, fa, fb, sharp, flat, 10.0, 0.5,
                                                    1.0, w_int)
    assert np.allclose(l, ln, rtol=1e-14) and en == pytest.approx(e, rel=1e-12)
    assert sn == pytest.approx(s, rel=1e-12)


@needs_numba
def test_closest_points_kernel_equals_numpy_twin(mesh, rng):
    from meshrepair.denoise import reproject as R

    V, F = mesh
    le = float(K.edge_lengths(V, edge_topology(F, len(V)).edges).mean())
    P = V + 0.4 * le * rng.normal(size=V.shape)
    P[:10] = V[:10]  # on the surface: the vertex itself
    a = R.closest_points_local(V, F, P)
    b = R._np_closest_points_local(V, F, P)
    # the same face chosen and the same operations: equal to rounding (bit for bit where
    # numpy's einsum sums three terms as the kernel does, (x0 y0 + x2 y2) + x1 y1)
    assert np.allclose(a, b, rtol=0, atol=1e-12 * le)
    assert np.array_equal(a[:10], V[:10])
    s = R.local_search(V, F)
    assert np.array_equal(R.closest_points_local(V, F, P, search=s), a)
    # a vertex without faces stays where it is
    V2 = np.vstack([V, [[5.0, 5.0, 5.0]]])
    P2 = np.vstack([P, [[5.1, 5.0, 5.0]]])
    c = R.closest_points_local(V2, F, P2)
    assert np.array_equal(c[-1], V2[-1]) and np.allclose(c[:-1], a, rtol=0, atol=1e-12 * le)


def test_unique_edges_are_the_topology_edges(mesh):
    from meshrepair.mesh.geometry import edge_lengths, mean_edge_length, unique_edges

    V, F = mesh
    topo = edge_topology(F, len(V))
    e = unique_edges(F)
    assert np.array_equal(e, topo.edges)
    he = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    assert np.array_equal(e, np.unique(he, axis=0))  # the rows of the row-wise unique
    assert mean_edge_length(V, F) == float(edge_lengths(V, np.unique(he, axis=0)).mean())
    assert unique_edges(np.zeros((0, 3), np.int64)).shape == (0, 2)


def test_discrepancy_with_edges_equals_without(mesh, rng):
    from meshrepair.denoise import discrepancy as dq

    V, F = mesh
    topo = edge_topology(F, len(V))
    V0 = V + 0.01 * rng.normal(size=V.shape)
    inside = rng.random(len(V)) < 0.4
    assert dq.discrepancy_ratio(V0, V, F, inside, clip=3.0, edges=topo.edges) == \
        dq.discrepancy_ratio(V0, V, F, inside, clip=3.0)


def test_cad_finish_targets_with_shared_face_geometry(mesh):
    from meshrepair.denoise import cadfinish as cf
    from meshrepair.denoise.polish import _neighbourhood_csr, _normals_areas

    V, F = mesh
    topo = edge_topology(F, len(V))
    sharp = np.zeros(topo.n_edges, bool)
    Kn = _neighbourhood_csr(topo, sharp, 1)
    gate = np.arange(len(F)) % 3 != 0
    a = cf.finish_targets(V, F, Kn, gate, sigma_c=0.1)
    b = cf.finish_targets(V, F, Kn, gate, sigma_c=0.1, faces=_normals_areas(V, F))
    assert np.array_equal(a, b)


@pytest.mark.parametrize("share", [0.0, 0.05, 0.4, 1.0])
def test_tangential_anchor_on_its_support_equals_the_full_pass(mesh, rng, share):
    from meshrepair._kernels import fidelity as KF

    V, F = mesh
    V0 = V + 0.02 * rng.normal(size=V.shape)
    w = np.where(rng.random(len(V)) < share, rng.uniform(0.2, 1.0, len(V)), 0.0)
    sup = KF.anchor_support(F, w)
    a = KF.tangential_anchor_on(V, V0, F, w, sup)
    assert np.array_equal(a, KF.tangential_anchor(V, V0, F, w))  # bit for bit (same sums)
    b = KF._np_tangential_anchor_on(V, V0, F, w, *sup)
    assert np.allclose(a, b, rtol=0, atol=1e-14)
    assert np.array_equal(a[w == 0], V[w == 0])
