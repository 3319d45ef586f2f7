"""The decision of the crease sharpening (meshrepair.denoise.sharpen_decision)."""

import importlib

import numpy as np
import pytest
import trimesh

from meshrepair import denoise, msae
from meshrepair.denoise.modes import MODE_FLAT_SHARE, MODE_RHO_FLAT, supported_by_data
from meshrepair.denoise.scale import correlated_noise
from meshrepair.denoise.sharpen_decision import flat_vertices, set_statistics
from meshrepair.mesh.topology import edge_topology
from meshrepair.synthetic import grid_plane

from .test_modes import _fold

rules_mod = importlib.import_module("meshrepair.denoise.rules")


def _segment_case(t, n=12, seed=0):
    """``V⁰ = V + t (X − V) + e`` with ``e ⟂ (X − V)`` (per vertex): ``ρ = t`` exactly."""
    V, F = grid_plane(n)
    rng = np.random.default_rng(seed)
    d = rng.normal(size=V.shape)
    e = rng.normal(size=V.shape)
    e -= np.einsum("ij,ij->i", e, d)[:, None] * d / np.einsum("ij,ij->i", d, d)[:, None]
    return V, V + d, V + t * d + e, F


def test_rho_is_the_least_squares_position_on_the_segment():
    """ρ_S = argmin_t Σ_S ‖V⁰ − V − t (X − V)‖² (brute force over a fine grid of t), on each
    of two separate sets with their own t."""
    V, X, V0, F = _segment_case(0.37)
    topo = edge_topology(F, len(V))
    left = V[:, 0] < 4.5
    right = V[:, 0] > 5.5
    V0 = np.where(right[:, None], V + 0.81 * (X - V) + (V0 - V - 0.37 * (X - V)), V0)
    moved = left | right
    lab, rho, phi = set_statistics(V0, V, X, topo.edges, moved)
    ts = np.linspace(-1, 2, 30001)
    for S, t_true in ((left, 0.37), (right, 0.81)):
        r = V0[S] - V[S]
        d = X[S] - V[S]
        cost = [np.sum((r - t * d) ** 2) for t in ts]
        t_bf = ts[int(np.argmin(cost))]
        k = lab[np.flatnonzero(S)[0]]
        assert np.all(lab[S] == k)
        assert rho[k] == pytest.approx(t_true, abs=1e-9)
        assert rho[k] == pytest.approx(t_bf, abs=1e-4)
        assert phi[k] == 0.0
    # ρ > 1/2 is the data test: X lowers the fidelity Σ‖V⁰ − ·‖²
    for S in (left, right):
        k = lab[np.flatnonzero(S)[0]]
        lower = np.sum((V0 - X)[S] ** 2) < np.sum((V0 - V)[S] ** 2)
        assert lower == (rho[k] > 0.5)


@pytest.mark.parametrize("t", [0.05, 0.3, 0.45, 0.6])
@pytest.mark.parametrize("share", [None, 0.0, 0.4, 0.6, 1.0])
def test_decision_table(t, share):
    """X is kept on S iff ρ_S > 1/2, or ρ_S > ρ_flat and φ_S ≥ φ_min (module docstring)."""
    V, X, V0, F = _segment_case(t)
    topo = edge_topology(F, len(V))
    flat = None
    if share is not None:
        flat = np.zeros(len(V), bool)
        flat[: int(round(share * len(V)))] = True
    st = {}
    keep = supported_by_data(V0, V, X, topo.edges, 1e-6, flat=flat, stats=st)
    expect = t > 0.5 or (share is not None and t > MODE_RHO_FLAT and share >= MODE_FLAT_SHARE)
    assert np.all(keep == expect)
    assert st["rho"] == pytest.approx(t)
    assert st["size"] == len(V)
    assert st["flat"] == pytest.approx(0.0 if share is None else share, abs=1 / len(V))


def test_flat_support_reads_planes_not_spheres():
    """Two planes meeting at a 40° crease: the faces away from the crease are flat at the
    noise scale (r_p = 7 rings, τ_p / 2 = 4.3°); a sphere 13 edge lengths in radius is not."""
    Vs, F = _fold(40, 40.0)
    topo = edge_topology(F, len(Vs))
    fv = flat_vertices(Vs, F, np.zeros(topo.n_edges, bool), topo, rings=7, tau=4.33)
    far = np.abs(Vs[:, 0] - 20.0) > 8
    assert fv[far].all() and fv.mean() > 0.6
    s = trimesh.creation.icosphere(subdivisions=4)
    V, F = 20.0 * np.asarray(s.vertices), np.asarray(s.faces, np.int64)
    topo = edge_topology(F, len(V))
    assert flat_vertices(V, F, np.zeros(topo.n_edges, bool), topo, rings=7,
                         tau=4.33).mean() < 0.1


def test_defaults_sharpen_a_noisy_crease_not_a_sphere_or_white_noise():
    """Through the defaults: correlated noise (γ 0.4, m = 3) on a 40° fold: the step keeps
    most of the moved vertices and the result beats the unsharpened one; on a sphere the flat
    support is low and nothing is kept; white noise on the fold never reaches the step."""
    Vs, F = _fold(40, 40.0)
    V0 = correlated_noise(Vs, F, 0.4, 3, seed=0)
    r = denoise(V0, F)
    assert r.params["willmore_weight"] > 1 and r.params["sharpened"] > 0.5
    assert r.params["sharpen_flat"] > MODE_FLAT_SHARE
    old = rules_mod.SHARPEN
    try:
        rules_mod.SHARPEN = False
        r0 = denoise(V0, F)
    finally:
        rules_mod.SHARPEN = old
    assert msae(r.V, Vs, F) < 0.8 * msae(r0.V, Vs, F)
    s = trimesh.creation.icosphere(subdivisions=4)
    V, Fs = 20.0 * np.asarray(s.vertices), np.asarray(s.faces, np.int64)
    rs = denoise(correlated_noise(V, Fs, 0.4, 3, seed=0), Fs)
    assert rs.params["willmore_weight"] > 1
    assert rs.params["sharpen_flat"] < MODE_FLAT_SHARE and rs.params["sharpened"] < 0.01
    rng = np.random.default_rng(1)
    rw = denoise(Vs + 0.3 * rng.normal(size=Vs.shape) * [0, 0, 1], F)
    assert rw.params["willmore_weight"] == 1.0 and np.isnan(rw.params["sharpen_rho"])
