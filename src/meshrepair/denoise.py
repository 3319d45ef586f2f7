"""Feature-aware denoising: the public one-shot function over the shared ADMM solver.

Default schedule (see docs/parameters.md for the measurements behind it):

0. *Unfold*: faces folded over by noise with a tangential part are unfolded by local umbrella
   smoothing of their 1-ring (:func:`meshrepair.relax.untangle`); nothing else moves.
1. *Robust stage*: the MC penalty on every edge with a small non-convexity ``a = 0.5``
   (ℓ1-like, a total-variation smoother of the normal field), ``β1 = 2a``, ``β2 = 10 β1``; at most
   ``clip(130 γ̂, 10, 40)`` iterations (40 when the noise folded faces over), left early when the
   relative change of V drops below ``2e-4``. A mask taken from
   the noisy input would freeze the noise in (40 % of edges look sharp at γ = 0.3); after this
   stage the dihedral mask is close to the true one.
2. *Feature stage*: M_E from the dihedral threshold ``th`` on the current normal field, refreshed
   every 3 iterations and cleaned of sharp-edge chains shorter than 6 edges (real creases are
   long lines, residual noise is not), ``a = 10`` (ℓ0-like on sharp edges, crisp creases),
   edge-Willmore on the others, ``β1 = 1.2 a``, ``β2 ≈ 1.67 β1``; at most 60 iterations or
   rule (35).

λ is set from the estimated noise level γ̂ (:func:`meshrepair.noise.estimate_noise`):
``λ = clip(0.02 / γ̂², 0.05, 1)``: little noise keeps the data, strong noise trusts the prior.
All parameters are in mean-edge-length units, so the result is equivariant under rotation,
translation and uniform scaling.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ._memory import heap_allocations
from .errors import MeshRepairError
from .noise import noise_statistics
from .relax import untangle
from .solver import ADMMSolver, SolverOptions, Stage

log = logging.getLogger(__name__)


@dataclass
class DenoiseResult:
    """Result of :func:`denoise`.

    Attributes
    ----------
    V : (nV, 3) float64, denoised vertices (same order as the input)
    F : (nF, 3) int64, the input connectivity
    M_E : (nE,) bool, the sharp-edge mask of the last stage
    edges : (nE, 2) int64, the edges M_E refers to
    M_V : (nV,) float64, the fidelity mask used
    history : list of dict, one per ADMM iteration (energy, rel_change, res_t, res_N, time, ...)
    iterations : int
    stop_reason : str
    noise_estimate : float, γ̂ of the input in mean edge lengths
    params : dict, the parameters actually used
    n_unfolded : int, faces folded over in the input that were unfolded before the solve
    """

    V: np.ndarray
    F: np.ndarray
    M_E: np.ndarray
    edges: np.ndarray
    M_V: np.ndarray
    history: list[dict] = field(default_factory=list)
    iterations: int = 0
    stop_reason: str = ""
    noise_estimate: float = float("nan")
    params: dict = field(default_factory=dict)
    n_unfolded: int = 0

    @property
    def mesh(self):
        """The result as a ``trimesh.Trimesh`` (no processing, same vertex order)."""
        import trimesh

        return trimesh.Trimesh(self.V, self.F, process=False)


REORDER_MIN_VERTICES = 200_000
"""Meshes this large are solved in a Morton (Z-curve) order of vertices and faces: every kernel
is memory-bound there, and the reordering measured 1.33 s instead of 1.76 s per iteration on a
1.18M-vertex subdivided mesh. Smaller meshes keep their order (results then do not depend on a
coordinate-dependent ordering, which keeps the rotation test exact to rounding)."""


def locality_order(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertex and face permutations along a Morton (Z-order) curve.

    Returns
    -------
    pv : (nV,) int64, new vertex i is old vertex ``pv[i]``
    pf : (nF,) int64, order of the faces (in the renumbered mesh)
    """
    from ._kernels import morton

    pv = np.argsort(morton(V), kind="stable")
    inv = np.empty_like(pv)
    inv[pv] = np.arange(len(pv))
    pf = np.argsort(morton(V[pv][inv[F]].mean(axis=1)), kind="stable")
    return pv, pf


def _edge_values_to(topo, edges_old_ids: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Re-index per-edge ``values`` given on ``edges_old_ids`` (vertex ids of ``topo``) onto
    ``topo.edges``."""
    n = np.int64(topo.n_vertices)
    e = np.sort(edges_old_ids, axis=1)
    code_src = e[:, 0] * n + e[:, 1]
    code_dst = topo.edges[:, 0] * n + topo.edges[:, 1]  # sorted (np.unique order)
    pos = np.searchsorted(code_dst, code_src)
    out = np.zeros(len(code_dst), dtype=values.dtype)
    out[pos] = values
    return out


def robust_iters_from_noise(gamma: float, folded_fraction: float = 0.0) -> int:
    """Default length of the robust stage: ``clip(130 γ̂, 10, 40)``, or 40 when more than 1 % of
    the faces were folded over. ``denoise`` passes the larger of the MAD and RMS noise
    estimates, so impulsive noise (RMS 1.5× MAD) also gets the long stage.

    Measured (benchmarks in docs/parameters.md): at γ = 0.1 a 10-iteration robust stage halves
    MSAE against 40 on organic meshes (spot 59 → 41, rocker_arm 72 → 41) and on fandisk (8.4 →
    5.0); at γ = 0.3 the long stage is needed (fandisk 25 with 40, 49 with 10). Random-direction
    noise reads about half its level but still wants the long stage; its fold-overs give it away.
    """
    if folded_fraction > 0.01:
        return 40
    return int(np.clip(round(130.0 * gamma), 10, 40))


def lambda_from_noise(gamma: float) -> float:
    """Default fidelity weight λ for an estimated noise level γ̂ (mean edge lengths)."""
    return float(np.clip(0.02 / max(gamma, 1e-3) ** 2, 0.05, 1.0))


def default_stages(*, robust_iters: int = 40, feature_iters: int = 60, a: float = 10.0
                   ) -> tuple[Stage, ...]:
    """The two-stage schedule described in the module docstring."""
    return (
        Stage(a=0.5, eps=2.0, beta2_ratio=10.0, mask="all", max_iter=robust_iters,
              switch_tol=2e-4, min_iter=min(10, robust_iters), name="robust"),
        Stage(a=a, eps=1.2, beta2_ratio=20.0 / 12.0, mask="adaptive", max_iter=feature_iters,
              name="feature"),
    )


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
    inner_iters: int = 3,
    n_solver: str = "auto",
    stages: tuple[Stage, ...] | None = None,
    callback: Callable[[dict], None] | None = None,
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
    unfold : unfold folded-over faces before the solve.
    inner_solver : V-subproblem solver (``"armijo"``, ``"gd"``, ``"heavy_ball"``, ``"lbfgs"``,
        ``"bfgs"``).
    inner_iters : inner iterations per ADMM iteration.
    n_solver : N-subproblem solver (``"auto"``, ``"cg"``, ``"direct"``).
    stages : a custom schedule replacing the default two stages.
    callback : called with each iteration's history entry; raise
        :class:`meshrepair.solver.StopRequested` to stop early.

    Returns
    -------
    DenoiseResult
        The input arrays are never modified.

    Raises
    ------
    MeshRepairError
        For invalid meshes (see :func:`meshrepair.validate.check_mesh`) or options.
    """
    from .io import as_arrays

    V, F = as_arrays(V, F)
    with heap_allocations():
        return _denoise(V, F, lam=lam, th=th, a=a, robust_iters=robust_iters,
                        feature_iters=feature_iters, mask_update_every=mask_update_every,
                        min_feature_edges=min_feature_edges, tol=tol, unfold=unfold,
                        inner_solver=inner_solver, inner_iters=inner_iters,
                        n_solver=n_solver, stages=stages, callback=callback)


COLLAPSE_VOLUME_RATIO = 0.5
"""A closed mesh whose enclosed volume falls below this fraction of the input's is collapsed:
measured with the defaults on the 7 closed shared meshes (fandisk, spot, trim_star, twelve,
rocker_arm, sharp_sphere, screwdriver) at γ = 0.3, normal and random directions, the ratio stays
in [0.9967, 1.0071], while the robust stage flattens a tetrahedron with γ = 0.1 to 1 % of its
volume."""


def _volume_ratio(V: np.ndarray, V_out: np.ndarray, F: np.ndarray, report) -> float | None:
    """Signed volume of the result over the input's, for a closed mesh with a clear volume
    (``|vol| > 1e-6 diag³``); None otherwise."""
    if not report.is_closed or len(F) == 0:
        return None

    def vol(X):
        a, b, c = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
        return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)

    Vc = V - V.mean(axis=0)
    v_in = vol(Vc)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    if not np.isfinite(v_in) or abs(v_in) <= 1e-6 * diag**3:
        return None
    return vol(V_out - V.mean(axis=0)) / v_in


def _solve(Vs, F, topo, opts, reorder: bool, callback):
    """One ADMM run (on a cache-friendly reordered copy for big meshes, mapped back exactly);
    returns ``(SolverResult, V_out, M_E)``."""
    if reorder:
        pv, pf = locality_order(Vs, F)
        inv = np.empty_like(pv)
        inv[pv] = np.arange(len(pv))
        Fw = inv[F][pf]
        res = ADMMSolver(Fw, len(Vs), options=opts).solve(Vs[pv], callback=callback)
        return res, res.V[inv], _edge_values_to(topo, pv[res.edges], res.M_E)
    res = ADMMSolver(F, len(Vs), options=opts, topo=topo).solve(Vs, callback=callback)
    return res, res.V, res.M_E


def _denoise(V, F, *, lam, th, a, robust_iters, feature_iters, mask_update_every,
             min_feature_edges, tol, unfold, inner_solver, inner_iters, n_solver, stages,
             callback) -> DenoiseResult:
    from .options import check_bool, check_int, check_number
    from .validate import _check_mesh

    # every option first (finite, in range), before any work on the mesh
    lam = check_number("lam", lam, low=0, allow_none=True)
    a = check_number("a", a, low=0, low_open=True)
    robust_iters = check_int("robust_iters", robust_iters, low=0, allow_none=True)
    feature_iters = check_int("feature_iters", feature_iters, low=0)
    mask_update_every = check_int("mask_update_every", mask_update_every, low=0)
    min_feature_edges = check_int("min_feature_edges", min_feature_edges, low=1)
    inner_iters = check_int("inner_iters", inner_iters, low=1)
    tol = check_number("tol", tol, low=0, low_open=True)
    unfold = check_bool("unfold", unfold)
    if callback is not None and not callable(callback):
        raise MeshRepairError(f"callback must be callable or None, got {type(callback).__name__}")
    if stages is not None:
        stages = tuple(stages)
    SolverOptions(th=th, tol=tol, inner_solver=inner_solver, inner_iters=inner_iters,
                  n_solver=n_solver, mask_update_every=mask_update_every,
                  min_feature_edges=min_feature_edges,
                  **({"stages": stages} if stages else {})).validate()
    report, topo = _check_mesh(V, F, name="input mesh")
    gamma, gamma_rms = noise_statistics(V, F, topo)
    lam_used = lambda_from_noise(gamma) if lam is None else float(lam)
    opts_kw = dict(lam=lam_used, th=th, tol=tol, inner_solver=inner_solver,
                   inner_iters=inner_iters, n_solver=n_solver,
                   mask_update_every=mask_update_every, min_feature_edges=int(min_feature_edges))
    SolverOptions(**opts_kw).validate()  # fail fast on bad options
    log.info("denoise: %d vertices, %d faces, noise estimate %.3f, lambda %.3g", len(V), len(F),
             gamma, lam_used)
    Vs = V
    n_unf = 0
    if unfold:
        from .relax import locally_flipped_faces

        n_unf = int(locally_flipped_faces(V, topo).sum())
        if n_unf:
            Vs, left = untangle(V, topo)
            log.info("unfolded %d folded-over faces (%d left)", n_unf - left, left)
    auto_robust = robust_iters is None and stages is None
    if robust_iters is None:
        robust_iters = robust_iters_from_noise(max(gamma, gamma_rms), n_unf / max(len(F), 1))
    if stages is None:
        stages = default_stages(robust_iters=int(robust_iters), feature_iters=int(feature_iters),
                                a=a)
    reorder = len(V) >= REORDER_MIN_VERTICES
    res, V_out, M_E = _solve(Vs, F, topo, SolverOptions(stages=tuple(stages), **opts_kw),
                             reorder, callback)
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
        stages = default_stages(robust_iters=0, feature_iters=int(feature_iters), a=a)
        res, V_out, M_E = _solve(Vs, F, topo, SolverOptions(stages=tuple(stages), **opts_kw),
                                 reorder, callback)
        shrink = _volume_ratio(V, V_out, F, report)
        if shrink is not None and shrink < COLLAPSE_VOLUME_RATIO:
            raise MeshRepairError(
                f"denoise collapsed this closed mesh: its volume fell to {shrink:.3g} of the "
                f"input's even without the robust stage ({len(V)} vertices; a mesh this coarse "
                "has no smooth regions for the model); it cannot be denoised")
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
                "reordered": reorder},
        n_unfolded=n_unf,
    )
