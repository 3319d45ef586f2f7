"""The probe's stopping rule in mean-edge-length units (meshrepair.denoise.scalefree)."""

from pathlib import Path

import numpy as np
import pytest
import trimesh
import trimesh.remesh

import meshrepair.model._fused as _fused
from meshrepair.denoise.scalefree import Q_REF, radius_in_edges, tolerance_factor
from meshrepair.mesh.geometry import mean_edge_length


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


def _box(k):
    m = trimesh.creation.box(extents=(1.0, 0.7, 0.5))
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    for _ in range(k):
        V, F = trimesh.remesh.subdivide(V, F)
    return V, F


def _probe_support(V, F, N):
    from meshrepair.denoise.regions import crease_support
    from meshrepair.mesh.topology import edge_topology

    topo = edge_topology(F, len(V))
    return topo, crease_support(topo, N)


def test_cad_support_of_a_box_does_not_depend_on_its_resolution():
    """f ∝ 1/q for a crease network, f_ref = max(f, f_g q / Q_c) does not: the box's exact
    normals, subdivided 5 and 6 times (q ≈ 18 and 36), give the same f q within 10 %, and the
    finer one, whose raw f is below 0.2, reads f_ref = f q / Q_c ≥ 0.2."""
    from meshrepair.denoise.scalefree import Q_CAD, cad_support, crease_like_share
    from meshrepair.mesh.geometry import face_normals

    out = []
    for k in (5, 6):
        V, F = _box(k)
        N = face_normals(V, F)
        topo, sup = _probe_support(V, F, N)
        assert crease_like_share(topo, N, sup) == pytest.approx(sup.mean())  # all crease-like
        q = radius_in_edges(V, F, topo.edges)
        assert q == pytest.approx(radius_in_edges(V, F), rel=1e-12)  # same unique edges
        out.append((sup.mean(), q, cad_support(topo, N, sup, q)))
    (f5, q5, _), (f6, q6, r6) = out
    assert q6 == pytest.approx(2 * q5, rel=0.05)
    assert f6 < 0.6 * f5 and f6 < 0.2  # the raw fraction falls with the resolution
    assert f6 * q6 == pytest.approx(f5 * q5, rel=0.10)
    assert r6 == pytest.approx(f6 * q6 / Q_CAD, rel=1e-12)
    assert r6 >= 0.2


def test_noise_creases_on_a_sphere_are_not_crease_like():
    """Jittered normals (25° rms) on a smooth sphere make long chains of creased edges; their
    sides are not flat (s > 5.5°), so none counts: f_ref = f."""
    from meshrepair.denoise.scalefree import cad_support, crease_like_share
    from meshrepair.mesh.geometry import face_normals

    m = trimesh.creation.icosphere(subdivisions=5)
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    rng = np.random.default_rng(3)
    N = face_normals(V, F) + 0.45 * rng.normal(size=(len(F), 3))
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    topo, sup = _probe_support(V, F, N)
    assert sup.mean() > 0.05  # the noise does make supported chains
    assert crease_like_share(topo, N, sup) == 0.0
    assert cad_support(topo, N, sup, radius_in_edges(V, F)) == sup.mean()


@pytest.mark.shared  # heavy (two denoise runs of 25k / 41k vertices), no shared data read
def test_fine_noisy_box_is_a_cad_part_and_fine_noisy_sphere_is_not():
    """End to end: a box subdivided to q ≈ 36 at γ 0.3 reads a raw crease support
    below 20 % but is a CAD part (outside weight 6); a sphere of 41k vertices at γ 0.5 is not."""
    from meshrepair import add_noise, denoise

    V, F = _box(6)
    r = denoise(add_noise(V, F, 0.3, seed=0), F)
    assert r.params["outside_weight"] > 1.0
    m = trimesh.creation.icosphere(subdivisions=6)
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    r = denoise(add_noise(V, F, 0.5, seed=0), F)
    assert r.params["outside_weight"] == 1.0
    assert r.params.get("presmooth_support_fraction", r.params["support_fraction"]) < 0.2


def test_willmore_extra_kernel_matches_its_numpy_twin():
    """The fused extra-energy pass of the per-edge Willmore weights (a cost at 1.18M vertices)
    equals the numpy expression it replaces."""
    rng = np.random.default_rng(5)
    nE, nF = 500, 300
    l, Nv = rng.random(nE), rng.normal(size=(nF, 3))
    fa, fb = rng.integers(0, nF, nE), rng.integers(0, nF, nE)
    w = np.where(rng.random(nE) < 0.5, 6.0, 1.0)
    skip = rng.random(nE) < 0.2
    want = _fused._np_willmore_extra(l, Nv, fa, fb, w, 1.0, skip)
    f = ~skip
    brute = sum((w[e] - 1.0) * l[e] ** 2 * np.sum((Nv[fa[e]] - Nv[fb[e]]) ** 2)
                for e in np.flatnonzero(f))
    assert want == pytest.approx(brute, rel=1e-12)
    assert _fused.willmore_extra(l, Nv, fa, fb, w, 1.0, skip) == pytest.approx(want, rel=1e-12)


def test_two_phase_gate_reads_q_and_the_switches(monkeypatch):
    """The gated probe: two phases only above Q_0 with rule 1 and the gate on; the second phase only
    when the first reads a non-empty crease-supported region."""
    from meshrepair.denoise import scalefree as sf

    assert not sf.two_phase(Q_REF) and not sf.two_phase(0.5 * Q_REF)
    assert sf.two_phase(Q_REF * 1.01) and sf.two_phase(10 * Q_REF)
    assert not sf.continue_probe(0.0) and sf.continue_probe(1e-6)
    monkeypatch.setattr(sf, "GATED_STOP", False)
    assert not sf.two_phase(10 * Q_REF)
    monkeypatch.setattr(sf, "GATED_STOP", True)
    monkeypatch.setattr(sf, "SCALE_FREE_STOP", False)
    assert not sf.two_phase(10 * Q_REF)


def _recording_solver():
    from meshrepair.model.solver import ADMMSolver

    calls = []

    class Rec(ADMMSolver):
        def solve(self, V0, V_init=None, **kw):
            r = super().solve(V0, V_init, **kw)
            calls.append((self.options.tol, self.options.stages[0].max_iter, r.iterations,
                          None if V_init is None else np.array(V_init)))
            return r

        def resume(self, state, *, tol=None, **kw):
            k1 = state.k
            r = super().resume(state, tol=tol, **kw)
            calls.append((tol, self.options.stages[0].max_iter - k1, r.iterations - k1, None))
            return r

    return Rec, calls


@pytest.mark.parametrize("shape", ["box", "sphere"])
def test_gated_probe_phases_tolerances_and_iterations(shape):
    """Phase 1 stops at the relative tolerance switch_tol; a box (creases) goes on, resuming
    phase 1's run, with the scale-free tolerance for the iterations left; a smooth sphere (no
    crease-supported edge) stops after phase 1. The iterations add up."""
    from meshrepair.denoise.run import default_stages
    from meshrepair.denoise.scalefree import gated_probe, probe_tol
    from meshrepair.mesh.topology import edge_topology
    from meshrepair.model.solver import SolverOptions

    if shape == "box":
        V, F = _box(3)
    else:
        m = trimesh.creation.icosphere(subdivisions=3)
        V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    topo = edge_topology(F, len(V))
    from meshrepair import add_noise

    V = add_noise(V, F, 0.2, seed=0)
    from dataclasses import replace

    st = replace(default_stages(robust_iters=300)[0], switch_tol=2e-3)  # a small mesh: looser
    q = 4 * Q_REF  # rule 1's tolerance a quarter of switch_tol
    kw = {"tol": probe_tol(st, q)}
    assert kw["tol"] == pytest.approx(st.switch_tol / 4)
    Rec, calls = _recording_solver()
    r = gated_probe(Rec, SolverOptions, F, len(V), topo, st, kw, V, None, q, 30.0)
    assert calls[0][0] == pytest.approx(st.switch_tol) and calls[0][1] == st.max_iter
    assert calls[0][2] < st.max_iter  # phase 1 stops on its rule
    if shape == "box":
        assert r.probe_phases == 2 and r.probe_gate_support > 0
        tol2, max2, it2, Vi2 = calls[1]
        assert tol2 == pytest.approx(st.switch_tol / 4)
        assert max2 == st.max_iter - calls[0][2]
        assert r.iterations == calls[0][2] + it2 and it2 > 0
        assert len(r.history) == r.iterations  # one run: the history goes on
    else:
        assert r.probe_phases == 1 and r.probe_gate_support == 0.0 and len(calls) == 1
        # the gate's read is handed on, equal to reading the result's normals again
        from meshrepair.denoise.crease_network import supported

        sup, net = supported(topo, r.N, th=30.0)
        np.testing.assert_array_equal(r.crease_support[0], sup)
        assert r.crease_support[1].rejected == net.rejected
