"""Round 11r: the probe's stopping rule in mean-edge-length units (meshrepair.scalefree)."""

from pathlib import Path

import numpy as np
import pytest
import trimesh
import trimesh.remesh

from meshrepair import _fused
from meshrepair.geometry import mean_edge_length
from meshrepair.scalefree import Q_REF, radius_in_edges, tolerance_factor


def _sphere(sub=2):
    m = trimesh.creation.icosphere(subdivisions=sub)
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


def test_rel_change_is_edge_step_over_radius():
    """rel = rms|ΔV| / rms|V − c| = (rms|ΔV| / l̄) / q, on centred coordinates."""
    V, F = _sphere(2)
    rng = np.random.default_rng(0)
    dV = 0.01 * rng.normal(size=V.shape)
    Vc = V - V.mean(axis=0)
    rel = _fused.rel_change(Vc + dV, Vc)
    step = np.sqrt(np.mean(np.sum(dV * dV, axis=1))) / mean_edge_length(V, F)
    assert rel * radius_in_edges(V, F) == pytest.approx(step, rel=1e-12)


def test_radius_in_edges_is_similarity_invariant_and_doubles_with_subdivision():
    V, F = _sphere(2)
    q = radius_in_edges(V, F)
    R = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))[0]
    assert radius_in_edges(3.7 * V @ R.T + [5.0, -2.0, 1.0], F) == pytest.approx(q, rel=1e-12)
    V2, F2 = trimesh.remesh.subdivide(V, F)  # every edge halved, same surface
    assert radius_in_edges(V2, F2) == pytest.approx(2.0 * q, rel=0.02)


def test_edge_unit_tolerance_is_capped_and_resolution_free_above_q_ref():
    V, F = _sphere(2)  # q ≈ 3: coarse, the relative test is unchanged
    assert radius_in_edges(V, F) < Q_REF
    assert tolerance_factor(V, F) == 1.0
    V4, F4 = V, F
    for _ in range(4):  # q ≈ 53: the tolerance in edge units, τ Q_REF
        V4, F4 = trimesh.remesh.subdivide(V4, F4)
    for X, G in ((V4, F4), (0.01 * V4, F4)):
        q = radius_in_edges(X, G)
        assert q > Q_REF
        assert tolerance_factor(X, G) * q == pytest.approx(Q_REF, rel=1e-12)


@pytest.mark.shared
def test_every_shared_input_keeps_the_relative_stop():
    """The rule changes nothing on the shared meshes (q 14-44 ≤ Q_REF): the guards of issue 12
    run the same code path."""
    from meshrepair import read_mesh

    from .conftest import SHARED

    root = Path(SHARED)
    paths = sorted(root.glob("*.ply")) + sorted(root.glob("noisy/*.ply")) + sorted(
        root.glob("published/*__noisy.ply"))
    assert len(paths) >= 20
    for p in paths:
        if p.stem in ("igea", "nefertiti"):  # q 87 / 60: truths of no quality guard
            continue
        m = read_mesh(p)
        assert tolerance_factor(m.V, m.F) == 1.0, p.name
