"""Feature-aware denoising: the public one-shot function over the shared ADMM solver.

Default schedule (docs/parameters.md has the measurements behind every rule; the decisions are
recorded in ``DenoiseResult.params``):

0. *Unfold* faces folded over by noise (:func:`meshrepair.model.relax.untangle`). The unfolded mesh
   is the start of the solves; the fidelity data stays the input, except for impulsive noise
   (:func:`fidelity_data`), and for the main run only where the probe reads that noise along
   the normals (:func:`unfolded_data_after_probe`, round 9r). Faces still folded in the
   result are unfolded the same way at the end (:func:`unfold_result`).
1. *Probe*: the robust stage below on the whole mesh (MC with ``a = 0.5`` on every edge, a
   total-variation-like smoother of the normals). Its result N¹ decides:

   * the *crease-supported region* C (:func:`meshrepair.denoise.regions.crease_support`): long
     chains
     (≥ 30 edges) of edges whose N¹-dihedral exceeds ``th``, dilated by 2 rings;
   * the *flat edges* of C (:func:`meshrepair.denoise.regions.flat_edges`, probe normal spread <
     7°);
   * the *noise scale* (:func:`meshrepair.denoise.scale.noise_scale`): correlation ratio ρ, length,
     level;
   * the *direction* of the noise (:func:`meshrepair.denoise.scale.tangential_ratio` r_t).

2. *Robust stage* from the input again: MC (``a = 0.5``, 0.25 for heavy noise γ̂ > 0.33) on C,
   edge-Willmore elsewhere; ``β1 = 2a``, ``β2 = 10 β1``; ``clip(130 γ̂, 10, 40)`` iterations
   (40 with fold-overs; ``40 + 600 (γ̂ - 0.33)`` up to 120 for heavy noise), left early when the
   relative change of V drops below ``2e-4``.
3. *Feature stage*: in C, M_E from the dihedral threshold (refreshed every 3 iterations, chains
   ≥ 6 edges) with ``a = 10``, and the flat-TV class (:mod:`meshrepair.model.priors`, MC ``a =
   0.5``)
   on C's flat edges; edge-Willmore elsewhere, with weight ``6 w`` outside C on CAD parts
   (:func:`outside_weight`); ``β1 = 1.2 a``, ``β2 ≈ 1.67 β1``; ≤ 60 iterations or rule (35).
4. *Polish* (heavy noise on CAD parts, correlated noise; :func:`polish_rule`): a bilateral
   normal filter bounded by the converged M_E on the flat patches, at the noise's scale, then
   the vertices to the filtered normals, keeping the solve's data term
   (:mod:`meshrepair.denoise.polish`, :mod:`meshrepair.denoise.polish_fidelity`).
4b. *Crease sharpening* (correlated noise, :func:`sharpen_rule`): mode-seeking face normals at
   the noise's scale, kept per connected region where they bring the result closer to the
   input (:mod:`meshrepair.denoise.modes`); it runs after the re-anchoring of step 5.
5. *Tangential re-anchoring* of the smooth region (:mod:`meshrepair.denoise.reproject`): outside C
the
   result's vertices slide along the result surface towards the closest points of the input's
   vertices, ``V_i + w_i (π_S(V⁰_i) - V_i)`` with the least-variance weights
   ``w_i = σ²/(σ² + κ² d_i²)``, when the residual tangential ratio reads noise along the
   normals (``ρ_t < 0.6``) and the noise is not heavy (:data:`REANCHOR`).
6. *Organic finish* (round 9, :mod:`meshrepair.denoise.organic`) on meshes that are not CAD parts,
with
   white noise that is not heavy (:func:`guidance_rule`): a one-ring bilateral normal filter
   bounded by M_E with Sun et al. vertex steps; then, for impulsive noise or a tangential drift
   the re-anchoring left (:func:`reintegrate_rule`), the vertices re-integrated from the input
   by a few Sun et al. steps towards those normals.
   Round 10s: a re-integration that folds faces its target does not have, where the input's
   tangential offset is large, is not kept (:func:`meshrepair.denoise.folds.reintegration_keeps`).
7. *CAD finish* (round 9c, :mod:`meshrepair.denoise.cadfinish`) on CAD parts with white noise: the
same
   one-ring filter, one-sided at M_E, on the faces away from M_E and the flat sides of its
   creases (:func:`meshrepair.denoise.cadfinish.cad_finish_rule`).

Round 9s: on a CAD part the outside weight 6 is lowered to 3 when the normal residual outside C
exceeds the one in C by more than 3 % (a discrepancy principle,
:mod:`meshrepair.denoise.discrepancy`;
the main run is solved again); on an organic mesh with white noise the smooth
region gets ``round((γ̂/0.13)²)`` Taubin λ|μ pairs before the re-anchoring
(:mod:`meshrepair.denoise.lowpass`).

Round 10h: heavy white noise on an organic mesh (total level ``γ̂ √(1 + 2 min(r_t, 1)²) > 0.32``
after the probe) is low-passed first: ``round((γ̂ √(1 + min(r_t, 1)²) / 0.044)²)`` (≤ 96)
Taubin λ|μ pairs on the input, then the whole schedule above runs on the low-passed mesh
(:mod:`meshrepair.denoise.presmooth`; ``params['presmooth_steps']``). The run on the low-passed mesh
is not polished. Round 11w: at most ``K_q`` pairs, the most that do not halve a wave of length
0.44 q (q the probe's radius in edge lengths; :mod:`meshrepair.denoise.coarse_lowpass`).

Round 11d: a crease chain of the probe is dropped from C when both the whole network of chains
and the chain itself branch (β > 0.2) and have rough sides (s > 5.5°): noise, not a CAD crease
(:mod:`meshrepair.denoise.crease_network`); when that removed part of C, the noise is read as heavy
for
this mesh and the round-10h gate does not ask for γ_t > 0.32.

Round 11x: the full Taubin steps of rounds 10h and 11c keep the input's vertex layout: the
low-passed surface is resampled at it (:mod:`meshrepair.denoise.layoutkeep`); the coarse-to-fine run
reads its noise level and tangential ratio on the low-passed mesh before the resampling.

Throughout: λ = ``clip(0.02 / γ̂², 0.05, 1)``; the Willmore weight ``w`` from ρ for correlated
noise along the normals (:func:`willmore_weight_from_scale`) and then ``3 max(1, ℓ²)`` V-steps
per iteration for its correlation length ℓ, the probe included (:func:`inner_iters_from_scale`);
a Huber fidelity for impulsive noise (:mod:`meshrepair.model.fidelity`); a tangential anchor on C
when the noise lies along the normals (r_t < 0.65). All parameters are in mean-edge-length
units, so the result is equivariant under rotation, translation and uniform scaling.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable

from meshrepair.denoise.finish import (  # noqa: F401  (re-exported)
    POLISH_DATA,
    REANCHOR,
    REINTEGRATE_KEEPS_FOLDS,
    finish_result,
)
from meshrepair.denoise.folds import (  # noqa: F401  (re-exported)
    COLLAPSE_VOLUME_RATIO,
    UNFOLD_DATA_IMPULSIVE,
    UNFOLD_RESULT,
    _keep_consistent_clusters,
    _volume_ratio,
    fidelity_data,
    unfold_result,
    unfolded_data_after_probe,
)
from meshrepair.denoise.plan import DenoisePlan
from meshrepair.denoise.result import DenoiseResult
from meshrepair.denoise.rules import (  # noqa: F401  (re-exported: the rules read from the input)
    CAD_SUPPORT,
    CAD_WILLMORE,
    FLAT_A,
    FLAT_SPREAD_DEFAULT,
    HEAVY_NOISE,
    HEAVY_ROBUST_A,
    HEAVY_SLOPE,
    IMPULSIVE_RATIO,
    POLISH,
    PROBE_EARLY_STOP,
    PROBE_MAX_ITERS,
    TANGENTIAL_MAX,
    guidance_rule,
    huber_from_noise,
    inner_iters_from_scale,
    is_impulsive,
    lambda_from_noise,
    outside_weight,
    polish_rule,
    reintegrate_rule,
    robust_a_from_noise,
    robust_iters_from_noise,
    sharpen_rule,
    warm_start_from_probe,
    willmore_weight_from_scale,
)
from meshrepair.denoise.run import (  # noqa: F401
    REORDER_MIN_VERTICES,
    _denoise,
    _execute,
    _plan,
    default_stages,
)
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.reorder import _edge_values_to, locality_order  # noqa: F401  (re-exported)
from meshrepair.model._memory import heap_allocations
from meshrepair.model.solver import Stage


def denoise(
    V,
    F=None,
    *,
    lam: float | None = None,
    th: float = 30.0,
    a: float = 10.0,
    robust_iters: int | None = None,
    feature_iters: int = 60,
    mask_update_every: int = 3,
    min_feature_edges: int = 6,
    tol: float = 1e-6,
    unfold: bool = True,
    inner_solver: str = "armijo",
    inner_iters: int | None = None,
    n_solver: str = "auto",
    stages: tuple[Stage, ...] | None = None,
    huber_delta: float | None = None,
    willmore_weight: float | None = None,
    regions: bool = True,
    polish: bool = True,
    callback: Callable[[dict], None] | None = None,
    plan: DenoisePlan | None = None,
) -> DenoiseResult:
    """Denoise a triangle mesh, keeping sharp features (energy (6) minimised by ADMM).

    Parameters
    ----------
    V : (nV, 3) float array, or a ``trimesh.Trimesh`` (then ``F`` is omitted)
    F : (nF, 3) int array
    lam : fidelity weight λ per squared mean edge length; default from the estimated noise.
    th : dihedral threshold (degrees) of the sharp-edge mask (5).
    a : MC non-convexity of the feature stage.
    robust_iters : cap of the robust stage; default from the noise: ``clip(130 γ̂, 10, 40)`` with
        γ̂ the larger of the MAD and RMS estimates, and
        40 when more than 1 % of the faces were folded over (noise with a tangential part).
    feature_iters : cap of the feature stage.
    mask_update_every : refresh M_E every this many feature-stage iterations (0: never).
    min_feature_edges : keep only sharp edges in chains of at least this many edges (1: all).
    tol : rule (35) tolerance.
    unfold : unfold folded-over faces before the solve, and those still folded after it.
    inner_solver : V-subproblem solver (``"armijo"``, ``"gd"``, ``"heavy_ball"``, ``"lbfgs"``,
        ``"bfgs"``).
    inner_iters : inner iterations per ADMM iteration; default 3, more for correlated noise
        (:func:`inner_iters_from_scale`).
    n_solver : N-subproblem solver (``"auto"``, ``"cg"``, ``"direct"``).
    stages : a custom schedule replacing the default two stages (then no region probe).
    huber_delta : threshold δ of the robust Huber fidelity (:mod:`meshrepair.model.fidelity`), mean
        edge lengths; default from the noise (``2 γ̂_rms`` when the noise looks impulsive,
        ``γ̂_rms > 1.3 γ̂``, else 0 = quadratic); 0 turns it off.
    willmore_weight : weight of edge-Willmore on smooth edges; default from the correlation of
        the noise (:func:`willmore_weight_from_scale`).
    regions : decide per region whether a crease is supported (:mod:`meshrepair.denoise.regions`)
    from a
        first robust probe, and use the smooth prior only elsewhere; ``False`` runs the MC stages
        on the whole mesh without probe, flat-TV class, anchor, correlated-noise weight or
        tangential re-anchoring (the heavy-noise and impulsive rules still apply).
    polish : apply the automatic polish rule (:func:`polish_rule`,
    :mod:`meshrepair.denoise.polish`);
        ``False`` never polishes.
    callback : called with each iteration's history entry; raise
        :class:`meshrepair.model.solver.StopRequested` to stop early.
    plan : a plan of this mesh from :func:`plan_denoise`, possibly edited with
        :func:`dataclasses.replace`; it is run as it is (no reading again), and every other
        option except ``callback`` must then be left at its default.

    Returns
    -------
    DenoiseResult
        The input arrays are never modified.

    Raises
    ------
    MeshRepairError
        For invalid meshes (see :func:`meshrepair.mesh.validate.check_mesh`) or options.
    """
    from meshrepair.mesh.array_contract import as_arrays

    V, F = as_arrays(V, F)
    if callback is not None and not callable(callback):
        raise MeshRepairError(f"callback must be callable or None, got {type(callback).__name__}")
    if plan is not None:
        if not isinstance(plan, DenoisePlan):
            raise MeshRepairError(f"plan must be a DenoisePlan from mr.plan_denoise, got "
                                  f"{type(plan).__name__}")
        given = {k: v for k, v in locals().items() if k in _OPTION_DEFAULTS
                 and not _same(v, _OPTION_DEFAULTS[k])}
        if given:
            raise MeshRepairError(f"with plan=, leave the other options at their defaults "
                                  f"(got {', '.join(sorted(given))}); change the plan instead, "
                                  "e.g. dataclasses.replace(plan, lam=0.2)")
        with heap_allocations():
            return _execute(plan, V, F, callback)
    with heap_allocations():
        return _denoise(V, F, lam=lam, th=th, a=a, robust_iters=robust_iters,
                        feature_iters=feature_iters, mask_update_every=mask_update_every,
                        min_feature_edges=min_feature_edges, tol=tol, unfold=unfold,
                        inner_solver=inner_solver, inner_iters=inner_iters,
                        n_solver=n_solver, stages=stages, huber_delta=huber_delta,
                        willmore_weight=willmore_weight, regions=regions, polish=polish,
                        callback=callback)


def plan_denoise(
    V,
    F=None,
    *,
    lam: float | None = None,
    th: float = 30.0,
    a: float = 10.0,
    robust_iters: int | None = None,
    feature_iters: int = 60,
    mask_update_every: int = 3,
    min_feature_edges: int = 6,
    tol: float = 1e-6,
    unfold: bool = True,
    inner_solver: str = "armijo",
    inner_iters: int | None = None,
    n_solver: str = "auto",
    stages: tuple[Stage, ...] | None = None,
    huber_delta: float | None = None,
    willmore_weight: float | None = None,
    regions: bool = True,
    polish: bool = True,
) -> DenoisePlan:
    """The plan :func:`denoise` would run on ``(V, F)``, without the main solve.

    It reads the input (noise level, outliers, the robust probe's crease support, the noise's
    direction and correlation across scales) and decides every parameter of the run; each
    decision records the values it read and the rule that made it (``print(plan)``). Options
    as :func:`denoise`; an option the user sets appears in the plan as set by the user, with
    what it switched off. Deterministic: the same input gives the same plan.

    Returns
    -------
    DenoisePlan
        Frozen; run it with ``denoise(V, F, plan=plan)``, after
        :func:`dataclasses.replace` of any of ``plan.editable()``.
    """
    from meshrepair.mesh.array_contract import as_arrays

    V, F = as_arrays(V, F)
    with heap_allocations():
        return _plan(V, F, lam=lam, th=th, a=a, robust_iters=robust_iters,
                     feature_iters=feature_iters, mask_update_every=mask_update_every,
                     min_feature_edges=min_feature_edges, tol=tol, unfold=unfold,
                     inner_solver=inner_solver, inner_iters=inner_iters, n_solver=n_solver,
                     stages=stages, huber_delta=huber_delta, willmore_weight=willmore_weight,
                     regions=regions, polish=polish)


_OPTION_DEFAULTS = {k: p.default for k, p in inspect.signature(plan_denoise).parameters.items()
                    if p.kind is p.KEYWORD_ONLY}
"""The options of :func:`denoise` a plan replaces, with their defaults."""


def _same(a, b) -> bool:
    try:
        return bool(a == b) if not (a is None or b is None) else a is b
    except (TypeError, ValueError):
        return False
