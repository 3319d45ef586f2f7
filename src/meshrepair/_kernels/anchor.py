"""The tangential anchor's proximal step (:func:`meshrepair.fidelity.tangential_anchor`) in one
vertex pass: ``V_i - w_i P_i (V_i - V⁰_i)`` with ``P_i = I - n_i n_iᵀ``. The numpy
expression makes four ``(nV, 3)`` temporaries; the kernel none (strict IEEE arithmetic, the dot
product summed in the order numpy's einsum uses: results equal the numpy twin's bit for bit on
this machine, ``tests/test_kernels.py``)."""

from __future__ import annotations

import numpy as np

from ._jit import HAVE_NUMBA, njit


def _np_anchor_step(V, V0, n, weight):
    d = V - V0
    dt = d - np.einsum("ij,ij->i", d, n)[:, None] * n
    return V - weight[:, None] * dt


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_anchor_step(V, V0, n, weight):  # pragma: no cover - compiled
        out = np.empty_like(V)
        for i in range(V.shape[0]):
            d0 = V[i, 0] - V0[i, 0]
            d1 = V[i, 1] - V0[i, 1]
            d2 = V[i, 2] - V0[i, 2]
            # the summation order of numpy's einsum here (bit-equal to the numpy expression)
            s = (d0 * n[i, 0] + d2 * n[i, 2]) + d1 * n[i, 1]
            w = weight[i]
            out[i, 0] = V[i, 0] - w * (d0 - s * n[i, 0])
            out[i, 1] = V[i, 1] - w * (d1 - s * n[i, 1])
            out[i, 2] = V[i, 2] - w * (d2 - s * n[i, 2])
        return out


def anchor_step(V, V0, n, weight):
    """``V - w (d - (d·n) n)`` with ``d = V - V0`` per vertex, a new ``(nV, 3)`` array."""
    if HAVE_NUMBA:
        return _nb_anchor_step(V, V0, n, weight)
    return _np_anchor_step(V, V0, n, weight)
