"""Fused edge passes of the ADMM loop with per-edge Willmore weights (the outside weight of a
CAD part, :func:`meshrepair.denoise.rules.outside_weight`).

With ``willmore_edges`` the loop of :class:`meshrepair.model.solver.ADMMSolver` took, per iteration,
``grad_edges`` (``D N``, an ``(nE, 3)`` temporary) then ``t_update_mixed`` for the t-update (17),
and ``lengths_reg_energy_mixed`` then ``willmore_extra`` for the edge lengths and the history
energy: four edge passes. Here they are two:

* :func:`t_from_normals_weighted`: ``D N`` and the t-update in one pass, the same arithmetic
  as the two kernels it replaces (``le (N_a - N_b)``, then ``beta1 DN + rho1`` and the per-edge
  path of ``_kernels.priors._nb_t_update_mixed``), so the iterates are the same bit for bit;
* :func:`lengths_reg_energy_weighted`: the lengths, the regulariser of
  ``lengths_reg_energy_mixed`` and the per-edge weights' share of ``willmore_extra`` in one
  pass, two accumulators summed as the two kernels sum them.

In the 1.18M-vertex profile (docs/performance.md; wall time on a loaded machine) the two
passes removed took 0.060 s (``willmore_extra``) and 0.026 s (``grad_edges``) per feature
iteration. The numpy twins are the compositions they replace
(``tests/test_kernels_weighted.py``).
"""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import FASTMATH, HAVE_NUMBA, njit


def _np_t_from_normals_weighted(N, l, fa, fb, rho1, sharp, flat, a, a_flat, beta1, w):
    from meshrepair._kernels.edges import _np_grad_edges
    from meshrepair._kernels.priors import _np_t_update_mixed

    return _np_t_update_mixed(_np_grad_edges(N, l, fa, fb), rho1, sharp, flat, a, a_flat,
                              beta1, w)


def _np_willmore_extra(l, Nv, fa, fb, w, w0, skip):
    f = np.flatnonzero(~skip)
    tf = l[f, None] * (Nv[fa[f]] - Nv[fb[f]])
    return float(((w[f] - w0) * np.einsum("ij,ij->i", tf, tf)).sum())


def _np_lengths_reg_energy_weighted(V, E, Nv, fa, fb, sharp, flat, a, a_flat, w, w_int):
    from meshrepair._kernels.priors import _np_lengths_reg_energy_mixed

    l, e = _np_lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, a, a_flat, w)
    return l, e, _np_willmore_extra(l, Nv, fa, fb, w_int, w, sharp | flat)


if HAVE_NUMBA:
    from meshrepair._kernels.admm import _edge_reg
    from meshrepair._kernels.priors import _firm

    @njit(cache=True)
    def _nb_t_from_normals_weighted(N, l, fa, fb, rho1, sharp, flat, a, a_flat, beta1, w
                                    ):  # pragma: no cover - compiled
        # grad_edges then the per-edge path of _nb_t_update_mixed, bit for bit
        n = fa.shape[0]
        t = np.empty((n, 3))
        v = beta1 / (beta1 - a) if beta1 > a else 0.0
        zeta = np.sqrt(2.0 * a) / (beta1 - a) if beta1 > a else 0.0
        vf = beta1 / (beta1 - a_flat) if beta1 > a_flat else 0.0
        zf = np.sqrt(2.0 * a_flat) / (beta1 - a_flat) if beta1 > a_flat else 0.0
        for e in range(n):
            p, q, le = fa[e], fb[e], l[e]
            r0 = beta1 * (le * (N[p, 0] - N[q, 0])) + rho1[e, 0]
            r1 = beta1 * (le * (N[p, 1] - N[q, 1])) + rho1[e, 1]
            r2 = beta1 * (le * (N[p, 2] - N[q, 2])) + rho1[e, 2]
            if sharp[e] or flat[e]:
                q0, q1, q2 = r0 / beta1, r1 / beta1, r2 / beta1
                nr = np.sqrt((q0 * q0 + q2 * q2) + q1 * q1)  # prox_mc's (numpy's einsum)
                if sharp[e]:
                    t[e, 0], t[e, 1], t[e, 2] = _firm(q0, q1, q2, v, zeta, nr)
                else:
                    t[e, 0], t[e, 1], t[e, 2] = _firm(q0, q1, q2, vf, zf, nr)
            else:
                d = beta1 + 2.0 * w[e]
                t[e, 0] = r0 / d
                t[e, 1] = r1 / d
                t[e, 2] = r2 / d
        return t

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_lengths_reg_energy_weighted(V, E, Nv, fa, fb, sharp, flat, a, a_flat, w, w_int
                                        ):  # pragma: no cover - compiled
        l = np.empty(E.shape[0])
        knee = np.sqrt(2.0 / a)
        s2a = np.sqrt(2.0 * a)
        knee_f = np.sqrt(2.0 / a_flat)
        s2a_f = np.sqrt(2.0 * a_flat)
        e = 0.0
        s = 0.0
        for i in range(E.shape[0]):
            u, q = E[i, 0], E[i, 1]
            dx = V[q, 0] - V[u, 0]
            dy = V[q, 1] - V[u, 1]
            dz = V[q, 2] - V[u, 2]
            le = np.sqrt(dx * dx + dy * dy + dz * dz)
            l[i] = le
            if flat[i] and not sharp[i]:
                e += _edge_reg(Nv, fa[i], fb[i], le, True, a_flat, w, knee_f, s2a_f)
            else:
                e += _edge_reg(Nv, fa[i], fb[i], le, sharp[i], a, w, knee, s2a)
            dw = w_int[i] - w
            if sharp[i] or flat[i] or dw == 0.0:
                continue
            pa = fa[i]
            pb = fb[i]
            d = 0.0
            for k in range(3):
                x = Nv[pa, k] - Nv[pb, k]
                d += x * x
            s += dw * le * le * d
        return l, e, s


def _check(sharp, flat, a, a_flat, beta1):
    if (flat & ~sharp).any() and not beta1 > a_flat:
        raise ValueError(f"the flat-TV class needs beta1 > a_flat (beta1={beta1}, "
                         f"a_flat={a_flat})")
    if sharp.any() and not beta1 > a:
        raise ValueError(f"beta1 must exceed a on sharp edges (rule (24)): beta1={beta1}, a={a}")


def t_from_normals_weighted(N, l, fa, fb, rho1, sharp, flat, *, a: float, a_flat: float,
                            beta1: float, w: np.ndarray) -> np.ndarray:
    """``t_update_mixed(grad_edges(N, l, fa, fb), rho1, sharp, flat, a, a_flat, beta1, w)``
    (the t-update (17) with per-edge Willmore weights ``w (nEi,)``) in one edge pass.

    Parameters
    ----------
    N : (nF, 3) the ADMM normals; l : (nEi,) interior-edge lengths; fa, fb : (nEi,) faces
    rho1 : (nEi, 3) multiplier
    sharp : (nEi,) bool, M_E (MC with ``a``); flat : (nEi,) bool or None, the flat-TV class
    beta1 : ``> a`` where sharp, ``> a_flat`` where flat (rule (24))
    w : (nEi,) float, the per-edge Willmore weights

    Returns
    -------
    (nEi, 3)
    """
    sharp = np.asarray(sharp, bool)
    flat_b = np.zeros(len(fa), bool) if flat is None else np.asarray(flat, bool)
    _check(sharp, flat_b, a, a_flat, beta1)
    w = np.ascontiguousarray(w, dtype=np.float64)
    if HAVE_NUMBA and N.dtype == np.float64 and rho1.dtype == np.float64:
        return _nb_t_from_normals_weighted(np.ascontiguousarray(N), l, fa, fb,
                                           np.ascontiguousarray(rho1), sharp, flat_b,
                                           float(a), float(a_flat), float(beta1), w)
    return _np_t_from_normals_weighted(N, l, fa, fb, rho1, sharp, flat, a, a_flat, beta1, w)


def lengths_reg_energy_weighted(V, E, Nv, fa, fb, sharp, flat, a, a_flat, w, w_int):
    """``lengths_reg_energy_mixed`` and ``willmore_extra`` (skipping ``sharp | flat``) in one
    pass: returns ``(l, energy, extra)``, the history energy being ``energy + extra``."""
    if HAVE_NUMBA:
        l, e, s = _nb_lengths_reg_energy_weighted(V, E, Nv, fa, fb, sharp, flat, float(a),
                                                  float(a_flat), float(w), w_int)
        return l, float(e), float(s)
    return _np_lengths_reg_energy_weighted(V, E, Nv, fa, fb, sharp, flat, a, a_flat, float(w),
                                           w_int)
