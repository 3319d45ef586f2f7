"""The steps after the solve of :func:`meshrepair.denoise`.

Each step reads the decisions the plan recorded in ``info`` (docs/parameters.md) and records its
own (they appear in ``DenoiseResult.plan.after_solve``), in this order:

1. *polish* (heavy noise on CAD parts, correlated noise;
   :func:`~meshrepair.denoise.rules.polish_rule`, :mod:`meshrepair.denoise.polish` with the
   solve's data term, :mod:`meshrepair.denoise.polish_fidelity`);
2. *low-pass* of the smooth region of organic meshes with white noise
   (:mod:`meshrepair.denoise.lowpass`);
3. *tangential re-anchoring* of the smooth region (:data:`REANCHOR`,
   :mod:`meshrepair.denoise.reproject`);
4. *organic finish*: one-ring guidance, then the re-integration from the input
   (:mod:`meshrepair.denoise.organic`, :func:`~meshrepair.denoise.rules.guidance_rule`,
   :func:`~meshrepair.denoise.rules.reintegrate_rule`);
4b. *longer low-pass* where the result is smooth at the mesh's resolution, its length the one
   of least estimated risk (SURE) of the same low-pass on the input
   (:mod:`meshrepair.denoise.coarse`);
5. *CAD finish*: the one-ring guidance on CAD parts (:mod:`meshrepair.denoise.cadfinish`);
6. *crease sharpening* for correlated noise (:func:`~meshrepair.denoise.rules.sharpen_rule`,
   :mod:`meshrepair.denoise.modes`).

The rules are mutually exclusive where they would act on the same faces (the organic and CAD
finishes need white noise, the sharpening correlated noise). The unfolding of faces still folded
in the result runs after these steps, in :mod:`meshrepair.denoise.execute`.
"""

from __future__ import annotations

import logging

import numpy as np

from meshrepair.denoise.rules import (
    HEAVY_NOISE,
    guidance_rule,
    polish_rule,
    reintegrate_rule,
    sharpen_rule,
)

log = logging.getLogger("meshrepair.denoise.api")

POLISH_DATA = True
"""The polish's vertex step keeps the fidelity to the solve's data: a forward-backward step, the
Sun et al. step then the proximal map of ``(η/2)‖x − V⁰‖²``
(:mod:`meshrepair.denoise.polish_fidelity`), so the polish cannot drift from the data."""

REANCHOR = True
REANCHOR_MAX_RATIO = 0.6
"""Tangential re-anchoring of the smooth region after the solve
(:mod:`meshrepair.denoise.reproject`): the result's vertices outside the crease-supported region
slide along the result surface towards the input's closest points, with the minimum-variance
weights of :func:`meshrepair.denoise.reproject.blend_weights`, when the residual tangential
ratio :func:`meshrepair.denoise.reproject.residual_tangential_ratio` reads noise along the
normals (``ρ_t < 0.6``) and the noise is not heavy (``γ̂ ≤ HEAVY_NOISE``); the targets are
smoothed tangentially first (:func:`meshrepair.denoise.reproject.tangential_smooth`). The
normal part of the noise is removed by the solve; its tangential part, which no normal-driven
V-update sees, is what the re-anchoring takes back towards the data. It runs before
:func:`unfold_result`, whose probe check then judges the final positions."""


def _reanchor_smooth(V_in, V_out, F, topo, sup_v, gamma, info):
    """:data:`REANCHOR` on the vertices outside ``sup_v``; records its decision in ``info``."""
    from meshrepair.denoise.organic_fidelity import reanchor_ratio_at_ungraded
    from meshrepair.denoise.reproject import reanchor, residual_tangential_ratio

    ratio = residual_tangential_ratio(V_out, V_in, F)
    info["reanchor_ratio"] = ratio  # as read; the test reads it at the default law's weight
    ratio = reanchor_ratio_at_ungraded(ratio, info.get("lambda_gain", 1.0))
    if not (ratio < REANCHOR_MAX_RATIO) or gamma > HEAVY_NOISE:
        return V_out
    V_new, w = reanchor(V_out, V_in, F, ~sup_v, topo=topo)
    info["reanchored"] = int((w > 0).sum())
    el = float(np.linalg.norm(V_in[topo.edges[:, 0]] - V_in[topo.edges[:, 1]], axis=1).mean())
    shift = np.sqrt(np.mean(np.sum((V_new - V_out) ** 2, axis=1)))
    info["reanchor_shift"] = float(shift / el) if el > 0 else 0.0  # mean edge lengths
    log.info("re-anchored %d smooth-region vertices tangentially (residual ratio %.2f)",
             info["reanchored"], ratio)
    return V_new


REINTEGRATE_KEEPS_FOLDS = True
"""After the re-integration from the input of Gaussian noise along the normals, the faces
folded in the result follow the input's own vertex layout (a layout the truth shares), so they
are kept; impulsive noise folds faces around its thrown vertices, and those are unfolded."""


REINTEGRATE_POST_STEPS = 5
"""Sun et al. steps of the guidance pass that follows the re-integration: the re-integrated
vertices carry the input's one-ring jitter along the normals that the ``k`` steps left, and one
more filter pass of these steps removes it."""


def _organic_finish(V_in, V_out, F, topo, M_E, gamma, impulsive, ww, info):
    """The organic finish (:mod:`meshrepair.denoise.organic`): the one-ring guidance filter on
    organic meshes
    (:func:`guidance_rule`), then the re-integration from the input (:func:`reintegrate_rule`);
    records its decisions in ``info``."""
    from meshrepair.denoise.organic import guidance_filter, reintegrate, residual_level
    from meshrepair.denoise.reproject import residual_tangential_ratio

    p = guidance_rule(gamma, info["outside_weight"], ww)
    if p == 0:
        return V_out
    X = guidance_filter(V_out, F, M_E, topo, passes=p)
    info["guidance_passes"] = p
    reanchored = info.get("reanchored", 0) > 0
    ratio = residual_tangential_ratio(V_out, V_in, F) if reanchored else float("nan")
    info["reanchor_ratio_after"] = ratio
    level = residual_level(V_out, V_in, F) / max(gamma, 1e-12)
    info["residual_level_ratio"] = level
    k = reintegrate_rule(p, reanchored, impulsive, ratio, gamma, level)
    from meshrepair.denoise.organic_fidelity import reintegrate_allowed

    if not reintegrate_allowed(info["tangential_ratio"], impulsive):  # the data weight's gate
        k = 0
    if k:  # then one more guidance pass with half the steps (REINTEGRATE_POST_STEPS)
        from meshrepair.denoise.folds import reintegration_keeps
        from meshrepair.model.relax import locally_flipped_faces as _folded

        Xr = reintegrate(V_out, V_in, F, X, steps=k)
        nr, ng = int(_folded(Xr, topo).sum()), int(_folded(X, topo).sum())
        if reintegration_keeps(ratio, nr, ng):  # no in-plane folds put back
            X = guidance_filter(Xr, F, M_E, topo, passes=1, steps=REINTEGRATE_POST_STEPS)
            info["reintegrate_steps"] = k
        else:
            info["reintegrate_rejected"] = nr - ng
            log.info("re-integration not kept: %d more folded faces than its target", nr - ng)
    log.info("organic finish: %d guidance passes, %d re-integration steps (ratio %.2f)",
             p, k, ratio)
    return X


def finish_result(V, V_out, F, topo, M_E, *, data, sup_v, gamma, gamma_rms, impulsive, ww,
                  w_cad, automatic, polish, info, probe=None,
                  lowpassed=False, lowpassed_from=None, lam_set=False, band_model=False):
    """Steps 1-6 of the module docstring on the solve's result ``V_out`` (input order).

    Parameters
    ----------
    V : (nV, 3) float64, the input vertices; ``data`` the solve's fidelity data (input order)
    V_out : (nV, 3) float64, the solve's result
    F : (nF, 3) int64; ``topo`` its edge topology; ``M_E`` (nE,) the converged sharp-edge mask
    sup_v : (nV,) bool or None, the crease-supported region (None: no probe ran)
    gamma, gamma_rms : the noise estimates; ``impulsive`` the outlier decision
    ww : the Willmore weight used; ``w_cad`` the probe's outside-weight (CAD-part) decision
    automatic : the Willmore weight was read from the input (not set by the user)
    polish : the user's ``polish`` switch
    info : dict, the decisions so far; updated in place with each step's
    probe : (nV, 3) float64 or None, the robust probe's result (the reference of the unfolding
        of the result, :func:`meshrepair.denoise.folds.unfold_result`)
    lowpassed : ``V`` is the low-passed input ``T^{k_p} y`` of the coarse-to-fine run
    lowpassed_from : ``(y, k_p)`` of that run, or None (no coarse low-pass on a low-passed ``V``)
    lam_set : the user set λ (no coarse low-pass: its length would override that fidelity)
    band_model : ``ww`` is the band read's correlated model
        (:func:`meshrepair.denoise.rules.willmore_weight_from_band`; no crease sharpening)

    Returns
    -------
    (nV, 3) float64, the finished vertices
    """
    info["polished"] = 0.0
    info.setdefault("lambda_gain", 1.0)  # the data weight's tangential gain
    # the rule reads the automatic decisions only (a user-set Willmore weight is not a finding)
    pr = polish_rule(max(gamma, gamma_rms), w_cad,
                     ww if automatic else 1.0, info["noise_length"])
    if polish and pr is not None:
        from meshrepair.denoise.polish import polish as _polish
        from meshrepair.denoise.polish_fidelity import POLISH_ETA

        # the vertex step keeps the solve's data term (meshrepair.denoise.polish_fidelity)
        V_out, info["polished"] = _polish(V_out, F, M_E, topo, rings=pr[0], tau=pr[1],
                                          passes=pr[2], data=data,
                                          eta=POLISH_ETA if POLISH_DATA else 0.0)
        log.info("polish (%d rings, %.1f deg, %d passes) on %.1f %% of the faces", *pr,
                 100 * info["polished"])
    info["lowpass_steps"] = 0
    if sup_v is not None and automatic:  # organic mesh, white noise
        from meshrepair.denoise import lowpass as _lp

        if _lp.applies(info["support_fraction"], ww):
            k = _lp.steps_from_noise(gamma)
            nrm = _lp.normal_only(info["tangential_ratio"], gamma)
            V_out = _lp.taubin_region(V_out, topo.edges, ~sup_v, k, F=F if nrm else None)
            info["lowpass_steps"] = k
    info.update(reanchor_ratio=float("nan"), reanchored=0, reanchor_shift=0.0)
    if REANCHOR and sup_v is not None:  # before the unfolding: it judges the final positions
        V_out = _reanchor_smooth(V, V_out, F, topo, sup_v, max(gamma, gamma_rms), info)
    info.update(guidance_passes=0, reintegrate_steps=0, reanchor_ratio_after=float("nan"),
                residual_level_ratio=float("nan"), reintegrate_rejected=0)
    if sup_v is not None and automatic:  # organic finish
        V_out = _organic_finish(V, V_out, F, topo, M_E, gamma, impulsive, ww, info)
    info.update(coarse_roughness=float("nan"), coarse_steps=0)
    if sup_v is not None and automatic and not lam_set:  # smooth at the mesh's resolution
        from meshrepair.denoise import coarse as _co

        y, kp = (V, 0) if not lowpassed else (lowpassed_from or (None, 0))
        # a low-passed input reads white, non-impulsive noise on the raw input (the
        # coarse-to-fine gate), whatever its own reading of the filtered noise says
        gate = dict(support_fraction=info["support_fraction"], outside=info["outside_weight"],
                    willmore=1.0 if lowpassed else ww, impulsive=impulsive and not lowpassed,
                    lowpassed=y is None)
        if _co.gated(**gate):
            c, kc = _co.coarse_read(y, V_out, F, topo.edges, before=kp, **gate)
            info["coarse_roughness"] = c
            if kc:
                nrm = _co.normal_only(info["tangential_ratio"], gamma)
                keep = bool(info["reintegrate_steps"]) and not impulsive  # its folds are kept
                V_out = _co.coarse_lowpass(V_out, F, topo, kc, normal=nrm, unfold=not keep,
                                           reference=probe, layout=V,
                                           tangential=info["tangential_ratio"])
                info["coarse_steps"] = kc
    info.update(cad_finish_passes=0, cad_finish_gated=0.0)
    if sup_v is not None and automatic:  # CAD finish
        from meshrepair.denoise.cadfinish import cad_finish, cad_finish_rule

        pc = cad_finish_rule(gamma, info["outside_weight"], ww)
        if pc:
            V_out, info["cad_finish_gated"] = cad_finish(V_out, F, M_E, topo, passes=pc)
            info["cad_finish_passes"] = pc
    info.update(sharpened=0.0, sharpen_rho=float("nan"), sharpen_flat=float("nan"))
    sr = sharpen_rule(ww if automatic else 1.0, info["noise_length"], band_model=band_model)
    if polish and sr is not None:  # correlated noise: rounded creases, kept where data agree
        from meshrepair.denoise.modes import sharpen
        from meshrepair.denoise.rules import SHARPEN_FLAT_SUPPORT

        # a flat-supported set passes at ρ > 0.2 (meshrepair.denoise.sharpen_decision)
        flat = (pr[0], pr[1]) if SHARPEN_FLAT_SUPPORT and pr is not None else None
        st: dict = {}
        V_out, info["sharpened"] = sharpen(V_out, V, F, M_E, topo, rings=sr, flat=flat,
                                           stats=st)
        info.update(sharpen_rho=st.get("rho", float("nan")),
                    sharpen_flat=st.get("flat", float("nan")))
        log.info("crease sharpening (%d rings) kept on %.1f %% of the vertices", sr,
                 100 * info["sharpened"])
    return V_out
