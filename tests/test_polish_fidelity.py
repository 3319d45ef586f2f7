"""The polish's vertex step keeps the data term (meshrepair.denoise.polish_fidelity)."""

import importlib

import numpy as np
import pytest
import trimesh

from meshrepair import add_noise, denoise, mean_angle_error, msae, vertex_error
from meshrepair.denoise.polish import polish, vertex_update
from meshrepair.denoise.polish_fidelity import (
    data_prox,
    polish_energy,
    vertex_update_with_data,
)
from meshrepair.mesh.geometry import face_normals
from meshrepair.mesh.topology import edge_topology
from meshrepair.synthetic import grid_plane

from .conftest import published_triple

denoise_mod = importlib.import_module("meshrepair.denoise.api")
finish_mod = importlib.import_module("meshrepair.denoise.finish")


def _plane(n=12):
    return grid_plane(n)


def test_data_prox_is_the_argmin():
    """prox(y) = argmin ½||x - y||² + (η/2)||x - V⁰||²: its gradient vanishes there, and a
    brute-force scan along random directions finds nothing lower."""
    rng = np.random.default_rng(0)
    Y, V0 = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    eta = 0.3
    X = data_prox(Y, V0, eta)
    assert np.allclose((X - Y) + eta * (X - V0), 0.0, atol=1e-14)

    def f(Z):
        return 0.5 * np.sum((Z - Y) ** 2) + 0.5 * eta * np.sum((Z - V0) ** 2)

    for _ in range(50):
        D = rng.normal(size=X.shape)
        for t in (1e-3, 1e-1, 1.0):
            assert f(X + t * D) >= f(X)


def test_zero_eta_is_the_plain_vertex_update():
    """η = 0 gives exactly the Sun steps of meshrepair.denoise.polish."""
    V, F = _plane()
    rng = np.random.default_rng(1)
    X = V + 0.05 * rng.normal(size=V.shape)
    Nt = np.tile([0.0, 0.0, 1.0], (len(F), 1))
    assert np.array_equal(vertex_update_with_data(X, F, Nt, V, eta=0.0, steps=7),
                          vertex_update(X, F, Nt, 7))


def test_unresisted_motion_decays_by_the_prox_factor():
    """A plane whose faces already have the target normals: a tangential slide and a uniform
    normal offset from the data cost nothing in E_n, so after k steps the distance to the data
    is exactly (1 + η)^-k of the start (the analytic case of the module docstring)."""
    V, F = _plane()
    Nt = face_normals(V, F)
    eta, k = 0.05, 12
    for shift in (np.array([0.3, -0.2, 0.0]), np.array([0.0, 0.0, 0.4])):
        X = V + shift
        Xk = vertex_update_with_data(X, F, Nt, V, eta=eta, steps=k)
        assert np.allclose(Xk - V, shift / (1 + eta) ** k, atol=1e-12)


def test_energy_decreases_on_a_noisy_plane():
    """Forward-backward steps lower E = E_n + (η/2)||x - V⁰||² step after step (noisy plane,
    flat target normals, data = the noisy plane)."""
    V, F = _plane(14)
    rng = np.random.default_rng(2)
    V0 = V + 0.3 * rng.normal(size=(len(V), 1)) * np.array([0.0, 0.0, 1.0])
    Nt = np.tile([0.0, 0.0, 1.0], (len(F), 1))
    eta = 0.002
    X, E = V0.copy(), [polish_energy(V0, F, Nt, V0, eta)]
    for _ in range(15):
        X = vertex_update_with_data(X, F, Nt, V0, eta=eta, steps=1)
        E.append(polish_energy(X, F, Nt, V0, eta))
    assert all(b <= a + 1e-12 for a, b in zip(E[:-1], E[1:], strict=True))
    assert E[-1] < 0.5 * E[0]


def test_isolated_spike_is_pulled_only_by_order_eta():
    """One vertex of a flat mesh offset along the normal in the data: the fixed point moves it
    by a small fraction of the offset (the normals resist), while a whole-plane offset is
    followed (previous test): the data correct what is consistent over many vertices."""
    V, F = _plane(14)
    Nt = face_normals(V, F)
    V0 = V.copy()
    i = 7 * 14 + 7
    V0[i, 2] = 1.0
    X = vertex_update_with_data(V, F, Nt, V0, eta=0.002, steps=300)
    assert 0 < X[i, 2] < 0.02


def test_polish_with_data_equivariant():
    """The polish with the data term commutes with a rotation, translation and scaling."""
    box = trimesh.creation.box(extents=(8, 8, 8)).subdivide().subdivide()
    V, F = np.asarray(box.vertices, float), np.asarray(box.faces, np.int64)
    Vn = add_noise(V, F, 0.3, seed=4)
    topo = edge_topology(F, len(V))
    N = face_normals(V, F)
    ie = np.flatnonzero(topo.interior)
    sharp = np.zeros(topo.n_edges, bool)
    sharp[ie] = np.einsum("ij,ij->i", N[topo.edge_faces[ie, 0]], N[topo.edge_faces[ie, 1]]) < 0.5
    X, _ = polish(Vn, F, sharp, topo, tau=20.0, passes=3, data=Vn, eta=0.002)
    R = trimesh.transformations.rotation_matrix(0.9, [1, 2, -1])[:3, :3]
    s, t = 2.5, np.array([3.0, -1.0, 7.0])
    Xr, _ = polish(s * Vn @ R.T + t, F, sharp, topo, tau=20.0, passes=3,
                   data=s * Vn @ R.T + t, eta=0.002)
    assert np.allclose(Xr, s * X @ R.T + t, atol=1e-9)


def test_box_heavy_noise_polish_with_data(monkeypatch):
    """A box with heavy normal noise (γ = 0.6): the data term in the polish lowers MSAE and E_V
    against the plain polish (measured 9.60 -> 7.99 and 4.49e-03 -> 3.61e-03)."""
    box = trimesh.creation.box(extents=(16, 16, 16))
    for _ in range(4):
        box = box.subdivide()
    V, F = np.asarray(box.vertices, float), np.asarray(box.faces, np.int64)
    Vn = add_noise(V, F, 0.6, seed=3)
    r = denoise(Vn, F)
    assert r.params["polished"] > 0
    monkeypatch.setattr(finish_mod, "POLISH_DATA", False)
    r0 = denoise(Vn, F)
    assert msae(r.V, V, F) < 0.92 * msae(r0.V, V, F)
    assert vertex_error(r.V, V) < 0.9 * vertex_error(r0.V, V)


@pytest.mark.shared
def test_quality_published_gcn_fandisk_n6_all_three():
    """gcn_fandisk_n6 (heavy noise): MSAE, E_a and E_V at most GCN-Denoiser's published output
    (measured 46.47 / 3.941° / 2.125e-03 against 53.90 / 3.951° / 2.169e-03; with the polish's
    vertex step without the data term 51.52 / 4.170° / 2.624e-03). E_a is within 0.3 % of the
    published one, so it is asserted within 1 %, the others strictly."""
    Vn, Vt, Vp, F = published_triple("gcn_fandisk_n6")
    r = denoise(Vn, F)
    assert msae(r.V, Vt, F) < 0.9 * msae(Vp, Vt, F)
    assert mean_angle_error(r.V, Vt, F) < 1.01 * mean_angle_error(Vp, Vt, F)
    assert vertex_error(r.V, Vt) < vertex_error(Vp, Vt)
    assert mean_angle_error(r.V, Vt, F) < 0.97 * 4.170


def test_polish_data_term_on_the_reordered_path(monkeypatch):
    """Meshes solved in Morton order hand the polish the data in the input's order: forcing
    the reordered path on the heavy-noise box gives the same result up to rounding-level
    differences of the solve (MSAE and E_V within 0.5 %)."""
    box = trimesh.creation.box(extents=(16, 16, 16))
    for _ in range(4):
        box = box.subdivide()
    V, F = np.asarray(box.vertices, float), np.asarray(box.faces, np.int64)
    Vn = add_noise(V, F, 0.6, seed=3)
    r = denoise(Vn, F)
    monkeypatch.setattr(importlib.import_module("meshrepair.denoise.analysis"),
                        "REORDER_MIN_VERTICES",
                        0)
    r2 = denoise(Vn, F)
    assert r2.params["reordered"] and r2.params["polished"] > 0
    assert abs(msae(r2.V, V, F) / msae(r.V, V, F) - 1) < 0.005
    assert abs(vertex_error(r2.V, V) / vertex_error(r.V, V) - 1) < 0.005
