"""Tests of the CAD finish (meshrepair.denoise.cadfinish): its maths and its effect."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from meshrepair import denoise, mean_angle_error, msae
from meshrepair.denoise.cadfinish import (
    cad_finish,
    cad_finish_rule,
    crease_side_gate,
    finish_targets,
)
from meshrepair.denoise.polish import _neighbourhood_csr, filter_normals
from meshrepair.mesh.geometry import face_normals
from meshrepair.mesh.topology import edge_topology
from meshrepair.synthetic import grid_plane

from .conftest import needs_meshes, shared_mesh


def _grid(n=14):
    return grid_plane(n)


def _fold(n=14, k=7, curved=False):
    """A 90° fold along x = k (plane z = 0 for x ≤ k, the wall x = k beyond), or, with
    ``curved``, the wall replaced by a cylinder of radius 2 rising from the crease at 60°
    (tangent-discontinuous at x = k: a crease with one flat and one curved side)."""
    V, F = _grid(n)
    m = V[:, 0] > k
    u = V[m, 0] - k
    if curved:
        r, a0 = 2.0, np.radians(60.0)  # a circle of radius r starting at a 60° slope
        t = u / r  # arc length u
        V[m, 0] = k + r * (np.sin(a0 + t) - np.sin(a0))
        V[m, 2] = r * (np.cos(a0) - np.cos(a0 + t))
    else:
        V[m, 2] = u
        V[m, 0] = k
    topo = edge_topology(F, len(V))
    N = face_normals(V, F)
    sharp = np.zeros(topo.n_edges, bool)
    ie = np.flatnonzero(topo.interior)
    on = np.isclose(V[topo.edges[ie, 0], 0], k) & np.isclose(V[topo.edges[ie, 1], 0], k)
    dot = np.einsum("ij,ij->i", N[topo.edge_faces[ie, 0]], N[topo.edge_faces[ie, 1]])
    sharp[ie] = on & (dot < 0.9)
    return V, F, topo, sharp


def _spread_brute(V, F, topo, sharp):
    """s_f of the module docstring by an explicit loop over the faces' edges."""
    N = face_normals(V, F)
    nb = [[f] for f in range(len(F))]
    for e in np.flatnonzero(topo.interior & ~sharp):
        a, b = topo.edge_faces[e]
        nb[a].append(b)
        nb[b].append(a)
    s = np.empty(len(F))
    for f, K in enumerate(nb):
        m = N[K].sum(axis=0)
        m /= np.linalg.norm(m)
        ang = np.arccos(np.clip(N[K] @ m, -1.0, 1.0))
        s[f] = np.degrees(np.sqrt(np.mean(ang**2)))
    return s


def test_piecewise_planar_mesh_with_its_crease_marked_is_a_fixed_point():
    V, F, topo, sharp = _fold()
    assert sharp.sum() == 13
    X, gated = cad_finish(V, F, sharp, topo, passes=3)
    assert np.allclose(X, V, atol=1e-12)
    assert gated == 1.0  # every face: away from the crease, or on its flat sides (s_f = 0)
    Y, g0 = cad_finish(V, F, sharp, topo, passes=0)
    assert Y is not V and np.array_equal(Y, V) and g0 == 0.0


@pytest.mark.parametrize("curved", [False, True])
def test_gate_against_brute_force(curved):
    """G = {f away from V_E} ∪ {f touching V_E with s_f < τ}, s_f by an explicit loop."""
    V, F, topo, sharp = _fold(curved=curved)
    rng = np.random.default_rng(4)
    Vn = V + 0.02 * rng.standard_normal(V.shape)
    on = np.zeros(len(V), bool)
    on[topo.edges[sharp].ravel()] = True
    touch = on[F].any(axis=1)
    for tau in (1.0, 5.0, 20.0):
        ref = ~touch | (_spread_brute(Vn, F, topo, sharp) < tau)
        assert np.array_equal(crease_side_gate(Vn, F, sharp, topo, tau=tau), ref)
    # no crease: every face is in G
    assert crease_side_gate(Vn, F, np.zeros(topo.n_edges, bool), topo).all()


def test_gate_keeps_the_curved_side_of_a_crease():
    """On a crease with one flat and one curved side (a cylinder of radius 2 mean edge lengths:
    29° between faces across its rulings' edges) the faces of the curved side that touch the
    crease and see the curvature within their one-sided ring are left out of G (half of them:
    the other half has only coplanar neighbours in its ring); the flat side's are in."""
    V, F, topo, sharp = _fold(curved=True)
    assert sharp.sum() == 13
    on = np.zeros(len(V), bool)
    on[topo.edges[sharp].ravel()] = True
    touch = on[F].any(axis=1)
    side = (np.arange(len(V)) % 14)[F].mean(axis=1) > 7  # grid columns beyond the crease
    G = crease_side_gate(V, F, sharp, topo)
    assert (~G[touch & side]).mean() >= 0.45
    assert G[touch & ~side].all()
    assert G[~touch].all()


def _targets_brute(V, F, topo, sharp, gate, sigma_c, s_in, s_out):
    """n'_f of the module docstring by an explicit loop over each face's one-sided ring."""
    N = face_normals(V, F)
    C = V[F].mean(axis=1)
    A = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    nb = [[f] for f in range(len(F))]
    for e in np.flatnonzero(topo.interior & ~sharp):
        a, b = topo.edge_faces[e]
        nb[a].append(b)
        nb[b].append(a)
    out = np.empty_like(N)
    for f, K in enumerate(nb):
        sg = s_in if gate[f] else s_out
        w = A[K] * np.exp(-np.sum((C[K] - C[f]) ** 2, 1) / (2 * sigma_c**2)
                          - np.sum((N[K] - N[f]) ** 2, 1) / (2 * sg**2))
        m = (w[:, None] * N[K]).sum(axis=0)
        out[f] = m / np.linalg.norm(m)
    return out


def test_targets_against_brute_force():
    """The two range widths (σ_s on G, σ_s' off G) against an explicit per-face loop, and
    σ_s' = 0: the faces off G keep their normals."""
    V, F, topo, sharp = _fold(curved=True)
    rng = np.random.default_rng(8)
    Vn = V + 0.03 * rng.standard_normal(V.shape)
    G = crease_side_gate(Vn, F, sharp, topo)
    assert 0 < (~G).sum() < len(F)
    K = _neighbourhood_csr(topo, sharp, 1)
    Nt = finish_targets(Vn, F, K, G, sigma_c=1.1, sigma_s=0.2, sigma_s_curved=0.1)
    assert np.allclose(Nt, _targets_brute(Vn, F, topo, sharp, G, 1.1, 0.2, 0.1), atol=1e-10)
    N0 = finish_targets(Vn, F, K, G, sigma_c=1.1, sigma_s=0.2, sigma_s_curved=0.0)
    assert np.allclose(N0[~G], face_normals(Vn, F)[~G], atol=1e-12)


def test_filter_is_one_sided_at_the_crease():
    """Side A exact, side B noisy: the filtered normals of A's faces, those touching the crease
    included, are A's exact normal (no normal crosses M_E), while B's change."""
    V, F, topo, sharp = _fold()
    rng = np.random.default_rng(7)
    Vn = V.copy()
    B = V[:, 2] > 0.5  # the wall above the crease line: the crease vertices stay exact
    Vn[B] += 0.05 * rng.standard_normal((B.sum(), 3))
    K = _neighbourhood_csr(topo, sharp, 1)
    gate = np.ones(len(F), bool)
    le = float(np.linalg.norm(Vn[topo.edges[:, 0]] - Vn[topo.edges[:, 1]], axis=1).mean())
    Nt = filter_normals(Vn, F, K, gate, sigma_c=le, sigma_s=0.2)
    A = ~B[F].any(axis=1)
    assert np.allclose(Nt[A], [0.0, 0.0, 1.0], atol=1e-12)
    assert not np.allclose(Nt[~A], face_normals(Vn, F)[~A], atol=1e-6)


def test_finish_lowers_the_normal_error_and_keeps_the_crease():
    V, F, topo, sharp = _fold()
    rng = np.random.default_rng(3)
    Vn = V + 0.04 * rng.standard_normal(V.shape)
    X, _ = cad_finish(Vn, F, sharp, topo, passes=2)
    assert mean_angle_error(X, V, F) < 0.7 * mean_angle_error(Vn, V, F)
    # the faces on the two sides keep their orientation: the crease is not rounded
    N = face_normals(X, F)
    side = (np.arange(len(V)) % 14)[F].mean(axis=1) > 7  # grid columns beyond the crease
    assert np.degrees(np.arccos(N[~side] @ [0, 0, 1.0])).max() < 12.0
    assert np.degrees(np.arccos(N[side] @ [-1.0, 0, 0])).max() < 12.0


def test_finish_is_equivariant():
    """Rotations, translations and uniform scalings commute with the finish."""
    V, F, topo, sharp = _fold()
    rng = np.random.default_rng(5)
    Vn = V + 0.03 * rng.standard_normal(V.shape)
    R = Rotation.from_euler("xyz", [0.3, -0.7, 1.1]).as_matrix()
    s, b = 2.5, np.array([1.0, -2.0, 0.5])
    a, ga = cad_finish(Vn, F, sharp, topo, passes=2)
    g, gg = cad_finish(s * Vn @ R.T + b, F, sharp, topo, passes=2)
    assert ga == gg
    assert np.allclose(g, s * a @ R.T + b, atol=1e-9)


def test_rule_truth_table():
    assert cad_finish_rule(0.28, 6.0, 1.0) == 3
    assert cad_finish_rule(0.206, 6.0, 1.0) == 2
    assert cad_finish_rule(0.11, 6.0, 1.0) == 1
    assert cad_finish_rule(0.02, 6.0, 1.0) == 1
    assert cad_finish_rule(0.44, 6.0, 1.0) == 3  # heavy noise: after the polish
    assert cad_finish_rule(0.28, 1.0, 1.0) == 0  # not a CAD part (the organic finish's case)
    assert cad_finish_rule(0.28, 6.0, 16.0) == 0  # correlated noise
    assert cad_finish_rule(float("nan"), 6.0, 1.0) == 0


@pytest.mark.shared
@needs_meshes
def test_cad_finish_on_shared_cad_pairs():
    """Defaults on fandisk γ0.3 (design) and trim_star n3 (held out): the finish fires and the
    MSAE is below 9.6 and 74.5 (measured 9.08 and 73.1), under the 10.32 and 74.95 the defaults
    read without the finish when it was added."""
    for noisy, truth, bound in (("noisy/fandisk__gauss0.3.ply", "fandisk.ply", 9.6),
                                ("noisy/trim_star__gauss_n3.ply", "trim_star.ply", 74.5)):
        Vn, F = shared_mesh(noisy)
        Vt, _ = shared_mesh(truth)
        r = denoise(Vn, F)
        assert r.params["cad_finish_passes"] == 3
        assert 0.9 < r.params["cad_finish_gated"] < 1.0
        assert msae(r.V, Vt, F) < bound
