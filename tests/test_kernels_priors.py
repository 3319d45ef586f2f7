"""The compiled kernels of the flat-TV class (t-update, lengths + regulariser) and of the
tangential anchor agree with their numpy twins, and the solver's mixed-class history energy is the
regulariser of :mod:`meshrepair.model.priors` evaluated directly."""

import numpy as np
import pytest
import trimesh

from meshrepair import _kernels as K
from meshrepair._kernels import fidelity as KF
from meshrepair._kernels import priors as KP
from meshrepair.mesh.topology import edge_topology
from meshrepair.model.priors import reg_energy_mixed

needs_numba = pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed: only numpy path")


@pytest.fixture
def mesh(rng):
    m = trimesh.creation.icosphere(3)
    V = np.asarray(m.vertices) + 0.05 * rng.normal(size=m.vertices.shape)
    return V, np.asarray(m.faces, dtype=np.int64)


def _edges(V, F):
    topo = edge_topology(F, len(V))
    ie = np.flatnonzero(topo.interior)
    E = np.ascontiguousarray(topo.edges[ie])
    fa, fb = (np.ascontiguousarray(c) for c in topo.edge_faces[ie].T)
    return E, fa, fb


@needs_numba
def test_t_update_mixed_kernel_agrees_with_numpy(rng):
    n = 500
    DN, rho1 = rng.normal(size=(n, 3)), 0.3 * rng.normal(size=(n, 3))
    DN[:5] = 0.0
    rho1[:5] = 0.0  # zero residual: t = 0 on every class
    sharp = rng.random(n) < 0.3
    flat = rng.random(n) < 0.5  # overlaps sharp: sharp wins
    for a, af, b1, w in ((10.0, 0.5, 12.0, 1.0), (0.5, 0.25, 1.0, 4.0)):
        t1 = KP._nb_t_update_mixed(DN, rho1, sharp, flat, a, af, b1, np.array([w]), False)
        t2 = KP._np_t_update_mixed(DN, rho1, sharp, flat, a, af, b1, w)
        assert np.allclose(t1, t2, rtol=1e-13, atol=1e-15)
        assert not t1[:5].any()
        # the composition it replaced (compiled t_update, then prox_mc on the flat edges): equal
        # bit for bit, so the solver's iterates do not change
        from meshrepair.model.penalties import prox_mc, t_update

        t3 = t_update(DN, rho1, sharp, a=a, beta1=b1, willmore_weight=w)
        f = flat & ~sharp
        t3[f] = prox_mc((b1 * DN[f] + rho1[f]) / b1, af, b1)
        assert np.array_equal(t1, t3)
        smooth = ~sharp & ~flat
        assert np.allclose(t1[smooth], (b1 * DN + rho1)[smooth] / (b1 + 2 * w), rtol=1e-14)


def test_t_update_mixed_refuses_a_weak_beta1(rng):
    DN = rng.normal(size=(4, 3))
    flat = np.ones(4, bool)
    with pytest.raises(ValueError, match="a_flat"):
        KP.t_update_mixed(DN, DN, np.zeros(4, bool), flat, 10.0, 0.5, 0.5, 1.0)
    with pytest.raises(ValueError, match="rule"):
        KP.t_update_mixed(DN, DN, flat, flat, 10.0, 0.5, 5.0, 1.0)


@needs_numba
def test_lengths_reg_energy_mixed_kernel_agrees(mesh, rng):
    V, F = mesh
    E, fa, fb = _edges(V, F)
    Nv = K._np_face_normals(V, F)
    sharp = rng.random(len(E)) < 0.2
    flat = rng.random(len(E)) < 0.5
    l1, e1 = KP._nb_lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, 10.0, 0.5, 2.0)
    l2, e2 = KP._np_lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, 10.0, 0.5, 2.0)
    assert np.allclose(l1, l2, rtol=1e-15) and e1 == pytest.approx(e2, rel=1e-12)


def test_lengths_reg_energy_mixed_is_the_mixed_regulariser(mesh, rng):
    """The history energy of a flat-TV stage: R(t) of meshrepair.model.priors at t = l (Nv_a -
    Nv_b),
    whichever path (compiled or numpy) is installed."""
    V, F = mesh
    E, fa, fb = _edges(V, F)
    Nv = K._np_face_normals(V + 0.02 * rng.normal(size=V.shape), F)
    sharp = rng.random(len(E)) < 0.2
    flat = rng.random(len(E)) < 0.5
    l, e = KP.lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, 10.0, 0.5, 2.0)
    t = l[:, None] * (Nv[fa] - Nv[fb])
    ref = reg_energy_mixed(t, sharp, flat, a=10.0, a_flat=0.5, willmore_weight=2.0)
    assert np.allclose(l, np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1), rtol=1e-14)
    assert e == pytest.approx(ref, rel=1e-12)


@needs_numba
def test_tangential_anchor_kernel_agrees_with_numpy(mesh, rng):
    V, F = mesh
    V0 = V + 0.1 * rng.normal(size=V.shape)
    w = rng.random(len(V))
    w[:10] = 0.0
    w[10:20] = 1.0
    out1 = KF._nb_tangential_anchor(V, V0, F, w)
    out2 = KF._np_tangential_anchor(V, V0, F, w)
    # bit for bit (the same sums in the same order): the solver's iterates do not change
    assert np.array_equal(out1, out2)
    assert np.array_equal(out1[:10], V[:10])  # weight 0: unchanged


def test_tangential_anchor_keeps_the_normal_offset(mesh, rng):
    """Weight 1 projects onto the normal line through V0: the offset left is along n_i."""
    V, F = mesh
    V0 = V + 0.1 * rng.normal(size=V.shape)
    out = KF.tangential_anchor(V, V0, F, np.ones(len(V)))
    n = K._np_vertex_normals(V, F)
    d = out - V0
    assert np.allclose(d - np.einsum("ij,ij->i", d, n)[:, None] * n, 0.0, atol=1e-12)
    assert np.allclose(np.einsum("ij,ij->i", d, n), np.einsum("ij,ij->i", V - V0, n), atol=1e-12)


@needs_numba
def test_t_update_mixed_kernel_with_per_edge_weights(rng):
    """Per-edge Willmore weights (and no flat class): the compiled pass equals the numpy code
    bit for bit, and the smooth edges get the closed form (β1 DN + ρ1) / (β1 + 2 w_e)."""
    n = 400
    DN, rho1 = rng.normal(size=(n, 3)), 0.3 * rng.normal(size=(n, 3))
    sharp = rng.random(n) < 0.3
    flat = rng.random(n) < 0.5
    w = 1.0 + 15.0 * rng.random(n)
    for fl in (flat, None):
        t1 = KP.t_update_mixed(DN, rho1, sharp, fl, 10.0, 0.5, 12.0, w)
        t2 = KP._np_t_update_mixed(DN, rho1, sharp, fl, 10.0, 0.5, 12.0, w)
        assert np.array_equal(t1, t2)
        smooth = ~sharp if fl is None else ~sharp & ~fl
        ref = (12.0 * DN + rho1)[smooth] / (12.0 + 2.0 * w[smooth])[:, None]
        assert np.array_equal(t1[smooth], ref)
