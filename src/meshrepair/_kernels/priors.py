"""Kernels of the flat-TV edge class (:mod:`meshrepair.model.priors`): the t-update (22) with three
edge classes and the edge lengths with the regulariser of (6) for the history energy, each in one
edge pass. As numpy expressions over the flat subset (fancy indexing, ``prox_mc``, the energy
recomputed and corrected) they were 6 % of a default denoise on a 4,610-vertex mesh; the
t-update measured 152 → 44 µs of CPU per call there (docs/performance.md).

Same arithmetic as ``_kernels._nb_t_update`` (sharp and smooth edges) and
:func:`meshrepair.model.penalties.prox_mc` (flat edges), and as ``_kernels._nb_lengths_reg_energy``
with the MC value of ``a_flat`` on the flat, non-sharp edges: the t-update equals the composition
it replaces bit for bit (its sums in the same order), so the solver's iterates do not change; the
history energy equals its twin to rounding (``tests/test_kernels_priors.py``)."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import FASTMATH, HAVE_NUMBA, njit


def _np_t_update_mixed(DN, rho1, sharp, flat, a, a_flat, beta1, w):
    from meshrepair._kernels.mc import prox_mc

    sharp = np.asarray(sharp, bool)
    w = np.asarray(w, dtype=np.float64)
    base = beta1 * DN + rho1
    t = base / (beta1 + 2.0 * w)[:, None] if w.ndim else base / (beta1 + 2.0 * float(w))
    if sharp.any():
        t[sharp] = prox_mc(base[sharp] / beta1, a, beta1)
    if flat is not None:
        f = np.asarray(flat, bool) & ~sharp
        if f.any():
            t[f] = prox_mc(base[f] / beta1, a_flat, beta1)
    return t


def _np_lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, a, a_flat, w):
    from meshrepair._kernels.admm import _np_reg_energy
    from meshrepair._kernels.edges import _np_edge_lengths
    from meshrepair._kernels.mc import mc_penalty

    l = _np_edge_lengths(V, E)
    f = flat & ~sharp
    k = ~f
    e = _np_reg_energy(Nv, l[k], fa[k], fb[k], sharp[k], a, w)
    tf = l[f, None] * (Nv[fa[f]] - Nv[fb[f]])
    return l, float(e) + float(mc_penalty(np.sqrt(np.einsum("ij,ij->i", tf, tf)), a_flat).sum())


if HAVE_NUMBA:
    from meshrepair._kernels.admm import _edge_reg

    @njit(cache=True, inline="always")
    def _firm(r0, r1, r2, v, zeta, nr):  # pragma: no cover - compiled
        """Firm thresholding of ``r`` (the prox of (23)) with ``nr = |r|``:
        ``min(max(v - ζ/|r|, 0), 1) r``."""
        s = 0.0
        if nr > 0:
            s = v - zeta / nr
            s = min(max(s, 0.0), 1.0)
        return s * r0, s * r1, s * r2

    @njit(cache=True)
    def _nb_t_update_mixed(DN, rho1, sharp, flat, a, a_flat, beta1, w, per_edge
                           ):  # pragma: no cover - compiled
        # the code it replaces, bit for bit: with one weight w[0] the compiled t_update
        # (reciprocal of beta1 + 2w, sums left to right on sharp edges) and prox_mc on the flat
        # ones; with per-edge weights (per_edge) numpy's expressions (a division per edge,
        # prox_mc on the sharp and the flat edges: its norm sums as numpy's einsum does)
        n = DN.shape[0]
        t = np.empty((n, 3))
        smooth_div = 1.0 / (beta1 + 2.0 * w[0])
        v = beta1 / (beta1 - a) if beta1 > a else 0.0
        zeta = np.sqrt(2.0 * a) / (beta1 - a) if beta1 > a else 0.0
        vf = beta1 / (beta1 - a_flat) if beta1 > a_flat else 0.0
        zf = np.sqrt(2.0 * a_flat) / (beta1 - a_flat) if beta1 > a_flat else 0.0
        for e in range(n):
            r0 = beta1 * DN[e, 0] + rho1[e, 0]
            r1 = beta1 * DN[e, 1] + rho1[e, 1]
            r2 = beta1 * DN[e, 2] + rho1[e, 2]
            if sharp[e] or flat[e]:
                q0, q1, q2 = r0 / beta1, r1 / beta1, r2 / beta1
                if sharp[e] and not per_edge:  # the order of sums of _nb_t_update
                    nr = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
                    t[e, 0], t[e, 1], t[e, 2] = _firm(q0, q1, q2, v, zeta, nr)
                elif sharp[e]:  # that of prox_mc (numpy's einsum)
                    nr = np.sqrt((q0 * q0 + q2 * q2) + q1 * q1)
                    t[e, 0], t[e, 1], t[e, 2] = _firm(q0, q1, q2, v, zeta, nr)
                else:
                    nr = np.sqrt((q0 * q0 + q2 * q2) + q1 * q1)
                    t[e, 0], t[e, 1], t[e, 2] = _firm(q0, q1, q2, vf, zf, nr)
            elif per_edge:
                d = beta1 + 2.0 * w[e]
                t[e, 0] = r0 / d
                t[e, 1] = r1 / d
                t[e, 2] = r2 / d
            else:
                t[e, 0] = r0 * smooth_div
                t[e, 1] = r1 * smooth_div
                t[e, 2] = r2 * smooth_div
        return t

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, a, a_flat, w
                                     ):  # pragma: no cover - compiled
        l = np.empty(E.shape[0])
        knee = np.sqrt(2.0 / a)
        s2a = np.sqrt(2.0 * a)
        knee_f = np.sqrt(2.0 / a_flat)
        s2a_f = np.sqrt(2.0 * a_flat)
        e = 0.0
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
        return l, e


def t_update_mixed(DN, rho1, sharp, flat, a, a_flat, beta1, w):
    """Minimiser of (22) with the MC class ``sharp`` (``a``), the flat-TV class ``flat & ~sharp``
    (``a_flat``; ``flat`` may be None: no such class) and ``w ||t||²`` elsewhere, ``w`` one
    weight or ``(nE,)`` per-edge weights; ``beta1 > max(a, a_flat)``. Returns ``(nE, 3)``."""
    sharp = np.asarray(sharp, bool)
    w = np.asarray(w, dtype=np.float64)
    n = len(DN)
    flat_b = np.zeros(n, bool) if flat is None else np.asarray(flat, bool)
    if (flat_b & ~sharp).any() and not beta1 > a_flat:
        raise ValueError(f"the flat-TV class needs beta1 > a_flat (beta1={beta1}, "
                         f"a_flat={a_flat})")
    if sharp.any() and not beta1 > a:
        raise ValueError(f"beta1 must exceed a on sharp edges (rule (24)): beta1={beta1}, a={a}")
    if HAVE_NUMBA and DN.dtype == np.float64 and rho1.dtype == np.float64:
        per_edge = w.ndim > 0
        wa = np.ascontiguousarray(w) if per_edge else w.reshape(1)
        return _nb_t_update_mixed(np.ascontiguousarray(DN), np.ascontiguousarray(rho1), sharp,
                                  flat_b, float(a), float(a_flat), float(beta1), wa, per_edge)
    return _np_t_update_mixed(DN, rho1, sharp, flat, a, a_flat, beta1, w)


def lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, a, a_flat, w):
    """Lengths of the interior edges ``E`` of ``V`` and the regulariser of the module
    :mod:`meshrepair.model.priors` there (MC ``a`` on ``sharp``, MC ``a_flat`` on ``flat & ~sharp``,
    ``w |t|²`` elsewhere, ``t = l (Nv[fa] - Nv[fb])``); returns ``(l, energy)``."""
    if HAVE_NUMBA:
        l, e = _nb_lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, float(a),
                                            float(a_flat), float(w))
        return l, float(e)
    return _np_lengths_reg_energy_mixed(V, E, Nv, fa, fb, sharp, flat, a, a_flat, w)
