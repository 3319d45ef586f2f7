"""The length of the input low-pass (:mod:`meshrepair.denoise.presmooth`) capped at the mesh's
resolution (:mod:`meshrepair.denoise.coarse_lowpass`)."""

import numpy as np
import pytest

from meshrepair.denoise import coarse_lowpass as clp
from meshrepair.denoise.lowpass import taubin_region
from meshrepair.denoise.presmooth import MAX_STEPS
from meshrepair.denoise.scalefree import radius_in_edges


def _sphere(subdivisions):
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)


def _lattice(n):
    """Periodic regular triangular lattice n × n: vertex (i, j) at x = i + j/2; its edges."""
    idx = np.arange(n * n).reshape(n, n)
    e = []
    for di, dj in ((1, 0), (0, 1), (-1, 1)):
        e.append(np.c_[idx.ravel(), np.roll(np.roll(idx, -di, 0), -dj, 1).ravel()])
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    return np.concatenate(e).astype(np.int64), (i + 0.5 * j).ravel()


@pytest.mark.parametrize("wavelength", [4.0, 6.0, 8.0, 12.0, 24.0])
def test_lattice_eigenvalue_and_transfer_brute_force(wavelength):
    # a plane wave on the periodic lattice: one λ|μ pair of the filter the rule caps multiplies
    # it by t(x(Λ)) exactly, k pairs by t^k
    n = 48
    edges, x = _lattice(n)
    h = np.cos(2 * np.pi * x / wavelength)
    V = np.c_[h, np.zeros_like(h), np.zeros_like(h)]
    t = clp.pair_transfer(clp.lattice_eigenvalue(wavelength))
    for k in (1, 3, 7):
        out = taubin_region(V, edges, np.ones(len(h), bool), k)[:, 0]
        assert np.allclose(out, t ** k * h, atol=1e-12)


def test_cap_halves_no_wave_of_length_c_q_times_the_radius():
    for q in (6.0, 7.2, 9.0, 12.3, 14.0):
        K = clp.max_presmooth_steps(q, 10_000)
        t = clp.pair_transfer(clp.lattice_eigenvalue(clp.C_Q * q))
        assert t ** K >= 0.5 > t ** (K + 1)
    # the design numbers of the docstring: spot dec (probe q 7.1-7.4) 4-5, spot x1 (14.7) ≥ 96
    assert [clp.max_presmooth_steps(q, MAX_STEPS) for q in (7.2, 7.4)] == [4, 5]
    assert clp.max_presmooth_steps(14.7, MAX_STEPS) == MAX_STEPS
    assert clp.half_steps(clp.C_Q * 14.7) >= 96 > clp.half_steps(0.43 * 14.7)


def test_cap_edge_cases_and_switch(monkeypatch):
    assert clp.max_presmooth_steps(float("nan"), MAX_STEPS) == MAX_STEPS
    assert clp.max_presmooth_steps(0.0, MAX_STEPS) == MAX_STEPS
    assert clp.half_steps(1e6) == float("inf")  # inside Taubin's pass band: never halved
    assert clp.max_presmooth_steps(1e6, MAX_STEPS) == MAX_STEPS
    assert clp.capped_steps(0, np.zeros((3, 3)), np.zeros((1, 3), np.int64), None) == 0
    monkeypatch.setattr(clp, "COARSE_CAP", False)
    assert clp.max_presmooth_steps(3.0, MAX_STEPS) == MAX_STEPS


@pytest.mark.parametrize("scale", [1e-3, 1.0, 250.0])
def test_cap_is_scale_and_rotation_free(scale):
    V, F = _sphere(2)
    R = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    q0 = radius_in_edges(V, F)
    q1 = radius_in_edges(scale * V @ R.T + 7.0, F)
    assert q1 == pytest.approx(q0, rel=1e-9)
    assert clp.max_presmooth_steps(q1, MAX_STEPS) == clp.max_presmooth_steps(q0, MAX_STEPS)


def _bumpy_sphere(freq=8.0, amp=0.2):
    """A coarse sphere with relief at its own resolution (curvature roughness above C_0)."""
    V, F = _sphere(3)
    return V * (1 + amp * np.cos(freq * V[:, 0]) * np.cos(freq * V[:, 1])
                * np.cos(freq * V[:, 2]))[:, None], F


def _low_pass_read(monkeypatch, Vn, F):
    """(steps the presmooth rule asks, K_q, probe roughness, steps taken) of denoise on
    (Vn, F)."""
    from meshrepair import denoise
    from meshrepair.denoise.coarse import curvature_roughness

    seen = {}
    orig = clp.capped_steps

    def spy(k, V_probe, F_, edges):
        seen["k"] = k
        seen["K"] = clp.max_presmooth_steps(radius_in_edges(V_probe, F_, edges), MAX_STEPS)
        seen["c"] = curvature_roughness(V_probe, F_, edges)
        return orig(k, V_probe, F_, edges)

    monkeypatch.setattr(clp, "capped_steps", spy)
    taken = denoise(Vn, F).params["presmooth_steps"]
    monkeypatch.undo()
    return seen["k"], seen["K"], seen["c"], taken


def test_denoise_caps_the_low_pass_where_the_coarse_surface_has_relief(monkeypatch):
    # heavy noise on a coarse organic mesh: the input low-pass fires; with relief at the
    # mesh's scale (probe roughness ≥ C_0) its length is K_q, on a plain sphere (no relief) it
    # is the uncapped presmooth length, however coarse the mesh
    from meshrepair import add_noise
    from meshrepair.denoise.coarse import C_0

    V, F = _bumpy_sphere()
    k, K, c, taken = _low_pass_read(monkeypatch, add_noise(V, F, 0.6, direction="normal",
                                                           seed=1), F)
    assert c >= C_0 and k > K > 0 and taken == K, (k, K, c, taken)
    V, F = _sphere(3)
    k, K, c, taken = _low_pass_read(monkeypatch, add_noise(V, F, 0.6, direction="normal",
                                                           seed=1), F)
    assert c < C_0 and k > K and taken == k, (k, K, c, taken)


def test_run_on_the_low_passed_mesh_keeps_the_white_read(monkeypatch):
    assert clp.keep_white(16.0, capped=True) == 1.0
    assert clp.keep_white(16.0, capped=False) == 16.0
    monkeypatch.setattr(clp, "KEEP_WHITE", False)
    assert clp.keep_white(16.0, capped=True) == 16.0


def test_short_low_pass_leaves_noise_that_reads_correlated_but_is_kept_white(monkeypatch):
    # a coarse noisy sphere low-passed by 2 pairs (the cap shortened the presmooth length): the
    # run on it reads the filter's left-over as correlated (w > 1) unless the white read is kept
    from meshrepair import add_noise, denoise

    V, F = _sphere(3)
    Vn = add_noise(V, F, 0.6, direction="normal", seed=1)
    monkeypatch.setattr(clp, "capped_steps", lambda k, *a: min(k, 2))
    assert denoise(Vn, F).params["willmore_weight"] == 1.0
    monkeypatch.setattr(clp, "KEEP_WHITE", False)
    p = denoise(Vn, F).params
    assert p["presmooth_steps"] == 2
    assert p["willmore_weight"] > 1.0
