"""The t-update (17) fused with ``D N``, for every edge class, in one edge pass.

Per ADMM iteration the solver needs, on the interior edges,
``t = prox(D N + ρ_1 / β_1)`` with the prox of (22)-(23) per edge class: the MC firm
thresholding with ``a`` on sharp edges (M_E), with ``a_f`` on the flat-TV edges of
:mod:`meshrepair.model.priors`, the Willmore shrinkage ``(β_1 D N + ρ_1) / (β_1 + 2 w)`` elsewhere.
Done separately (``grad_edges``, then ``t_update`` or ``t_update_mixed``) that is two edge passes
with a ``(nE, 3)`` temporary ``DN`` between them and, for the flat class, numpy gathers.
:func:`t_from_normals` is one pass with no temporary.

The results are those of the separate kernels bit for bit (strict IEEE arithmetic as in
``_nb_t_update``; the flat class sums ``|r|²`` in the order numpy's einsum uses in
``prox_mc``); ``tests/test_kernels.py`` checks them against the separate kernels and the numpy
twin. The right-hand side of (25) is not fused into the same pass: that kernel needs
numba's fast-math flags, which would then also apply to the prox, and the rounding differences
that follow move a CAD benchmark row at γ0.4 normal noise by 12 % in MSAE.
"""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import HAVE_NUMBA, njit
from meshrepair._kernels.edges import _np_grad_edges


def prox_constants(a: float, beta1: float, w: float) -> tuple[float, float, float]:
    """``(1/(β1 + 2w), β1/(β1 - a), sqrt(2a)/(β1 - a))``: the Willmore shrinkage factor and
    the firm-thresholding constants ``v, ζ`` of (23) (0, 0 when ``β1 ≤ a``)."""
    smooth_div = 1.0 / (beta1 + 2.0 * w)
    v = beta1 / (beta1 - a) if beta1 > a else 0.0
    zeta = float(np.sqrt(2.0 * a)) / (beta1 - a) if beta1 > a else 0.0
    return smooth_div, v, zeta


def _np_t_from_normals(N, l, fa, fb, rho1, sharp, flat, a, a_flat, beta1, w):
    from meshrepair._kernels.priors import _np_t_update_mixed

    return _np_t_update_mixed(_np_grad_edges(N, l, fa, fb), rho1, sharp, flat, a, a_flat, beta1,
                              w)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_t_from_normals(N, l, fa, fb, rho1, sharp, flat, has_flat, beta1, smooth_div, v,
                           zeta, vf, zetaf):  # pragma: no cover - compiled
        n = fa.shape[0]
        t = np.empty((n, 3))
        for e in range(n):
            p, q, le = fa[e], fb[e], l[e]
            r0 = beta1 * (le * (N[p, 0] - N[q, 0])) + rho1[e, 0]
            r1 = beta1 * (le * (N[p, 1] - N[q, 1])) + rho1[e, 1]
            r2 = beta1 * (le * (N[p, 2] - N[q, 2])) + rho1[e, 2]
            if sharp[e]:  # _nb_t_update's firm thresholding
                r0 /= beta1
                r1 /= beta1
                r2 /= beta1
                nr = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
                s = 0.0
                if nr > 0:
                    s = v - zeta / nr
                    s = min(max(s, 0.0), 1.0)
            elif has_flat and flat[e]:  # prox_mc with a_flat (numpy's summation order)
                r0 /= beta1
                r1 /= beta1
                r2 /= beta1
                nr = np.sqrt((r0 * r0 + r2 * r2) + r1 * r1)
                s = 0.0
                if nr > 0:
                    s = vf - zetaf / nr
                    s = min(max(s, 0.0), 1.0)
            else:  # Willmore
                s = smooth_div
            t[e, 0] = s * r0
            t[e, 1] = s * r1
            t[e, 2] = s * r2
        return t


def t_from_normals(N, l, fa, fb, rho1, sharp, flat=None, *, a: float, a_flat: float = 0.0,
                   beta1: float, w: float = 1.0) -> np.ndarray:
    """The t-update (17): the minimiser of (22) on every interior edge, from ``N`` directly.

    Parameters
    ----------
    N : (nF, 3) the ADMM normals; l : (nEi,) interior-edge lengths; fa, fb : (nEi,) their faces
    rho1 : (nEi, 3) multiplier
    sharp : (nEi,) bool, M_E (MC with ``a``)
    flat : (nEi,) bool or None, the flat-TV class (MC with ``a_flat`` where not sharp)
    beta1 : penalty parameter, ``> a`` where sharp and ``> a_flat`` where flat (rule (24))
    w : Willmore weight on the other edges

    Returns
    -------
    t : (nEi, 3), the values of ``t_update`` (``t_update_mixed`` with ``flat``) on
    ``grad_edges(N, l, fa, fb)``
    """
    sharp = np.asarray(sharp, dtype=bool)
    if sharp.any() and not beta1 > a:
        raise ValueError(f"beta1 must exceed a on sharp edges (rule (24)): beta1={beta1}, a={a}")
    if not HAVE_NUMBA:
        return _np_t_from_normals(N, l, fa, fb, rho1, sharp, flat, a, a_flat, beta1, w)
    smooth_div, v, zeta = prox_constants(float(a), float(beta1), float(w))
    has_flat = flat is not None
    if has_flat:
        _, vf, zetaf = prox_constants(float(a_flat), float(beta1), float(w))
        fl = np.asarray(flat, dtype=bool)
    else:
        vf = zetaf = 0.0
        fl = sharp  # not read
    return _nb_t_from_normals(N, l, fa, fb, rho1, sharp, fl, has_flat, float(beta1), smooth_div,
                              v, zeta, vf, zetaf)
