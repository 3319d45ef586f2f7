"""Is the probe's crease network a CAD part's creases or noise (:mod:`meshrepair.crease_network`,
issue 12, round 11c)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshrepair import add_noise, denoise, msae
from meshrepair import crease_network as cn
from meshrepair import presmooth as ps
from meshrepair.baselines import taubin_smooth
from meshrepair.geometry import face_normals
from meshrepair.regions import creased_edges, long_chains
from meshrepair.topology import edge_topology

from .bundled import bundled_mesh
from .test_regions import ROOF, _strip


def test_branching_counts_junction_vertices():
    """β = |{v : d(v) ≥ 3}| / |V_C|: 0 on a polyline and on a closed loop, 1/(k+1) on a star
    of k spokes of one edge, the fraction of interior vertices of a full triangle grid."""
    path = np.c_[np.arange(9), np.arange(1, 10)]
    assert cn.branching(path, 10) == 0.0
    loop = np.c_[np.arange(10), (np.arange(10) + 1) % 10]
    assert cn.branching(loop, 10) == 0.0
    star = np.c_[np.zeros(5, int), np.arange(1, 6)]
    assert cn.branching(star, 6) == pytest.approx(1 / 6)
    # every edge of a 6x6 vertex grid with diagonals: all but the two corners of the
    # diagonal's ends with degree 2 have degree >= 3
    V, F = _strip(lambda x: 0 * x, nx=3, ny=5, h=1.0)  # 7 x 6 vertices
    topo = edge_topology(F, len(V))
    d = np.bincount(topo.edges.ravel())
    assert cn.branching(topo.edges, len(V)) == pytest.approx((d >= 3).sum() / len(V))
    assert cn.branching(topo.edges, len(V)) > 0.9
    assert np.isnan(cn.branching(np.zeros((0, 2), int), 3))


def test_side_spread_is_zero_beside_a_roof_edge_and_large_on_rough_sides():
    """Two planes meeting at a 60° roof: the sides of every chain edge are flat, s = 0, β = 0,
    not a noise network. The same roof with heavy normal noise on the faces' normals is."""
    V, F = _strip(ROOF, ny=40)
    topo = edge_topology(F, len(V))
    N = face_normals(V, F)
    st = cn.network_statistics(topo, N)
    assert st.n_edges == 40 and st.branching == 0.0
    assert st.side_spread == pytest.approx(0.0, abs=1e-6)
    assert not cn.is_noise_network(st)
    cre = creased_edges(topo, N, 30.0)
    s = cn.side_spreads(topo, N, cre, np.flatnonzero(long_chains(topo, cre, 30)))
    assert np.allclose(s, 0.0, atol=1e-6)
    # rough normals everywhere: many creased edges, joined into a branched network
    rng = np.random.default_rng(3)
    Nn = N + 0.9 * rng.normal(size=N.shape)
    Nn /= np.linalg.norm(Nn, axis=1, keepdims=True)
    st2 = cn.network_statistics(topo, Nn)
    assert st2.n_edges > 100
    assert st2.branching > cn.BRANCHING and st2.side_spread > cn.SIDE_SPREAD
    assert cn.is_noise_network(st2)


def test_statistics_invariant_under_similarity():
    """Angles and connectivity only: a rotated, scaled, translated mesh reads the same."""
    V, F = bundled_mesh("spot.ply")
    Vn = add_noise(V, F, 0.4, direction="normal", seed=1)
    topo = edge_topology(F, len(V))
    R = trimesh.transformations.random_rotation_matrix(np.random.default_rng(2).random(3))[:3, :3]
    a = cn.network_statistics(topo, face_normals(Vn, F))
    b = cn.network_statistics(topo, face_normals(3.7 * Vn @ R.T + 5.0, F))
    assert a.n_edges == b.n_edges
    assert a.branching == pytest.approx(b.branching)
    assert a.side_spread == pytest.approx(b.side_spread, rel=1e-9)


def test_empty_network_is_not_noise_and_support_is_kept():
    st = cn.NetworkStatistics(float("nan"), float("nan"), 0)
    assert not cn.is_noise_network(st)
    assert not cn.heavy_from_network(0.0) and cn.heavy_from_network(0.3)


def test_spot_under_heavy_normal_noise_is_not_a_cad_part():
    """Bundled spot (2,930 vertices) at γ = 0.4 normal noise: the probe's creases cover ≥ 20 %
    of the edges (the CAD read before round 11c), but they form a branched network with rough
    sides, so no crease is supported; the noise is then heavy for this mesh and the input is
    low-passed first (round 10h). The result beats Taubin's filter at its defaults by far
    (main before round 11c: 208.9 against Taubin's 202.9)."""
    V, F = bundled_mesh("spot.ply")
    Vn = add_noise(V, F, 0.4, direction="normal", seed=1)
    r = denoise(Vn, F)
    p = r.params
    assert p["presmooth_network_rejected"] >= 0.2  # it would have been read as a CAD part
    assert p["presmooth_steps"] > 0 and p["outside_weight"] == 1.0
    assert p["cad_finish_passes"] == 0
    ours, tau = msae(r.V, V, F), msae(taubin_smooth(Vn, F), V, F)
    assert ours < 0.5 * tau


def test_noisy_sphere_is_not_a_cad_part():
    """A finely sampled smooth sphere under heavy normal noise gets no crease support."""
    m = trimesh.creation.icosphere(4)
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    Vn = add_noise(V, F, 0.4, direction="normal", seed=4)
    r = denoise(Vn, F)
    assert r.params["support_fraction"] < 0.05
    assert r.params["outside_weight"] == 1.0


@pytest.mark.parametrize("gamma", [0.2, 0.4, 0.7])
def test_noisy_fandisk_keeps_its_cad_read(gamma):
    """Bundled fandisk under normal noise: its creases are polylines with flat sides (β ≈ 0.04,
    s ≈ 2-3.5°), so the network is not noise and the CAD rules still apply."""
    V, F = bundled_mesh("fandisk.ply")
    Vn = add_noise(V, F, gamma, direction="normal", seed=1)
    r = denoise(Vn, F)
    p = r.params
    assert p["network_rejected"] == 0.0
    assert p["network_branching"] < 0.1 and p["network_side_spread"] < 4.0
    assert p["support_fraction"] >= 0.2 and p["outside_weight"] > 1.0


def test_heavy_flag_opens_the_presmooth_gate_only():
    """``heavy`` skips the level test of the presmooth gate, not the other conditions."""
    kw = dict(support_fraction=0.0, outside=1.0, willmore=1.0, impulsive=False)
    assert ps.presmooth_steps(0.25, 0.1, **kw) == 0
    k = ps.presmooth_steps(0.25, 0.1, **kw, heavy=True)
    assert k == round((ps.effective_level(0.25, 0.1) / ps.GAMMA_P) ** 2)
    assert ps.presmooth_steps(0.25, 0.1, **{**kw, "impulsive": True}, heavy=True) == 0
    assert ps.presmooth_steps(0.25, 0.1, **{**kw, "willmore": 4.0}, heavy=True) == 0
