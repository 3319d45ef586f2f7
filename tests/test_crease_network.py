"""Is the probe's crease network a CAD part's creases or noise
(:mod:`meshrepair.denoise.crease_network`)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshrepair import add_noise, denoise, msae
from meshrepair.baselines import taubin_smooth
from meshrepair.denoise import crease_network as cn
from meshrepair.denoise import presmooth as ps
from meshrepair.denoise.regions import creased_edges, long_chains
from meshrepair.mesh.geometry import face_normals
from meshrepair.mesh.topology import edge_topology

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


def _reads(topo, N):
    cre = creased_edges(topo, N, 30.0)
    return cn.chain_reads(topo, N, cre, long_chains(topo, cre, 30)), cre


def test_side_spread_is_zero_beside_a_roof_edge_and_large_on_rough_sides():
    """Two planes meeting at a 60° roof: one chain, flat sides (s = 0), no junction (β = 0):
    not noise, and the support keeps it. The same roof with rough normals everywhere: a
    branched network with rough sides, every chain of it dropped."""
    V, F = _strip(ROOF, ny=40)
    topo = edge_topology(F, len(V))
    N = face_normals(V, F)
    (idx, g, beta, spread), cre = _reads(topo, N)
    assert len(idx) == 40 and len(beta) == 1 and beta[0] == 0.0
    assert spread[0] == pytest.approx(0.0, abs=1e-6)
    assert not cn.is_noise_chain(beta, spread).any()
    sup, read = cn.supported(topo, N)
    assert sup.any() and read.dropped == 0 and read.rejected == 0.0
    rng = np.random.default_rng(3)
    Nn = N + 0.6 * rng.normal(size=N.shape)
    Nn /= np.linalg.norm(Nn, axis=1, keepdims=True)
    (idx2, g2, beta2, spread2), _ = _reads(topo, Nn)
    big = np.bincount(g2) >= 60
    assert big.any()
    assert (beta2[big] > cn.BRANCHING).all() and (spread2[big] > cn.SIDE_SPREAD).all()
    sup2, read2 = cn.supported(topo, Nn)
    assert read2.dropped >= big.sum() and read2.rejected > 0.0
    assert cn.heavy_from_network(read2.rejected)


def test_a_face_closed_in_by_creases_gives_no_evidence():
    """Every edge creased: no side exists, s = NaN (not 0, not ∞); a regular tetrahedron (every
    vertex a junction, β = 1, every face closed in) is therefore not a noise network."""
    V, F = _strip(ROOF, ny=10)
    topo = edge_topology(F, len(V))
    cre = np.ones(topo.n_edges, bool)
    e = np.flatnonzero(topo.interior)[:5]
    assert np.isnan(cn.side_spreads(topo, face_normals(V, F), cre, e)).all()
    TV = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1.0]])
    TF = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    t = edge_topology(TF, 4)
    N = face_normals(TV, TF)
    cre_t = creased_edges(t, N, 30.0)
    idx, g, beta, spread = cn.chain_reads(t, N, cre_t, long_chains(t, cre_t, 1))
    assert len(idx) == 6 and beta[0] == 1.0 and np.isnan(spread[0])
    assert not cn.is_noise_chain(beta, spread).any()
    sup, read = cn.supported(t, N)
    assert read.dropped == 0 and sup.all()


def test_statistics_invariant_under_similarity():
    """Angles and connectivity only: a rotated, scaled, translated mesh reads the same."""
    V, F = bundled_mesh("spot.ply")
    Vn = add_noise(V, F, 0.4, direction="normal", seed=1)
    topo = edge_topology(F, len(V))
    R = trimesh.transformations.random_rotation_matrix(np.random.default_rng(2).random(3))[:3, :3]
    (ia, ga, ba, sa), _ = _reads(topo, face_normals(Vn, F))
    (ib, gb, bb, sb), _ = _reads(topo, face_normals(3.7 * Vn @ R.T + 5.0, F))
    assert np.array_equal(ia, ib) and np.array_equal(ga, gb)
    assert np.allclose(ba, bb) and np.allclose(sa, sb, rtol=1e-9)


def test_empty_network_reads_nothing():
    assert not cn.heavy_from_network(0.0) and cn.heavy_from_network(0.3)
    assert not cn.heavy_from_network(0.02)  # sparse terrace chains of a subdivided CAD part
    z = np.zeros(0)
    assert cn.is_noise_chain(z, z).shape == (0,)


def test_spot_under_heavy_normal_noise_is_not_a_cad_part():
    """Bundled spot (2,930 vertices) at γ = 0.4 normal noise: the probe's creases cover ≥ 20 %
    of the edges (the support fraction alone would read a CAD part), but they form a branched
    network with rough sides, so no crease is supported; the noise is then heavy for this mesh
    and the input is low-passed first (:mod:`meshrepair.denoise.presmooth`). The result beats
    Taubin's filter at its defaults by far (read as a CAD part it measured 208.9 against
    Taubin's 202.9)."""
    V, F = bundled_mesh("spot.ply")
    Vn = add_noise(V, F, 0.4, direction="normal", seed=1)
    r = denoise(Vn, F)
    p = r.params
    assert p["presmooth_network_rejected"] >= 0.2  # it would have been read as a CAD part
    assert p["support_fraction"] < 0.2
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
    assert p["network_dropped"] == 0 and p["network_rejected"] == 0.0
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


@pytest.mark.shared
def test_cad_part_with_noise_chains_keeps_its_creases():
    """sharp_sphere γ0.4 seed 8: the probe left noise chains beside the creases, so the whole
    network reads noise; only the chains that read noise themselves are dropped and the mesh
    keeps its CAD read (the network test alone emptied its support: 186.5 -> 346.7)."""
    from .conftest import shared_mesh

    V, F = shared_mesh("sharp_sphere.ply")
    Vn = add_noise(V, F, 0.4, direction="normal", seed=8)
    r = denoise(Vn, F)
    p = r.params
    assert p["network_dropped"] >= 1 and p["network_rejected"] > 0.0
    assert p["support_fraction"] >= 0.2 and p["outside_weight"] > 1.0
    assert msae(r.V, V, F) < 200.0  # main 2273a91: 186.5


@pytest.mark.shared
@pytest.mark.parametrize("gamma", [0.3, 0.4])
def test_camelhead_heavy_normal_noise_beats_taubin(gamma):
    """camelhead (held out while the rule was chosen): its noise chains are dropped, the noise
    is read heavy and the input low-passed first; the result beats Taubin at its defaults by
    far (main 2273a91: 315.9 / 552.8 against Taubin's 237.2 / 363.1, seed 1)."""
    from .conftest import shared_mesh

    V, F = shared_mesh("camelhead.ply")
    Vn = add_noise(V, F, gamma, direction="normal", seed=1)
    r = denoise(Vn, F)
    assert r.params["presmooth_network_rejected"] > 0.5
    assert msae(r.V, V, F) < 0.5 * msae(taubin_smooth(Vn, F), V, F)
