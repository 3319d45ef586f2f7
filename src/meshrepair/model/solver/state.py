"""The resumable state of the ADMM loop (17)-(21): :class:`ADMMState`.

A run of :meth:`meshrepair.model.solver.ADMMSolver.solve` is a deterministic map of its state

.. math:: s^{k} = (V^k, N^k, N_V^k, l^k, ρ_1^k, ρ_2^k, η^k;\\ β_1, β_2, M_E, c, \\bar l;
          k, i, j),

the iterates in normalised units (``(V − c) / l̄``, ``c`` and ``l̄`` fixed when the run starts),
the multipliers, the inner solver's last step ``η``, the stage's penalties and mask (fixed when
stage ``i`` starts, the mask refreshed every ``mask_update_every`` iterations of the stage) and
the counters (``k`` in all, ``j`` in stage ``i``). One iteration is ``s^{k+1} = T(s^k)``; the
stopping rule (35) only *reads* ``rel^{k+1} = ||V^{k+1} − V^k|| / ||V^k||`` and never changes
``s``. Hence, with ``τ_2 < τ_1``, a run stopped by ``rel < τ_1`` at ``k_1`` and resumed from
``s^{k_1}`` with ``τ_2`` produces exactly the iterates of one run with ``τ_2``: the one-phase
run cannot stop before ``k_1`` (every ``rel^k`` there is ``≥ τ_1 > τ_2``, apart from the
``min_iter`` iterations that neither run may stop in) and from ``k_1`` on both apply the same
``T`` to the same ``s``. :meth:`ADMMSolver.resume` continues from such a state; a restart (a
new solve from the returned vertices) would reset ``ρ_1, ρ_2, η``, the normalisation and ``j``,
and so would not be the same run (tests/test_admm_resume.py).

The state is written at the end of each iteration, before the callback, so a run stopped by
rule (35) or by :class:`~meshrepair.model.solver.result.StopRequested` resumes exactly; after a
``KeyboardInterrupt`` inside an iteration the multipliers (updated in place) may be one step
ahead of ``V``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from meshrepair.model.inner import InnerState


@dataclass
class ADMMState:
    """Everything the loop (17)-(21) carries from one iteration to the next.

    Attributes
    ----------
    center : (3,) float, the centre ``c`` of the normalisation.
    scale : float, the mean edge length ``l̄`` of the initial mesh.
    X0 : (nV, 3) float, the data of the fidelity term, normalised.
    fid : (nV,) float, ``λ M_V²``.
    V : (nV, 3) float, the current vertices, normalised.
    N, Nv : (nF, 3) float, the normal variable and the normals of ``V``.
    l : (nE_int,) float, the interior edge lengths of ``V``.
    rho1 : (nE_int, 3) float, rho2 : (nF, 3) float, the multipliers of (20), (21).
    inner : InnerState, the inner solver's memory (its last accepted step).
    given_mask : (nE,) bool or None, M_E of the stages whose mask is ``"given"``.
    sharp : (nE,) bool, the current mask M_E; beta1, beta2 : the current stage's penalties.
    k : int, iterations done; stage : int, the current stage; j : int, its iterations done.
    begun : bool, whether the current stage's mask and penalties are set.
    history : list of dict, one entry per iteration so far; elapsed : float, seconds so far.
    """

    center: np.ndarray
    scale: float
    X0: np.ndarray
    fid: np.ndarray
    V: np.ndarray
    N: np.ndarray
    Nv: np.ndarray
    l: np.ndarray
    rho1: np.ndarray
    rho2: np.ndarray
    inner: InnerState
    given_mask: np.ndarray | None = None
    sharp: np.ndarray | None = None
    beta1: float = 0.0
    beta2: float = 0.0
    k: int = 0
    stage: int = 0
    j: int = 0
    begun: bool = False
    history: list[dict] = field(default_factory=list)
    elapsed: float = 0.0
