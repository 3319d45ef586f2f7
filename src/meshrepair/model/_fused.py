"""Fused passes of the hot loop, compiled with numba when present.

The preconditioned Armijo V-descent (26).

:func:`meshrepair.model.inner.solve_armijo` needs, per call, the energy, gradient (28) and Jacobi
scale of (26) at the start point, then per descent step the direction ``d = -D⁻¹ ∇J`` with its
slope, and per backtracking trial the energy at ``V + s d``. Done with separate kernels and numpy
expressions that is one face pass for the energy-gradient, one more for the scale, and per trial
a numpy temporary ``V + s d`` plus one energy pass. Here:

* :func:`venergy_grad_hdiag`: energy, gradient and the scale of ``vhess_diag`` in one face pass
  (same arithmetic as ``_kernels.venergy_grad`` and ``_kernels.vhess_diag``: results equal);
* :func:`descent_direction`: ``d = -g / max(h, h_min)`` and ``⟨g, -d⟩`` in one vertex pass;
* :func:`venergy_trial`: writes ``V + s d`` into a reused buffer and evaluates (26) there, in one
  vertex pass and one face pass; :func:`venergy_grad_trial` the same with the gradient (28) (for
  a trial after a rejected one, which is then usually accepted: its gradient is needed next).

The ADMM loop's relative change of V (rule (35)) is :func:`rel_change`: one pass, no
temporaries. :func:`normals_update_rho2` computes the normals of the new V and the multiplier
update (21) in one face pass; :func:`lengths_reg_energy` the new edge lengths and the
regulariser of (6) (the history energy) in one edge pass.

Each kernel has a numpy twin (``tests/test_kernels.py`` checks they agree). The compiled face
passes of :func:`venergy_grad_hdiag`, :func:`venergy_trial` and :func:`normals_update_rho2`
share their loop bodies (inlined helpers) with ``_kernels.venergy_grad``, ``_kernels.venergy``
and ``_kernels.face_normals`` and are compiled beside them in :mod:`meshrepair._kernels.venergy`
and :mod:`meshrepair._kernels.faces`; likewise :func:`lengths_reg_energy` with
``_kernels.reg_energy`` in :mod:`meshrepair._kernels.admm`.
"""

from __future__ import annotations

import numpy as np

from meshrepair import _kernels as _k
from meshrepair._kernels import FASTMATH, HAVE_NUMBA, _np_venergy, _np_venergy_grad, _np_vhess_diag
from meshrepair._kernels.weighted import _np_willmore_extra  # noqa: F401  (the twin)

if HAVE_NUMBA:
    # the face passes and the lengths + regulariser pass share their loop bodies with
    # _kernels.venergy / _kernels.faces / _kernels.admm (inlined helpers there), so they are
    # compiled there; the two passes below share none
    from meshrepair._kernels import njit
    from meshrepair._kernels.admm import _nb_lengths_reg_energy
    from meshrepair._kernels.faces import _nb_normals_update_rho2
    from meshrepair._kernels.venergy import (
        _nb_venergy_grad_hdiag,
        _nb_venergy_grad_trial,
        _nb_venergy_trial,
    )

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_descent_direction(g, h, h_min, d):  # pragma: no cover - compiled
        s = 0.0
        for v in range(g.shape[0]):
            hv = h[v]
            if hv < h_min:
                hv = h_min
            hinv = 1.0 / hv
            for k in range(3):
                x = -g[v, k] * hinv
                d[v, k] = x
                s -= g[v, k] * x
        return s

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_rel_change(A, B):  # pragma: no cover - compiled
        num = 0.0
        den = 0.0
        for i in range(A.shape[0]):
            for k in range(3):
                x = A[i, k] - B[i, k]
                num += x * x
                den += B[i, k] * B[i, k]
        return np.sqrt(num / max(den, 1e-300))

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_willmore_extra(l, Nv, fa, fb, w, w0, skip):  # pragma: no cover - compiled
        s = 0.0
        for e in range(l.shape[0]):
            dw = w[e] - w0
            if skip[e] or dw == 0.0:
                continue
            a = fa[e]
            b = fb[e]
            d = 0.0
            for k in range(3):
                x = Nv[a, k] - Nv[b, k]
                d += x * x
            s += dw * l[e] * l[e] * d
        return s


def willmore_extra(l, Nv, fa, fb, w, w0, skip):
    """The per-edge Willmore weights' share of the regulariser that
    :func:`lengths_reg_energy` (weight ``w0`` on every smooth edge) leaves out:
    ``Σ_{e ∉ skip} (w_e − w0) l_e² |Nv_{fa(e)} − Nv_{fb(e)}|²``, one pass without temporaries
    (the numpy twin builds three ``(nE, 3)`` arrays: 0.15 s an iteration at 1.18M vertices)."""
    if HAVE_NUMBA:
        return float(_nb_willmore_extra(l, Nv, fa, fb, w, float(w0), skip))
    return _np_willmore_extra(l, Nv, fa, fb, w, float(w0), skip)


def normals_update_rho2(V, F, N, rho2, beta2):
    """Unit face normals ``Nv`` of ``V`` (zero rows for degenerate faces) and the multiplier
    update (21) ``ρ2 -= β2 (N - Nv)`` in place; returns ``(Nv, ||N - Nv||²)``."""
    if HAVE_NUMBA:
        Nv, s = _nb_normals_update_rho2(V, F, N, rho2, float(beta2))
        return Nv, float(s)
    Nv = _k.face_normals(V, F)
    return Nv, _k.update_rho2(N, Nv, rho2, beta2)


def lengths_reg_energy(V, E, Nv, fa, fb, sharp, a, w):
    """Lengths of the interior edges ``E`` of ``V`` and the regulariser of (6) there (see
    ``_kernels.reg_energy``); returns ``(l, energy)``."""
    if HAVE_NUMBA:
        l, e = _nb_lengths_reg_energy(V, E, Nv, fa, fb, sharp, float(a), float(w))
        return l, float(e)
    l = _k.edge_lengths(V, E)
    return l, _k.reg_energy(Nv, l, fa, fb, sharp, a, w)


def _np_rel_change(A, B):
    d = A - B
    return float(np.sqrt(np.einsum("ij,ij->", d, d) / max(np.einsum("ij,ij->", B, B), 1e-300)))


def rel_change(A, B):
    """``||A - B||_F / ||B||_F`` (rule (35) with ``A = V^(k+1)``, ``B = V^(k)``)."""
    f = _nb_rel_change if HAVE_NUMBA else _np_rel_change
    return float(f(A, B))


def _np_venergy_grad_hdiag(V, F, z, V0, wfid, S):
    e, g = _np_venergy_grad(V, F, z, V0, wfid, S)
    return e, g, _np_vhess_diag(V, F, z, wfid)


def _np_descent_direction(g, h, h_min, d):
    d[:] = -g * (1.0 / np.maximum(h, h_min))[:, None]
    return -float(np.einsum("ij,ij->", g, d))


def _np_venergy_trial(V, d, step, out, F, z, V0, wfid):
    np.add(V, step * d, out=out)
    return _np_venergy(out, F, z, V0, wfid)


def venergy_grad_trial(V, d, step, out, F, z, V0, wfid, S=None):
    """Write ``V + step d`` into ``out`` and return the energy (26) and gradient (28) there
    (one vertex pass and one face pass; the values of ``venergy_trial`` followed by
    ``_kernels.venergy_grad(out, ...)``)."""
    if HAVE_NUMBA:
        grad = np.empty_like(V)
        e = _nb_venergy_grad_trial(V, d, float(step), out, F, z, V0, wfid, grad)
        return float(e), grad
    np.add(V, step * d, out=out)
    return _np_venergy_grad(out, F, z, V0, wfid, S)


def venergy_grad_hdiag(V, F, z, V0, wfid, S=None):
    """Energy (26), gradient (28) ``(nV, 3)`` and the Jacobi scale ``(nV,)`` of
    ``_kernels.vhess_diag``, in one face pass; ``S`` is the corner scatter matrix (numpy path)."""
    if HAVE_NUMBA:
        grad = np.empty_like(V)
        h = np.empty(len(V))
        e = _nb_venergy_grad_hdiag(V, F, z, V0, wfid, grad, h)
        return float(e), grad, h
    return _np_venergy_grad_hdiag(V, F, z, V0, wfid, S)


def descent_direction(g, h, h_min, d):
    """``d = -g / max(h, h_min)`` (per vertex, written into ``d``); returns ``⟨g, -d⟩ ≥ 0``."""
    f = _nb_descent_direction if HAVE_NUMBA else _np_descent_direction
    return float(f(g, h, float(h_min), d))


def venergy_trial(V, d, step, out, F, z, V0, wfid):
    """Write ``V + step d`` into ``out`` and return the energy (26) there."""
    f = _nb_venergy_trial if HAVE_NUMBA else _np_venergy_trial
    return float(f(V, d, float(step), out, F, z, V0, wfid))
