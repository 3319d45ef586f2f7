"""Holes in cylinders and tori are refilled by the cylinder / torus (issue 13), and the bounded
cotangents of the fairing of Liepa patches (``holes.fairing.LIEPA_COT_RANGE``)."""

from __future__ import annotations

import numpy as np
import pytest

from meshrepair.fill import fill_holes
from meshrepair.holes import find_holes
from meshrepair.holes._geom2d import _cotan_weights_2d


def _staggered(nu: int, nv: int, wrap_v: bool):
    """Faces of an ``nu x nv`` vertex grid, periodic in u (and in v with ``wrap_v``), rows of
    triangles alternating diagonals (nearly equilateral when odd rows are shifted half a step)."""
    nvv = nv if wrap_v else nv - 1
    F = []
    for i in range(nu):
        for j in range(nvv):
            a, b = (i % nu) * nv + j, ((i + 1) % nu) * nv + j
            c, d = ((i + 1) % nu) * nv + (j + 1) % nv, (i % nu) * nv + (j + 1) % nv
            F += [[a, b, d], [b, c, d]] if j % 2 == 0 else [[a, b, c], [a, c, d]]
    return np.asarray(F, np.int64)


def _cylinder(R=1.0, H=4.0, nt=96):
    nz = int(H / (2 * np.pi * R / nt))
    t = np.linspace(0, 2 * np.pi, nt, endpoint=False)
    T, Z = np.meshgrid(t, np.linspace(-H / 2, H / 2, nz + 1), indexing="ij")
    T = T + (np.arange(nz + 1)[None, :] % 2) * (np.pi / nt)
    V = np.c_[R * np.cos(T.ravel()), R * np.sin(T.ravel()), Z.ravel()]
    return V, _staggered(nt, nz + 1, wrap_v=False)


def _torus(R=2.0, r=0.7, nu=128, nv=48):
    u = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    U, W = np.meshgrid(u, np.linspace(0, 2 * np.pi, nv, endpoint=False), indexing="ij")
    U = U + (np.arange(nv)[None, :] % 2) * (np.pi / nu)
    V = np.c_[(R + r * np.cos(W.ravel())) * np.cos(U.ravel()),
              (R + r * np.cos(W.ravel())) * np.sin(U.ravel()), r * np.sin(W.ravel())]
    return V, _staggered(nu, nv, wrap_v=True)


def _cut_ball(V, F, c, rad):
    rm = (np.linalg.norm(V[F] - np.asarray(c), axis=2) < rad).any(axis=1)
    used = np.unique(F[~rm])
    m = -np.ones(len(V), np.int64)
    m[used] = np.arange(len(used))
    return V[used], m[F[~rm]]


def _hole_near(V, F, c):
    return [h.index for h in find_holes(V, F)
            if np.linalg.norm(V[h.vertices].mean(axis=0) - np.asarray(c)) < 0.5]


@pytest.mark.parametrize("rad", [0.25, 0.4, 0.6])
def test_cylinder_hole_refilled_by_the_cylinder(rad):
    """Unit cylinder (edges 0.07), holes of radius 3.5, 5.7 and 8.5 edge lengths: every new
    vertex within 0.002 of the cylinder (measured 0.0004 / 0.0005 / 0.0011; the plain thin
    plate without the solve: 0.0004 / 0.0008 / 0.0029)."""
    V, F = _cylinder()
    Vc, Fc = _cut_ball(V, F, (1.0, 0.0, 0.0), rad)
    res = fill_holes(Vc, Fc, holes=_hole_near(Vc, Fc, (1.0, 0.0, 0.0)))
    assert res.n_filled == 1
    err = np.abs(np.linalg.norm(res.V[res.new_vertices][:, :2], axis=1) - 1.0)
    assert err.max() < 0.002, err.max()


def test_cylinder_hole_liepa_patch_on_the_cylinder(monkeypatch):
    """The same hole (radius 0.6) enclosed by Liepa's triangulation, whose thin plate uses the
    bounded cotangents: still on the cylinder within 0.002 (measured 0.0004; exact cotangents
    0.0005)."""
    import meshrepair.fill.options as mf

    monkeypatch.setattr(mf, "ENCLOSE_ORDER", ("liepa",))
    V, F = _cylinder()
    Vc, Fc = _cut_ball(V, F, (1.0, 0.0, 0.0), 0.6)
    sel = _hole_near(Vc, Fc, (1.0, 0.0, 0.0))
    res = fill_holes(Vc, Fc, holes=sel)
    rep = [h for h in res.holes if h.index == sel[0]][0]
    assert res.n_filled == 1 and rep.reason.startswith("liepa"), rep.reason
    err = np.abs(np.linalg.norm(res.V[res.new_vertices][:, :2], axis=1) - 1.0)
    assert err.max() < 0.002, err.max()


@pytest.mark.parametrize("where", [(2.7, 0.0, 0.0), (1.3, 0.0, 0.0), (2.0, 0.0, 0.7)])
@pytest.mark.parametrize("rad", [0.25, 0.4])
def test_torus_hole_refilled_by_the_torus(where, rad):
    """Torus R = 2, r = 0.7 (edges about 0.09): holes on the outer equator (positive Gaussian
    curvature), the inner one (negative) and the top circle (zero), radius 0.25 and 0.4: every
    new vertex within 0.006 (0.9 % of the tube radius) of the torus (measured at most 0.0038)."""
    V, F = _torus()
    Vc, Fc = _cut_ball(V, F, where, rad)
    res = fill_holes(Vc, Fc)
    assert res.n_filled == 1
    X = res.V[res.new_vertices]
    err = np.abs(np.hypot(np.linalg.norm(X[:, :2], axis=1) - 2.0, X[:, 2]) - 0.7)
    assert err.max() < 0.006, err.max()


def test_cotan_weights_clipped():
    """Cotangent clipping: exact weights where every angle's cotangent is inside the range; an
    obtuse angle (negative cotangent) and a tiny one (huge cotangent) get the bounds."""
    # equilateral: cot 60° = 0.577 inside [0.3, 3]
    X = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, np.sqrt(3) / 2]])
    T = np.array([[0, 1, 2]])
    W = _cotan_weights_2d(X, T, 3).toarray()
    Wc = _cotan_weights_2d(X, T, 3, (0.3, 3.0)).toarray()
    assert np.allclose(W, Wc) and np.isclose(W[0, 1], 0.5 / np.sqrt(3))
    # angles 120° at vertex 2 (cot -0.577), 30° at 0 and 1 (cot 1.732)
    X = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.5 / np.sqrt(3)]])
    W = _cotan_weights_2d(X, T, 3).toarray()
    Wc = _cotan_weights_2d(X, T, 3, (0.3, 3.0)).toarray()
    assert np.isclose(W[0, 1], -0.5 / np.sqrt(3)) and np.isclose(Wc[0, 1], 0.5 * 0.3)
    assert np.isclose(Wc[1, 2], 0.5 * np.sqrt(3)) and np.isclose(Wc[0, 2], 0.5 * np.sqrt(3))
    # a sliver: angle of 5° (cot 11.4) clipped to 3
    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, np.tan(np.radians(5.0))]])
    Wc = _cotan_weights_2d(X, T, 3, (0.3, 3.0)).toarray()
    assert np.isclose(Wc[1, 2], 0.5 * 3.0)
    assert np.allclose(Wc, Wc.T)


def test_fair_vertices_clipping_only_in_marked_faces():
    """``cot_faces``: clipping no face is the exact thin plate; clipping every face is the same
    as ``cot_faces=None``; on an irregular surround the clipped fairing differs."""
    from meshrepair.holes import fair_vertices

    V, F = _torus(nu=48, nv=20)
    rng = np.random.default_rng(3)
    V = V + 0.02 * rng.standard_normal(V.shape)  # irregular angles
    free = np.flatnonzero(np.linalg.norm(V - np.array([2.7, 0.0, 0.0]), axis=1) < 0.5)
    Vs = V.copy()
    Vs[free] += 0.1  # a start off the surface
    exact = fair_vertices(Vs, F, free, iterations=2)
    none = fair_vertices(Vs, F, free, iterations=2, cot_range=(0.3, 3.0),
                         cot_faces=np.zeros(len(F), bool))
    every = fair_vertices(Vs, F, free, iterations=2, cot_range=(0.3, 3.0),
                          cot_faces=np.ones(len(F), bool))
    default = fair_vertices(Vs, F, free, iterations=2, cot_range=(0.3, 3.0))
    assert np.allclose(exact, none) and np.allclose(every, default)
    assert np.abs(every - exact).max() > 1e-4
