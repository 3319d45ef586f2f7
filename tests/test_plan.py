"""The plan of a denoise call: read once, printable, editable, and run exactly as planned."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import meshrepair as mr
from meshrepair.errors import MeshRepairError

from .bundled import bundled_mesh, data_path


@pytest.fixture(scope="module")
def noisy_fandisk():
    return bundled_mesh("fandisk_noisy.ply")


@pytest.fixture(scope="module")
def heavy_spot():
    """An organic mesh under heavy random noise: the plan low-passes the input first and plans
    the low-passed input (a nested plan)."""
    V, F = bundled_mesh("spot.ply")
    return mr.add_noise(V, F, 0.5, direction="random", seed=1), F


def test_plan_is_deterministic_and_pure(noisy_fandisk):
    V, F = noisy_fandisk
    V0, F0 = V.copy(), F.copy()
    a, b = mr.plan_denoise(V, F), mr.plan_denoise(V, F)
    assert a == b and str(a) == str(b)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)  # inputs untouched
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.lam = 1.0  # type: ignore[misc]


def test_plan_records_every_decision_with_its_reads(noisy_fandisk):
    p = mr.plan_denoise(*noisy_fandisk)
    names = [d.name for d in p.decisions]
    for n in ("lam", "huber_delta", "robust_iters", "willmore_weight", "outside_weight",
              "presmooth_steps", "start_from_probe"):
        assert n in names
    lam = next(d for d in p.decisions if d.name == "lam")
    assert lam.value == p.lam and lam.reads["gamma"] == p.reading["gamma"] and not lam.by_user
    text = p.explain()
    assert "decisions:" in text and "stages of the main solve" in text
    assert set(p.editable()) == {"lam", "huber_delta", "willmore_weight", "outside_weight",
                                 "inner_iters", "stages", "start_from_probe",
                                 "presmooth_steps", "polish"}


@pytest.mark.parametrize("case", ["noisy_fandisk", "heavy_spot"])
def test_running_the_plan_equals_the_one_shot_call(case, request):
    V, F = request.getfixturevalue(case)
    r = mr.denoise(V, F)
    p = mr.plan_denoise(V, F)
    q = mr.denoise(V, F, plan=p)
    assert np.array_equal(r.V, q.V)
    assert r.params == q.params or _same_params(r.params, q.params)
    assert q.plan.after_solve  # the finish's decisions are recorded in the plan that ran
    if case == "heavy_spot":
        assert p.presmooth_steps > 0 and p.inner is not None
        assert "low-passed by" in p.explain() and "the plan `inner` runs" in p.explain()


@pytest.mark.parametrize("case", ["noisy_fandisk", "heavy_spot"])
def test_the_readings_progress_sees_the_probe_and_changes_nothing(case, request):
    # plan_denoise's callback gets each iteration of the probe (and of the low-passed input's
    # probe, for the heavy noise plan), and the plan is the one made without it
    V, F = request.getfixturevalue(case)
    seen: list[dict] = []
    p = mr.plan_denoise(V, F, callback=seen.append)
    assert p == mr.plan_denoise(V, F) and str(p) == str(mr.plan_denoise(V, F))
    restarts = sum(b["iter"] <= a["iter"] for a, b in zip(seen, seen[1:], strict=False))
    assert len(seen) >= 3 and all(e["stage"] == "robust" for e in seen)
    assert restarts == (1 if case == "heavy_spot" else 0)  # one probe per input read


def test_a_stop_during_the_reading_is_raised_again(noisy_fandisk):
    # a plan is not made from part of the probe: Ctrl-C and StopRequested reach the caller
    from meshrepair.model.solver import StopRequested

    def stop_at(k, exc):
        def cb(entry):
            if entry["iter"] == k:
                raise exc
        return cb

    with pytest.raises(KeyboardInterrupt):
        mr.plan_denoise(*noisy_fandisk, callback=stop_at(2, KeyboardInterrupt))
    with pytest.raises(StopRequested, match="reading"):
        mr.plan_denoise(*noisy_fandisk, callback=stop_at(2, StopRequested()))
    with pytest.raises(MeshRepairError, match="callback"):
        mr.plan_denoise(*noisy_fandisk, callback=3)


def _same_params(a, b):
    if a.keys() != b.keys():
        return False
    return all((x != x and y != y) or x == y for x, y in ((a[k], b[k]) for k in a))


def test_an_edited_plan_runs_as_edited(noisy_fandisk):
    V, F = noisy_fandisk
    p = mr.plan_denoise(V, F)
    q = dataclasses.replace(p, lam=4 * p.lam)
    r = mr.denoise(V, F, plan=q)
    assert r.params["lam"] == pytest.approx(4 * p.lam) and r.plan.lam == q.lam
    assert not np.array_equal(r.V, mr.denoise(V, F, plan=p).V)
    # the edited plan and the plan that ran print the value that runs, as the user's edit
    for text in (str(q), str(r.plan)):
        line = next(s for s in text.splitlines() if s.strip().startswith("lam "))
        assert f"{q.lam:.4g}" in line and "[user] edited" in line, line
    # an edited field is the user's, not credited to a step after the solve
    assert p.outside_weight > 1.0  # a CAD part
    r = mr.denoise(V, F, plan=dataclasses.replace(p, outside_weight=0.5 * p.outside_weight))
    assert not [d for d in r.plan.after_solve if d.name == "outside_weight"]
    line = next(s for s in str(r.plan).splitlines() if s.strip().startswith("outside_weight"))
    assert "[user] edited" in line, line
    # the records a plan carries are plans or None
    for name in ("if_correlated", "if_structured", "inner"):
        with pytest.raises(MeshRepairError, match=f"plan.{name} must be a DenoisePlan"):
            mr.denoise(V, F, plan=dataclasses.replace(p, **{name: "x"}))
    # the record fields are read, not edited (options={...} raised a KeyError at run time)
    for name, value in (("options", {"lam": -5}), ("reading", {}), ("decisions", ())):
        with pytest.raises(MeshRepairError, match=f"plan.{name} records how"):
            mr.denoise(V, F, plan=dataclasses.replace(p, **{name: value}))


def test_user_options_appear_as_set_by_the_user(heavy_spot):
    V, F = heavy_spot
    p = mr.plan_denoise(V, F, lam=0.3)
    lam = next(d for d in p.decisions if d.name == "lam")
    assert lam.by_user and lam.value == 0.3
    pre = next(d for d in p.decisions if d.name == "presmooth_steps")
    # what the user's option switched off is said, not silent
    assert pre.value == 0 and pre.by_user and "set by the user" in pre.rule


def test_plan_misuse_is_refused(noisy_fandisk, heavy_spot):
    V, F = noisy_fandisk
    p = mr.plan_denoise(V, F)
    with pytest.raises(MeshRepairError, match="another mesh"):
        mr.denoise(*heavy_spot, plan=p)
    with pytest.raises(MeshRepairError, match="another mesh"):  # same size, other vertices
        mr.denoise(V + 1e-3, F, plan=p)
    with pytest.raises(MeshRepairError, match="leave the other options"):
        mr.denoise(V, F, plan=p, lam=0.5)
    with pytest.raises(MeshRepairError, match="DenoisePlan"):
        mr.denoise(V, F, plan={"lam": 1})
    with pytest.raises(MeshRepairError, match="record"):
        mr.denoise(V, F, plan=mr.denoise(V, F).plan)
    ps = mr.plan_denoise(*heavy_spot)
    with pytest.raises(MeshRepairError, match="presmooth_steps"):
        mr.denoise(*heavy_spot, plan=dataclasses.replace(ps, presmooth_steps=ps.presmooth_steps
                                                         + 3))
    for edit, msg in (({"stages": None}, "plan.stages must be a non-empty tuple"),
                      ({"stages": ()}, "plan.stages must be a non-empty tuple"),
                      ({"outside_weight": -1.0}, "outside_weight must be")):
        with pytest.raises(MeshRepairError, match=msg):
            mr.denoise(V, F, plan=dataclasses.replace(p, **edit))
    with pytest.raises(MeshRepairError, match="at least one stage"):
        mr.plan_denoise(V, F, stages=())  # as denoise(stages=()) refuses it


def test_presmooth_can_be_switched_off_in_the_plan(heavy_spot):
    V, F = heavy_spot
    p = mr.plan_denoise(V, F)
    r = mr.denoise(V, F, plan=dataclasses.replace(p, presmooth_steps=0))
    assert r.params["presmooth_steps"] == 0 and np.isfinite(r.V).all()


def test_an_edit_the_run_would_not_use_is_refused(heavy_spot):
    """A low-passing plan runs ``inner``: its own fields are those of a run on the raw input.
    An edit of them would change nothing, so it is refused with the ways to say what is meant,
    and both ways run with the edit."""
    V, F = heavy_spot
    p = mr.plan_denoise(V, F)
    assert p.presmooth_steps > 0 and p.inner.if_correlated is None
    assert p.polish and not p.inner.polish  # (an edit to the value inner holds is carried)
    for edit in ({"lam": 2 * p.lam}, {"stages": p.stages[:1]}, {"outside_weight": 3.0}):
        with pytest.raises(MeshRepairError, match=rf"inner.*\({next(iter(edit))}\)"):
            mr.denoise(V, F, plan=dataclasses.replace(p, **edit))
    r0 = mr.denoise(V, F, plan=p)
    ri = mr.denoise(V, F, plan=dataclasses.replace(
        p, inner=dataclasses.replace(p.inner, lam=2 * p.inner.lam)))
    assert ri.plan.inner.lam == 2 * p.inner.lam and not np.array_equal(ri.V, r0.V)
    both = dataclasses.replace(p, lam=2 * p.lam,  # edited in both: the edit of inner runs
                               inner=dataclasses.replace(p.inner, lam=2 * p.inner.lam))
    np.testing.assert_array_equal(mr.denoise(V, F, plan=both).V, ri.V)
    rr = mr.denoise(V, F, plan=dataclasses.replace(p, presmooth_steps=0, lam=2 * p.lam))
    assert rr.params["presmooth_steps"] == 0 and rr.params["lam"] == pytest.approx(2 * p.lam)
    with pytest.raises(MeshRepairError, match=r"`inner` was edited \(lam\)"):
        mr.denoise(V, F, plan=dataclasses.replace(
            p, presmooth_steps=0, inner=dataclasses.replace(p.inner, lam=2 * p.inner.lam)))
    # an edit back to the planned value is no edit
    assert np.array_equal(mr.denoise(V, F, plan=dataclasses.replace(p, lam=p.lam)).V, r0.V)


def test_an_edit_the_correlated_alternative_lacks_is_refused():
    """A plan with ``if_correlated`` may run that plan instead: an edit it does not carry is
    refused; edited in both, or without the alternative, the run takes it."""
    V, F = bundled_mesh("trim_star.ply")
    Y = mr.add_noise(V, F, 0.1, direction="normal", seed=1)
    p = mr.plan_denoise(Y, F)
    assert p.if_correlated is not None and p.presmooth_steps == 0
    with pytest.raises(MeshRepairError, match=r"if_correlated.*\(lam\)"):
        mr.denoise(Y, F, plan=dataclasses.replace(p, lam=2 * p.lam))
    both = dataclasses.replace(p, lam=2 * p.lam,
                               if_correlated=dataclasses.replace(p.if_correlated, lam=2 * p.lam))
    assert mr.denoise(Y, F, plan=both).params["lam"] == pytest.approx(2 * p.lam)
    alone = dataclasses.replace(p, lam=2 * p.lam, if_correlated=None)
    assert mr.denoise(Y, F, plan=alone).params["lam"] == pytest.approx(2 * p.lam)


def test_cli_explain_prints_the_plan_and_writes_nothing(tmp_path, capsys, monkeypatch):
    from meshrepair.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["denoise", str(data_path("fandisk_noisy.ply")), "--explain"]) == 0
    out = capsys.readouterr().out
    assert "denoise plan:" in out and "lam" in out and "nothing written" in out
    assert list(tmp_path.iterdir()) == []
    assert main(["denoise", str(data_path("fandisk_noisy.ply")), str(tmp_path / "x.ply"),
                 "--explain"]) != 0
    assert list(tmp_path.iterdir()) == []
