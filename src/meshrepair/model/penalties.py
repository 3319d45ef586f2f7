"""The minimax-concave (MC) penalty (7), the edge Willmore term, and the closed-form t-update (23).

The t-subproblem (22) separates over edges: for edge j with residual ``r_j`` it minimises

.. math::  (M_E)_j\\,\\phi(\\|t_j\\|; a) + (M_E^c)_j\\,w\\,\\|t_j\\|^2
           - \\langle \\rho_{1j}, t_j - (DN)_j \\rangle + \\tfrac{\\beta_1}{2}\\|t_j - (DN)_j\\|^2 .

``w`` is the weight of the Willmore term (1 in the paper's (6)).
"""

from __future__ import annotations

import numpy as np

from meshrepair._kernels.mc import mc_penalty, prox_mc  # noqa: F401  (the model's (7) and (23))


def beta1_rule(a: float, eps: float, *, any_sharp: bool = True, willmore_weight: float = 1.0
               ) -> float:
    """β1 from (24): ``ε · max_j {(M_E)_j a - 2 w (M_E^c)_j}`` with ε > 1.

    When no edge is sharp the t-subproblem is convex for any β1 > 0; we then return ``ε · a`` so
    that β1 stays on the same scale (the rule's maximum would be negative).
    """
    if eps <= 1.0:
        raise ValueError(f"eps must be > 1 for the t-subproblem to be strongly convex, got {eps}")
    if any_sharp:
        return eps * a
    return eps * max(a, 2.0 * willmore_weight)


def t_update(
    DN: np.ndarray,
    rho1: np.ndarray,
    sharp: np.ndarray,
    *,
    a: float,
    beta1: float,
    willmore_weight: float = 1.0,
) -> np.ndarray:
    """Exact minimiser of the t-subproblem (22) edge by edge.

    Parameters
    ----------
    DN : (nE, 3) the current ``D N``
    rho1 : (nE, 3) multiplier
    sharp : (nE,) bool, the mask M_E
    a : MC non-convexity
    beta1 : penalty parameter, must exceed ``a`` where ``sharp`` (rule (24))
    willmore_weight : weight ``w`` of ``||t||²`` on non-sharp edges

    Returns
    -------
    (nE, 3)
    """
    sharp = np.asarray(sharp, dtype=bool)
    if sharp.any() and not beta1 > a:
        raise ValueError(f"beta1 must exceed a on sharp edges (rule (24)): beta1={beta1}, a={a}")
    from meshrepair import _kernels as _k

    if _k.HAVE_NUMBA and DN.dtype == np.float64 and rho1.dtype == np.float64:
        return _k._nb_t_update(np.ascontiguousarray(DN), np.ascontiguousarray(rho1), sharp,
                               float(a), float(beta1), float(willmore_weight))
    base = beta1 * DN + rho1
    t = base / (beta1 + 2.0 * willmore_weight)
    if sharp.any():
        t[sharp] = prox_mc(base[sharp] / beta1, a, beta1)
    return t


def t_objective(
    t: np.ndarray, DN: np.ndarray, rho1: np.ndarray, sharp: np.ndarray, *, a: float, beta1: float,
    willmore_weight: float = 1.0,
) -> np.ndarray:
    """Per-edge value of the objective of (22) (for tests and energy reporting), shape ``(nE,)``."""
    nt = np.sqrt(np.einsum("ij,ij->i", t, t))
    reg = np.where(sharp, mc_penalty(nt, a), willmore_weight * nt**2)
    d = t - DN
    return reg - np.einsum("ij,ij->i", rho1, d) + 0.5 * beta1 * np.einsum("ij,ij->i", d, d)
