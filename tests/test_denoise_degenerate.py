"""Tiny closed meshes (issue 11): the unfold step used to shrink a regular tetrahedron to
~1e-24 (every face looks "flipped" against its neighbours at a 109° crease) and return it as if
fine; the robust stage flattened noisy tetrahedra. Now the result never collapses: it is
sensible, solved again without the robust stage, or refused with a clear message."""

from __future__ import annotations

import logging

import numpy as np
import pytest
import trimesh

import meshrepair as mr
from meshrepair.mesh.topology import edge_topology
from meshrepair.model.relax import locally_flipped_faces, untangle

TET_V = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1.0]])
TET_F = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])


def _volume(V, F):
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6)


def test_untangle_leaves_a_tetrahedron_alone():
    topo = edge_topology(TET_F, 4)
    assert locally_flipped_faces(TET_V, topo).all()  # convex 109° creases, not fold-overs
    V, left = untangle(TET_V, topo)
    assert left == 4 and np.array_equal(V, TET_V)


def test_regular_tetrahedron_comes_back_unchanged():
    r = mr.denoise(TET_V, TET_F)
    assert np.allclose(r.V, TET_V, atol=1e-9), r.V  # was shrunk to ~1e-24
    assert r.n_unfolded == 4


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_noisy_tetrahedron_does_not_collapse(seed):
    Vn = TET_V + 0.1 * np.random.default_rng(seed).normal(size=TET_V.shape)
    r = mr.denoise(Vn, TET_F)
    assert np.isfinite(r.V).all()
    assert _volume(r.V, TET_F) / _volume(Vn, TET_F) > 0.5


@pytest.mark.parametrize("direction", ["normal", "random"])
def test_collapsing_robust_stage_is_solved_again_without_it(direction, caplog):
    """λ = 1: at this weight the robust stage alone collapses the noisy tetrahedron (volume
    ratio 0.01-0.05), and the call solves again without it. (At the default weight of the random
    draw, λ 1.63, the robust stage keeps 0.61 of the volume and no second solve is needed.)"""
    Vn = mr.add_noise(TET_V, TET_F, 0.1, direction=direction, seed=3)
    with caplog.at_level(logging.WARNING, logger="meshrepair.denoise.api"):
        r = mr.denoise(Vn, TET_F, lam=1.0)
    assert "solving again without it" in caplog.text  # the robust stage alone: volume ~0.01
    assert r.params["robust_iters"] == 0
    assert _volume(r.V, TET_F) / _volume(Vn, TET_F) > 0.5


def test_explicit_robust_stage_that_collapses_is_refused():
    Vn = mr.add_noise(TET_V, TET_F, 0.1, seed=3)
    with pytest.raises(mr.MeshRepairError, match=r"collapsed .* volume fell to .*robust_iters=0"):
        mr.denoise(Vn, TET_F, robust_iters=40)


def test_collapse_even_without_robust_stage_is_refused():
    Vn = mr.add_noise(TET_V, TET_F, 0.3, seed=3)
    with pytest.raises(mr.MeshRepairError, match="cannot be denoised"):
        mr.denoise(Vn, TET_F)


@pytest.mark.parametrize("make", [trimesh.creation.box, trimesh.creation.icosahedron,
                                  lambda: trimesh.creation.icosphere(1)])
@pytest.mark.parametrize("gamma", [0.0, 0.1])
def test_small_closed_meshes_keep_their_volume(make, gamma):
    m = make()
    V, F = np.asarray(m.vertices), np.asarray(m.faces)
    Vn = mr.add_noise(V, F, gamma, seed=3)
    r = mr.denoise(Vn, F)
    q = _volume(r.V, F) / _volume(Vn, F)
    assert np.isfinite(r.V).all() and 0.5 < q < 2.0, q
    if gamma == 0:
        assert np.abs(r.V - V).max() < 0.05 * np.ptp(V)  # a clean mesh stays put
