"""The ADMM schedule and the solver's options: :class:`Stage` (a, ε of rule (24), β2/β1, how the
mask M_E of (5) is made) and :class:`SolverOptions` (λ and th of (6) and (5), rule (35)'s tol, the
inner V-solver of (26)-(31) and the N-solver of (25)), each option checked by ``validate``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from meshrepair.model.inner import INNER_SOLVERS
from meshrepair.model.linear import N_SOLVERS

MASK_MODES = ("all", "adaptive", "none", "given")


@dataclass(frozen=True)
class Stage:
    """One phase of the ADMM schedule.

    Attributes
    ----------
    a : MC non-convexity of (7).
    eps : ε > 1 of rule (24); ``β1 = ε a``.
    beta2_ratio : ``β2 / β1``.
    mask : how M_E is made, one of ``"all" | "adaptive" | "none" | "given"``.
    max_iter : iteration cap of the stage.
    switch_tol : leave the stage when the relative change of V is below this (after ``min_iter``).
    min_iter : minimum number of iterations.
    relax : tangential relaxation weight per iteration (0 disables).
    flat_a : MC non-convexity on the non-sharp edges of the solver's ``flat_edges`` (the
        flat-TV class of :mod:`meshrepair.model.priors`; 0: edge-Willmore there as in the paper).
    willmore_edges : use the solver's per-edge Willmore weights (``willmore_edges`` of
        :class:`ADMMSolver`) in this stage; False: ``SolverOptions.willmore_weight`` everywhere.
    name : label shown in the history.
    """

    a: float
    eps: float
    beta2_ratio: float
    mask: str = "adaptive"
    max_iter: int = 100
    switch_tol: float = 0.0
    min_iter: int = 1
    relax: float = 0.0
    flat_a: float = 0.0
    willmore_edges: bool = True
    name: str = "stage"

    @property
    def beta1(self) -> float:
        return self.eps * self.a


@dataclass(frozen=True)
class SolverOptions:
    """Options of :class:`ADMMSolver` (paper symbols in brackets).

    Attributes
    ----------
    lam : fidelity weight [λ], per squared mean edge length.
    th : dihedral threshold of (5) in degrees [th].
    willmore_weight : weight of the edge-Willmore term on non-sharp edges (1 in (6)).
    stages : the schedule (see :class:`Stage`).
    tol : rule (35) tolerance for the last stage.
    inner_solver : V-subproblem solver: ``"armijo" | "gd" | "heavy_ball" | "lbfgs" | "bfgs"``.
    inner_iters : inner iterations per ADMM iteration (warm-started).
    n_solver : N-subproblem solver, ``"auto" | "cg" | "direct"``.
    n_rtol : relative residual of the iterative N-solve.
    mask_update_every : recompute an adaptive M_E every this many iterations (0 = only at stage
        start); the paper's dynamic update uses 3.
    mask_source : ``"N"`` (the ADMM normal variable, less noisy) or ``"V"`` (normals of the mesh).
    precondition : Jacobi-precondition the Armijo V-descent (a per-vertex step): a few sliver or
        folded faces otherwise force a tiny global step and stall the whole mesh.
    huber_delta : threshold δ (mean edge lengths) of the robust Huber fidelity of
        :mod:`meshrepair.model.fidelity` (0: the paper's quadratic fidelity).
    min_feature_edges : an adaptive mask keeps only sharp edges in connected chains of at least
        this many sharp edges (1 keeps all). Real creases are long lines; what residual noise
        marks sharp is scattered in short pieces.
    """

    lam: float = 0.1
    th: float = 30.0
    willmore_weight: float = 1.0
    stages: tuple[Stage, ...] = (Stage(a=10.0, eps=1.2, beta2_ratio=1.7, mask="adaptive",
                                       max_iter=200, name="feature"),)
    tol: float = 1e-6
    inner_solver: str = "armijo"
    inner_iters: int = 3
    n_solver: str = "auto"
    n_rtol: float = 1e-3
    mask_update_every: int = 0
    mask_source: str = "N"
    min_feature_edges: int = 1
    precondition: bool = True
    huber_delta: float = 0.0

    def validate(self) -> None:
        """Check every option (finite, in range, known choice); MeshRepairError naming it."""
        from meshrepair.errors import MeshRepairError
        from meshrepair.options import (
            MAX_INNER_ITERATIONS,
            MAX_ITERATIONS,
            check_angle,
            check_bool,
            check_choice,
            check_int,
            check_number,
        )

        check_choice("inner_solver", self.inner_solver, INNER_SOLVERS)
        check_choice("n_solver", self.n_solver, N_SOLVERS)
        check_choice("mask_source", self.mask_source, ("N", "V"))
        check_number("lam", self.lam, low=0)
        check_angle("th", self.th)
        check_number("huber_delta", self.huber_delta, low=0)
        check_number("willmore_weight", self.willmore_weight, low=0)
        check_number("tol", self.tol, low=0, low_open=True)
        check_int("inner_iters", self.inner_iters, low=1, high=MAX_INNER_ITERATIONS)
        check_number("n_rtol", self.n_rtol, low=0, high=1, low_open=True, high_open=True)
        check_int("mask_update_every", self.mask_update_every, low=0)
        check_int("min_feature_edges", self.min_feature_edges, low=1)
        check_bool("precondition", self.precondition)
        if not self.stages:
            raise MeshRepairError("at least one stage is needed")
        for s in self.stages:
            if not isinstance(s, Stage):
                raise MeshRepairError(f"stages must be Stage objects, got {type(s).__name__}")
            if s.mask not in MASK_MODES:
                raise MeshRepairError(f"stage mask must be one of {MASK_MODES}, got {s.mask!r}")
            if not (isinstance(s.eps, (int, float, np.number)) and s.eps > 1
                    and np.isfinite(s.eps)):
                raise MeshRepairError(f"stage eps must be > 1 (rule (24)), got {s.eps}")
            try:
                check_number("stage a", s.a, low=0, low_open=True)
                check_number("stage beta2_ratio", s.beta2_ratio, low=0, low_open=True)
                check_int("stage max_iter", s.max_iter, low=0, high=MAX_ITERATIONS)
                check_number("stage switch_tol", s.switch_tol, low=0)
                check_int("stage min_iter", s.min_iter, low=0)
                check_number("stage relax", s.relax, low=0, high=1)
            except MeshRepairError as exc:
                raise MeshRepairError(f"invalid stage {s.name!r}: {exc}") from None
