"""A run stopped by rule (35) at ``τ_1`` and resumed from its
:class:`~meshrepair.model.solver.state.ADMMState` at ``τ_2 < τ_1`` is the same run as one solve at
``τ_2`` (the stop only reads ``rel``; :mod:`meshrepair.model.solver.state`), and the two-phase
gated probe (:func:`meshrepair.denoise.scalefree.gated_probe`) with its gate forced open equals
the one-phase probe."""

from dataclasses import replace

import numpy as np
import pytest
import trimesh

from meshrepair import add_noise
from meshrepair.errors import MeshRepairError
from meshrepair.model.solver import ADMMSolver, SolverOptions, Stage


def _noisy_box(n=3, gamma=0.2):
    m = trimesh.creation.box()
    for _ in range(n):
        m = m.subdivide()
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    return add_noise(V, F, gamma, seed=0), F


def _probe_stage():
    from meshrepair.denoise.run import default_stages

    return replace(default_stages(robust_iters=300)[0], switch_tol=2e-3)


@pytest.mark.parametrize("huber", [0.0, 0.05])
def test_resume_equals_one_run_to_the_smaller_tolerance(huber):
    V, F = _noisy_box()
    st = _probe_stage()
    S = ADMMSolver(F, len(V), options=SolverOptions(stages=(st,), tol=2e-3, huber_delta=huber))
    r1 = S.solve(V, keep_state=True)
    assert r1.stop_reason == "rule (35)" and r1.iterations < st.max_iter
    r2 = S.resume(r1.state, tol=5e-4)
    one = ADMMSolver(F, len(V), options=SolverOptions(stages=(st,), tol=5e-4,
                                                       huber_delta=huber)).solve(V)
    assert r2.iterations == one.iterations > r1.iterations
    np.testing.assert_allclose(r2.V, one.V, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r2.N, one.N, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(r2.M_E, one.M_E)
    assert [h["rel_change"] for h in r2.history] == pytest.approx(
        [h["rel_change"] for h in one.history], rel=1e-12)


def test_resume_across_stages_and_mask_updates():
    """A schedule of two stages, the last one's adaptive mask refreshed every 3 iterations:
    the resumed run keeps the stage, its iteration counter (the refresh cadence), its
    penalties and its mask."""
    V, F = _noisy_box()
    st = (Stage(name="robust", mask="all", a=2.0, eps=2.0, beta2_ratio=1.0, max_iter=8,
                switch_tol=1e-9),
          Stage(name="feature", mask="adaptive", a=1.0, eps=2.0, beta2_ratio=1.0, max_iter=200))
    o = SolverOptions(stages=st, tol=2e-3, mask_update_every=3)
    S = ADMMSolver(F, len(V), options=o)
    r1 = S.solve(V, keep_state=True)
    assert r1.state.stage == 1 and r1.iterations > 8
    r2 = S.resume(r1.state, tol=2e-4)
    one = ADMMSolver(F, len(V), options=replace(o, tol=2e-4)).solve(V)
    assert r2.iterations == one.iterations > r1.iterations
    np.testing.assert_allclose(r2.V, one.V, rtol=0, atol=1e-12)


def test_restart_is_not_the_same_run():
    """A restart (a new solve from phase 1's vertices) is not the one run: the multipliers and
    the normalisation start again, so the result differs; phase 2 resumes instead."""
    V, F = _noisy_box()
    st = _probe_stage()
    S = ADMMSolver(F, len(V), options=SolverOptions(stages=(st,), tol=2e-3))
    r1 = S.solve(V)
    left = st.max_iter - r1.iterations
    st2 = replace(st, max_iter=left, min_iter=min(st.min_iter, left))
    rr = ADMMSolver(F, len(V), options=SolverOptions(stages=(st2,), tol=5e-4)).solve(V, r1.V)
    one = ADMMSolver(F, len(V), options=SolverOptions(stages=(st,), tol=5e-4)).solve(V)
    assert np.abs(rr.V - one.V).max() > 1e-6


def test_resume_checks_its_input():
    V, F = _noisy_box(1)
    S = ADMMSolver(F, len(V), options=SolverOptions(stages=(_probe_stage(),), tol=2e-3))
    r = S.solve(V, keep_state=True)
    assert S.solve(V).state is None  # the state is handed back only when asked for
    with pytest.raises(MeshRepairError, match="tol"):
        S.resume(r.state, tol=float("nan"))
    V2, F2 = _noisy_box(2)
    with pytest.raises(MeshRepairError, match="state"):
        ADMMSolver(F2, len(V2), options=S.options).resume(r.state)


def test_gated_probe_with_the_gate_open_is_the_one_phase_probe(monkeypatch):
    from meshrepair.denoise import scalefree as sf
    from meshrepair.mesh.topology import edge_topology

    V, F = _noisy_box()
    st = _probe_stage()
    q = 4 * sf.Q_REF
    kw = {"tol": sf.probe_tol(st, q)}
    monkeypatch.setattr(sf, "GATE_SUPPORT", -1.0)  # phase 2 whatever phase 1 reads
    topo = edge_topology(F, len(V))
    r = sf.gated_probe(ADMMSolver, SolverOptions, F, len(V), topo, st, kw, V, None, q, 30.0)
    one = ADMMSolver(F, len(V), options=SolverOptions(stages=(st,), **kw),
                     topo=topo).solve(V)
    assert r.probe_phases == 2 and r.iterations == one.iterations
    np.testing.assert_allclose(r.V, one.V, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.N, one.N, rtol=0, atol=1e-12)
