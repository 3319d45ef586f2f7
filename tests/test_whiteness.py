"""The white-noise test of a residual (:mod:`meshrepair.denoise.whiteness`) and the plan that
runs the white-noise model first when the reading finds correlated noise."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import trimesh

import meshrepair as mr
from meshrepair.baselines import taubin_smooth
from meshrepair.denoise.scale import correlated_noise
from meshrepair.denoise.whiteness import RHO1_MAX, white_residual
from meshrepair.mesh.topology import edge_topology
from meshrepair.model.noise import noise_statistics

from .bundled import bundled_mesh


def _sphere(subdivisions: int = 4, r: float = 15.0):
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(m.vertices, np.float64) * r, np.asarray(m.faces, np.int64)


def _test(Y, X, F):
    topo = edge_topology(F, len(Y))
    return white_residual(Y, X, F, topo.edges, noise_statistics(Y, F, topo)[0])


def test_constant_residual_is_fully_correlated():
    """A residual equal on every vertex of a closed mesh is its own one-ring average: ρ₁ = 1."""
    V, F = _sphere(3)
    from meshrepair.mesh.geometry import vertex_normals

    X = V - 0.05 * vertex_normals(V, F)  # the sphere shrunk: r_i the same everywhere
    t = _test(V, X, F)
    assert t.rho1 == pytest.approx(1.0, abs=1e-3)
    assert not t.white


@pytest.mark.parametrize("seed", [1, 2])
def test_white_noise_passes_correlated_noise_fails(seed):
    """The white model (Willmore weight 1) removes white noise and leaves it as the residual:
    uncorrelated with its neighbours (ρ₁ ≤ 0: a high-pass of white noise) at a level below γ̂.
    On noise correlated over ≈ 1.7 rings (m = 3) it removes the noise's shorter waves, which
    correlate with their neighbours (measured ρ₁ 0.18 at the organic law's weight)."""
    V, F = _sphere(4)
    Yw = mr.add_noise(V, F, 0.1, direction="normal", seed=seed)
    tw = _test(Yw, mr.denoise(Yw, F, willmore_weight=1.0).V, F)
    assert tw.rho1 < 0.0 and tw.level_ratio < 0.95 and tw.white
    Yc = correlated_noise(V, F, 0.4, 3, seed=seed)
    tc = _test(Yc, mr.denoise(Yc, F, willmore_weight=1.0).V, F)
    assert tc.rho1 > 1.5 * RHO1_MAX and not tc.white


def test_level_above_the_white_level_fails():
    """A result that removes more than the white noise the one-ring level sees (here: the
    input moved by a smooth bump ten times the noise level) fails on its level alone."""
    V, F = _sphere(4)
    Y = mr.add_noise(V, F, 0.05, direction="normal", seed=4)
    from meshrepair.mesh.geometry import vertex_normals

    z = V[:, 2] / 15.0
    X = Y - (0.5 * np.sin(3 * z))[:, None] * vertex_normals(Y, F)  # a long wave taken away
    t = _test(Y, X, F)
    assert t.level_ratio > 1.0 and not t.white


def test_invariant_to_rotation_scale_and_order():
    V, F = _sphere(3)
    Y = correlated_noise(V, F, 0.2, 2, seed=5)
    X = taubin_smooth(Y, F, iterations=2)
    t0 = _test(Y, X, F)
    Q, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))
    t1 = _test(3.7 * Y @ Q.T + 1.0, 3.7 * X @ Q.T + 1.0, F)
    p = np.random.default_rng(1).permutation(len(V))
    inv = np.argsort(p)
    t2 = _test(Y[p], X[p], inv[F])
    for t in (t1, t2):
        assert t.rho1 == pytest.approx(t0.rho1, rel=1e-9)
        assert t.level_ratio == pytest.approx(t0.level_ratio, rel=1e-9)


def test_white_noise_read_as_correlated_keeps_the_white_model():
    """Low white noise on a finely curved mesh reads correlated (the probe removes relief at
    two rings); the plan runs the white model first, its residual passes, and its result is
    closer to the truth than the correlated model's."""
    V, F = bundled_mesh("trim_star.ply")
    Y = mr.add_noise(V, F, 0.1, direction="normal", seed=1)
    p = mr.plan_denoise(Y, F)
    assert p.if_correlated is not None and p.willmore_weight == 1.0
    assert p.if_correlated.willmore_weight > 1.0
    assert "white-noise test" in str(p)
    r = mr.denoise(Y, F, plan=p)
    assert r.params["noise_model"] == "white"
    assert r.params["main_solves"] == 1  # the white model's solve only
    assert any(d.name == "noise_model" for d in r.plan.after_solve)
    rc = mr.denoise(Y, F, plan=p.if_correlated)
    assert mr.msae(r.V, V, F) < 0.8 * mr.msae(rc.V, V, F)


def test_correlated_noise_runs_the_correlated_model(monkeypatch):
    from meshrepair.denoise import discrepancy as dq

    V, F = bundled_mesh("fandisk.ply")
    Y = correlated_noise(V, F, 0.4, 3, seed=7)
    p = mr.plan_denoise(Y, F)
    assert p.if_correlated is not None
    r = mr.denoise(Y, F, plan=p)
    assert r.params["noise_model"] == "correlated"
    # the white model's solve and the correlated model's; the discrepancy principle is read on
    # the white model's solve (ratio 0.949: accepted), so the correlated model keeps w_out = 6
    assert r.params["main_solves"] == 2
    assert r.params["discrepancy_ratio"] == pytest.approx(0.949, abs=0.01)
    assert r.params["outside_weight"] == p.if_correlated.outside_weight == 6.0
    monkeypatch.setattr(dq, "FALLBACK_WEIGHTS", ())  # the correlated plan alone at w_out = 6
    rc = mr.denoise(Y, F, plan=p.if_correlated)
    np.testing.assert_array_equal(r.V, rc.V)
    monkeypatch.undo()
    rw = mr.denoise(Y, F, plan=replace(p, if_correlated=None))  # the white model alone
    assert mr.msae(r.V, V, F) < mr.msae(rw.V, V, F)


@pytest.mark.parametrize("white", [True, False])
def test_a_failed_discrepancy_test_costs_one_solve(monkeypatch, white):
    """When the discrepancy test on the white model's solve fails, the lowered outside weight is
    solved once: by the white model again (white residual) or by the correlated model (not
    white); never a third solve."""
    from meshrepair.denoise import discrepancy as dq
    from meshrepair.denoise import whiteness

    V, F = bundled_mesh("fandisk.ply")
    Y = correlated_noise(V, F, 0.4, 3, seed=7)
    p = mr.plan_denoise(Y, F)
    monkeypatch.setattr(dq, "accept_weight", lambda q, tol=dq.DISCREPANCY_TOL: False)
    if white:
        real = whiteness.white_residual
        monkeypatch.setattr(whiteness, "white_residual",
                            lambda *a, **k: replace(real(*a, **k), white=True))
    r = mr.denoise(Y, F, plan=p)
    assert r.params["main_solves"] == 2
    assert r.params["outside_weight"] == dq.FALLBACK_WEIGHTS[0]
    assert r.params["noise_model"] == ("white" if white else "correlated")
    assert r.plan.willmore_weight == (p.willmore_weight if white
                                      else p.if_correlated.willmore_weight)
