"""The run of the denoising schedule of :mod:`meshrepair.denoise` (the steps and the maths are
documented there): the options checked, the robust probe deciding the crease-supported region C
(5), the main ADMM solve of energy (6) by (17)-(21) ending by rule (35), the discrepancy (6) and
collapse fallbacks, then the finish after the solve
(:func:`meshrepair.denoise.finish.finish_result`).
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from meshrepair.denoise import coarse_lowpass as _clp
from meshrepair.denoise import crease_network as _cn
from meshrepair.denoise import scalefree as _sf
from meshrepair.denoise.finish import (
    REINTEGRATE_KEEPS_FOLDS,
    finish_result,
)
from meshrepair.denoise.folds import (
    COLLAPSE_VOLUME_RATIO,
    UNFOLD_RESULT,
    _volume_ratio,
    fidelity_data,
    unfold_result,
    unfolded_data_after_probe,
)
from meshrepair.denoise.regions import flat_edges
from meshrepair.denoise.result import DenoiseResult
from meshrepair.denoise.rules import (
    FLAT_A,
    FLAT_SPREAD_DEFAULT,
    PROBE_EARLY_STOP,
    PROBE_MAX_ITERS,
    TANGENTIAL_MAX,
    huber_from_noise,
    inner_iters_from_scale,
    is_impulsive,
    lambda_from_noise,
    outside_weight,
    robust_a_from_noise,
    robust_iters_from_noise,
    warm_start_from_probe,
    willmore_weight_from_scale,
)
from meshrepair.denoise.scale import noise_scale, tangential_ratio
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.reorder import _edge_values_to, locality_order
from meshrepair.model.noise import noise_statistics
from meshrepair.model.relax import untangle
from meshrepair.model.schedule import default_stages  # noqa: F401  (re-exported)
from meshrepair.model.solver import ADMMSolver, SolverOptions

log = logging.getLogger(__name__)


REORDER_MIN_VERTICES = 200_000
"""Meshes this large are solved in a Morton (Z-curve) order of vertices and faces: every kernel
is memory-bound there, and the reordering measured 1.33 s instead of 1.76 s per iteration on a
1.18M-vertex subdivided mesh. Smaller meshes keep their order (results then do not depend on a
coordinate-dependent ordering, which keeps the rotation test exact to rounding)."""


def _denoise(V, F, *, lam, th, a, robust_iters, feature_iters, mask_update_every,
             min_feature_edges, tol, unfold, inner_solver, inner_iters, n_solver, stages,
             huber_delta, willmore_weight, regions, callback, polish=True,
             presmoothed: bool = False, read_from: np.ndarray | None = None,
             capped: bool = False) -> DenoiseResult:
    from meshrepair.mesh.validate import _check_mesh
    from meshrepair.options import check_bool, check_int, check_number

    # every option first (finite, in range), before any work on the mesh
    lam = check_number("lam", lam, low=0, allow_none=True)
    a = check_number("a", a, low=0, low_open=True)
    robust_iters = check_int("robust_iters", robust_iters, low=0, allow_none=True)
    feature_iters = check_int("feature_iters", feature_iters, low=0)
    mask_update_every = check_int("mask_update_every", mask_update_every, low=0)
    min_feature_edges = check_int("min_feature_edges", min_feature_edges, low=1)
    auto_inner = inner_iters is None
    inner_iters = check_int("inner_iters", 3 if auto_inner else inner_iters, low=1)
    tol = check_number("tol", tol, low=0, low_open=True)
    unfold = check_bool("unfold", unfold)
    regions = check_bool("regions", regions)
    polish = check_bool("polish", polish)
    huber_delta = check_number("huber_delta", huber_delta, low=0, low_open=True, allow_none=True)
    willmore_weight = check_number("willmore_weight", willmore_weight, low=0, low_open=True,
                                   allow_none=True)
    if callback is not None and not callable(callback):
        raise MeshRepairError(f"callback must be callable or None, got {type(callback).__name__}")
    if stages is not None:
        stages = tuple(stages)
    SolverOptions(th=th, tol=tol, inner_solver=inner_solver, inner_iters=inner_iters,
                  n_solver=n_solver, mask_update_every=mask_update_every,
                  min_feature_edges=min_feature_edges,
                  **({"stages": stages} if stages else {})).validate()
    report, topo = _check_mesh(V, F, name="input mesh")
    Vr = V if read_from is None else read_from  # round 11x: the readings' vertices
    gamma, gamma_rms = noise_statistics(Vr, F, topo)
    impulsive = is_impulsive(gamma, gamma_rms)
    lam_used = lambda_from_noise(gamma) if lam is None else float(lam)
    delta = huber_from_noise(gamma, gamma_rms) if huber_delta is None else float(huber_delta)
    opts_kw = dict(lam=lam_used, huber_delta=delta, th=th, tol=tol, inner_solver=inner_solver,
                   inner_iters=inner_iters, n_solver=n_solver,
                   mask_update_every=mask_update_every, min_feature_edges=int(min_feature_edges))
    SolverOptions(**opts_kw).validate()  # fail fast on bad options
    log.info("denoise: %d vertices, %d faces, noise estimate %.3f (rms %.3f), lambda %.3g",
             len(V), len(F), gamma, gamma_rms, lam_used)
    Vs = V
    n_unf = 0
    if unfold:
        from meshrepair.model.relax import locally_flipped_faces

        n_unf = int(locally_flipped_faces(V, topo).sum())
        if n_unf:
            Vs, left = untangle(V, topo)
            log.info("unfolded %d folded-over faces (%d left)", n_unf - left, left)
    auto_robust = robust_iters is None and stages is None
    if robust_iters is None:
        robust_iters = robust_iters_from_noise(max(gamma, gamma_rms), n_unf / max(len(F), 1))
    probe = stages is None and regions
    if stages is None:
        stages = default_stages(robust_iters=int(robust_iters), feature_iters=int(feature_iters),
                                a=a, flat_a=FLAT_A if regions else 0.0,
                                robust_a=robust_a_from_noise(max(gamma, gamma_rms)))
    reorder = len(V) >= REORDER_MIN_VERTICES
    if reorder:  # run on a cache-friendly copy, map the result back exactly
        pv, pf = locality_order(Vs, F)
        inv = np.empty_like(pv)
        inv[pv] = np.arange(len(pv))
        Fw, Vw, Vd = inv[F][pf], Vs[pv], V[pv]
        from meshrepair.mesh.topology import edge_topology

        topo_w = edge_topology(Fw, len(V))
    else:
        Fw, Vw, Vd, topo_w = F, Vs, V, topo
    Vd = fidelity_data(Vd, Vw, impulsive)
    Vi = None if Vd is Vw else Vw
    info = {"tangential_ratio": float("nan"), "support_fraction": float("nan"),
            "outside_weight": 1.0,
            "willmore_weight": 1.0, "noise_rho": float("nan"), "noise_length": float("nan"),
            "noise_gamma_scale": float("nan")}
    force = flat = anchor = wedges = None
    r1_V = None
    sup_v = None  # vertices of the crease-supported region, input order
    ww = 1.0 if willmore_weight is None else float(willmore_weight)
    if probe and stages[0].max_iter > 0:
        n1 = int(min(stages[0].max_iter, PROBE_MAX_ITERS))
        st1 = replace(stages[0], max_iter=n1, min_iter=min(stages[0].min_iter, n1))
        # the probe is one stage: its switch rule (in edge units, round 11r) is the stop rule
        q_edges = _sf.radius_in_edges(V, F, topo.edges)  # the mesh's radius in edge lengths
        kw1 = {**opts_kw, "tol": _sf.probe_tol(st1, q_edges) if PROBE_EARLY_STOP else tol}
        Vn_w = V[pv] if reorder else V
        Vt_w = Vr[pv] if reorder else Vr  # round 11x: the tangential ratio's vertices

        def run_probe(kw):
            """The probe; round 11s: to the relative stop, then on to 11r's scale-free stop
            only when that probe already reads crease support (:func:`scalefree.gated_probe`)."""
            if not (PROBE_EARLY_STOP and _sf.two_phase(q_edges)):
                return ADMMSolver(Fw, len(V), options=SolverOptions(stages=(st1,), **kw),
                                  topo=topo_w).solve(Vd, Vi)
            return _sf.gated_probe(ADMMSolver, SolverOptions, Fw, len(V), topo_w, st1, kw,
                                   Vd, Vi, q_edges, th)

        r1 = run_probe(kw1)
        tr = tangential_ratio(Vt_w, Fw, r1.V, topo=topo_w)
        ns = noise_scale(Vn_w, Fw, reference=r1.V, topo=topo_w)
        if willmore_weight is None:
            ww = _clp.keep_white(willmore_weight_from_scale(ns.rho, impulsive, tr), capped)
        if auto_inner and ww > 1.0:  # correlated noise: more V-steps for its long waves,
            inner_iters = inner_iters_from_scale(ns.length)  # in the probe too (its creases)
            opts_kw["inner_iters"] = inner_iters
            if inner_iters != kw1["inner_iters"]:
                kw1["inner_iters"] = inner_iters
                r1 = run_probe(kw1)
                tr = tangential_ratio(Vt_w, Fw, r1.V, topo=topo_w)
        r1_V = r1.V[inv] if reorder else r1.V
        cs = getattr(r1, "crease_support", None)  # read by round 11s's gate on these normals
        sup, net = cs if cs is not None else _cn.supported(topo_w, r1.N, th=th)  # without noise
        info.update(network_branching=net.branching, network_side_spread=net.side_spread,
                    network_dropped=net.dropped, network_rejected=net.rejected)  # round 11d
        force = np.where(sup, -1, 0).astype(np.int8)
        sup_v = np.zeros(len(V), bool)
        sup_v[topo_w.edges[sup].ravel()] = True
        if reorder:
            sup_v = sup_v[inv]
        flat = flat_edges(topo_w, r1.N, sup, max_spread=FLAT_SPREAD_DEFAULT)
        if tr < TANGENTIAL_MAX and sup.any():  # noise along the normals: anchor the CAD region
            anchor = np.zeros(len(V))
            anchor[topo_w.edges[sup].ravel()] = 1.0
        info["tangential_ratio"] = tr
        sf = _sf.cad_support(topo_w, r1.N, sup, q_edges, th=th)  # round 11r: scale-free CAD
        if n_unf and Vd is Vw and not unfolded_data_after_probe(impulsive, tr, sf):
            Vd, Vi = Vn_w, Vw  # noise with a tangential part: the input is the main run's data
        if lam is None and ww > 1.0:  # correlated noise: λ from its level at its own scale
            lam_used = lambda_from_noise(max(gamma, ns.gamma))
            opts_kw["lam"] = lam_used
        w_out = outside_weight(sf, tr) if willmore_weight is None else 1.0
        if w_out != 1.0:  # a CAD part: its smooth patches get the stronger smooth prior
            wedges = np.where(sup, ww, ww * w_out)
        info["outside_weight"] = w_out
        from meshrepair.denoise import organic_fidelity as _of

        if lam is None and _of.applies(sf, ww, w_out, impulsive, ns.rho):
            lam_used = _of.main_lambda(gamma, tr, info, graded=not presmoothed)  # 10l, 11n
            opts_kw["lam"] = lam_used
        info.update(support_fraction=sf, willmore_weight=ww,
                    noise_rho=ns.rho, noise_length=ns.length, noise_gamma_scale=ns.gamma)
        log.info("crease support on %.1f %% of the edges; noise correlation %.2f (length %.1f, "
                 "level %.3f); willmore weight %g", 100 * sup.mean(), ns.rho, ns.length,
                 ns.gamma, ww)

    if sup_v is not None and willmore_weight is None and lam is None and not presmoothed:
        from meshrepair.denoise.presmooth import presmooth_steps  # round 10h: heavy organic noise

        kp = presmooth_steps(gamma, info["tangential_ratio"],
                             support_fraction=info["support_fraction"],
                             outside=info["outside_weight"], willmore=ww, impulsive=impulsive,
                             heavy=_cn.heavy_from_network(info["network_rejected"]))
        kp0, kp = kp, _clp.capped_steps(kp, r1_V, F, topo.edges)  # round 11w: the resolution
        if kp:  # coarse-to-fine: the whole model runs again on the low-passed input
            from meshrepair.denoise.heavylength import (
                heavy_length,  # round 11t: the length reads relief
            )

            kc = kp  # the cap's length (round 11w); 11t may shorten it further
            from meshrepair.denoise.presmooth import presmooth

            Vk = presmooth(V, topo.edges, np.ones(len(V), bool), kc)  # T^k V, read by 11t and 11z
            kp, Vp, hc, hw = heavy_length(V, F, topo.edges, gamma, info["tangential_ratio"], kp,
                                          Vk=Vk)
            from meshrepair.denoise.lengthcheck import (
                checked_length,  # round 11z: the two lengths' risk
            )

            kp, Vp, hd = checked_length(V, F, topo.edges, kp, Vp, kc, hw, X_long=Vk)
            log.info("heavy noise on an organic mesh: %d Taubin pairs on the input first", kp)
            from meshrepair.denoise import layoutkeep as _lk

            Vread = Vp
            if _lk.LAYOUT_KEEP and _lk.PRESMOOTH_KEEP:  # round 11x: the input's layout back,
                Vp = _lk.apply(Vp, V, F, topo.edges, info["tangential_ratio"])  # read on Vread
            r = _denoise(Vp, F, lam=lam, th=th, a=a,
                         robust_iters=None if auto_robust else robust_iters,
                         feature_iters=feature_iters, mask_update_every=mask_update_every,
                         min_feature_edges=min_feature_edges, tol=tol, unfold=unfold,
                         inner_solver=inner_solver,
                         inner_iters=None if auto_inner else inner_iters, n_solver=n_solver,
                         stages=None, huber_delta=huber_delta, willmore_weight=None,
                         regions=regions, callback=callback, polish=False,  # 10h: not polished
                         presmoothed=True, read_from=Vread, capped=kc < kp0)
            r.params.update(presmooth_steps=kp, presmooth_noise_estimate=r.noise_estimate,
                            presmooth_roughness=hc, presmooth_tangential_weight=hw,
                            presmooth_risk_difference=hd,  # round 11z
                            presmooth_network_rejected=info["network_rejected"],
                            presmooth_tangential_ratio=info["tangential_ratio"],
                            presmooth_noise_rho=info["noise_rho"],
                            presmooth_noise_length=info["noise_length"],
                            presmooth_noise_gamma_scale=info["noise_gamma_scale"],
                            presmooth_support_fraction=info["support_fraction"])
            r.noise_estimate = gamma
            from meshrepair.denoise import corrlowpass as _cl

            r.V = _cl.apply(r.V, F, topo, gamma, info, impulsive, V, r1_V)
            r.params.update({k_: info[k_] for k_ in _cl.RECORDED})
            return r
    info["presmooth_steps"] = 0
    Vi_main = Vi  # impulsive noise on a CAD part: the main run starts from the probe
    warm = r1_V is not None and warm_start_from_probe(impulsive, info["outside_weight"], gamma)
    if warm:
        Vi_main = r1.V
    info["start_from_probe"] = bool(warm)

    def solve(stages_):
        """The main run; on a reordered copy the result is mapped back exactly."""
        opts = SolverOptions(stages=tuple(stages_), willmore_weight=ww, **opts_kw)
        res = ADMMSolver(Fw, len(V), options=opts, topo=topo_w, edge_force=force,
                         flat_edges=flat, anchor=anchor, willmore_edges=wedges
                         ).solve(Vd, Vi_main, callback=callback)
        if reorder:
            return res, res.V[inv], _edge_values_to(topo, topo_w, pf, res.M_E)
        return res, res.V, res.M_E

    res, V_out, M_E = solve(stages)
    w_cad = info["outside_weight"]  # the CAD-part decision, read by the polish rule below
    info["discrepancy_ratio"] = float("nan")
    from meshrepair.denoise import discrepancy as _dq

    if wedges is not None and _dq.applies(gamma, gamma_rms) and res.stop_reason != "interrupted":
        # the discrepancy principle on w_out (round 9s): lower it where it smooths away signal
        q = _dq.discrepancy_ratio(V, V_out, F, sup_v, clip=_dq.CLIP * gamma,
                                       edges=topo.edges)
        info["discrepancy_ratio"] = q
        for w_try in _dq.FALLBACK_WEIGHTS:
            if _dq.accept_weight(q):
                break
            wedges = np.where(force < 0, ww, ww * w_try) if w_try != 1.0 else None
            info["outside_weight"] = w_try
            res, V_out, M_E = solve(stages)
            q = _dq.discrepancy_ratio(V, V_out, F, sup_v, clip=_dq.CLIP * gamma,
                                       edges=topo.edges)
            log.info("outside weight lowered to %g (discrepancy ratio %.3f)", w_try, q)
    shrink = _volume_ratio(V, V_out, F, report)
    if shrink is not None and shrink < COLLAPSE_VOLUME_RATIO and res.stop_reason != "interrupted":
        if not auto_robust:
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
        ww = 1.0 if willmore_weight is None else float(willmore_weight)
        lam_used = lambda_from_noise(gamma) if lam is None else float(lam)
        opts_kw["lam"] = lam_used
        stages = default_stages(robust_iters=0, feature_iters=int(feature_iters), a=a,
                                flat_a=FLAT_A if regions else 0.0,
                                robust_a=robust_a_from_noise(max(gamma, gamma_rms)))
        res, V_out, M_E = solve(stages)
        shrink = _volume_ratio(V, V_out, F, report)
        if shrink is not None and shrink < COLLAPSE_VOLUME_RATIO:
            raise MeshRepairError(
                f"denoise collapsed this closed mesh: its volume fell to {shrink:.3g} of the "
                f"input's even without the robust stage ({len(V)} vertices; a mesh this coarse "
                "has no smooth regions for the model); it cannot be denoised")
    V_out = finish_result(V, V_out, F, topo, M_E, data=Vd[inv] if reorder else Vd, sup_v=sup_v,
                          gamma=gamma, gamma_rms=gamma_rms, impulsive=impulsive, ww=ww,
                          w_cad=w_cad, automatic=willmore_weight is None, polish=polish,
                          info=info, probe=r1_V)
    n_res_folded = 0
    if unfold and UNFOLD_RESULT and not (info["reintegrate_steps"] and REINTEGRATE_KEEPS_FOLDS
                                           and not impulsive):
        V_out, n_res_folded = unfold_result(V_out, topo, r1_V)
        if n_res_folded:
            log.info("unfolded %d faces folded over in the result", n_res_folded)
    info.update(corr_lowpass_steps=0, band_beta=float("nan"), band_tau=float("nan"),
                band_length=float("nan"))
    if sup_v is not None and willmore_weight is None and lam is None and not presmoothed:
        from meshrepair.denoise import corrlowpass as _cl

        V_out = _cl.apply(V_out, F, topo, gamma, info, impulsive, V, r1_V)
    return DenoiseResult(
        V=V_out,
        F=F,
        M_E=M_E,
        edges=topo.edges.copy(),
        M_V=res.M_V,
        history=res.history,
        iterations=res.iterations,
        stop_reason=res.stop_reason,
        noise_estimate=gamma,
        params={"lam": lam_used, "th": th, "a": a, "robust_iters": robust_iters,
                "feature_iters": feature_iters, "mask_update_every": mask_update_every,
                "min_feature_edges": min_feature_edges,
                "tol": tol, "inner_solver": inner_solver, "inner_iters": inner_iters,
                "n_solver": n_solver, "unfold": unfold, "n_components": report.n_components,
                "reordered": reorder, "huber_delta": delta, "impulsive": impulsive,
                "regions": probe,
                "fidelity_data": "input" if (Vd is not Vw or not n_unf) else "unfolded",
                "result_folds_unfolded": n_res_folded, **info},
        n_unfolded=n_unf,
    )
