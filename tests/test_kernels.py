"""The compiled kernels agree with their numpy twins (the fallback without numba)."""

import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp
import trimesh

from meshrepair import _kernels as K
from meshrepair.linear import NormalSystem, block_pcg
from meshrepair.topology import edge_topology

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
