"""The default two-stage ADMM schedule of the model and the fidelity weight λ read from the
noise level: shared by every task that runs the solver (denoising, the fill's and the
completion's optional denoise)."""

from __future__ import annotations

import numpy as np

from meshrepair.model.solver import Stage


def default_stages(*, robust_iters: int = 40, feature_iters: int = 60, a: float = 10.0,
                   flat_a: float = 0.0, robust_a: float = 0.5) -> tuple[Stage, ...]:
    """The two-stage schedule: a robust stage (MC with a small ``a`` on every edge,
    a total-variation-like smoother of the normals), then the feature stage (MC with ``a`` on the
    adaptive sharp-edge mask M_E of (5), edge-Willmore elsewhere)."""
    return (
        Stage(a=robust_a, eps=2.0, beta2_ratio=10.0, mask="all", max_iter=robust_iters,
              switch_tol=2e-4, min_iter=min(10, robust_iters), willmore_edges=False,
              name="robust"),
        Stage(a=a, eps=1.2, beta2_ratio=20.0 / 12.0, mask="adaptive", max_iter=feature_iters,
              flat_a=flat_a, name="feature"),
    )


def lambda_from_noise(gamma: float) -> float:
    """Default fidelity weight λ for an estimated noise level γ̂ (mean edge lengths)."""
    return float(np.clip(0.02 / max(gamma, 1e-3) ** 2, 0.05, 1.0))
