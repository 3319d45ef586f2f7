"""What a solve returns: :class:`SolverResult` (V, N, the mask M_E of (5), M_V of (6), the
history of energy (6) and of rule (35)'s change), and :class:`StopRequested`, raised by a
callback to stop the loop (17)-(21) early.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class SolverResult:
    """Output of :meth:`ADMMSolver.solve`.

    Attributes
    ----------
    V : (nV, 3) float64, restored vertices (input units).
    F : (nF, 3) int64, the connectivity (unchanged).
    N : (nF, 3) the ADMM normal variable at the end.
    M_E : (nE,) bool, the sharp-edge mask of the last stage.
    M_V : (nV,) float64, the fidelity mask.
    edges : (nE, 2) the edge list M_E refers to.
    history : list of dict per iteration: ``iter, stage, energy, rel_change, res_t, res_N,
        n_sharp, time``.
    iterations : int
    stop_reason : str
    scale : float, the mean edge length of the normalisation.
    state : ADMMState or None, the loop's state (``keep_state=True``), for
        :meth:`ADMMSolver.resume`.
    """

    V: np.ndarray
    F: np.ndarray
    N: np.ndarray
    M_E: np.ndarray
    M_V: np.ndarray
    edges: np.ndarray
    history: list[dict] = field(default_factory=list)
    iterations: int = 0
    stop_reason: str = ""
    scale: float = 1.0
    state: object | None = None


class StopRequested(Exception):
    """Raise from a callback to stop the solver; the current iterate is returned."""
