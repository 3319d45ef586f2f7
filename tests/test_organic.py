"""Tests of the organic finish (meshrepair.denoise.organic): its maths and its effect."""

import importlib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from meshrepair import mean_angle_error, msae, vertex_error
from meshrepair.denoise.organic import guidance_filter, reintegrate, reintegration_start
from meshrepair.mesh.geometry import face_normals, vertex_normals
from meshrepair.mesh.topology import edge_topology
from meshrepair.synthetic import grid_plane

from .conftest import needs_meshes, published_triple

denoise_mod = importlib.import_module("meshrepair.denoise.api")
rules_mod = importlib.import_module("meshrepair.denoise.rules")


def _plane(n=12):
    return grid_plane(n)


def _sphere(subdiv=3):
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdiv)
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


def _sun_energy(X, F, Nt):
    """E(x) = Σ_f Σ_{i∈f} ⟨n*_f, x_i − c_f⟩² (module docstring of meshrepair.denoise.organic)."""
    C = X[F].mean(axis=1)
    return float(sum(np.sum(np.einsum("ij,ij->i", Nt, X[F[:, k]] - C) ** 2) for k in range(3)))


def test_guidance_filter_fixed_point_on_a_plane():
    """All face normals equal: the filter returns them and the Sun steps do not move a vertex
    (``c_f − x_i`` lies in each face's plane)."""
    V, F = _plane()
    topo = edge_topology(F, len(V))
    X = guidance_filter(V, F, np.zeros(topo.n_edges, bool), topo, passes=3)
    assert np.allclose(X, V, atol=1e-12)
    assert guidance_filter(V, F, np.zeros(topo.n_edges, bool), topo, passes=0) is not V


def test_guidance_filter_reduces_normal_noise_and_keeps_a_marked_crease():
    """On a noisy 90° fold with its crease in M_E the filter lowers the normal error of both
    planes and the crease faces stay on their own side (the neighbourhood never crosses M_E)."""
    V, F = _plane(14)
    m = V[:, 0] > 7
    V[m, 2] = V[m, 0] - 7
    V[m, 0] = 7
    Vc = V.copy()
    topo = edge_topology(F, len(V))
    Nc = face_normals(Vc, F)
    ie = np.flatnonzero(topo.interior)
    sharp = np.zeros(topo.n_edges, bool)
    sharp[ie] = np.einsum("ij,ij->i", Nc[topo.edge_faces[ie, 0]], Nc[topo.edge_faces[ie, 1]]) < 0.5
    rng = np.random.default_rng(3)
    Vn = Vc + 0.04 * rng.standard_normal(V.shape)
    X = guidance_filter(Vn, F, sharp, topo, passes=2)
    assert mean_angle_error(X, Vc, F) < 0.7 * mean_angle_error(Vn, Vc, F)
    assert mean_angle_error(X, Vc, F) < 10.0


def test_reintegration_start_analytic():
    """On a planar result (normal e_z) the start is the input's tangential position with its
    normal offset capped at clip · median |d|, exactly."""
    V, F = _plane(10)
    rng = np.random.default_rng(1)
    t = 0.1 * rng.standard_normal((len(V), 2))
    d = 0.2 * rng.standard_normal(len(V))
    d[::7] *= 8.0  # thrown vertices
    V0 = V + np.c_[t, d]
    Y = reintegration_start(V, V0, F, clip=2.0)
    s = 2.0 * np.median(np.abs(d))
    assert np.allclose(Y[:, :2], V0[:, :2], atol=1e-12)
    assert np.allclose(Y[:, 2], np.clip(d, -s, s), atol=1e-12)
    assert np.allclose(reintegrate(V, V0, F, V, steps=0), Y)


def test_reintegrate_moves_only_along_the_target_normals():
    """Target normals all e_z: every Sun step changes z only, so the vertices keep the input's
    tangential positions exactly, and the planar energy decreases monotonically to 0."""
    V, F = _plane(10)
    rng = np.random.default_rng(2)
    V0 = V + np.c_[0.05 * rng.standard_normal((len(V), 2)), 0.2 * rng.standard_normal(len(V))]
    Nt = np.tile([0.0, 0.0, 1.0], (len(F), 1))
    energies = []
    for k in (0, 1, 2, 4, 8, 16):
        X = reintegrate(V, V0, F, V, steps=k)
        assert np.allclose(X[:, :2], V0[:, :2], atol=1e-12)
        energies.append(_sun_energy(X, F, Nt))
    assert all(b < a for a, b in zip(energies, energies[1:], strict=False))
    assert energies[-1] < 0.2 * energies[0]


def test_reintegrate_is_equivariant():
    """Rotation, translation and uniform scaling commute with the re-integration (the cap
    scales with the mesh, the steps are geometric)."""
    V, F = _sphere(2)
    rng = np.random.default_rng(5)
    n = vertex_normals(V, F)
    V0 = V + 0.03 * rng.standard_normal((len(V), 1)) * n
    T = V * 1.01
    R = Rotation.from_euler("xyz", [0.3, -0.7, 1.1]).as_matrix()
    s, b = 3.5, np.array([1.0, -2.0, 0.5])
    a = reintegrate(V, V0, F, T, steps=4)
    g = reintegrate(s * V @ R.T + b, s * V0 @ R.T + b, F, s * T @ R.T + b, steps=4)
    assert np.allclose(g, s * a @ R.T + b, atol=1e-9)


def test_rules_truth_table():
    """The two rules of the organic finish (guidance and re-integration) fire only where their
    docstrings say."""
    g = rules_mod.guidance_rule
    assert g(0.27, 1.0, 1.0) == 3 and g(0.2, 1.0, 1.0) == 2 and g(0.14, 1.0, 1.0) == 2
    assert g(0.05, 1.0, 1.0) == 1
    assert g(0.27, 6.0, 1.0) == 0  # a CAD part
    assert g(0.27, 1.0, 16.0) == 0  # correlated noise
    assert g(0.5, 1.0, 1.0) == 0  # heavy noise
    r = rules_mod.reintegrate_rule
    assert r(3, True, False, 0.2, 0.27) == 5
    assert r(2, True, True, 0.1, 0.14) == 3
    assert r(2, True, True, 0.1, 0.05) == 2
    assert r(2, True, False, 0.13, 0.2) == 0  # drift taken back by the re-anchoring
    assert r(2, False, True, 0.3, 0.2) == 0  # not re-anchored: the tangential layout is wrong
    assert r(0, True, True, 0.3, 0.2) == 0  # no guidance (a CAD part)
    assert r(3, True, False, 0.4, 0.2, 0.5) == 0  # residual below the noise level: correlated
    assert r(3, True, False, 0.4, 0.2, 0.8) == 4


@pytest.mark.shared
@needs_meshes
@pytest.mark.parametrize("case", ["nllr_igea", "nllr_pierrot"])
def test_organic_finish_beats_published_nllr(case):
    """Quality on two NLLR triples: the defaults beat the published NLLR output on MSAE, E_a and
    E_V (docs/parameters.md, organic.py), and without the finish they do not on MSAE."""
    Vn, Vt, Vp, F = published_triple(case)
    r = denoise_mod.denoise(Vn, F)
    assert r.params["guidance_passes"] > 0 and r.params["reintegrate_steps"] > 0
    assert msae(r.V, Vt, F) < 0.99 * msae(Vp, Vt, F)
    assert mean_angle_error(r.V, Vt, F) < mean_angle_error(Vp, Vt, F)
    assert vertex_error(r.V, Vt) < vertex_error(Vp, Vt)
    old = rules_mod.ORGANIC
    try:
        rules_mod.ORGANIC = False
        r0 = denoise_mod.denoise(Vn, F)
    finally:
        rules_mod.ORGANIC = old
    assert r0.params["guidance_passes"] == 0
    assert msae(r0.V, Vt, F) > msae(Vp, Vt, F)
