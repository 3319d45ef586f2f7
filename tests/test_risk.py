"""Stein's unbiased risk of a Taubin low-pass (:mod:`meshrepair.denoise.risk`): the noise
level it reads, the risk against the true error and against brute force, its ranking of two
lengths and its invariance."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshrepair.denoise import risk as rk
from meshrepair.denoise.presmooth import presmooth
from meshrepair.mesh.geometry import vertex_normals
from meshrepair.mesh.topology import edge_topology


def _sphere(sub: int = 4, bumps: float = 0.0, freq: float = 12.0):
    s = trimesh.creation.icosphere(subdivisions=sub)
    V, F = np.asarray(s.vertices, np.float64), np.asarray(s.faces, np.int64)
    if bumps:
        V = V * (1 + bumps * np.prod(np.sin(freq * V), axis=1))[:, None]
    E = edge_topology(F, len(V)).edges
    ell = float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())
    return V, F, E, ell


def _noisy(V, F, sigma, seed=1):
    n = vertex_normals(V, F)
    return V + np.random.default_rng(seed).normal(0, sigma, len(V))[:, None] * n


def test_probe_trace_matches_the_exact_trace():
    """Hutchinson's ``(1/3) Σ_c z_cᵀ T^k z_c`` against ``tr T^k`` from the identity's columns,
    within three of its standard deviations ``√(2 Σ_{i≠j} S_ij² / 3)`` (a Rademacher probe)."""
    V, F, E, _ = _sphere(sub=3)
    n, free = len(V), np.ones(len(V), bool)
    Z = rk._probe(V, E)
    for k in (1, 5, 20):
        S = presmooth(np.eye(n), E, free, k)
        exact = float(np.trace(S))
        sd = float(np.sqrt(2.0 * ((S - np.diag(np.diag(S))) ** 2).sum() / 3.0))
        est = float((Z * presmooth(Z, E, free, k)).sum()) / 3.0
        assert abs(est - exact) < 3.0 * sd and sd < 0.1 * exact


def test_normal_level_reads_white_normal_noise():
    """σ̂ of one λ|μ pair is within 3 % of a known white normal noise (0.1-0.4 ℓ̄)."""
    V, F, E, ell = _sphere()
    for g in (0.1, 0.25, 0.4):
        s = rk.normal_level(_noisy(V, F, g * ell), F, E)
        assert s == pytest.approx(g * ell, rel=0.03)


def test_risk_estimates_the_normal_error_up_to_its_constant():
    """``R(k) − nσ²`` against the true ``‖P(T^k y − x)‖²`` (Stein: unbiased; one draw of the
    noise on 2,562 vertices agrees within 3 % of ``nσ²``, the spread of one draw, plus three
    standard deviations ``2σ² √(2 Σ_{i≠j} S_ij² / 3)`` of the probe's trace), and the
    differences of two lengths agree in sign."""
    V, F, E, ell = _sphere(bumps=0.02)
    sigma = 0.3 * ell
    Y = _noisy(V, F, sigma, seed=3)
    free = np.ones(len(V), bool)
    true, est = {}, {}
    for k in (3, 30):
        X = presmooth(Y, E, free, k)
        e = np.einsum("ij,ij->i", X - V, vertex_normals(X, F))
        true[k] = float(e @ e)
        est[k] = rk.normal_risk(Y, X, F, E, k, sigma) - len(V) * sigma ** 2
        S = presmooth(np.eye(len(V)), E, free, k)
        sd = 2 * sigma ** 2 * np.sqrt(2.0 * ((S - np.diag(np.diag(S))) ** 2).sum() / 3.0)
        assert abs(est[k] - true[k]) < 0.03 * len(V) * sigma ** 2 + 3.0 * sd
    assert np.sign(est[30] - est[3]) == np.sign(true[30] - true[3])


def test_risk_curve_is_the_risk_of_each_length():
    """``risk_curve`` against ``normal_risk`` of each ``T^k y`` filtered from ``y`` (brute
    force), and the analytic ``k = 0`` value: no residual and ``tr I = n`` exactly (a
    Rademacher probe has ``z_i² = 1``), so ``R(0) = 2nσ²``."""
    V, F, E, ell = _sphere(sub=3, bumps=0.02)
    Y = _noisy(V, F, 0.2 * ell, seed=5)
    s = rk.normal_level(Y, F, E)
    free = np.ones(len(V), bool)
    curve = rk.risk_curve(Y, F, E, 12)
    brute = [rk.normal_risk(Y, presmooth(Y, E, free, k), F, E, k, s) for k in range(13)]
    assert curve == pytest.approx(brute, rel=1e-9)
    assert curve[0] == pytest.approx(2 * len(V) * s * s, rel=1e-12)
    assert rk.risk_curve(Y, F, E, 3, sigma=2 * s)[0] == pytest.approx(8 * len(V) * s * s)


def _graph_laplacian(E, n):
    L = np.zeros((n, n))
    np.add.at(L, (E[:, 0], E[:, 1]), -1.0)
    np.add.at(L, (E[:, 1], E[:, 0]), -1.0)
    L[np.arange(n), np.arange(n)] = -L.sum(axis=1)
    return L


def test_risk_of_the_normals_against_brute_force():
    """``risk_curve(normals=True)`` against dense matrices: ``Σ_E (r_i − r_j)²`` of each
    ``T^k y`` filtered from ``y`` plus ``2σ²/3 Σ_c (L z_c)ᵀ T^k z_c`` with the dense graph
    Laplacian and ``T^k`` from the identity's columns; ``R_∇(0) = 2σ² tr L`` exactly (a
    Rademacher probe: ``(Lz)ᵀz`` sums the degrees), ``tr L = 2 n_E``."""
    V, F, E, ell = _sphere(sub=2, bumps=0.02)
    Y = _noisy(V, F, 0.2 * ell, seed=5)
    n, s = len(V), rk.normal_level(Y, F, E)
    free = np.ones(n, bool)
    L, Z = _graph_laplacian(E, n), rk._probe(Y, E)
    curve = rk.risk_curve(Y, F, E, 8, normals=True)
    for k in range(9):
        X = presmooth(Y, E, free, k)
        r = np.einsum("ij,ij->i", Y - X, vertex_normals(X, F))
        Tk = presmooth(np.eye(n), E, free, k)
        brute = float(((r[E[:, 0]] - r[E[:, 1]]) ** 2).sum()) + 2 * s * s * float(
            ((L @ Z) * (Tk @ Z)).sum()) / 3.0
        assert curve[k] == pytest.approx(brute, rel=1e-9)
    dz = Z[E[:, 0]] - Z[E[:, 1]]
    assert curve[0] == pytest.approx(2 * s * s * float((dz * dz).sum()) / 3.0, rel=1e-12)


def test_risk_of_the_normals_estimates_the_gradient_error():
    """``R_∇(k) − σ² tr L`` against the true ``‖G P(T^k y − x)‖²`` (G the edge differences):
    unbiased, one draw within 5 % of ``σ² tr L``; and on a smooth sphere its least length is
    the least true error's within a few pairs, where the positions' risk stops much shorter."""
    V, F, E, ell = _sphere(sub=4)
    sigma = 0.1 * ell
    Y = _noisy(V, F, sigma, seed=3)
    free = np.ones(len(V), bool)
    curve = rk.risk_curve(Y, F, E, 40, sigma=sigma, normals=True)
    pos = rk.risk_curve(Y, F, E, 40, sigma=sigma)
    true = []
    X = Y
    for k in range(41):
        if k:
            X = presmooth(X, E, free, 1)
        e = np.einsum("ij,ij->i", X - V, vertex_normals(X, F))
        true.append(float(((e[E[:, 0]] - e[E[:, 1]]) ** 2).sum()))
    c = sigma ** 2 * 2 * len(E)
    for k in (2, 10, 40):
        assert abs(curve[k] - c - true[k]) < 0.05 * c
    k_true, k_grad = int(np.argmin(true)), int(np.argmin(curve))
    assert abs(k_grad - k_true) <= 3
    assert int(np.argmin(pos)) < k_true - 5


def _risk_difference(Y, F, E, k_short, k_long):
    """``(R(k') − R(k)) / (n ℓ̄²)`` at the level read from ``Y`` (edge units)."""
    free = np.ones(len(Y), bool)
    s = rk.normal_level(Y, F, E)
    ell = float(np.linalg.norm(Y[E[:, 0]] - Y[E[:, 1]], axis=1).mean())
    r = [rk.normal_risk(Y, presmooth(Y, E, free, k), F, E, k, s) for k in (k_short, k_long)]
    return (r[0] - r[1]) / (len(Y) * ell * ell)


def test_risk_ranks_two_lengths_as_the_truth_does():
    """A smooth sphere under heavy noise wants the long filter; a sphere with relief at the
    mesh's scale under light noise the short one: the risk, read with the level estimated
    from the input, ranks the two lengths as the true normal error does."""
    for bumps, g, want_short in ((0.0, 0.35, False), (0.03, 0.05, True)):
        V, F, E, ell = _sphere(bumps=bumps)
        free = np.ones(len(V), bool)
        Y = _noisy(V, F, g * ell, seed=2)
        err = [float(np.sum(np.einsum("ij,ij->i", X - V, vertex_normals(X, F)) ** 2))
               for X in (presmooth(Y, E, free, 2), presmooth(Y, E, free, 40))]
        assert (err[0] < err[1]) == want_short
        assert (_risk_difference(Y, F, E, 2, 40) <= 0) == want_short


def test_risk_is_invariant_to_similarity():
    """The risk difference in edge units does not move under scale, rotation and
    translation."""
    V, F, E, ell = _sphere(bumps=0.02)
    Y = _noisy(V, F, 0.25 * ell, seed=4)
    Q, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))
    Yt = 7.5 * Y @ Q.T + np.array([3.0, -2.0, 1.0])
    d0, d1 = (_risk_difference(Z, F, E, 4, 25) for Z in (Y, Yt))
    assert d1 == pytest.approx(d0, rel=1e-6, abs=1e-12)
