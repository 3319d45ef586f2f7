"""Heavy noise on smooth organic meshes: a low-pass of the *input* before the solve.

At heavy white noise (γ ≳ 0.3 mean edge lengths) on a smooth organic surface the ADMM of energy
(6) started from the noisy input freezes part of the noise in: the edge-Willmore prior acts on
the normals of the *noisy* faces, the V-step follows them and the vertices drift tangentially
(about 0.2 mean edge lengths at γ 0.5 normal noise, whose input has no tangential error at
all). No finish after the solve takes that back. An isotropic low-pass of the input itself
does not freeze it. So the schedule becomes coarse-to-fine: the low-pass removes the noise's
wavelengths up to a few rings
(√k), and the whole variational model (probe, regions, solve, finishes) then runs on the
low-passed mesh, whose remaining noise is small (γ̂ 0.03-0.06), to restore what the isotropic
filter rounded.

**The low-pass.** Taubin's λ|μ filter (1995), the full (tangential too) step of
:func:`meshrepair.denoise.lowpass.taubin_region` on every vertex (the probe's crease-supported
region C is not kept fixed: at this noise level on an organic mesh its chains are noise, and
fixing them would leave their vertices as spikes):

.. math:: V \\leftarrow V + λ (WV - V),\\quad V \\leftarrow V + μ (WV - V),
          \\qquad λ = 0.5,\\ μ = -0.53,

``k`` times. On the eigenvalue ``x ∈ [0, 2]`` of ``I − W`` the transfer function is
``t(x)^k = ((1 − λx)(1 − μx))^k``: 1 at ``x = 0`` (a translation, and an affine field on a flat
grid, are fixed points; no shrinkage inside Taubin's pass band ``x < 1/λ + 1/μ``) and below 1
on the noise's band, so ``k`` pairs are a filter of width ∝ √k rings. The width is taken
proportional to the noise level (the diffusion time to γ²):

.. math:: k = \\mathrm{clip}\\bigl(\\mathrm{round}((γ_k / γ_p)^2), 0, K_{max}\\bigr),
          \\qquad γ_k = γ̂\\,\\sqrt{1 + \\min(r_t, 1)^2}, \\quad γ_p = 0.044,\\ K_{max} = 96,

where γ̂ is the MAD level of the normal part of the umbrella Laplacian
(:func:`meshrepair.model.noise.noise_statistics`) and ``r_t`` the tangential ratio of
:func:`meshrepair.denoise.scale.tangential_ratio` read on the probe (0.1-0.4 for noise along the
normals, ≈ 1 for random directions). γ̂ sees only the normal part of the noise; the full step
also removes the tangential part, which counts half in ``γ_k`` (the whole tangential part,
``c = 2`` below, over-smooths random-direction inputs on the benchmark grid).

**The gate** (:func:`presmooth_steps`): an organic mesh (crease support below
:data:`meshrepair.denoise.rules.CAD_SUPPORT`, outside weight 1), white noise (Willmore weight 1),
not impulsive (Taubin's mean would spread a thrown vertex over its rings) and heavy:

.. math:: γ_t = γ̂\\,\\sqrt{1 + 2 \\min(r_t, 1)^2} > γ_{min} = 0.32,

``γ_t`` the total level of the displacement: a random-direction displacement of level γ has
normal part γ/√3 (what γ̂ reads) and r_t reads ≈ 1 on it, so ``γ_t ≈ γ̂√3 ≈ γ``. γ_min lies
between the benchmark rows where the step pays (γ_t ≥ 0.336) and those where it loses
(γ_t 0.305-0.311; docs/parameters.md).

The run on the low-passed mesh skips the polish of :mod:`meshrepair.denoise.polish`: what is left
after the filter is correlated by the filter itself, and the polish at that scale is the
dominant cost (about three times the run's time and memory) while it does not lower the error
there.
"""

from __future__ import annotations

import numpy as np

PRESMOOTH = True
GAMMA_P = 0.044
GAMMA_MIN = 0.32
MAX_STEPS = 96


def effective_level(gamma: float, tangential: float, weight: float = 1.0) -> float:
    """``γ̂ √(1 + c min(r_t, 1)²)`` of the module docstring: ``c = 2`` the total level ``γ_t``
    of the gate, ``c = 1`` the level ``γ_k`` of the length (NaN ``r_t`` counts as 0)."""
    r = float(tangential) if np.isfinite(tangential) else 0.0
    r = min(max(r, 0.0), 1.0)
    return float(gamma) * float(np.sqrt(1.0 + float(weight) * r * r))


def presmooth_steps(gamma: float, tangential: float, *, support_fraction: float,
                    outside: float, willmore: float, impulsive: bool,
                    gamma_p: float | None = None, gamma_min: float | None = None,
                    max_steps: int | None = None, heavy: bool = False) -> int:
    """λ|μ pairs ``k`` of the module docstring, 0 when the gate does not fire. ``heavy``: the
    noise is known to be heavy for this mesh from another read than γ_t
    (:func:`meshrepair.denoise.crease_network.heavy_from_network`), so the level test is not
    asked."""
    from meshrepair.denoise.rules import CAD_SUPPORT

    gp = GAMMA_P if gamma_p is None else float(gamma_p)
    gm = GAMMA_MIN if gamma_min is None else float(gamma_min)
    cap = MAX_STEPS if max_steps is None else int(max_steps)
    if not PRESMOOTH or impulsive or outside != 1.0 or willmore != 1.0:
        return 0
    if not (support_fraction < CAD_SUPPORT) or not np.isfinite(gamma):
        return 0
    if not heavy and not effective_level(gamma, tangential, 2.0) > gm:
        return 0
    return int(np.clip(round((effective_level(gamma, tangential) / gp) ** 2), 0, cap))


def presmooth(V: np.ndarray, edges: np.ndarray, free: np.ndarray, steps: int) -> np.ndarray:
    """The low-pass of the module docstring: ``steps`` full λ|μ pairs on the vertices ``free``.

    Parameters
    ----------
    V : (nV, 3) float64, the input
    edges : (nE, 2) int64, the mesh's edges
    free : (nV,) bool, the vertices that move (``denoise`` moves all of them)
    steps : number of λ|μ pairs (0 returns a copy)

    Returns
    -------
    (nV, 3) float64, a new array
    """
    from meshrepair.denoise.lowpass import taubin_region

    return taubin_region(V, edges, free, int(steps))
