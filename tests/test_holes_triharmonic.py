"""Triharmonic (curvature-continuous) fairing of hole patches (docs/holes.md, section 5)."""

from __future__ import annotations

import numpy as np
import pytest

from meshrepair.fill import fill_holes
from meshrepair.holes import fair_vertices
from meshrepair.holes.triharmonic import _rings, fair_triharmonic
from meshrepair.synthetic import grid_plane


def _sphere_with_cap_removed(z_cut: float, level: int = 4):
    import trimesh

    s = trimesh.creation.icosphere(level)
    V, F = np.asarray(s.vertices), np.asarray(s.faces, np.int64)
    cap = V[:, 2] > z_cut
    return V, F, cap


def _grid(n: int = 21):
    """:func:`meshrepair.synthetic.grid_plane` scaled to the square [-1, 1]²."""
    V, F = grid_plane(n)
    V[:, :2] = V[:, :2] * (2.0 / (n - 1)) - 1.0
    return V, F


def test_plane_is_reproduced():
    """Linear precision: a tilted plane is reproduced exactly from its own positions, and with
    the free vertices scrambled off the plane they come back onto it (any planar triangulation
    has zero energy for its own cotangent weights, so only the plane residual is checked)."""
    V, F = _grid()
    V[:, 2] = 0.3 * V[:, 0] - 0.2 * V[:, 1] + 0.1
    free = np.linalg.norm(V[:, :2], axis=1) < 0.45
    Vp = V.copy()
    rng = np.random.default_rng(0)
    Vp[free, 2] += rng.normal(0, 0.1, free.sum())
    same = fair_triharmonic(V, F, free, iterations=1)
    assert np.abs(same - V).max() < 1e-9
    out = fair_triharmonic(Vp, F, free, iterations=3)
    resid = out[free, 2] - (0.3 * out[free, 0] - 0.2 * out[free, 1] + 0.1)
    assert np.abs(resid).max() < 1e-3 * np.abs(Vp[free, 2] - V[free, 2]).max()
    assert np.array_equal(out[~free], Vp[~free])


def test_inputs_unchanged_and_empty_free():
    V, F = _grid(9)
    V0 = V.copy()
    out = fair_triharmonic(V, F, np.zeros(len(V), bool))
    assert np.array_equal(out, V0) and out is not V
    fair_triharmonic(V, F, np.linalg.norm(V[:, :2], axis=1) < 0.3)
    assert np.array_equal(V, V0)


def test_rings():
    V, F = _grid(9)
    seed = np.zeros(len(V), bool)
    seed[40] = True  # centre of the 9x9 grid
    d = _rings(F, seed, len(V), 2)
    assert d[40] == 0 and (d == 1).sum() == 6 and d.max() == 3


@pytest.mark.parametrize("z_cut", [0.8, 0.6])
def test_sphere_cap_closer_than_thin_plate(z_cut):
    """Free cap of a unit icosphere (level 4), the rest as data: the triharmonic fairing, which
    uses the curvature of two rings of the surround, is several times closer to the sphere than
    the thin plate (measured radial max error: cap 0.2: 0.0024 vs 0.0164; cap 0.4: 0.018 vs
    0.069)."""
    V, F, cap = _sphere_with_cap_removed(z_cut)
    Vs = V.copy()
    Vs[cap, 2] = z_cut  # flat start
    thin = fair_vertices(Vs, F, cap, order=2, iterations=3)
    tri = fair_triharmonic(thin, F, cap, iterations=3)
    e_thin = np.abs(np.linalg.norm(thin[cap], axis=1) - 1).max()
    e_tri = np.abs(np.linalg.norm(tri[cap], axis=1) - 1).max()
    assert e_tri < 0.3 * e_thin, (e_tri, e_thin)


def test_fill_keeps_triharmonic_by_seam():
    """A cap hole of a sphere: the triharmonic patch has the smoother seam and is kept (reason
    says so); ``triharmonic=False`` keeps the curvature-continuity thin plate."""
    V, F, cap = _sphere_with_cap_removed(0.7)
    keep = ~cap[F].any(axis=1)
    used = np.unique(F[keep])
    m = -np.ones(len(V), np.int64)
    m[used] = np.arange(len(used))
    Vc, Fc = V[used], m[F[keep]]
    on = fill_holes(Vc, Fc, refine=False)
    off = fill_holes(Vc, Fc, refine=False, triharmonic=False)
    assert "triharmonic" in on.holes[0].reason
    assert "triharmonic" not in off.holes[0].reason
    e_on = np.abs(np.linalg.norm(on.V[on.new_vertices], axis=1) - 1).max()
    e_off = np.abs(np.linalg.norm(off.V[off.new_vertices], axis=1) - 1).max()
    assert e_on < 0.03 and e_off < 0.03


def test_region_cut_off_from_the_surround_is_pinned():
    """Every surround vertex excluded (as crease routes cut a corner of the patch off from the
    surround): only the free vertices' Laplacians enter the energy, whose Dirichlet part does not
    see a constant ``y``; the screening term pins it and the planar patch comes back planar."""
    V, F = _grid()
    free = np.linalg.norm(V[:, :2], axis=1) < 0.45
    Vp = V.copy()
    Vp[free, 2] = np.random.default_rng(1).normal(0, 0.05, free.sum())
    out = fair_triharmonic(Vp, F, free, iterations=1, exclude_rows=~free)
    assert np.isfinite(out).all()
    assert np.abs(out[free, 2]).max() < 1e-8
