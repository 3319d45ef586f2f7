"""The band read of correlated noise (:mod:`meshrepair.denoise.corrwhite`) and branch 2 of the
correlated low-pass gate (:func:`meshrepair.denoise.corrlowpass.white_steps`)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshrepair import add_noise, denoise, msae
from meshrepair.denoise import corrlowpass as cl
from meshrepair.denoise.corrwhite import CANDIDATE_STEPS, band_models, band_read
from meshrepair.denoise.scale import _interior_vertices, _umbrella_operator, correlated_noise
from meshrepair.mesh.topology import edge_topology

from .test_denoise_model import grid


def _sphere(subdivisions: int = 4, r: float = 15.0):
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(m.vertices, np.float64) * r, np.asarray(m.faces, np.int64)


@pytest.mark.parametrize("steps", [0, 2, 4, 8])
def test_band_read_on_correlated_noise_of_known_scale(steps):
    """Known scale on a flat grid: m, the length √m (within 25 %) and the level γ (25 %)."""
    V, F = grid(60)
    for seed in (1, 2):
        est = band_read(correlated_noise(V, F, 0.3, steps, seed=seed), F)
        assert abs(est.gamma - 0.3) <= 0.25 * 0.3
        if steps == 0:
            assert est.steps == 0 and abs(est.beta - 1.0) < 0.06
        else:
            assert abs(est.length - np.sqrt(steps)) <= 0.25 * np.sqrt(steps)
            assert est.beta > 1.3
        assert est.tau < 0.15  # noise along the normals


@pytest.mark.parametrize("steps", [2, 8])
def test_band_read_reference_removes_the_relief(steps):
    V, F = _sphere()
    est = band_read(correlated_noise(V, F, 0.3, steps, seed=2), F, reference=V)
    assert abs(est.length - np.sqrt(steps)) <= 0.25 * np.sqrt(steps)
    assert abs(est.gamma - 0.3) <= 0.25 * 0.3
    assert est.tau < 0.1


def test_tau_tells_random_directions_from_normal_noise():
    """τ ≈ 1 for isotropic white noise, ≈ 0 along the normals (same level, same sphere)."""
    V, F = _sphere()
    rnd = band_read(add_noise(V, F, 0.3, direction="random", seed=2), F, reference=V)
    nrm = band_read(add_noise(V, F, 0.3, direction="normal", seed=2), F, reference=V)
    assert rnd.tau > 0.7 and nrm.tau < 0.1
    assert abs(nrm.beta - 1.0) < 0.08 and nrm.steps <= 1


def test_band_models_are_the_definition():
    """c_a(m) = MAD-std of B_a W^m Z, σ(W^m Z) = rms, for B_0 = I − W, B_1 = W − W²."""
    V, F = _sphere(3)
    topo = edge_topology(F, len(V))
    W = _umbrella_operator(topo)
    ok = _interior_vertices(topo, 2, W)
    C, S = band_models(W, ok)
    rng = np.random.default_rng(0)
    Z = rng.normal(size=(len(V), int(np.clip(np.ceil(20_000 / ok.sum()), 1, 8))))

    def mad(x):
        x = x.ravel()
        return 1.4826 * np.median(np.abs(x - np.median(x)))

    for i, m in enumerate(CANDIDATE_STEPS):
        Zm = Z
        for _ in range(m):
            Zm = W @ Zm
        Z1 = W @ Zm
        Z2 = W @ Z1
        assert np.isclose(C[i, 0], mad((Zm - Z1)[ok]), rtol=1e-12)
        assert np.isclose(C[i, 1], mad((Z1 - Z2)[ok]), rtol=1e-12)
        assert np.isclose(S[i], np.sqrt(np.mean(Zm[ok] ** 2)), rtol=1e-12)
    beta = (C[:, 1] / C[0, 1]) / (C[:, 0] / C[0, 0])
    assert beta[0] == 1.0 and np.all(np.diff(beta[:5]) > 0)  # β(m) rises with m


def test_white_steps_gate():
    assert cl.white_steps(0.15, 1.4, 0.1, np.sqrt(2)) == round((np.sqrt(2) * 0.15 / 0.02) ** 2)
    assert cl.white_steps(0.3, 1.4, 0.1, 2.0) == cl.MAX_STEPS
    for g, b, t in ((0.12, 1.4, 0.1), (0.15, 1.15, 0.1), (0.15, 1.4, 0.5),
                    (float("nan"), 1.4, 0.1)):
        assert cl.white_steps(g, b, t, 1.41) == 0
    org = dict(support_fraction=0.02, outside=1.0, impulsive=False)
    assert cl.band_gate(0.15, **org)
    assert not cl.band_gate(0.12, **org)
    assert not cl.band_gate(0.15, **{**org, "support_fraction": 0.3})
    assert not cl.band_gate(0.15, **{**org, "impulsive": True})
    assert not cl.band_gate(0.15, **{**org, "outside": 6.0})


def test_denoise_m2_sphere_fires_and_helps(monkeypatch):
    """m = 2 correlated noise reads ρ < 1.4 (branch 1 silent); branch 2 low-passes it."""
    V, F = _sphere(4, 1.0)
    Vn = correlated_noise(V, F, 0.5, 2, seed=1)
    r = denoise(Vn, F)
    assert r.params["noise_rho"] < cl.RHO_0
    assert r.params["corr_lowpass_steps"] > 20 and r.params["band_beta"] >= cl.BETA_0
    monkeypatch.setattr(cl, "CORR_WHITE", False)
    r0 = denoise(Vn, F)
    assert r0.params["corr_lowpass_steps"] == 0
    assert msae(r.V, V, F) < 0.9 * msae(r0.V, V, F)


@pytest.mark.parametrize("direction", ["normal", "random"])
def test_white_noise_sphere_does_not_fire(direction):
    V, F = _sphere(4, 1.0)
    r = denoise(add_noise(V, F, 0.4, direction=direction, seed=1), F)
    assert r.params["corr_lowpass_steps"] == 0


@pytest.mark.shared
def test_m2_fields_on_shared_organic_meshes(monkeypatch):
    """Check rows of the band read (docs/parameters.md, corrwhite.py): m = 2, γ = 0.4, seed 3 on
    nicolo and the pierrot truth, measured 365.5 → 262.8 and 465.9 → 372.6; the white nicolo
    γ0.2 pair reads β < β_0 and is not touched."""
    from .conftest import shared_mesh

    for name, gain in (("nicolo.ply", 0.8), ("published/nllr_pierrot__truth.ply", 0.85)):
        Vt, F = shared_mesh(name)
        Vn = correlated_noise(Vt, F, 0.4, 2, seed=3)
        r = denoise(Vn, F)
        assert r.params["corr_lowpass_steps"] > 50 and r.params["noise_rho"] < cl.RHO_0
        monkeypatch.setattr(cl, "CORR_WHITE", False)
        r0 = denoise(Vn, F)
        monkeypatch.setattr(cl, "CORR_WHITE", True)
        assert msae(r.V, Vt, F) < gain * msae(r0.V, Vt, F)
    Vn, F = shared_mesh("noisy/nicolo__gauss0.2.ply")
    r = denoise(Vn, F)
    assert r.params["corr_lowpass_steps"] == 0 and r.params["band_beta"] < cl.BETA_0
