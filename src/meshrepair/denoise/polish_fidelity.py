"""The polish's vertex step with the fidelity kept: forward-backward splitting.

The polish of :mod:`meshrepair.denoise.polish` moves the vertices to the filtered face normals
``n'`` by Sun et al. steps, the V-subproblem (26) of the paper *with* ``λ = 0``: nothing ties
the polished vertices to the data any more. On a heavy-noise CAD part that lets two things the
solve left stand: the narrow strips between a detected crease and a soft one tilt (a shallow
crease comes out several times steeper), and the vertices keep the solve's tangential drift
(about 0.16 mean edge lengths outside the crease-supported region where the input has almost
none). Both are errors the *data* do not support, averaged over a few rings.

**Energy.** For fixed target normals ``n'`` (one filter pass) the vertex step now descends

.. math:: E(x) = \\underbrace{\\sum_f \\sum_{i \\in f} \\big(n'_f \\cdot (x_i - c_f)\\big)^2}_{
          E_n(x)} + \\frac{η}{2} \\sum_i \\|x_i - V^0_i\\|^2,

the V-subproblem (26) with a data term of weight η (``V⁰`` the solve's fidelity data).

**Iteration** (forward-backward splitting, one pair per step): a Sun step ``G`` on ``E_n``
(:func:`meshrepair.denoise.polish.vertex_update`, one step: ``x_i ← x_i + (1/|F_i|) Σ_{f ∋ i}
n'_f (n'_f · (c_f - x_i))``), then the proximal map of the data term with unit step,

.. math:: \\operatorname{prox}(y) = \\operatorname{argmin}_x \\tfrac12 \\|x - y\\|^2
          + \\tfrac{η}{2} \\|x - V^0\\|^2 = \\frac{y + η V^0}{1 + η}.

A fixed point satisfies ``G(x*) - x* = η (x* - V⁰)``: the Sun displacement (the normal-fitting
force in the Sun metric) balances the pull towards the data. Where ``E_n`` does not resist a
motion (a tangential slide on a plane whose faces already have the normals ``n'``, or a
translation of the whole plane) the step is the prox alone and the distance to the data
shrinks by exactly ``(1 + η)^{-k}`` after k steps (tested); where the normals do resist
(an isolated vertex pulled off its plane) the pull moves it by only ``O(η)`` of its offset.
So the data correct what is consistent over many vertices, not the per-vertex noise.

``η = POLISH_ETA = 0.002`` per step, ``POLISH_FIT_STEPS = 30`` steps per filter pass (the
polish's 10 passes give 300 steps, so the data's weight in the fixed point is what matters,
not the count); both scale-free (positions enter linearly). Chosen on heavy-noise CAD rows
and a real scan of the benchmark grid (docs/parameters.md).
"""

from __future__ import annotations

import numpy as np

POLISH_ETA = 0.002
"""``η``: weight of the data term per Sun step (module docstring)."""

POLISH_FIT_STEPS = 30
"""Sun steps (each followed by the prox) per filter pass when the data term is on."""


def data_prox(Y: np.ndarray, V0: np.ndarray, eta: float) -> np.ndarray:
    """``(Y + η V⁰) / (1 + η)``: the proximal map of ``(η/2)||x - V⁰||²`` at ``Y`` (unit
    step), a new array."""
    return (np.asarray(Y, dtype=np.float64) + eta * np.asarray(V0, dtype=np.float64)) / (1.0 + eta)


def vertex_update_with_data(X: np.ndarray, F: np.ndarray, Nt: np.ndarray, V0: np.ndarray, *,
                            eta: float = POLISH_ETA, steps: int = POLISH_FIT_STEPS
                            ) -> np.ndarray:
    """``steps`` forward-backward steps on ``E`` of the module docstring.

    Parameters
    ----------
    X : (nV, 3) float64, the start
    F : (nF, 3) int64
    Nt : (nF, 3) float64, unit target normals ``n'``
    V0 : (nV, 3) float64, the data
    eta : float >= 0, the data weight per step (0: plain Sun steps)
    steps : int >= 0

    Returns
    -------
    (nV, 3) float64, a new array
    """
    from meshrepair._kernels.bilateral import sun_steps

    X = np.array(X, dtype=np.float64, copy=True)
    if eta <= 0:
        return sun_steps(X, F, Nt, steps)
    for _ in range(int(steps)):
        X = data_prox(sun_steps(X, F, Nt, 1), V0, eta)
    return X


def polish_energy(X: np.ndarray, F: np.ndarray, Nt: np.ndarray, V0: np.ndarray,
                  eta: float) -> float:
    """``E(x)`` of the module docstring (for tests and diagnostics)."""
    X = np.asarray(X, dtype=np.float64)
    C = X[F].mean(axis=1)
    en = sum(float(np.sum(np.einsum("ij,ij->i", X[F[:, j]] - C, Nt) ** 2)) for j in range(3))
    d = X - np.asarray(V0, dtype=np.float64)
    return en + 0.5 * eta * float(np.einsum("ij,ij->", d, d))
