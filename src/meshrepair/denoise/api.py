"""Feature-aware denoising: :func:`denoise` and :func:`plan_denoise`, thin public functions over
the plan (:mod:`meshrepair.denoise.analysis`) and its execution (:mod:`meshrepair.denoise.execute`).

A call reads the input once and decides (``print(mr.plan_denoise(V, F))`` shows each decision,
the values it read and its rule; docs/parameters.md lists every threshold):

0. *Unfold* faces folded over by noise (:func:`meshrepair.model.relax.untangle`). The unfolded
   mesh starts the solves; the fidelity data stay the input, except for impulsive noise along
   the normals (:func:`fidelity_data`, :func:`unfolded_data_after_probe`). Faces still folded
   in the result are unfolded the same way at the end (:func:`unfold_result`).
1. *Probe*: the robust stage below on the whole mesh (MC with ``a = 0.5`` on every edge, a
   total-variation-like smoother of the normals). Its normals N¹ decide the crease-supported
   region C (:func:`meshrepair.denoise.regions.crease_support`: chains of ≥ 30 edges whose
   N¹-dihedral exceeds ``th``, dilated by 2 rings; chains whose network branches and has rough
   sides are noise, :mod:`meshrepair.denoise.crease_network`), the flat edges of C, the noise's
   correlation across scales (:func:`meshrepair.denoise.scale.noise_scale`: ratio ρ, length ℓ,
   level) and its direction (:func:`meshrepair.denoise.scale.tangential_ratio` r_t).
2. *Robust stage* from the input again: MC (``a = 0.5``, 0.25 above γ̂ = 0.33) on C,
   edge-Willmore elsewhere; ``β1 = 2a``, ``β2 = 10 β1``; ``clip(130 γ̂, 10, 40)`` iterations
   (40 with fold-overs, more for heavy noise), left early when the relative change of V drops
   below ``2e-4``.
3. *Feature stage*: in C, M_E from the dihedral threshold (refreshed every 3 iterations, chains
   ≥ 6 edges) with ``a = 10``, and the flat-TV class (:mod:`meshrepair.model.priors`) on C's
   flat edges; edge-Willmore elsewhere, with weight ``6 w`` outside C on CAD parts
   (:func:`outside_weight`, lowered when the discrepancy principle of
   :mod:`meshrepair.denoise.discrepancy` finds it smooths away signal); ``β1 = 1.2 a``,
   ``β2 ≈ 1.67 β1``; ≤ 60 iterations or rule (35).
4. *After the solve* (:func:`meshrepair.denoise.finish.finish_result`): the polish of heavy or
   correlated noise (:mod:`meshrepair.denoise.polish`), the Taubin low-pass of the smooth
   region of organic meshes (:mod:`meshrepair.denoise.lowpass`), the tangential re-anchoring
   of the smooth region (:mod:`meshrepair.denoise.reproject`), the organic and CAD finishes
   (:mod:`meshrepair.denoise.organic`, :mod:`meshrepair.denoise.cadfinish`), the crease
   sharpening of correlated noise (:mod:`meshrepair.denoise.modes`), and the correlated-noise
   low-pass (:mod:`meshrepair.denoise.corrlowpass`).

*Which noise model*: when the reading finds correlated noise (w > 1 below), steps 2-4 run with
the white-noise model (w = 1) first, and again with the correlated model only when the white
result's residual fails the white-noise test of :mod:`meshrepair.denoise.whiteness` (one-ring
correlation or level above the white noise's).

*Coarse to fine*: heavy white noise on an organic mesh is low-passed first by Taubin λ|μ
pairs on the input (:mod:`meshrepair.denoise.presmooth`; the length capped at the mesh's
resolution, :mod:`meshrepair.denoise.coarse_lowpass`, read from the relief,
:mod:`meshrepair.denoise.heavylength`; the input's vertex layout kept,
:mod:`meshrepair.denoise.layoutkeep`), then the whole schedule runs on the low-passed mesh.

Throughout: λ = ``max(0.02 / γ̂², 0.05)``; the Willmore weight ``w`` from ρ for correlated
noise along the normals (:func:`willmore_weight_from_scale`) and then ``3 max(1, ℓ²)`` V-steps
per iteration of the main solve for its correlation length ℓ (:func:`inner_iters_from_scale`);
a Huber fidelity for impulsive noise (:mod:`meshrepair.model.fidelity`); a tangential anchor on C
when the noise lies along the normals (r_t < 0.65). All parameters are in mean-edge-length
units, so the result is equivariant under rotation, translation and uniform scaling.
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Callable

import numpy as np

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
        ``"bfgs"``; see :mod:`meshrepair.model.inner`). ``"gd"`` halves its fixed step whenever
        it would raise the energy; ``"bfgs"`` is dense and refused above
        :data:`meshrepair.model.inner.BFGS_MAX_VERTICES` vertices. An iterate with non-finite
        coordinates raises :class:`MeshRepairError`.
    inner_iters : inner iterations per ADMM iteration; default 3, more for correlated noise
        (:func:`inner_iters_from_scale`).
    n_solver : N-subproblem solver (``"auto"``, ``"cg"``, ``"direct"``).
    stages : a custom schedule replacing the default two stages (then no region probe).
    huber_delta : threshold δ of the robust Huber fidelity (:mod:`meshrepair.model.fidelity`), mean
        edge lengths, > 0; default from the noise (``2 γ̂_rms`` when the noise looks impulsive,
        ``γ̂_rms > 1.3 γ̂``, else 0 = quadratic).
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
    callback : called with each iteration's history entry of the main solve; raise
        :class:`meshrepair.model.solver.StopRequested` to stop early. A ``KeyboardInterrupt``
        (Ctrl-C) during the main solve returns its current iterate (``stop_reason``
        ``"interrupted"``); during the reading before it (the probe) it is raised again.
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

    options = {k: v for k, v in locals().items() if k in _OPTION_DEFAULTS}
    V, F = as_arrays(V, F)
    from meshrepair.options import check_callable

    check_callable("callback", callback)
    if plan is not None:
        if not isinstance(plan, DenoisePlan):
            raise MeshRepairError(f"plan must be a DenoisePlan from mr.plan_denoise, got "
                                  f"{type(plan).__name__}")
        given = [k for k, v in options.items() if not _same(v, _OPTION_DEFAULTS[k])]
        if given:
            raise MeshRepairError(f"with plan=, leave the other options at their defaults "
                                  f"(got {', '.join(sorted(given))}); change the plan instead, "
                                  "e.g. dataclasses.replace(plan, lam=0.2)")
        sub = _in_use(V, F)
        with heap_allocations():
            if sub is None:
                return _execute(plan, V, F, callback)
            return _expanded(_execute(plan, sub[1], sub[2], callback), V, F, sub[0])
    sub = _checked_in_use(V, F)
    with heap_allocations():
        if sub is None:
            return _denoise(V, F, callback=callback, **options)
        idx, Vc, Fc, checked = sub
        return _expanded(_denoise(Vc, Fc, callback=callback, checked=checked, **options),
                         V, F, idx)


def _in_use(V: np.ndarray, F: np.ndarray):
    """``(idx, V[idx], F renumbered)``, the vertices some face uses, when others are in ``V``;
    None when every vertex is used or ``F`` has an index out of range (the validation refuses
    it). The denoiser reads and solves on the used vertices only: a vertex no face uses is in
    no energy term, and must not move a reading (a median, a centroid) of the others."""
    from meshrepair.mesh.topology import compact

    if F.size == 0 or F.min() < 0 or F.max() >= len(V):
        return None
    sub = compact(V, F)
    return None if len(sub[0]) == len(V) else sub


def _checked_in_use(V: np.ndarray, F: np.ndarray):
    """:func:`_in_use` after the validation of the user's arrays (their refusals and warnings
    in the user's numbering), with ``(report, topology)`` of the used part checked quietly."""
    from meshrepair.mesh.validate import _check_mesh

    sub = _in_use(V, F)
    if sub is None:
        return None
    _check_mesh(V, F, name="input mesh")
    idx, Vc, Fc = sub
    return idx, Vc, Fc, _check_mesh(Vc, Fc, name="input mesh", quiet=True)


def _expanded(r: DenoiseResult, V: np.ndarray, F: np.ndarray, idx: np.ndarray) -> DenoiseResult:
    """The result ``r`` on the used vertices ``idx`` put back in the user's numbering: the
    vertices no face uses at their input positions bit for bit (the validation's promise), the
    edges renumbered (same order: the renumbering is monotone), ``M_V`` 1 on the unused ones."""
    Vo = np.array(V, dtype=np.float64)
    Vo[idx] = r.V
    M_V = np.ones(len(V))
    M_V[idx] = r.M_V
    return dataclasses.replace(r, V=Vo, F=F, edges=idx[r.edges], M_V=M_V)


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
    callback: Callable[[dict], None] | None = None,
) -> DenoisePlan:
    """The plan :func:`denoise` would run on ``(V, F)``, without the main solve.

    It reads the input (noise level, outliers, the robust probe's crease support, the noise's
    direction and correlation across scales) and decides every parameter of the run; each
    decision records the values it read and the rule that made it (``print(plan)``). Options
    as :func:`denoise`; an option the user sets appears in the plan as set by the user, with
    what it switched off. Deterministic: the same input gives the same plan.

    ``callback`` is called with each iteration's history entry of the probe (the robust
    solve that reads the crease support; a second one on the low-passed input when the plan
    low-passes heavy noise first), for a progress display; a ``KeyboardInterrupt`` during the
    probe, or :class:`meshrepair.model.solver.StopRequested` raised by the callback, is raised
    again (a plan is not made from part of the reading).

    Returns
    -------
    DenoisePlan
        Frozen; run it with ``denoise(V, F, plan=plan)``, after
        :func:`dataclasses.replace` of any of ``plan.editable()``.
    """
    from meshrepair.mesh.array_contract import as_arrays
    from meshrepair.options import check_callable

    options = {k: v for k, v in locals().items() if k in _OPTION_DEFAULTS}
    check_callable("callback", callback)
    V, F = as_arrays(V, F)
    sub = _checked_in_use(V, F)
    with heap_allocations():
        if sub is None:
            return _plan(V, F, progress=callback, **options)
        return _plan(sub[1], sub[2], checked=sub[3], progress=callback, **options)


_OPTION_DEFAULTS = {k: p.default for k, p in inspect.signature(plan_denoise).parameters.items()
                    if p.kind is p.KEYWORD_ONLY and k != "callback"}
"""The options of :func:`denoise` a plan replaces, with their defaults."""


def _same(a, b) -> bool:
    try:
        return bool(a == b) if not (a is None or b is None) else a is b
    except (TypeError, ValueError):
        return False
