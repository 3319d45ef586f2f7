"""The noise reading across scales (:mod:`meshrepair.denoise.spectrum`): the band-pass
maths, the reading of synthetic noise of known level and correlation length, invariances and
determinism."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from meshrepair import add_noise, read_mesh
from meshrepair.denoise.scale import correlated_noise
from meshrepair.denoise.spectrum import (
    BANDS,
    CANDIDATE_STEPS,
    band_gains,
    grid_torus,
    read_noise,
    tangent_edge_length,
    umbrella_operator,
)
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.geometry import mean_edge_length, vertex_normals

DATA = Path(__file__).parent / "data"


def _mesh(name: str):
    m = read_mesh(DATA / f"{name}.ply")
    return m.V, m.F


def _normal_level(Vn, V, F) -> float:
    h = np.einsum("ij,ij->i", Vn - V, vertex_normals(V, F))
    return float(np.sqrt(np.mean(h * h)) / mean_edge_length(V, F))


def test_band_pass_transfer_on_a_plane_wave():
    """On the periodic grid a plane wave is an eigenvector of W (eigenvalue μ); the band-pass
    W^t (I - W^t)² multiplies it by μ^t (1 - μ^t)²."""
    n = 24
    edges, nv = grid_torus(n)
    W = umbrella_operator(edges, nv)
    i, j = np.divmod(np.arange(nv), n)
    a, b = 3, 5
    x = np.cos(2 * np.pi * (a * i + b * j) / n)
    mu = (2 * np.cos(2 * np.pi * a / n) + 2 * np.cos(2 * np.pi * b / n)
          + 2 * np.cos(2 * np.pi * (a + b) / n)) / 6.0
    assert np.allclose(W @ x, mu * x, atol=1e-12)
    for t in (1, 2, 4):
        Wt = x
        for _ in range(t):
            Wt = W @ Wt
        W2t, W3t = Wt, Wt
        for _ in range(t):
            W2t = W @ W2t
        for _ in range(2 * t):
            W3t = W @ W3t
        h = Wt - 2 * W2t + W3t
        assert np.allclose(h, mu**t * (1 - mu**t) ** 2 * x, atol=1e-12)


def test_gains_peak_at_the_noise_scale():
    """White noise has most band energy in the finest band; a field of m steps peaks in the band
    of t ≈ m (the transfer's peak meets the field's wavelength) and is nearly absent at t = 1."""
    G = band_gains()
    assert G.shape == (len(CANDIDATE_STEPS), len(BANDS))
    assert np.argmax(G[0]) == 0 and np.all(np.diff(G[0]) < 0)
    for m in (8, 16):
        k = int(np.argmax(G[CANDIDATE_STEPS.index(m)]))
        assert BANDS[k] in (m // 2, m, 2 * m)
        assert G[CANDIDATE_STEPS.index(m), 0] < 0.05 * G[0, 0]


def test_tangent_edge_length_ignores_normal_noise():
    """Noise along the normals lengthens edges by √(1 + 2γ²); the tangent projection does not."""
    V, F = _mesh("spot")
    from meshrepair.mesh.topology import edge_topology

    e = edge_topology(F, len(V)).edges
    lbar = mean_edge_length(V, F)
    Vn = add_noise(V, F, 0.5, seed=3)
    assert mean_edge_length(Vn, F) > 1.1 * lbar
    got = tangent_edge_length(Vn[e[:, 1]] - Vn[e[:, 0]], vertex_normals(V, F), e)
    assert abs(got / lbar - 1) < 0.03


@pytest.mark.parametrize("gamma", [0.1, 0.3])
@pytest.mark.parametrize("name", ["spot", "fandisk"])
def test_white_noise_of_known_level(name, gamma):
    V, F = _mesh(name)
    for seed in (1, 2):
        Vn = add_noise(V, F, gamma, seed=seed)
        r = read_noise(Vn, F)
        assert abs(r.level / _normal_level(Vn, V, F) - 1) <= 0.25, r
        assert r.length <= 1.0 and not r.correlated


@pytest.mark.parametrize("name", ["spot", "fandisk", "trim_star"])
def test_correlated_noise_of_known_level_and_length(name):
    """Noise of 4 diffusion steps (ℓ = 2 edges) at 0.6 l̄: level within 25 %, ℓ within 1.5×."""
    V, F = _mesh(name)
    for seed in (1, 2):
        Vn = correlated_noise(V, F, 0.6, 4, seed=seed)
        r = read_noise(Vn, F)
        assert abs(r.level / _normal_level(Vn, V, F) - 1) <= 0.25, r
        assert 2 / 1.5 <= r.length <= 2 * 1.5 and r.correlated, r
        assert r.white_evidence > 1.0  # the best white model fits worse


def test_invariant_to_rotation_scale_and_order():
    V, F = _mesh("fandisk")
    Vn = correlated_noise(V, F, 0.4, 4, seed=5)
    r0 = read_noise(Vn, F)
    q, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))
    r1 = read_noise(3.7 * Vn @ q.T + np.array([5.0, -2.0, 1.0]), F)
    perm = np.random.default_rng(1).permutation(len(V))
    inv = np.argsort(perm)
    r2 = read_noise(Vn[perm], inv[F][np.random.default_rng(2).permutation(len(F))])
    for r in (r1, r2):
        assert r.length == r0.length and r.bands == r0.bands
        assert r.level == pytest.approx(r0.level, rel=1e-9)
        assert np.allclose(r.energies, r0.energies, rtol=1e-9)
    assert r1.mean_edge == pytest.approx(3.7 * r0.mean_edge, rel=1e-12)


def test_deterministic_and_input_untouched():
    V, F = _mesh("spot")
    Vn = add_noise(V, F, 0.2, seed=4)
    keep = Vn.copy()
    a, b = read_noise(Vn, F), read_noise(Vn, F)
    assert np.array_equal(Vn, keep)
    assert a.level == b.level and a.length == b.length
    assert np.array_equal(a.energies, b.energies)


def test_stable_under_rounding_level_jitter():
    """Every vertex moved by 1e-10 of the bounding-box diagonal: the same ℓ̂, the level to 1e-6."""
    V, F = _mesh("trim_star")
    Vn = correlated_noise(V, F, 0.5, 4, seed=6)
    d = np.random.default_rng(0).normal(size=Vn.shape)
    d *= 1e-10 * np.linalg.norm(np.ptp(Vn, axis=0)) / np.linalg.norm(d, axis=1, keepdims=True)
    a, b = read_noise(Vn, F), read_noise(Vn + d, F)
    assert a.length == b.length and abs(b.level / a.level - 1) < 1e-6


def test_field_reading_and_errors():
    """A known field laid on the mesh reads its own level and length (no relief)."""
    V, F = _mesh("spot")
    Vn = correlated_noise(V, F, 0.5, 16, seed=2)
    eta = np.einsum("ij,ij->i", Vn - V, vertex_normals(V, F))
    r = read_noise(V, F, field=eta)
    assert abs(r.level / 0.5 - 1) <= 0.25 and 4 / 1.5 <= r.length <= 4 * 1.5
    with pytest.raises(MeshRepairError, match="field"):
        read_noise(V, F, field=eta[:-1])
    with pytest.raises(MeshRepairError):
        read_noise(V[:3], np.array([[0, 1, 2]]))


@pytest.mark.shared
@pytest.mark.parametrize("name", ["bunny__gauss0.2", "fandisk__gauss0.3", "fandisk__gauss0.7",
                                  "nicolo__gauss0.2", "sharp_sphere__gauss0.3",
                                  "trim_star__gauss_n3"])
def test_shared_published_gaussian_inputs(name):
    """The sources' own Gaussian noisy files: the level of the displacement from the truth along
    the truth's normals is read within 25 %, as not correlated."""
    from .conftest import shared_mesh

    Vn, F = shared_mesh(f"noisy/{name}.ply")
    Vt, _ = shared_mesh(f"{name.split('__')[0]}.ply")
    r = read_noise(Vn, F)
    assert abs(r.level / _normal_level(Vn, Vt, F) - 1) <= 0.25, r
    assert not r.correlated, r


SHARED_MESHES = ("fandisk", "trim_star", "twelve", "nicolo", "spot", "bunny", "camelhead")


@pytest.mark.shared
@pytest.mark.parametrize("name", SHARED_MESHES)
def test_shared_reading_within_25_percent(name):
    """Shared organic and CAD meshes: white noise along the normals (0.1, 0.3 l̄) and correlated
    noise of ℓ = 2 edges at 0.6 l̄ read within 25 % in level (ℓ within 1.5×)."""
    from .conftest import shared_mesh

    V, F = shared_mesh(f"{name}.ply")
    for gamma in (0.1, 0.3):
        Vn = add_noise(V, F, gamma, seed=1)
        r = read_noise(Vn, F)
        assert abs(r.level / _normal_level(Vn, V, F) - 1) <= 0.25, (gamma, r)
        assert not r.correlated, (gamma, r)
    Vn = correlated_noise(V, F, 0.6, 4, seed=1)
    r = read_noise(Vn, F)
    assert abs(r.level / _normal_level(Vn, V, F) - 1) <= 0.25, r
    assert 2 / 1.5 <= r.length <= 3.0 and r.correlated, r
