"""The ADMM solver (17)-(21) for energy (6), shared by every task.

A task (denoise, fill, complete) only builds the masks and the initial mesh, then calls
:class:`ADMMSolver`. The solver never knows which task called it.

Units. The solver works in centred coordinates divided by the mean edge length ``l̄`` of the
initial mesh, so every parameter is scale-free: scaling, rotating or translating the input does
the same to the output. λ is therefore "per squared mean edge length".

Schedule. A run is a sequence of :class:`Stage` s sharing the variables and multipliers. Each
stage fixes the MC non-convexity ``a``, ``β1 = ε a`` (rule (24)), ``β2 = ratio · β1`` and how the
sharp-edge mask M_E is made: ``"all"`` (MC on every free edge: a robust ℓ0-like smoother),
``"adaptive"`` (dihedral threshold ``th`` on the current normals, taken when the stage starts and
optionally every ``mask_update_every`` iterations) or ``"none"`` (edge-Willmore only). A stage
ends after ``max_iter`` iterations or when the relative change of V falls below its
``switch_tol``; the last stage ends by rule (35):

.. math:: \\|V^{(k+1)} - V^{(k)}\\|_2 / \\|V^{(k)}\\|_2 < \\text{tol}.

Modules: :mod:`~meshrepair.model.solver.options` (:class:`Stage`, :class:`SolverOptions`),
:mod:`~meshrepair.model.solver.admm` (:class:`ADMMSolver`: the loop and the masks),
:mod:`~meshrepair.model.solver.result` (:class:`SolverResult`, :class:`StopRequested`),
:mod:`~meshrepair.model.solver.state` (:class:`ADMMState`: what the loop carries, so that
:meth:`ADMMSolver.resume` continues a run stopped by rule (35) with a smaller tolerance).
"""

from meshrepair.model.solver.admm import ADMMSolver
from meshrepair.model.solver.options import MASK_MODES, SolverOptions, Stage
from meshrepair.model.solver.result import SolverResult, StopRequested
from meshrepair.model.solver.state import ADMMState

__all__ = ["ADMMSolver", "ADMMState", "MASK_MODES", "SolverOptions", "SolverResult", "Stage",
           "StopRequested"]
