"""Local surface fitted to a hole's surround and the fairing relative to it (docs/holes.md,
section 5, "Fitted surround")."""

from __future__ import annotations

import numpy as np
import pytest

from meshrepair.holes.fitted import (
    _rings_from,
    fair_on_fit,
    fit_hole,
    fit_surround,
    hole_rings,
)
from meshrepair.synthetic import grid_plane


def _grid(n: int = 41, half: float = 1.0):
    """:func:`meshrepair.synthetic.grid_plane` scaled to the square [-half, half]²."""
    V, F = grid_plane(n)
    V[:, :2] = V[:, :2] * (2.0 * half / (n - 1)) - half
    return V, F


def _cubic(x, y):
    return 0.3 * x**2 - 0.2 * y**2 + 0.15 * x * y + 0.05 * x**3 - 0.04 * x * y**2 + 0.1 * x


def _height_mesh(height, n: int = 41, hole: float = 0.3):
    """A grid lifted to ``z = height(x, y)`` with a disc of radius ``hole`` cut out: the mesh
    without the disc's vertices, the loop, and the original (full) vertex array."""
    V, F = _grid(n)
    V[:, 2] = height(V[:, 0], V[:, 1])
    inside = np.linalg.norm(V[:, :2], axis=1) < hole
    keepf = ~inside[F].any(axis=1)
    return V, F, inside, keepf


def _ring_data(V, F, keepf, inside):
    """Original vertices near the hole: their ring distance from the loop and normals."""
    from meshrepair.holes.fairing import _vertex_normals
    from meshrepair.mesh.topology import boundary_loops

    Fk = F[keepf]
    loops = boundary_loops(Fk, len(V))
    loop = max(loops, key=lambda lp: -np.linalg.norm(V[lp, :2], axis=1).mean())
    d = _rings_from(Fk, loop, len(V), 12)
    near = np.flatnonzero((d <= 12) & ~inside)
    N = _vertex_normals(V, Fk, len(V))[near]
    return near, d, N, loop


def _scattered(height, R0: float = 1.0, n_loop: int = 64, n_data: int = 1500, seed: int = 0,
               aspect: float = 1.0):
    """A loop of ``n_loop`` points evenly on the circle of radius ``R0`` at height
    ``height(x, y)``, and scattered data over the annulus ``R0 .. 2.5 R0`` (ring = distance
    beyond the circle in steps of ``l̄ = 2π R0 / n_loop``), with the normals of the graph;
    ``aspect``: the loop is an ellipse of semi-axes ``R0 aspect``, ``R0 / aspect`` instead."""
    t = 2 * np.pi * (np.arange(n_loop) + 0.3) / n_loop  # none on a sector boundary
    lx, ly = R0 * aspect * np.cos(t), R0 / aspect * np.sin(t)
    loop = np.c_[lx, ly, height(lx, ly)]
    rng = np.random.default_rng(seed)
    rad = R0 * (1 + 1.5 * rng.random(n_data))
    ang = 2 * np.pi * rng.random(n_data)
    x, y = rad * np.cos(ang), rad * np.sin(ang)
    X = np.r_[loop, np.c_[x, y, height(x, y)]]
    le = 2 * np.pi * R0 / n_loop
    ring = np.r_[np.zeros(n_loop, np.int64), np.floor((rad - R0) / le).astype(np.int64) + 1]
    eps = 1e-6
    gx = (height(X[:, 0] + eps, X[:, 1]) - height(X[:, 0] - eps, X[:, 1])) / (2 * eps)
    gy = (height(X[:, 0], X[:, 1] + eps) - height(X[:, 0], X[:, 1] - eps)) / (2 * eps)
    N = np.c_[-gx, -gy, np.ones(len(X))]
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    return X, ring, N, loop, le


SURFACES = {
    "saddle": lambda x, y: 0.3 * (x**2 - y**2) + 0.2 * x * y,
    "bowl": lambda x, y: 0.25 * (x**2 + y**2 - 1.0),
    "cubic": lambda x, y: 0.2 * (x**2 + y**2 - 1.0) * (1.0 + 0.3 * x - 0.2 * y),
}


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_fit_reproduces_polynomial_height_field(name):
    """A surround that is a polynomial height field of degree <= 3 over the loop's plane is
    reproduced exactly, also inside the loop where there is no data."""
    h = SURFACES[name]
    X, ring, N, loop, le = _scattered(h)
    fit = fit_surround(X, ring, N, loop, le)
    assert fit is not None and fit.degree >= 2
    assert fit.cv < 1e-10 < 1e-3 < fit.cv_plane
    rng = np.random.default_rng(1)
    r, a = np.sqrt(rng.random(200)), 2 * np.pi * rng.random(200)
    P = np.c_[r * np.cos(a), r * np.sin(a), np.zeros(200)]
    P[:, 2] = h(P[:, 0], P[:, 1])
    assert np.abs(fit.flatten(P)[:, 2] - fit.origin[2]).max() < 1e-9
    assert np.abs(fit.unflatten(fit.flatten(X)) - X).max() < 1e-12


def test_fit_invariant_to_rotation_translation_scale():
    X, ring, N, loop, le = _scattered(lambda x, y: _cubic(x, y) - _cubic(0.0, 0.0), seed=2,
                                      aspect=1.3)
    fit = fit_surround(X, ring, N, loop, le)
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    if np.linalg.det(Q) < 0:
        Q[:, 0] = -Q[:, 0]
    s, t = 7.3, np.array([10.0, -4.0, 2.5])

    def tf(Y):
        return s * Y @ Q.T + t

    fit2 = fit_surround(tf(X), ring, N @ Q.T, tf(loop), s * le)
    assert (fit2.degree, fit2.rings) == (fit.degree, fit.rings)
    assert fit2.cv == pytest.approx(fit.cv, rel=1e-6)
    P = X[:50] * [0.5, 0.5, 1.0]  # points inside the loop, off the surface
    assert np.abs(tf(fit.flatten(P)) - fit2.flatten(tf(P))).max() < 1e-9 * s


def test_plane_is_not_fitted():
    """On a plane the fit adds nothing: ``fit_hole`` returns None."""
    V, F, inside, keepf = _height_mesh(lambda x, y: 0.2 * x - 0.1 * y)
    Fk = F[keepf]
    from meshrepair.mesh.topology import boundary_loops

    loop = max(boundary_loops(Fk, len(V)), key=lambda lp: -np.linalg.norm(V[lp, :2], axis=1
                                                                          ).mean())
    d, le, _ = hole_rings(Fk, loop, len(V), V)
    assert fit_hole(V, Fk, d, le, len(V)) is None


def test_fair_on_fit_reproduces_the_surface():
    """The patch faired relative to the fit of a quadric surround lies on the quadric (the
    flattened surround is a plane, which the thin plate reproduces), while the plain thin plate
    does not."""
    def h(x, y):
        return 0.6 * x**2 - 0.5 * y**2 + 0.3 * x * y

    V, F, inside, keepf = _height_mesh(h, hole=0.35)
    near, d, N, loop = _ring_data(V, F, keepf, inside)
    le = float(np.linalg.norm(V[loop] - V[np.roll(loop, -1)], axis=1).mean())
    fit = fit_surround(V[near], d[near], N, V[loop], le)
    free = np.flatnonzero(inside)
    start = V.copy()
    start[free, 2] = 0.0  # a flat membrane start
    out = fair_on_fit(start, F, free, fit, order=2, weights="cotan", iterations=3)
    err = np.abs(out[free, 2] - h(out[free, 0], out[free, 1])).max()
    assert err < 1e-6
    plain = fair_on_fit(start, F, free, None, order=2, weights="cotan", iterations=3)
    err_plain = np.abs(plain[free, 2] - h(plain[free, 0], plain[free, 1])).max()
    assert err_plain > 100 * err
    assert np.array_equal(out[~inside], start[~inside])


def test_sphere_hole_keeps_the_curvature_fairing():
    """On a sphere the curvature-continuous fairing is already exact up to discretisation; the
    probe keeps it (no fitted surface), and the cap is refilled within 0.001 radii."""
    import trimesh

    from meshrepair.fill import fill_holes

    s = trimesh.creation.icosphere(4)
    V, F = np.asarray(s.vertices), np.asarray(s.faces, np.int64)
    keepf = ~(V[F][:, :, 2] > 0.8).all(axis=1)
    used = np.unique(F[keepf])
    m = -np.ones(len(V), np.int64)
    m[used] = np.arange(len(used))
    res = fill_holes(V[used], m[F[keepf]], fitted=True)
    assert "fitted" not in res.holes[0].reason
    r = np.linalg.norm(res.V[len(used):], axis=1)
    assert np.abs(r - 1).max() < 0.0015
