"""The paper's variational model and its solver: the MC penalty and its proximal map (7),
(22)-(24) (``penalties``), the flat-TV prior (``priors``), the robust fidelity and tangential
anchor (``fidelity``), the V-subproblem (26)-(31) and its inner solvers (``inner``), the
N-subproblem (25) (``linear``), the ADMM loop (17)-(21) (``solver/``), the noise model (32)
(``noise``), fold-over detection and tangential relaxation (``relax``), and the fused passes of
the hot loop (``_fused``).

May import: ``meshrepair.mesh``, ``meshrepair._kernels``, ``meshrepair.errors``,
``meshrepair.options``. It never imports a task: the solver does not know which task called it.
"""
