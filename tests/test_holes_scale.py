"""Hole filling commutes with a uniform scale and a translation of the input: the planar
triangulation is made in units of the polygon's own radius (meshrepair.holes._geom2d)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshrepair.fill import fill_holes
from meshrepair.holes._geom2d import _triangulate


def _polygon(n=40, seed=0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 1 + 0.2 * np.random.default_rng(seed).random(n)
    Q = np.c_[r * np.cos(t), r * np.sin(t)]
    segs = np.c_[np.arange(n), (np.arange(n) + 1) % n]
    return Q, segs


@pytest.mark.parametrize("k, shift", [(1.1, 0.0), (7.3, 3.0), (1e-3, -0.5), (1e4, 100.0)])
def test_triangulation_of_a_scaled_polygon_is_the_scaled_triangulation(k, shift):
    Q, segs = _polygon()
    X, T = _triangulate(Q, segs, 0.01)
    Xk, Tk = _triangulate(Q * k + shift, segs, 0.01 * k * k)
    assert np.array_equal(T, Tk)
    np.testing.assert_allclose((Xk - shift) / k, X, rtol=0, atol=1e-11)
    assert np.array_equal(Xk[: len(Q)], Q * k + shift)  # the polygon's vertices exactly


@pytest.mark.parametrize("k", [1.1, 7.3, 0.5, 3.0])
def test_fill_commutes_with_scale(k):
    """Scales within three orders of magnitude; at 1e-3 and 1e3 this patch still comes out
    differently (a threshold of the enclosing outside the planar triangulation, not yet found)."""
    s = trimesh.creation.icosphere(3)
    V, F = np.asarray(s.vertices), np.asarray(s.faces)
    keep = V[F].mean(axis=1)[:, 2] < 0.75
    a = fill_holes(V, F[keep], refine=False)
    b = fill_holes(V * k, F[keep], refine=False)
    assert np.array_equal(a.F, b.F)
    np.testing.assert_allclose(b.V / k, a.V, rtol=0, atol=1e-10)
