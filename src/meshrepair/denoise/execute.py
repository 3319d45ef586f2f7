"""The execution of a :class:`~meshrepair.denoise.plan.DenoisePlan` (:func:`_execute`): the
coarse-to-fine low-pass when the plan has one, the main ADMM solve of energy (6) by (17)-(21)
ending by rule (35), the discrepancy principle on the outside weight and the collapse fallback,
then the finish after the solve (:func:`meshrepair.denoise.finish.finish_result`), the result's
fold-overs and the correlated-noise low-pass.
"""

from __future__ import annotations

import logging
from dataclasses import fields, replace

import numpy as np

from meshrepair.denoise import structure as _structure
from meshrepair.denoise.finish import REINTEGRATE_KEEPS_FOLDS, finish_result
from meshrepair.denoise.folds import (
    COLLAPSE_VOLUME_RATIO,
    UNFOLD_RESULT,
    _volume_ratio,
    unfold_result,
)
from meshrepair.denoise.plan import (
    Decision,
    DenoisePlan,
    _State,
    as_record,
    edited_fields,
    mesh_key,
)
from meshrepair.denoise.result import DenoiseResult
from meshrepair.denoise.rules import FLAT_A, lambda_from_noise, robust_a_from_noise
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.reorder import _edge_values_to
from meshrepair.model.schedule import default_stages
from meshrepair.model.solver import ADMMSolver, SolverOptions

log = logging.getLogger("meshrepair.denoise.run")


def _execute(plan: DenoisePlan, V, F, callback=None, *, made_here: bool = False,
             outside: float | None = None, resolve: bool = True) -> DenoiseResult:
    """Run ``plan`` on ``(V, F)`` (the mesh it was made from; module docstring).
    ``made_here``: the plan was just made from these very arrays by the caller, so their
    digest is not checked again. ``outside``: the outside weight the discrepancy principle
    already chose on this input (solved with directly, no test); ``resolve=False``: the test
    is read and recorded but the run is not solved again (the caller decides)."""
    st: _State = plan._state
    if st is None:
        raise MeshRepairError("this plan carries no reading of a mesh (DenoiseResult.plan is a "
                              "record of what ran): make a plan with mr.plan_denoise(V, F)")
    _check_edits(plan)
    if (plan.n_vertices != len(V) or plan.n_faces != len(F)
            or (not made_here and st.mesh_key != mesh_key(V, F))):
        raise MeshRepairError("this plan was made for another mesh: make it with "
                              "mr.plan_denoise(V, F) on the mesh you denoise")
    planned = 0 if st.presmooth is None else st.presmooth["steps"]
    if plan.presmooth_steps not in (0, planned) or (plan.presmooth_steps and plan.inner is None):
        raise MeshRepairError(
            f"presmooth_steps of a plan can be kept ({planned}) or set to 0, not "
            f"{plan.presmooth_steps}: the low-passed input and its plan are made by "
            "plan_denoise")
    _refuse_unused_edits(plan, planned)
    if plan.if_correlated is not None:
        return _execute_tested(plan, V, F, callback, made_here)
    if plan.if_structured is not None:
        return _structure.execute_structured(plan, V, F, callback, made_here, _execute)
    o = plan.options
    info = dict(st.info)
    gamma, gamma_rms, impulsive, topo = st.gamma, st.gamma_rms, st.impulsive, st.topo
    if plan.presmooth_steps:
        r = _execute(plan.inner, st.presmooth["Vp"], F, callback, made_here=made_here)
        r.params.update(presmooth_steps=plan.presmooth_steps,
                        presmooth_noise_estimate=r.noise_estimate,
                        presmooth_roughness=st.presmooth["roughness"],
                        presmooth_tangential_weight=st.presmooth["tangential_weight"],
                        presmooth_network_rejected=info["network_rejected"],
                        presmooth_tangential_ratio=info["tangential_ratio"],
                        presmooth_noise_rho=info["noise_rho"],
                        presmooth_noise_length=info["noise_length"],
                        presmooth_noise_gamma_scale=info["noise_gamma_scale"],
                        presmooth_support_fraction=info["support_fraction"])
        r.noise_estimate = gamma
        from meshrepair.denoise import corrlowpass as _cl

        r.V = _cl.apply(r.V, F, topo, gamma, info, impulsive, V, st.r1_V)
        r.params.update({k_: info[k_] for k_ in _cl.RECORDED})
        r.plan = as_record(plan, inner=r.plan,
                           after_solve=_after(info, st.info, _cl.RECORDED, plan))
        return r
    info["presmooth_steps"] = 0
    reorder, inv, Fw, topo_w = st.reorder, st.inv, st.Fw, st.topo_w
    opts_kw = {**st.opts_kw, "lam": plan.lam, "huber_delta": plan.huber_delta,
               "inner_iters": plan.inner_iters}
    ww, Vd, Vi, force, flat, anchor = (plan.willmore_weight, st.Vd, st.Vi, st.force, st.flat,
                                       st.anchor)
    sup_v, r1_V = st.sup_v, st.r1_V
    wedges = None
    if st.sup is not None and plan.outside_weight != 1.0:  # a CAD part: its smooth patches
        wedges = np.where(st.sup, ww, ww * plan.outside_weight)  # get the stronger prior
    info["outside_weight"] = plan.outside_weight
    tested = wedges is not None and outside is None
    if wedges is not None and outside is not None and outside != plan.outside_weight:
        wedges = _fallback_edges(st.force, ww, outside)
        info["outside_weight"] = outside
    Vi_main = st.r1.V if plan.start_from_probe else Vi
    info["start_from_probe"] = bool(plan.start_from_probe)
    stages = plan.stages
    lam_used = plan.lam
    robust_iters = st.robust_iters

    n_solves = [0]

    def solve(stages_):
        """The main run; on a reordered copy the result is mapped back exactly."""
        n_solves[0] += 1
        opts = SolverOptions(stages=tuple(stages_), willmore_weight=ww, **opts_kw)
        res = ADMMSolver(Fw, len(V), options=opts, topo=topo_w, edge_force=force,
                         flat_edges=flat, anchor=anchor, willmore_edges=wedges
                         ).solve(Vd, Vi_main, callback=callback)
        if reorder:
            return res, res.V[inv], _edge_values_to(topo, topo_w, st.pf, res.M_E)
        return res, res.V, res.M_E

    res, V_out, M_E = solve(stages)
    w_cad = plan.outside_weight  # the CAD-part decision, read by the polish rule
    info["discrepancy_ratio"] = float("nan")
    from meshrepair.denoise import discrepancy as _dq

    if tested and _dq.applies(gamma, gamma_rms) and res.stop_reason != "interrupted":
        # the discrepancy principle on w_out: lower it where it smooths away signal
        q = _dq.discrepancy_ratio(V, V_out, F, sup_v, clip=_dq.CLIP * gamma, edges=topo.edges)
        info["discrepancy_ratio"] = q
        for w_try in _dq.FALLBACK_WEIGHTS if resolve else ():
            if _dq.accept_weight(q):
                break
            wedges = _fallback_edges(force, ww, w_try)
            info["outside_weight"] = w_try
            res, V_out, M_E = solve(stages)
            q = _dq.discrepancy_ratio(V, V_out, F, sup_v, clip=_dq.CLIP * gamma,
                                      edges=topo.edges)
            log.info("outside weight lowered to %g (discrepancy ratio %.3f)", w_try, q)
    shrink = _volume_ratio(V, V_out, F, st.report)
    if shrink is not None and shrink < COLLAPSE_VOLUME_RATIO and res.stop_reason != "interrupted":
        if not st.auto_robust:
            raise MeshRepairError(
                f"denoise collapsed this closed mesh: its volume fell to {shrink:.3g} of the "
                f"input's ({len(V)} vertices; a mesh this coarse has no smooth regions for the "
                "model). Try robust_iters=0 (no robust stage) or a finer mesh")
        log.warning("denoise: the robust stage collapsed this coarse closed mesh (volume ratio "
                    "%.3g, %d vertices); solving again without it", shrink, len(V))
        robust_iters = 0
        # the probe's decisions came from the collapsed robust run: drop them too
        force = flat = anchor = wedges = sup_v = None
        Vi_main = Vi
        info["start_from_probe"] = False
        info["collapse_fallback"] = True
        ww = 1.0 if o["willmore_weight"] is None else float(o["willmore_weight"])
        lam_used = (lambda_from_noise(gamma, lowpassed=st.presmoothed) if o["lam"] is None
                    else float(o["lam"]))
        opts_kw["lam"] = lam_used
        stages = default_stages(robust_iters=0, feature_iters=int(o["feature_iters"]),
                                a=o["a"], flat_a=FLAT_A if o["regions"] else 0.0,
                                robust_a=robust_a_from_noise(max(gamma, gamma_rms)))
        res, V_out, M_E = solve(stages)
        shrink = _volume_ratio(V, V_out, F, st.report)
        if shrink is not None and shrink < COLLAPSE_VOLUME_RATIO:
            raise MeshRepairError(
                f"denoise collapsed this closed mesh: its volume fell to {shrink:.3g} of the "
                f"input's even without the robust stage ({len(V)} vertices; a mesh this coarse "
                "has no smooth regions for the model); it cannot be denoised")
    V_out = finish_result(V, V_out, F, topo, M_E, data=Vd[inv] if reorder else Vd,
                          sup_v=sup_v, gamma=gamma, gamma_rms=gamma_rms, impulsive=impulsive,
                          ww=ww, w_cad=w_cad, automatic=o["willmore_weight"] is None,
                          polish=plan.polish, info=info, probe=r1_V,
                          lowpassed=st.presmoothed,
                          lowpassed_from=st.lowpassed_from,
                          lam_set=o["lam"] is not None,
                          band_model=st.band is not None and ww > 1.0)
    n_res_folded = 0
    if o["unfold"] and UNFOLD_RESULT and not (info["reintegrate_steps"]
                                              and REINTEGRATE_KEEPS_FOLDS and not impulsive):
        V_out, n_res_folded = unfold_result(V_out, topo, r1_V)
        if n_res_folded:
            log.info("unfolded %d faces folded over in the result", n_res_folded)
    info.update(corr_lowpass_steps=0, band_beta=float("nan"), band_tau=float("nan"),
                band_length=float("nan"))
    if (sup_v is not None and o["willmore_weight"] is None and o["lam"] is None
            and not st.presmoothed):
        from meshrepair.denoise import corrlowpass as _cl

        V_out = _cl.apply(V_out, F, topo, gamma, info, impulsive, V, r1_V, band=st.band)
    params = {"lam": lam_used, "th": o["th"], "a": o["a"], "robust_iters": robust_iters,
              "feature_iters": o["feature_iters"], "mask_update_every": o["mask_update_every"],
              "min_feature_edges": o["min_feature_edges"], "tol": o["tol"],
              "inner_solver": o["inner_solver"], "inner_iters": plan.inner_iters,
              "n_solver": o["n_solver"], "unfold": o["unfold"],
              "n_components": st.report.n_components, "reordered": reorder,
              "huber_delta": plan.huber_delta, "impulsive": impulsive,
              "regions": st.probe,
              "fidelity_data": "input" if (Vd is not st.Vw or not st.n_unf) else "unfolded",
              "result_folds_unfolded": n_res_folded, "main_solves": n_solves[0], **info}
    return DenoiseResult(
        V=V_out, F=F, M_E=M_E, edges=topo.edges.copy(), M_V=res.M_V, history=res.history,
        iterations=res.iterations, stop_reason=res.stop_reason, noise_estimate=gamma,
        params=params, n_unfolded=st.n_unf,
        # the record keeps no arrays of the reading: it would hold the probe's result alive
        plan=as_record(plan, after_solve=_after(info, st.info, (), plan)),
    )


def _check_edits(plan: DenoisePlan) -> None:
    """The fields a user may edit with ``dataclasses.replace``, checked as the options of
    :func:`meshrepair.denoise` are (MeshRepairError naming the field)."""
    from meshrepair.model.solver import Stage
    from meshrepair.options import check_number

    if not (isinstance(plan.stages, tuple) and plan.stages
            and all(isinstance(s, Stage) for s in plan.stages)):
        raise MeshRepairError(f"plan.stages must be a non-empty tuple of Stage objects (edit the "
                              f"plan's own, e.g. plan.stages[:1]), got {plan.stages!r}")
    check_number("outside_weight", plan.outside_weight, low=0)
    record = getattr(plan._state, "record", None)
    if record is not None:
        changed = [k for k, v in record.items() if getattr(plan, k) is not v]
        if changed:
            raise MeshRepairError(f"plan.{changed[0]} records how the plan was made and is not "
                                  f"edited: change the fields of plan.editable() instead, or "
                                  f"make a new plan with mr.plan_denoise(V, F, ...)")
    for name in ("inner", "if_correlated", "if_structured"):
        sub = getattr(plan, name)
        if sub is not None and not isinstance(sub, DenoisePlan):
            raise MeshRepairError(f"plan.{name} must be a DenoisePlan or None (a record the plan "
                                  f"carries: edit its fields instead), got {type(sub).__name__}")


def _refuse_unused_edits(plan: DenoisePlan, planned: int) -> None:
    """Raise when fields the user edited on ``plan`` would not be used by the run.

    A plan that low-passes its input first (``presmooth_steps > 0``) runs the whole model on the
    low-passed input with the plan in ``inner``: its own fields describe a run on the raw input
    and are used only with ``presmooth_steps=0``. A plan that carries ``if_correlated`` runs
    that plan instead when the white result fails the white-noise test. An edit of a field
    that the plan run instead neither carries (the same value) nor edits itself, or an edit of
    ``inner`` when ``presmooth_steps=0``, would be dropped without a word, so the run is
    refused with the way to say what is meant. ``planned``: the plan's own ``presmooth_steps``."""
    if plan.presmooth_steps:
        lost = _not_carried(plan, plan.inner)
        if lost:
            raise MeshRepairError(
                f"this plan low-passes the input first (presmooth_steps="
                f"{plan.presmooth_steps}) and runs the model on the result with the plan in "
                f"`inner`; the fields edited here ({', '.join(lost)}) belong to a run on the "
                f"raw input and would not be used: edit `inner` (dataclasses.replace(plan, "
                f"inner=dataclasses.replace(plan.inner, ...))) or also set presmooth_steps=0 "
                f"to run the raw input with them")
    elif plan.inner is not None and (lost := edited_fields(plan.inner)):
        raise MeshRepairError(
            f"`inner` was edited ({', '.join(lost)}) but presmooth_steps=0 runs the raw input "
            f"without it: keep presmooth_steps={planned} to run `inner`, or edit the plan's own "
            f"fields")
    if plan.if_correlated is not None and (lost := _not_carried(plan, plan.if_correlated)):
        raise MeshRepairError(
            f"this plan runs the white-noise model and, when its residual fails the "
            f"white-noise test, the plan in `if_correlated`, which does not carry the fields "
            f"edited here ({', '.join(lost)}): set if_correlated=None to run this plan alone, "
            f"or edit `if_correlated` too")


def _not_carried(plan: DenoisePlan, other: DenoisePlan | None) -> list[str]:
    """The fields edited on ``plan`` that ``other``, the plan that may run instead, neither
    edits itself nor holds at the same value."""
    edited = edited_fields(plan)
    if other is None or not edited:
        return edited
    also = set(edited_fields(other))
    return [k for k in edited if k not in also and getattr(other, k) != getattr(plan, k)]


def _fallback_edges(force, ww: float, w: float):
    """The per-edge Willmore weights of a lowered outside weight ``w``: ``ww`` on the edges the
    crease force marks (``force < 0``), ``ww·w`` elsewhere (``None`` for ``w = 1``)."""
    return np.where(force < 0, ww, ww * w) if w != 1.0 else None


def _execute_tested(plan: DenoisePlan, V, F, callback, made_here: bool = False
                    ) -> DenoiseResult:
    """The white model's plan, then the correlated model's when the white result's residual
    fails the white-noise test (:mod:`meshrepair.denoise.whiteness`).

    The discrepancy principle on the outside weight (:mod:`meshrepair.denoise.discrepancy`) is
    read once, on the white model's first solve: when the residual is white and the test
    fails, the white model is solved again with the lowered weight; when it is correlated, the
    correlated model is solved once with the weight that reading chose. A call so runs at most
    two main solves (three only after a collapse, :data:`COLLAPSE_VOLUME_RATIO`)."""
    from meshrepair.denoise import discrepancy as _dq
    from meshrepair.denoise.whiteness import white_residual

    st: _State = plan._state
    pw = replace(plan, if_correlated=None)
    r = _execute(pw, V, F, callback, made_here=made_here, resolve=False)
    t = white_residual(V, r.V, F, st.topo.edges, st.gamma)
    log.info("white-noise test of the residual: rho1 %.3f, level %.3f gamma (%s)", t.rho1,
             t.level_ratio, "white" if t.white else "correlated")
    n_white = r.params["main_solves"]
    q = r.params["discrepancy_ratio"]
    lowered = _dq.lowered_weight(q)  # the one further solve a call affords
    done = r.stop_reason == "interrupted"  # a user's stop: the white result is the answer
    if not done and not t.white:
        r = _execute(plan.if_correlated, V, F, callback, made_here=made_here,
                     outside=lowered, resolve=False)
        r.params["main_solves"] += n_white
        r.params["discrepancy_ratio"] = q
    elif not done and lowered is not None:
        log.info("outside weight lowered to %g (discrepancy ratio %.3f)", lowered, q)
        r = _execute(pw, V, F, callback, made_here=made_here, outside=lowered)
        r.params["main_solves"] += n_white
        r.params["discrepancy_ratio"] = q
    dec = Decision("noise_model", "white" if t.white else "correlated",
                   "white-noise test of the white model's residual (whiteness.py)",
                   {"rho1": t.rho1, "level_ratio": t.level_ratio})
    r.plan = replace(r.plan, after_solve=r.plan.after_solve + (dec,))
    r.params.update(noise_model="white" if t.white else "correlated", white_test_rho1=t.rho1,
                    white_test_level=t.level_ratio)
    return r


_AFTER = {
    "discrepancy_ratio": "discrepancy principle on the outside weight: normal residual outside "
                         "C over inside it (discrepancy.py)",
    "collapse_fallback": "the robust stage collapsed a coarse closed mesh: solved again "
                         "without it",
    "polished": "polish: fraction of faces under the bilateral normal filter (polish_rule)",
    "lambda_gain": "organic fidelity: gain on λ from the noise direction (organic_fidelity.py)",
    "lowpass_steps": "Taubin low-pass of the smooth region (lowpass.py)",
    "reanchor_ratio": "tangential re-anchoring: residual tangential ratio (reproject.py)",
    "reanchored": "tangential re-anchoring: vertices re-anchored",
    "reanchor_shift": "tangential re-anchoring: mean shift, edge lengths",
    "guidance_passes": "organic finish: one-ring guidance passes (guidance_rule)",
    "reintegrate_steps": "organic finish: re-integration steps from the input "
                         "(reintegrate_rule)",
    "reanchor_ratio_after": "tangential ratio after the re-integration",
    "residual_level_ratio": "residual noise level over the input's after the re-integration",
    "reintegrate_rejected": "re-integration undone by its fold check",
    "coarse_roughness": "curvature variation c of the result (coarse.py)",
    "coarse_steps": "Taubin pairs where the result is smooth at the mesh's resolution",
    "cad_finish_passes": "CAD finish passes (cadfinish.py)",
    "cad_finish_gated": "CAD finish: fraction of faces it moved",
    "sharpened": "crease sharpening: fraction kept (sharpen_rule, sharpen_decision.py)",
    "sharpen_rho": "crease sharpening: the data's position ρ on result → candidate",
    "sharpen_flat": "crease sharpening: flat support φ",
    "corr_lowpass_steps": "correlated-noise low-pass: Taubin pairs (corrlowpass.py)",
    "band_beta": "two-octave band read of the noise (corrwhite.py)",
    "band_tau": "two-octave band read: its threshold",
    "band_length": "two-octave band read: its length",
    "result_folds_unfolded": "faces folded in the result, unfolded",
}
"""What each record of the steps after the solve means (the stage's module has the maths)."""


_PLAN_FIELDS = frozenset(f.name for f in fields(DenoisePlan))


def _after(info: dict, before: dict, keys, plan: DenoisePlan) -> tuple[Decision, ...]:
    """The decisions taken on the solve's result: every record of ``info`` the reading did not
    hold (or that the run changed), except a field of the ``plan`` at the plan's value (the
    plan shows it, with who set it)."""
    out = []
    for k, v in info.items():
        if k in ("presmooth_steps", "start_from_probe") or (
                k in before and before[k] == v and k not in keys) or (
                k in _PLAN_FIELDS and getattr(plan, k) == v):
            continue
        if isinstance(v, (bool, int, float, str)) or v is None:
            out.append(Decision(k, v, _AFTER.get(k, "a step after the solve")))
    return tuple(out)
