"""The reading and the plan of a denoise call (:func:`_plan`): the options checked, the noise
level and its outliers (:func:`~meshrepair.model.noise.noise_statistics`), the fold-overs, the
robust probe deciding the crease-supported region C (5), the noise's direction
(:func:`~meshrepair.denoise.scale.tangential_ratio`) and its correlation across scales
(:func:`~meshrepair.denoise.scale.noise_scale`), and every decision read from them; the result
is a frozen :class:`~meshrepair.denoise.plan.DenoisePlan`. The main solve is
:mod:`meshrepair.denoise.execute`'s.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from meshrepair.denoise import coarse_lowpass as _clp
from meshrepair.denoise import crease_network as _cn
from meshrepair.denoise import scalefree as _sf
from meshrepair.denoise import structure as _structure
from meshrepair.denoise.checks import _checked
from meshrepair.denoise.corrwhite import BandRead, band_read
from meshrepair.denoise.folds import fidelity_data, unfolded_data_after_probe, unfolded_input
from meshrepair.denoise.plan import (
    RECORD_FIELDS,
    Decision,
    DenoisePlan,
    _State,
    mesh_key,
    planned_values,
)
from meshrepair.denoise.regions import flat_edges
from meshrepair.denoise.rules import (
    CAD_SUPPORT,
    CAD_WILLMORE,
    FLAT_A,
    FLAT_SPREAD_DEFAULT,
    HEAVY_NOISE,
    HEAVY_SLOPE,
    IMPULSIVE_RATIO,
    PROBE_EARLY_STOP,
    PROBE_MAX_ITERS,
    TANGENTIAL_MAX,
    WARM_IMPULSIVE_GAMMA,
    huber_from_noise,
    inner_iters_from_scale,
    is_impulsive,
    lambda_from_noise,
    outside_weight,
    robust_a_from_noise,
    robust_iters_from_noise,
    warm_start_from_probe,
    willmore_weight_from_band,
    willmore_weight_from_scale,
)
from meshrepair.denoise.scale import noise_scale, tangential_ratio
from meshrepair.mesh.reorder import reordered
from meshrepair.model.noise import noise_statistics
from meshrepair.model.schedule import default_stages
from meshrepair.model.solver import ADMMSolver, SolverOptions, StopRequested

log = logging.getLogger("meshrepair.denoise.run")

REORDER_MIN_VERTICES = 200_000
"""Meshes this large are solved in a Morton (Z-curve) order of vertices and faces: every kernel
is memory-bound there, and the reordering measured 1.33 s instead of 1.76 s per iteration on a
1.18M-vertex subdivided mesh. Smaller meshes keep their order (results then do not depend on a
coordinate-dependent ordering, which keeps the rotation test exact to rounding)."""


def _plan(V, F, *, digest: bool = True, probe_result=None, checked=None, progress=None,
          **options) -> DenoisePlan:
    """Read ``(V, F)`` and decide (module docstring); returns the plan, runs no main solve.

    When the reading finds correlated noise (an automatic Willmore weight above 1: the
    profile's, or where the profile reads white the band read's, :func:`_band`), the plan is
    the white-noise model's, read from the same probe, and carries the correlated-noise model's
    plan in ``if_correlated``: the executor runs the white model first and the correlated one
    only when the white result's residual fails the white-noise test of
    :mod:`meshrepair.denoise.whiteness`. A CAD part's plan on white noise carries the organic
    reading's plan in ``if_structured`` (:mod:`meshrepair.denoise.structure`). ``digest``:
    record the digest of ``(V, F)`` that :func:`~meshrepair.denoise.execute._execute` checks
    (off when the caller runs the plan on these arrays at once). ``probe_result``: a robust
    probe already run on an input of this connectivity and vertex order (:func:`_plan_one`);
    the plan reads it instead of running its own. ``checked``: the ``(report, topology)`` of
    :func:`meshrepair.mesh.validate._check_mesh` on these arrays, when the caller has it.
    ``progress``: called with each iteration entry of the probes (:func:`_probe_stopped`)."""
    memo: dict = {} if checked is None else {"check": checked}  # the readings of this input
    p = _plan_one(V, F, digest=digest, probe_result=probe_result, memo=memo, progress=progress,
                  **options)
    first, p._state.first_probe = p._state.first_probe, None
    auto = options.get("willmore_weight") is None
    band = _band(V, F, p, memo) if auto and p.willmore_weight <= 1.0 else None
    if not auto or (p.willmore_weight <= 1.0 and band is None):
        if not _structure.applies(p, options):
            return _sealed(p)
        po = _plan_one(V, F, digest=digest, **options, organic=True, probe_result=first,
                       memo=memo)
        po._state.first_probe = None
        return _sealed(replace(p, if_structured=po))
    if band is not None:  # the profile reads white noise, the band read correlated noise
        pw, p = p, _plan_one(V, F, digest=digest, **options, probe_result=first, memo=memo,
                             band=band)
    else:
        pw = _plan_one(V, F, digest=digest, **options, white=True, probe_result=first,
                       memo=memo)
    pw._state.first_probe = p._state.first_probe = None
    from meshrepair.denoise.whiteness import LEVEL_MAX, RHO1_MAX

    dec = Decision("noise_model", "white, tested",
                   "the reading finds correlated noise (willmore_weight "
                   f"{p.willmore_weight:.3g}); the white model runs first and the correlated "
                   f"plan below only if the residual fails the white-noise test (one-ring "
                   f"correlation ρ₁ > {RHO1_MAX:g} or level > {LEVEL_MAX:g} γ̂; whiteness.py)",
                   {"rho": p.reading["noise_rho"], "willmore_weight": p.willmore_weight})
    return _sealed(replace(pw, decisions=pw.decisions + (dec,), if_correlated=p))


def _plan_one(V, F, *, lam, th, a, robust_iters, feature_iters, mask_update_every,
              min_feature_edges, tol, unfold, inner_solver, inner_iters, n_solver, stages,
              huber_delta, willmore_weight, regions, polish=True,
              presmoothed: bool = False, read_from: np.ndarray | None = None,
              capped: bool = False, white: bool = False, organic: bool = False,
              probe_result=None, digest: bool = True,
              memo: dict | None = None, band: BandRead | None = None,
              progress=None) -> DenoisePlan:
    """One noise model's plan: the white model's with ``white`` (Willmore weight 1), else the
    reading's; with ``organic``, the crease support is not taken as a CAD part (the organic
    alternative of :mod:`meshrepair.denoise.structure`); ``probe_result`` is a probe already
    run on this input (not run again); ``memo``: the readings of an earlier plan of the same
    input and probe (:func:`_once`), read from there instead of again; ``band``: the band read
    of correlated noise that the profile reads white (:func:`_band`), whose weight the plan
    takes."""
    from meshrepair.mesh.validate import _check_mesh

    options = _checked(lam, th, a, robust_iters, feature_iters, mask_update_every,
                       min_feature_edges, tol, unfold, inner_solver, inner_iters, n_solver,
                       stages, huber_delta, willmore_weight, regions, polish)
    stages = options["stages"]
    auto_inner = inner_iters is None
    inner_iters = 3 if auto_inner else options["inner_iters"]
    dec: list[Decision] = []
    report, topo = _once(memo, "check", lambda: _check_mesh(V, F, name="input mesh"))
    Vr = V if read_from is None else read_from  # the readings' vertices
    gamma, gamma_rms, gamma_iso = _once(memo, "noise", lambda: noise_statistics(
        Vr, F, topo, isolated=True))
    impulsive = is_impulsive(gamma, gamma_iso)
    lam_used = lambda_from_noise(gamma, lowpassed=presmoothed) if lam is None else float(lam)
    delta = huber_from_noise(gamma_rms, impulsive) if huber_delta is None else float(huber_delta)
    rule = (f"huber_from_noise: 2 γ̂_rms when γ̂_rms,iso > {IMPULSIVE_RATIO:g} γ̂ (impulsive; "
            "the RMS without coherent relief), else 0")
    dec.append(Decision("huber_delta", delta, "set by the user" if huber_delta is not None
                        else rule, {"gamma": gamma, "gamma_rms": gamma_rms,
                                    "gamma_rms_isolated": gamma_iso},
                        huber_delta is not None))
    opts_kw = dict(lam=lam_used, huber_delta=delta, th=th, tol=tol, inner_solver=inner_solver,
                   inner_iters=inner_iters, n_solver=n_solver,
                   mask_update_every=mask_update_every, min_feature_edges=int(min_feature_edges))
    SolverOptions(**opts_kw).validate()  # fail fast on bad options
    log.info("denoise: %d vertices, %d faces, noise estimate %.3f (rms %.3f), lambda %.3g",
             len(V), len(F), gamma, gamma_rms, lam_used)
    Vs, n_unf = _once(memo, "unfold", lambda: unfolded_input(V, topo)) if unfold else (V, 0)
    auto_robust = robust_iters is None and stages is None
    if robust_iters is None:
        robust_iters = robust_iters_from_noise(max(gamma, gamma_rms), n_unf / max(len(F), 1))
    probe = stages is None and regions
    if stages is None:
        stages = default_stages(robust_iters=int(robust_iters), feature_iters=int(feature_iters),
                                a=a, flat_a=FLAT_A if regions else 0.0,
                                robust_a=robust_a_from_noise(max(gamma, gamma_rms)))
        dec.append(Decision("robust_iters", int(robust_iters), "set by the user"
                            if not auto_robust else "robust_iters_from_noise: clip(130 γ̂, 10, "
                            "40); 40 with > 1 % folded faces; 40 + "
                            f"{HEAVY_SLOPE:g} (γ̂ − {HEAVY_NOISE:g}) up to 120 above "
                            f"γ̂ = {HEAVY_NOISE:g}",
                            {"gamma_max": max(gamma, gamma_rms),
                             "folded_fraction": n_unf / max(len(F), 1)}, not auto_robust))
    else:
        dec.append(Decision("stages", len(stages), "set by the user: no probe, no region "
                            "decisions", by_user=True))
    reorder = len(V) >= REORDER_MIN_VERTICES
    pf = inv = None
    if reorder:  # run on a cache-friendly copy, map the result back exactly
        pv, pf, inv, Fw, topo_w = _once(memo, "reorder", lambda: reordered(Vs, F, topo))
        V_pv = V[pv]  # (read only: shared by the fidelity data and the readings below)
        Vw, Vd = Vs[pv], V_pv
    else:
        Fw, Vw, Vd, topo_w = F, Vs, V, topo
    Vd = fidelity_data(Vd, Vw, impulsive)
    Vi = None if Vd is Vw else Vw
    info = {"tangential_ratio": float("nan"), "support_fraction": float("nan"),
            "outside_weight": 1.0,
            "willmore_weight": 1.0, "noise_rho": float("nan"), "noise_length": float("nan"),
            "noise_gamma_scale": float("nan"), "gamma_relief": float("nan")}
    force = flat = anchor = None
    sup = r1 = r1_V = first_probe = None
    sup_v = None  # vertices of the crease-supported region, input order
    w_out = 1.0
    ww = 1.0 if willmore_weight is None else float(willmore_weight)
    rule_lam = "lambda_from_noise: max(0.02 / γ̂², 0.05)" + (
        ", at most 1 (low-passed data)" if presmoothed else "")
    if probe and stages[0].max_iter > 0:
        n1 = int(min(stages[0].max_iter, PROBE_MAX_ITERS))
        st1 = replace(stages[0], max_iter=n1, min_iter=min(stages[0].min_iter, n1))
        # the probe is one stage: its switch rule, in edge units, is the stop rule
        # the mesh's radius in edge lengths
        q_edges = _once(memo, "radius", lambda: _sf.radius_in_edges(V, F, topo.edges))
        kw1 = {**opts_kw, "tol": _sf.probe_tol(st1, q_edges) if PROBE_EARLY_STOP else tol}
        Vn_w = V_pv if reorder else V
        # the tangential ratio's vertices
        Vt_w = (V_pv if Vr is V else Vr[pv]) if reorder else Vr

        def run_probe(kw):
            """The probe: to the relative stop, then on to the scale-free stop only when that
            probe already reads crease support (:func:`scalefree.gated_probe`)."""
            if not (PROBE_EARLY_STOP and _sf.two_phase(q_edges)):
                return ADMMSolver(Fw, len(V), options=SolverOptions(stages=(st1,), **kw),
                                  topo=topo_w).solve(Vd, Vi, callback=progress)
            return _sf.gated_probe(ADMMSolver, SolverOptions, Fw, len(V), topo_w, st1, kw,
                                   Vd, Vi, q_edges, th, callback=progress)

        r1 = _probe_stopped(run_probe(kw1) if probe_result is None else probe_result)
        first_probe = r1  # the one probe of the call, shared by both noise models' plans
        tr = _once(memo, "tangential", lambda: tangential_ratio(Vt_w, Fw, r1.V, topo=topo_w))
        ns = _once(memo, "scale", lambda: noise_scale(Vn_w, Fw, reference=r1.V, topo=topo_w))
        if willmore_weight is None:
            ww = 1.0 if white else _clp.keep_white(
                willmore_weight_from_scale(ns.rho, impulsive, tr), capped)
        rule = (f"willmore_weight_from_scale: clip(1 + 150 (ρ − 1.12), 1, 16) for noise "
                f"along the normals (r_t < {TANGENTIAL_MAX:g}), not impulsive; else 1")
        reads = {"rho": ns.rho, "tangential_ratio": tr, "impulsive": float(impulsive)}
        if band is not None and willmore_weight is None:
            ww = willmore_weight_from_band(band.steps)
            rule = ("willmore_weight_from_band: clip(4 m̂, 1, 16), the profile reading white "
                    "noise and the two-octave band read m̂ ≥ 1 diffusion steps (band_correlated, "
                    "corrlowpass.py)")
            reads.update(band_beta=band.beta, band_tau=band.tau, band_steps=band.steps)
        if white:
            rule = ("the white-noise model, tried first when the reading finds correlated "
                    "noise (noise_model)")
        dec.append(Decision("willmore_weight", ww, "set by the user" if willmore_weight
                            is not None else rule, reads, willmore_weight is not None))
        if auto_inner and ww > 1.0:  # correlated noise: more V-steps for its long waves
            inner_iters = inner_iters_from_scale(ns.length)  # (the probe is not run again)
            opts_kw["inner_iters"] = inner_iters
        r1_V = r1.V[inv] if reorder else r1.V
        cs = getattr(r1, "crease_support", None)  # the gate's read on these normals
        sup, net = cs if cs is not None else _once(memo, "support", lambda: _cn.supported(
            topo_w, r1.N, th=th))
        info.update(network_branching=net.branching, network_side_spread=net.side_spread,
                    network_dropped=net.dropped, network_rejected=net.rejected)
        force = np.where(sup, -1, 0).astype(np.int8)
        sup_v = np.zeros(len(V), bool)
        sup_v[topo_w.edges[sup].ravel()] = True
        if reorder:
            sup_v = sup_v[inv]
        flat = _once(memo, "flat", lambda: flat_edges(topo_w, r1.N, sup,
                                                       max_spread=FLAT_SPREAD_DEFAULT))
        if tr < TANGENTIAL_MAX and sup.any():  # noise along the normals: anchor the CAD region
            anchor = np.zeros(len(V))
            anchor[topo_w.edges[sup].ravel()] = 1.0
        dec.append(Decision("tangential_anchor", anchor is not None,
                            "on C when the noise lies along the normals (r_t < "
                            f"{TANGENTIAL_MAX:g})",
                            {"tangential_ratio": tr, "crease_edges": float(sup.sum())}))
        info["tangential_ratio"] = tr
        sf = _once(memo, "cad", lambda: _sf.cad_support(  # scale-free CAD support
            topo_w, r1.N, sup, q_edges, th=th))
        if n_unf and Vd is Vw and not unfolded_data_after_probe(impulsive, tr, sf):
            Vd, Vi = Vn_w, Vw  # noise with a tangential part: the input is the main run's data
        sf_read = sf
        if organic:  # the organic alternative of a CAD plan (structure.py)
            dec.append(_structure.organic_decision(sf))
            sf = 0.0
        if lam is None and ww > 1.0:  # correlated noise: λ from its level at its own scale
            lam_used = lambda_from_noise(max(gamma, ns.gamma), lowpassed=presmoothed)
            opts_kw["lam"] = lam_used
            rule_lam = "lambda_from_noise at the noise's own scale: max(γ̂, γ̂_scale)"
        w_out = outside_weight(sf, tr) if willmore_weight is None else 1.0
        info["outside_weight"] = w_out
        rule = (f"outside_weight: {CAD_WILLMORE:g} off the creases of a CAD part (crease "
                f"support ≥ {CAD_SUPPORT:g}) with noise along the normals (r_t < "
                f"{TANGENTIAL_MAX:g}); else 1")
        dec.append(Decision("outside_weight", w_out, rule, {"support_fraction": sf,
                                                            "tangential_ratio": tr}))
        from meshrepair.denoise import organic_fidelity as _of

        if lam is None and _of.applies(sf, ww, w_out, impulsive, ns.rho):
            g_relief = _once(memo, "relief", lambda: noise_statistics(  # the probe keeps
                r1.V, Fw, topo_w)[0])  # the relief
            info["gamma_relief"] = g_relief
            sigma = _of.noise_level(gamma, g_relief)
            lam_used = _of.main_lambda(sigma, tr, info, graded=not presmoothed)
            opts_kw["lam"] = lam_used
            rule_lam = ("organic_fidelity.main_lambda: λ of an organic mesh with white noise, "
                        "at the noise level σ̂ = √(γ̂² − γ̂_relief²) (the probe's γ̂ reads the "
                        "relief)")
        info.update(support_fraction=sf, willmore_weight=ww,
                    noise_rho=ns.rho, noise_length=ns.length, noise_gamma_scale=ns.gamma)
        log.info("crease support on %.1f %% of the edges; noise correlation %.2f (length %.1f, "
                 "level %.3f); willmore weight %g", 100 * sup.mean(), ns.rho, ns.length,
                 ns.gamma, ww)
    else:
        dec.append(Decision("probe", False, "off: custom stages or regions=False" if
                            (options["stages"] is not None or not regions) else
                            "off: a robust stage of 0 iterations",
                            by_user=options["stages"] is not None or not regions))
    lam_reads = {"gamma": gamma}
    if rule_lam.startswith("organic_fidelity"):
        lam_reads["tangential_ratio"] = info["tangential_ratio"]
        lam_reads["gamma_relief"] = info["gamma_relief"]
    elif "own scale" in rule_lam:
        lam_reads["gamma_scale"] = info["noise_gamma_scale"]
    dec.insert(0, Decision("lam", lam_used, "set by the user" if lam is not None else rule_lam,
                           lam_reads, lam is not None))
    if inner_iters != 3 or not auto_inner:
        dec.append(Decision("inner_iters", inner_iters, "set by the user" if not auto_inner else
                            "inner_iters_from_scale: more V-steps for correlated noise",
                            {"noise_length": info["noise_length"]}, not auto_inner))
    st = _State(topo=topo, report=report, gamma=gamma, gamma_rms=gamma_rms, impulsive=impulsive,
                n_unf=n_unf, reorder=reorder, Fw=Fw, topo_w=topo_w, pf=pf, inv=inv, Vw=Vw,
                Vd=Vd, Vi=Vi, opts_kw=opts_kw, force=force, flat=flat, anchor=anchor, sup=sup,
                sup_v=sup_v, r1=r1, r1_V=r1_V, info=info, auto_robust=auto_robust,
                auto_inner=auto_inner, robust_iters=int(robust_iters), probe=bool(probe),
                presmoothed=bool(presmoothed), mesh_key=mesh_key(V, F) if digest else "",
                first_probe=first_probe, band=band)
    kp = 0
    inner_plan = None
    if sup_v is not None and willmore_weight is None and lam is None and not presmoothed:
        kp, inner_plan = _plan_presmooth(V, F, st, options, dec=dec, progress=progress)
    elif sup_v is not None and not presmoothed:
        dec.append(Decision("presmooth_steps", 0, "off: lam or willmore_weight set by the "
                            "user (the coarse-to-fine low-pass and the correlated low-pass "
                            "read automatic weights only)", by_user=True))
    warm = r1_V is not None and warm_start_from_probe(impulsive, info["outside_weight"], gamma)
    if r1_V is not None:
        dec.append(Decision("start_from_probe", bool(warm), "warm_start_from_probe: impulsive "
                            "noise on a CAD part (outside weight > 1) above γ̂ = "
                            f"{WARM_IMPULSIVE_GAMMA:g} starts the main solve from the probe",
                            {"impulsive": float(impulsive), "outside_weight": w_out,
                             "gamma": gamma}))
    dec.append(Decision("fidelity_data", "input" if (Vd is not Vw or not n_unf) else
                        "unfolded", "fidelity_data / unfolded_data_after_probe: the unfolded "
                        "input for impulsive noise along the normals", {"folded": n_unf}))
    if reorder:
        dec.append(Decision("reorder", True, f"Morton order: ≥ {REORDER_MIN_VERTICES} vertices",
                            {"vertices": len(V)}))
    for t in {id(topo): topo, id(topo_w): topo_w}.values():  # the readings' operators: the
        t.drop_cache(keep=("interior_edges",))  # main solve keeps only the solver's tables
    reading = {"gamma": gamma, "gamma_rms": gamma_rms, "gamma_rms_isolated": gamma_iso,
               "impulsive": bool(impulsive),
               "folded_faces": n_unf, **{k: info[k] for k in
                                         ("tangential_ratio", "support_fraction", "noise_rho",
                                          "noise_length", "noise_gamma_scale")}}
    if organic:  # the value read; the plan's gates saw 0
        reading["support_fraction"] = sf_read
    if np.isfinite(info["gamma_relief"]):  # read where the organic law's σ̂ needs it
        reading["gamma_relief"] = info["gamma_relief"]
    plan = DenoisePlan(
        n_vertices=len(V), n_faces=len(F), options=options, reading=reading, lam=lam_used,
        huber_delta=delta, willmore_weight=ww, outside_weight=w_out, inner_iters=inner_iters,
        stages=tuple(stages), start_from_probe=bool(warm), presmooth_steps=int(kp),
        polish=options["polish"], decisions=tuple(dec), inner=inner_plan, _state=st)
    st.planned = planned_values(plan)  # what the executor compares a user's edits against
    return _sealed(plan)


def _sealed(plan: DenoisePlan) -> DenoisePlan:
    """``plan`` with its record fields (:data:`~meshrepair.denoise.plan.RECORD_FIELDS`) noted in
    its state as made, so that an edit of them is refused (the executor's ``_check_edits``)."""
    plan._state.record = {k: getattr(plan, k) for k in RECORD_FIELDS}
    return plan


def _band(V, F, p: DenoisePlan, memo: dict) -> BandRead | None:
    """The band read of :mod:`meshrepair.denoise.corrwhite` on the input against the probe's
    result, where branch 2 of :mod:`meshrepair.denoise.corrlowpass` needs it (an organic mesh,
    not impulsive, ``γ̂ > γ_1``) and the plan has no coarse-to-fine run (that run's own plan
    reads its low-passed input). It is kept on ``p`` (its low-pass reads it after the solve);
    returned when it reads correlated noise (:func:`~meshrepair.denoise.corrlowpass.
    band_correlated`), else ``None``."""
    from meshrepair.denoise import corrlowpass as _cl

    st = p._state
    if st is None or st.r1_V is None or st.presmooth is not None:
        return None
    kw = dict(support_fraction=st.info["support_fraction"], outside=p.outside_weight,
              impulsive=st.impulsive)
    if not _cl.band_gate(st.gamma, **kw):
        return None
    st.band = _once(memo, "band", lambda: band_read(V, F, reference=st.r1_V, topo=st.topo))
    b = st.band
    log.info("band read: beta %.3f, tau %.3f, %d diffusion steps", b.beta, b.tau, b.steps)
    return b if _cl.band_correlated(st.gamma, b.tau, b.steps) else None


def _probe_stopped(r):
    """The probe's result ``r``, or the user's stop it ended by raised again: a probe that a
    Ctrl-C (``KeyboardInterrupt``) or the progress callback (:class:`StopRequested`) stopped
    read part of the input, and no plan is made from it."""
    if r.stop_reason == "interrupted":
        raise KeyboardInterrupt
    if r.stop_reason == "callback":
        raise StopRequested("the reading of the input (the probe) was stopped by the callback")
    return r


def _once(memo: dict | None, key: str, read):
    """``read()``, computed once per :func:`_plan` call: the plans it makes of one input (the
    white and the correlated model's, the CAD and the organic reading's) read the same arrays
    and the same probe, so each reading is a pure function of what the first plan read.
    ``memo=None``: always computed."""
    if memo is None:
        return read()
    if key not in memo:
        memo[key] = read()
    return memo[key]


def _plan_presmooth(V, F, st: _State, options: dict, *, dec: list, progress=None):
    """The coarse-to-fine decision: Taubin pairs ``k`` on the input for heavy noise on an
    organic mesh (:func:`presmooth_steps`), capped at the mesh's resolution and shortened
    where the low-passed input reads relief at the mesh's scale; with ``k > 0`` the plan of the
    low-passed input."""
    from meshrepair.denoise.heavylength import heavy_length
    from meshrepair.denoise.presmooth import presmooth, presmooth_steps

    info, topo = st.info, st.topo
    kp = presmooth_steps(st.gamma, info["tangential_ratio"],
                         support_fraction=info["support_fraction"],
                         outside=info["outside_weight"], willmore=info["willmore_weight"],
                         impulsive=st.impulsive,
                         heavy=_cn.heavy_from_network(info["network_rejected"]))
    kp0, kp = kp, _clp.capped_steps(kp, st.r1_V, F, topo.edges)
    reads = {"gamma": st.gamma, "tangential_ratio": info["tangential_ratio"],
             "support_fraction": info["support_fraction"], "steps_before_cap": kp0}
    if not kp:
        dec.append(Decision("presmooth_steps", 0, "presmooth_steps: heavy noise on an organic "
                            "mesh only", reads))
        return 0, None
    kc = kp  # the resolution cap's length; the relief read may shorten it further
    Vk = presmooth(V, topo.edges, np.ones(len(V), bool), kc)
    kp, Vp, hc, hw = heavy_length(V, F, topo.edges, st.gamma, info["tangential_ratio"], kp,
                                  Vk=Vk)
    log.info("heavy noise on an organic mesh: %d Taubin pairs on the input first", kp)
    from meshrepair.denoise import layoutkeep as _lk

    Vread = Vp
    if _lk.LAYOUT_KEEP and _lk.PRESMOOTH_KEEP:  # the input's vertex layout back
        Vp = _lk.apply(Vp, V, F, topo.edges, info["tangential_ratio"])
    o = options
    inner = _plan(Vp, F, lam=None, th=o["th"], a=o["a"],
                  robust_iters=None if st.auto_robust else o["robust_iters"],
                  feature_iters=o["feature_iters"], mask_update_every=o["mask_update_every"],
                  min_feature_edges=o["min_feature_edges"], tol=o["tol"], unfold=o["unfold"],
                  inner_solver=o["inner_solver"],
                  inner_iters=None if st.auto_inner else o["inner_iters"],
                  n_solver=o["n_solver"], stages=None, huber_delta=o["huber_delta"],
                  willmore_weight=None, regions=o["regions"], polish=False,
                  presmoothed=True, read_from=Vread, capped=kc < kp0,
                  digest=bool(st.mesh_key), progress=progress)
    for q in (inner, inner.if_correlated):  # the raw input, for the final low-pass
        if q is not None and q._state is not None:
            q._state.lowpassed_from = (V, int(kp))
    st.presmooth = {"Vp": Vp, "steps": int(kp), "roughness": hc, "tangential_weight": hw}
    dec.append(Decision("presmooth_steps", int(kp), "presmooth_steps → capped_steps → "
                        "heavy_length: heavy noise on an organic mesh is low-passed first, the "
                        "whole model then runs on the result",
                        {**reads, "steps_after_cap": kc, "roughness": hc,
                         "tangential_weight": hw}))
    return kp, inner
