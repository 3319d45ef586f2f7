"""Crease-support statistics of :mod:`meshrepair.denoise.regions` on synthetic
folds."""

import numpy as np
import pytest

from meshrepair.denoise.regions import (
    LONG_CHAIN,
    chain_statistics,
    crease_support,
    creased_edges,
    long_chains,
    supported_chains,
)
from meshrepair.mesh.geometry import face_normals
from meshrepair.mesh.topology import edge_topology


def _strip(f, nx=20, ny=40, h=0.1):
    """Grid over x in [-nx h, nx h], y in [0, ny h] with z = f(x): the line x = 0 is a chain of
    ``ny`` edges along y (the x = 0 vertices are grid vertices)."""
    x, y = np.arange(-nx, nx + 1) * h, np.arange(ny + 1) * h
    X, Y = np.meshgrid(x, y, indexing="ij")
    V = np.c_[X.ravel(), Y.ravel(), f(X.ravel())]
    idx = np.arange(len(V)).reshape(len(x), len(y))
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return V, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


ROOF = lambda x: -np.tan(np.radians(30.0)) * np.abs(x)  # noqa: E731  a 60° box-like edge
FOLD = lambda x: -0.3 * np.abs(x) - 1.2 * x**2  # noqa: E731  a crease between curved sides
RIDGE = lambda x: 0.1 * np.exp(-np.abs(x) / 0.15)  # noqa: E731  a narrow spike ridge


def _chain(f, ny=40):
    V, F = _strip(f, ny=ny)
    topo = edge_topology(F, len(V))
    N = face_normals(V, F)
    cre = creased_edges(topo, N, 30.0)
    return V, F, topo, N, cre, np.flatnonzero(long_chains(topo, cre, 30))


def test_roof_edge_persists_with_flat_sides():
    """Two planes: every side mean is the plane's normal, so p = 1 and s = 0 exactly."""
    _, _, topo, N, cre, ch = _chain(ROOF)
    assert len(ch) == 40 and cre.sum() == 40
    p, s = chain_statistics(topo, N, cre, ch)
    assert p == pytest.approx(1.0, abs=1e-12) and s == pytest.approx(0.0, abs=1e-6)
    sup = crease_support(topo, N)
    assert sup[ch].all() and sup.sum() == crease_support(topo, N, persist_tol=None).sum()


def test_curved_fold_grows_and_spike_ridge_fades_at_the_coarse_scale():
    """Curved sides add their turn to the coarse angle (p > 1); a spike ridge's sides turn back
    to the plane, so its coarse angle is smaller (p < 1); both sides are curved (s > 0)."""
    _, _, topo, N, cre, ch = _chain(FOLD)
    p, s = chain_statistics(topo, N, cre, ch)
    assert p > 1.2 and s > 1.0
    _, _, topo2, N2, cre2, ch2 = _chain(RIDGE)
    p2, s2 = chain_statistics(topo2, N2, cre2, ch2)
    assert p2 < 0.8 and s2 > 1.0
    # with a single-ring persistence scale the mean normal is the edge's own pair: p = 1
    assert chain_statistics(topo, N, cre, ch, persist_rings=0)[0] == pytest.approx(1.0)


@pytest.mark.parametrize("f", [FOLD, RIDGE])
def test_short_organic_chains_are_dropped_long_ones_kept(f):
    _, _, topo, N, cre, ch = _chain(f)
    assert len(ch) == 40 < LONG_CHAIN
    assert crease_support(topo, N, persist_tol=None)[ch].all()  # length alone keeps it
    assert not crease_support(topo, N).any()
    assert not supported_chains(topo, N, cre, long_chains(topo, cre, 30)).any()
    _, _, topo, N, cre, ch = _chain(f, ny=LONG_CHAIN)  # a long chain is kept by its length
    assert crease_support(topo, N)[ch].all()


def test_statistics_invariant_under_similarity():
    V, F, topo, N, cre, ch = _chain(FOLD)
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    V2 = 2.5 * V @ Q.T + [1.0, -2.0, 0.5]
    N2 = face_normals(V2, F)
    a = chain_statistics(topo, N, cre, ch)
    b = chain_statistics(topo, N2, creased_edges(topo, N2, 30.0), ch)
    assert np.allclose(a, b, atol=1e-9)
