"""The discrepancy test on the outside weight (:mod:`meshrepair.denoise.discrepancy`)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshrepair import add_noise, denoise, msae
from meshrepair.denoise import discrepancy as dq
from meshrepair.mesh.geometry import mean_edge_length, vertex_normals

from .conftest import shared_mesh


def _sphere():
    s = trimesh.creation.icosphere(subdivisions=3, radius=10.0)
    return np.asarray(s.vertices, dtype=np.float64), np.asarray(s.faces, dtype=np.int64)


def test_ratio_analytic_normal_offsets():
    """V⁰ = V + d_i n_i with d = a in C and b outside: q = b² / a² exactly; a tangential
    offset does not count; the cap clips every residual at clip²."""
    V, F = _sphere()
    n = vertex_normals(V, F)
    el = mean_edge_length(V, F)
    inside = V[:, 2] > 0.0
    a, b = 0.2, 0.3
    d = np.where(inside, a, b) * el
    V0 = V + d[:, None] * n
    assert dq.discrepancy_ratio(V0, V, F, inside) == pytest.approx((b / a) ** 2, rel=1e-9)
    # mean edge lengths are those of V⁰ (a scale-free ratio: the same whatever the scale)
    assert dq.discrepancy_ratio(3 * V0, 3 * V, F, inside) == pytest.approx((b / a) ** 2, rel=1e-9)
    t = np.cross(n, [0.0, 0.0, 1.0])  # tangential direction (zero at the poles)
    V0t = V0 + 0.5 * el * t
    r = dq.normal_residuals(V0t, V, F)
    assert np.allclose(np.sqrt(r), np.where(inside, a, b) * el / mean_edge_length(V0t, F))
    el0 = mean_edge_length(V0, F)
    cap = 0.25 * el / el0  # between a and b, in V⁰'s mean edge lengths
    assert dq.discrepancy_ratio(V0, V, F, inside, clip=cap) == pytest.approx(
        cap**2 / (a * el / el0) ** 2, rel=1e-9)
    assert np.isnan(dq.discrepancy_ratio(V0, V, F, np.ones(len(V), bool)))
    assert np.isnan(dq.discrepancy_ratio(V, V, F, inside))  # zero residual in C


def test_accept_and_gate():
    assert dq.accept_weight(1.0) and dq.accept_weight(1.03) and not dq.accept_weight(1.031)
    assert dq.accept_weight(float("nan"))
    assert dq.applies(0.11, 0.156) and not dq.applies(0.206, 0.306)  # fandisk γ0.1 / twelve


@pytest.mark.shared
def test_fandisk_low_noise_weight_lowered_and_better(monkeypatch):
    """fandisk γ0.1 normal (docs/comparison.md's row, seed 1): the test rejects w_out = 6 (its
    curved blends lose signal) and the result is better than with 6 (4.09 before, measured)."""
    V, F = shared_mesh("fandisk.ply")
    Vn = add_noise(V, F, 0.1, direction="normal", seed=1)
    r = denoise(Vn, F)
    assert r.params["discrepancy_ratio"] > 1.03  # the ratio read with w_out = 6
    assert r.params["outside_weight"] == 3.0
    monkeypatch.setattr(dq, "DISCREPANCY", False)
    r6 = denoise(Vn, F)
    assert r6.params["outside_weight"] == 6.0
    assert msae(r.V, V, F) < 0.92 * msae(r6.V, V, F)
