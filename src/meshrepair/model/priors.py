"""A third edge class for the regulariser of (6): flat-region total variation inside CAD regions.

The paper's regulariser has two classes of edges: sharp (``M_E``, MC penalty with non-convexity
``a``, ℓ0-like) and the rest (edge-Willmore ``w ||t||²``). On a CAD part the non-sharp edges are
mostly *flat* regions, where the quadratic Willmore term only damps the residual noise of the
normals (it keeps a ripple of a few degrees on planar patches, more than a TGV prior leaves),
while a total-variation-like penalty makes them exactly constant. Inside the
crease-supported region (:mod:`meshrepair.denoise.regions`) the non-sharp edges therefore keep an MC
penalty with a small non-convexity ``a_f`` (ℓ1-like, the robust stage's prior) during the feature
stage:

.. math::
    R(t) = \\sum_{e \\in M_E} φ(\\|t_e\\|; a) + \\sum_{e \\in T \\setminus M_E} φ(\\|t_e\\|; a_f)
           + \\sum_{e \\notin T \\cup M_E} w \\|t_e\\|^2 ,

``T`` the crease-supported edges. The t-subproblem (22) still separates over edges; on ``T`` it is
the firm-thresholding prox of (23) with ``a_f`` in place of ``a`` (strongly convex since
``β1 > a ≥ a_f``, rule (24)). Outside ``T`` (smooth, organic regions) nothing changes.

**Per-edge Willmore weight.** The Willmore class may carry one weight per edge, ``w_e`` in place
of ``w`` (``willmore_weight`` given as an array); the t-step stays the exact minimiser of (22),
edge by edge ``t_e = (β1 (DN)_e + ρ_{1e}) / (β1 + 2 w_e)`` (convex for every ``w_e ≥ 0``, so
rule (24) is unchanged). :func:`meshrepair.denoise.api.outside_weight` uses it to give the smooth
patches of CAD parts, outside the crease-supported region, a stronger smooth prior.
"""

from __future__ import annotations

import numpy as np

from meshrepair._kernels.priors import t_update_mixed as _t_update_mixed_kernel
from meshrepair.model.penalties import mc_penalty


def t_update_mixed(DN: np.ndarray, rho1: np.ndarray, sharp: np.ndarray, flat: np.ndarray, *,
                   a: float, a_flat: float, beta1: float, willmore_weight: float = 1.0
                   ) -> np.ndarray:
    """Exact minimiser of (22) with the three edge classes of the module docstring.

    Parameters
    ----------
    DN, rho1 : (nE, 3)
    sharp : (nE,) bool, ``M_E`` (MC with ``a``)
    flat : (nE,) bool, the flat-TV class ``T`` (MC with ``a_flat`` where not sharp)
    a, a_flat : non-convexities, ``beta1 > max(a, a_flat)``
    beta1 : penalty parameter
    willmore_weight : ``w`` on the remaining edges, a float or ``(nE,)`` per-edge weights
        (:data:`meshrepair.model.priors` module docstring, "per-edge Willmore weight")

    Returns
    -------
    (nE, 3)
    """
    # one compiled edge pass (_kernels.priors; its numpy twin without numba)
    return _t_update_mixed_kernel(DN, rho1, sharp, flat, a, a_flat, beta1, willmore_weight)


def reg_energy_mixed(t: np.ndarray, sharp: np.ndarray, flat: np.ndarray, *, a: float,
                     a_flat: float, willmore_weight: float = 1.0) -> float:
    """``R(t)`` of the module docstring for per-edge vectors ``t (nE, 3)``."""
    nt = np.sqrt(np.einsum("ij,ij->i", t, t))
    val = np.where(sharp, mc_penalty(nt, a), np.asarray(willmore_weight) * nt * nt)
    if flat is not None:
        f = np.asarray(flat, bool) & ~np.asarray(sharp, bool)
        val[f] = mc_penalty(nt[f], a_flat)
    return float(val.sum())
