"""The result of :func:`meshrepair.denoise`: :class:`DenoiseResult`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


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
    params : dict, the parameters actually used (``params["main_solves"]``: main ADMM solves
        the call ran, the probe not counted: 1, plus one for the correlated model when the
        white result fails the white-noise test or for the discrepancy test's lowered weight;
        at most 2, 3 only when the collapse check solves again)
    n_unfolded : int, faces folded over in the input that were unfolded before the solve
        (``params["result_folds_unfolded"]``: faces folded in the solve's result, unfolded
        after it)
    plan : DenoisePlan, a record of the plan that ran (:func:`meshrepair.plan_denoise`), with
        the decisions taken after the solve in ``plan.after_solve``; ``print(r.plan)`` explains
        it (it keeps no arrays of the reading, so it is printed, not run again)
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
    plan: Any = None

    @property
    def mesh(self):
        """The result as a ``trimesh.Trimesh`` (no processing, same vertex order)."""
        import trimesh

        return trimesh.Trimesh(self.V, self.F, process=False)
