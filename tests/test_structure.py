"""The method-noise test of a CAD part's result (meshrepair.denoise.structure): the organic
plan it carries, when that plan runs, which result is kept, and what a call costs."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import meshrepair as mr
from meshrepair.denoise import discrepancy as dq
from meshrepair.denoise import whiteness

from .bundled import bundled_mesh


@pytest.fixture(scope="module")
def cad_case():
    """A CAD part under white noise along the normals: a CAD reading, no correlated plan."""
    V, F = bundled_mesh("fandisk.ply")
    return mr.add_noise(V, F, 0.3, seed=1), F


def test_a_cad_plan_carries_the_organic_plan(cad_case):
    Y, F = cad_case
    p = mr.plan_denoise(Y, F)
    assert p.if_correlated is None and p.outside_weight > 1.0
    po = p.if_structured
    assert po is not None and po.if_structured is None
    # one difference, recorded: the crease support is not taken as a CAD part
    # the same reading (the organic law of λ also reads the probe's relief level)
    assert {k: v for k, v in po.reading.items() if k != "gamma_relief"} == p.reading
    assert po.outside_weight == 1.0
    cad = next(d for d in po.decisions if d.name == "cad_part")
    assert cad.value is False and cad.reads["support_fraction"] == p.reading["support_fraction"]
    assert "the organic plan" in p.explain()


def test_an_organic_mesh_or_user_weights_carry_none(cad_case):
    Y, F = cad_case
    assert mr.plan_denoise(Y, F, lam=5.0).if_structured is None
    assert mr.plan_denoise(Y, F, willmore_weight=1.0).if_structured is None
    V, Fs = bundled_mesh("spot.ply")
    assert mr.plan_denoise(mr.add_noise(V, Fs, 0.2, seed=1), Fs).if_structured is None


def _rho_sequence(monkeypatch, values):
    """Make the residual test read ``values`` in turn (the first for the CAD result)."""
    real = whiteness.white_residual
    seq = iter(values)

    def fake(*a, **k):
        return dataclasses.replace(real(*a, **k), rho1=next(seq))

    monkeypatch.setattr(whiteness, "white_residual", fake)


def _white_cad_run(cad_case, monkeypatch, discrepancy_passes: bool):
    """The CAD plan and its result when the CAD residual reads white (ρ₁ −0.05) and the
    discrepancy test of the outside weight passes or fails."""
    Y, F = cad_case
    p = mr.plan_denoise(Y, F)
    monkeypatch.setattr(dq, "accept_weight",
                        lambda q, tol=dq.DISCREPANCY_TOL: discrepancy_passes)
    _rho_sequence(monkeypatch, [-0.05])
    r = mr.denoise(Y, F, plan=p)
    assert r.params["structure_test"] == "CAD part"
    return Y, F, p, r


def test_a_white_cad_residual_keeps_the_cad_result_in_one_solve(cad_case, monkeypatch):
    Y, F, p, r = _white_cad_run(cad_case, monkeypatch, discrepancy_passes=True)
    assert r.params["main_solves"] == 1
    alone = mr.denoise(Y, F, plan=dataclasses.replace(p, if_structured=None))
    np.testing.assert_array_equal(r.V, alone.V)


def test_a_structured_cad_residual_runs_the_organic_plan(cad_case, monkeypatch):
    Y, F = cad_case
    p = mr.plan_denoise(Y, F)
    _rho_sequence(monkeypatch, [0.3, -0.02])
    r = mr.denoise(Y, F, plan=p)
    assert r.params["structure_test"] == "organic" and r.params["main_solves"] == 2
    assert r.params["structure_rho1_cad"] == 0.3
    assert r.params["structure_rho1_organic"] == -0.02
    assert r.plan.outside_weight == 1.0
    assert any(d.name == "structure_test" and d.value == "organic"
               for d in r.plan.after_solve)
    monkeypatch.undo()
    np.testing.assert_array_equal(r.V, mr.denoise(Y, F, plan=p.if_structured).V)


def test_an_organic_result_that_also_fails_is_not_kept(cad_case, monkeypatch):
    """Both residuals hold structure: the CAD result stays, and no third solve is made (the
    discrepancy principle's lowered weight is not tried)."""
    Y, F = cad_case
    p = mr.plan_denoise(Y, F)
    monkeypatch.setattr(dq, "accept_weight", lambda q, tol=dq.DISCREPANCY_TOL: False)
    _rho_sequence(monkeypatch, [0.3, 0.25])
    r = mr.denoise(Y, F, plan=p)
    assert r.params["structure_test"] == "CAD part" and r.params["main_solves"] == 2
    assert r.params["outside_weight"] == p.outside_weight
    monkeypatch.setattr(dq, "FALLBACK_WEIGHTS", ())
    _rho_sequence(monkeypatch, [-1.0])
    cad = mr.denoise(Y, F, plan=dataclasses.replace(p, if_structured=None))
    np.testing.assert_array_equal(r.V, cad.V)


def test_an_edited_cad_plan_runs_alone_and_says_so(cad_case, monkeypatch):
    Y, F = cad_case
    p = mr.plan_denoise(Y, F)
    q = dataclasses.replace(p, lam=2 * p.lam)
    _rho_sequence(monkeypatch, [0.3, -0.02])  # would run the organic plan if not edited
    r = mr.denoise(Y, F, plan=q)
    assert r.params["structure_test"] == "off" and r.plan.lam == q.lam
    off = next(d for d in r.plan.after_solve if d.name == "structure_test")
    assert off.by_user and "lam" in off.rule
    monkeypatch.undo()
    np.testing.assert_array_equal(r.V, mr.denoise(Y, F, plan=dataclasses.replace(
        q, if_structured=None)).V)


def test_the_plans_of_one_input_read_it_once(cad_case, monkeypatch):
    """The CAD plan and its organic alternative read the same input and probe: each reading
    (validation, noise level, direction, correlation, crease support) runs once."""
    from meshrepair.denoise import analysis

    calls: dict[str, int] = {}
    for name in ("noise_statistics", "tangential_ratio", "noise_scale", "flat_edges"):
        real = getattr(analysis, name)

        def counted(*a, _real=real, _name=name, **k):
            calls[_name] = calls.get(_name, 0) + 1
            return _real(*a, **k)

        monkeypatch.setattr(analysis, name, counted)
    p = mr.plan_denoise(*cad_case)
    assert p.if_structured is not None
    # noise_statistics: the input's level, and the probe's relief level of the organic law
    assert calls == {"noise_statistics": 2, "tangential_ratio": 1, "noise_scale": 1,
                     "flat_edges": 1}


def test_a_white_cad_residual_with_a_failed_discrepancy_test_costs_one_more_solve(
        cad_case, monkeypatch):
    r = _white_cad_run(cad_case, monkeypatch, discrepancy_passes=False)[3]
    assert r.params["main_solves"] == 2
    assert r.params["outside_weight"] == dq.FALLBACK_WEIGHTS[0]


def test_a_result_that_removed_shape_fails_the_test_and_one_that_removed_noise_passes():
    """The test's premise on an analytic case: on a sphere with white noise along the normals,
    the truth as the result leaves the noise (ρ₁ near 0: passes); a result that flattened the
    curvature into facets (every vertex projected on the nearest face plane of a coarse
    icosahedral sphere, up to 0.86 l̄ deep) leaves those caps in the residual (fails)."""
    import trimesh

    from meshrepair.mesh.topology import edge_topology
    from meshrepair.model.noise import noise_statistics

    s = trimesh.creation.icosphere(subdivisions=4)
    V, F = np.asarray(s.vertices, np.float64), np.asarray(s.faces, np.int64)
    Y = mr.add_noise(V, F, 0.2, seed=3)
    topo = edge_topology(F, len(V))
    gamma = noise_statistics(Y, F, topo)[0]
    assert whiteness.white_residual(Y, V, F, topo.edges, gamma).rho1 <= whiteness.RHO1_MAX
    c = trimesh.creation.icosphere(subdivisions=1)
    n = np.asarray(c.face_normals)
    d = np.einsum("ij,ij->i", n, np.asarray(c.vertices)[c.faces[:, 0]])
    k = np.argmax(V @ n.T, axis=1)
    facets = V * (d[k] / np.einsum("ij,ij->i", V, n[k]))[:, None]
    assert whiteness.white_residual(Y, facets, F, topo.edges, gamma).rho1 > whiteness.RHO1_MAX
