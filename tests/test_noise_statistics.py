"""The noise levels of :func:`meshrepair.model.noise.noise_statistics`: the robust (MAD) level,
the RMS level, and the RMS level without the surface's coherent relief (creases and ridges)
that decides whether the noise is impulsive."""

from __future__ import annotations

import numpy as np
import pytest

import meshrepair as mr
from meshrepair.mesh.geometry import mean_edge_length, vertex_normals
from meshrepair.model.noise import noise_statistics

from .bundled import bundled_mesh
from .conftest import shared_mesh


def _thrown(V, F, fraction, seed=0):
    """Gaussian noise of 0.05 l̄ plus ``fraction`` of the vertices thrown along their normals by
    0.5-1.5 l̄ (either side): impulsive noise."""
    rng = np.random.default_rng(seed)
    Y = mr.add_noise(V, F, 0.05, direction="normal", seed=1)
    idx = rng.choice(len(V), int(fraction * len(V)), replace=False)
    step = rng.choice([-1.0, 1.0], len(idx)) * rng.uniform(0.5, 1.5, len(idx))
    Y[idx] += (step * mean_edge_length(V, F))[:, None] * vertex_normals(V, F)[idx]
    return Y


@pytest.mark.parametrize("name", ["fandisk.ply", "trim_star.ply"])
def test_creases_at_low_noise_do_not_read_impulsive(name):
    """A CAD part's creases are outliers of the Laplacian that come in same-sign lines: they leave
    the RMS, so Gaussian noise reads RMS/MAD near 1 even where the creases dominate the tail."""
    from meshrepair.denoise.rules import IMPULSIVE_RATIO

    V, F = bundled_mesh(name)
    for g in (0.05, 0.1, 0.3):
        mad, _, rms = noise_statistics(mr.add_noise(V, F, g, direction="normal", seed=1), F,
                                       isolated=True)
        assert 0.85 < rms / mad < IMPULSIVE_RATIO - 0.1, (g, rms / mad)


@pytest.mark.parametrize("name", ["fandisk.ply", "trim_star.ply"])
def test_isolated_impulses_still_read_impulsive(name):
    V, F = bundled_mesh(name)
    mad, _, rms = noise_statistics(_thrown(V, F, 0.1), F, isolated=True)
    assert rms / mad > 2.0


def test_rms_without_coherent_relief_brute_force():
    """The RMS equals a per-vertex loop over the definition (outlier with a same-sign outlier
    neighbour leaves), on a noisy part with both creases and thrown vertices."""
    from meshrepair.mesh.topology import edge_topology

    V, F = bundled_mesh("trim_star.ply")
    Y = _thrown(V, F, 0.03)
    topo = edge_topology(F, len(Y))
    nbr = [set() for _ in range(len(Y))]
    for a, b in topo.edges:
        nbr[a].add(b)
        nbr[b].add(a)
    bnd = set(topo.edges[topo.boundary].ravel().tolist())
    n = vertex_normals(Y, F)
    h = {}
    for i in range(len(Y)):
        if i in bnd or not nbr[i]:
            continue
        lap = np.mean([Y[j] for j in sorted(nbr[i])], axis=0) - Y[i]
        h[i] = float(lap @ n[i]) / np.sqrt(1.0 + 1.0 / len(nbr[i]))
    med = np.median(list(h.values()))
    dev = {i: v - med for i, v in h.items()}
    s = 1.4826 * np.median(np.abs(list(dev.values())))
    side = {i: (1 if d > 3 * s else -1 if d < -3 * s else 0) for i, d in dev.items()}
    kept = [d for i, d in dev.items()
            if not (side[i] and any(side.get(j, 0) == side[i] for j in nbr[i]))]
    L = float(np.mean(np.linalg.norm(Y[topo.edges[:, 0]] - Y[topo.edges[:, 1]], axis=1)))
    mad, rms, iso = noise_statistics(Y, F, topo, isolated=True)
    assert mad == pytest.approx(s / L, rel=1e-9)
    assert rms == pytest.approx(np.sqrt(np.mean(np.square(list(dev.values())))) / L, rel=1e-9)
    assert iso == pytest.approx(np.sqrt(np.mean(np.square(kept))) / L, rel=1e-9)
    assert len(kept) < len(dev)  # the creases' outliers left
    assert noise_statistics(Y, F, topo) == (mad, rms)


def test_invariant_to_rotation_scale_and_order():
    V, F = bundled_mesh("fandisk.ply")
    Y = mr.add_noise(V, F, 0.05, direction="normal", seed=2)
    a = noise_statistics(Y, F, isolated=True)
    Q, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))
    p = np.random.default_rng(1).permutation(len(Y))
    inv = np.argsort(p)
    for Z, G in ((2.5 * Y @ Q.T + 3.0, F), (Y[p], inv[F])):
        b = noise_statistics(Z, G, isolated=True)
        assert b == pytest.approx(a, rel=1e-9)


@pytest.mark.shared
def test_shared_impulsive_input_reads_impulsive():
    """The shared impulsive input (73 % of the vertices moved) keeps its heavy tail."""
    from meshrepair.denoise.rules import IMPULSIVE_RATIO

    V, F = shared_mesh("noisy/twelve__impulsive0.5.ply")
    mad, _, rms = noise_statistics(V, F, isolated=True)
    assert rms / mad > IMPULSIVE_RATIO + 0.1
