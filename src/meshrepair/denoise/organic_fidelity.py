"""The data weight of smooth organic meshes at low noise, and the input's tangential layout
.

**Fidelity weight.** The default weight of the data term of energy (6),
:func:`meshrepair.denoise.rules.lambda_from_noise`, is ``λ = max(0.02 / γ̂², 0.05)``: the
term ``(λ/2)‖V − V⁰‖²`` is the negative log-likelihood of white Gaussian noise of level ``γ̂``
(mean edge lengths) up to the prior's scale, so the weight grows as ``1/γ̂²`` (for a quadratic
prior and a signal whose spectrum is the prior's inverse, ``λ = c/σ²`` is exactly the Wiener
filter: tests/test_organic_fidelity.py). For a prior-matched signal, whose spectrum times
the prior's symbol is a constant ``K``, the Wiener weight is ``λ = wK/σ²``: the constant of the
law is the signal's relief against the prior. A CAD part is flat between its creases (small
``K`` where the prior acts); an organic surface carries relief at every scale, and its data
deserve the larger weight. On meshes that are not CAD parts
(crease support below :data:`meshrepair.denoise.rules.CAD_SUPPORT` of the edges), with white
(Willmore weight 1 and correlation ratio ``ρ <`` :data:`RHO_WHITE`), non-impulsive noise, the
main run uses

.. math:: λ = \\max(c / σ̂^2,\\; 0.05), \\qquad
          c = \\begin{cases} 0.04 & r_t < 0.65 \\\\ 0.08 & r_t \\ge 0.65, \\end{cases}

(:func:`organic_lambda`), twice the default for noise along the normals (``c = 0.04``
chosen on the design half of the benchmark grid). ``γ̂`` is a
level of the offsets *along the normals*; noise with a tangential part
(``r_t ≥`` :data:`meshrepair.denoise.rules.TANGENTIAL_MAX`,
:func:`meshrepair.denoise.scale.tangential_ratio`) puts part of its variance where the prior does
not act (the tangential layout), so the normal level under-reads the noise the data term
sees; the constant doubles there (``c = 0.08``). The robust probe
that decides the crease support keeps the default: its decisions do not change.
Correlated noise that the Willmore rule misses (it reads ``r_t ≥ 0.65``) reads ``ρ ≥ 1.42``
on the benchmark grid, white noise ``ρ ≤ 1.36``: hence :data:`RHO_WHITE` = 1.4 between them (a
larger λ keeps correlated bumps).

**Noise level.** The likelihood's ``σ`` is the level of the noise, while ``γ̂`` (a MAD of the
normal part of the umbrella Laplacian) reads the noise *and* the surface's own relief at the
one-ring scale (the clean shared organic meshes read 0.025-0.053). The two are independent, so their
variances add: ``γ̂² ≈ σ² + γ̂_relief²``. The probe's result (the robust stage of the one probe,
:mod:`meshrepair.denoise.analysis`) keeps the relief and little of the noise, and the same
estimator read on it gives ``γ̂_relief``; the law then reads

.. math:: σ̂ = \\sqrt{\\max(γ̂^2 − γ̂_{relief}^2,\\; 0)}

(:func:`noise_level`) in place of ``γ̂``. On the shared organic meshes with noise along the
normals of 0.05 l̄, γ̂ reads 0.057-0.085 and σ̂ 0.047-0.063; with random directions (normal part
0.029 l̄) γ̂ reads 0.037-0.071 and σ̂ 0.023-0.045; at 0.2 l̄ they differ by 1-5 % (the probe's
reading is then small against γ̂). A clean input reads σ̂ near 0 and
keeps its data (λ large). What the probe leaves of the noise enters ``γ̂_relief`` too, so σ̂
errs low, towards keeping the data.

**Graded by the tangential ratio** (:func:`tangential_gain`). The tangential ratio
``r_t`` is the robust level of the tangential part of the input's high-passed umbrella residual
over that of its normal part; for Gaussian noise of standard deviation σ_n along the normal and
σ_t per tangential axis on a regular layout it reads exactly ``√(ln 2) σ_t/σ_n`` (0.83 for
isotropic, random-direction noise; tests/test_organic_fidelity_graded.py), and 1.0-1.2 on
organic meshes with random-direction noise of 0.3 mean edge lengths. Above 1 the tangential
part dominates the normal one by more than random-direction noise itself gives: at low noise
the input's own irregular layout (up to 1.9-2.3) and its curvature leak into the one-ring
estimate ``γ̂``, which then over-reads the noise that the prior must remove, so the data weight
grows with ``r_t`` there. The law of the main run, for ``r_t ≥ 0.65``,

.. math:: λ = \\max\\bigl(g\\, c / σ̂^2,\\; 0.05\\bigr), \\qquad
          g(r_t) = \\tfrac12 \\bigl(1 + \\max(r_t, 1)^2\\bigr),

is the ungraded law for ``r_t ≤ 1`` (``g = 1``) and multiplies its constant by
``(1 + r_t²)/2`` above (``g c = 0.04 (1 + r_t²)``: the normal constant times the ratio of the
total to the normal part of the residual as ``r_t`` measures them), for ``r_t`` up to
:data:`GAIN_RATIO_MAX` = 2.5 (above it ``g = 1``: not a measurement). The run on a low-passed
input (:mod:`meshrepair.denoise.presmooth`) keeps ``g = 1`` and caps λ at
:data:`LOWPASSED_LAMBDA_MAX`: its ``r_t`` reads the filter's residue, not the input's noise.
σ̂ removes the relief from the level, not the layout's share of ``r_t``. On the
random-direction rows of ``benchmarks/monotone.py`` (6 meshes × 0.05-0.2 l̄) the gain at σ̂ is
mixed: without it three meshes lose up to 7-12 % and one gains 8-11 %; the median ratio to a
tuned Taubin filter is 0.91 with it and 0.89 without, 8 of 18 rows above the filter either way.

**Input layout.** The re-integration from the input of :mod:`meshrepair.denoise.organic` restarts
from
the input's *tangential* positions (NLLR's vertex update): right when the noise lies along the
normals, wrong when the noise has a tangential part of its own. With the stronger data weight
the solve's result stays closer to the input, its residual reads more normal, and the
re-anchoring and then the re-integration could fire on random-direction noise and restore
its tangential part. :func:`reintegrate_allowed` keeps it off when the
input's own tangential ratio (:func:`meshrepair.denoise.scale.tangential_ratio`, read on the probe)
says the noise is not along the normals, ``r_t ≥`` :data:`meshrepair.denoise.rules
.TANGENTIAL_MAX`, unless the noise is impulsive (the thrown vertices are what the
re-integration is for).
"""

from __future__ import annotations

import numpy as np

ORGANIC_FIDELITY = True
LAMBDA_SCALE = 0.04
LAMBDA_SCALE_TANGENTIAL = 0.08
LOWPASSED_LAMBDA_MAX = 8.0
"""Largest λ of this law on a low-passed input (the coarse-to-fine run): the residual
roughness γ̂ read there measures the noise left, not the filter's bias."""
RHO_WHITE = 1.4
GAIN_RATIO_MAX = 2.5
"""Largest ``r_t`` :func:`tangential_gain` trusts: random-direction noise on the benchmark
grid reads at most about 2.3; above it the robust levels are not a measurement (a 4-vertex
tetrahedron, with no vertex two rings inside, reads 18.6, and a gain there would keep a
collapsed result) and the gain is 1."""


def noise_level(gamma: float, gamma_relief: float) -> float:
    """``σ̂ = √(max(γ̂² − γ̂_relief², 0))``: the level of the noise alone (module docstring,
    *Noise level*), mean edge lengths; ``γ̂`` when ``γ̂_relief`` is not finite."""
    g, r = float(gamma), float(gamma_relief)
    if not np.isfinite(r):
        return g
    return float(np.sqrt(max(g * g - r * r, 0.0)))


def organic_lambda(gamma: float, tangential: float = 0.0, *, graded: bool = True) -> float:
    """``λ = max(g c / max(σ̂, γ_0)², 0.05)`` (module docstring); ``gamma`` is the noise level
    σ̂ of :func:`noise_level` (the one-ring level γ̂ where no relief was read), mean edge lengths,
    ``γ_0`` = :data:`meshrepair.denoise.rules.GAMMA_FLOOR`, ``c = 0.04`` for noise along the
    normals (``r_t < 0.65``), ``c = 0.08`` otherwise.

    ``graded`` (:func:`tangential_gain`): for ``r_t ≥ 0.65`` ``c`` is multiplied by
    ``g(r_t) = (1 + max(r_t, 1)²) / 2`` (1 for ``r_t ≤ 1``: the ungraded law there). The run on
    a low-passed input (:mod:`meshrepair.denoise.presmooth`) passes ``graded=False``: its
    ``r_t`` reads the filter's residue, not the input's noise, and its γ̂ under-reads the
    data's error, so ``g = 1`` and ``λ ≤`` :data:`LOWPASSED_LAMBDA_MAX`."""
    from meshrepair.denoise.rules import GAMMA_FLOOR, TANGENTIAL_MAX

    g = tangential_gain(tangential) if graded else 1.0
    gam = max(float(gamma), GAMMA_FLOOR) if np.isfinite(gamma) else GAMMA_FLOOR
    c = LAMBDA_SCALE if tangential < TANGENTIAL_MAX else LAMBDA_SCALE_TANGENTIAL
    lam = max(g * c / gam ** 2, 0.05)
    return float(lam if graded else min(lam, LOWPASSED_LAMBDA_MAX))


def tangential_gain(tangential: float) -> float:
    """``g(r_t)`` of the module docstring: 1 below
    :data:`meshrepair.denoise.rules.TANGENTIAL_MAX` (noise along the normals) and for ``0.65 ≤
    r_t ≤ 1`` (random-direction noise at moderate level reads 0.86-1.22), ``(1 + r_t²) / 2``
    above 1: where the tangential part of the input's high-passed umbrella residual dominates
    its normal part (low random-direction noise on an irregular layout reads up to about 2.3),
    up to :data:`GAIN_RATIO_MAX` (``g ≤ 3.625``); a ratio above it is not a measurement and,
    like a NaN ratio (no probe), gives 1 (the ungraded law)."""
    from meshrepair.denoise.rules import TANGENTIAL_MAX

    r = float(tangential)
    if not np.isfinite(r) or r < TANGENTIAL_MAX or r > GAIN_RATIO_MAX:
        return 1.0
    return 0.5 * (1.0 + max(r, 1.0) ** 2)


def main_lambda(gamma: float, tangential: float, info: dict, *, graded: bool = True) -> float:
    """:func:`organic_lambda` for the main run of :func:`meshrepair.denoise`; records in
    ``info["lambda_gain"]`` the factor the re-anchoring's direction test corrects for
    (:func:`reanchor_ratio_at_ungraded`): for noise with a tangential part (``r_t ≥``
    :data:`meshrepair.denoise.rules.TANGENTIAL_MAX`), where a raised weight makes the residual
    read falsely "along the normals", ``g c / c_d``, the raise over the constant ``c_d`` =
    :data:`meshrepair.denoise.rules.LAMBDA_SCALE` of the default law; 1 for noise along the
    normals (re-anchoring is meant for it) and when ``graded`` is off (the run on a low-passed
    input, whose λ is capped)."""
    from meshrepair.denoise.rules import LAMBDA_SCALE as C_DEFAULT
    from meshrepair.denoise.rules import TANGENTIAL_MAX

    info["lambda_gain"] = (tangential_gain(tangential) * LAMBDA_SCALE / C_DEFAULT
                           if graded and tangential >= TANGENTIAL_MAX else 1.0)
    return organic_lambda(gamma, tangential, graded=graded)


def reanchor_ratio_at_ungraded(ratio: float, gain: float) -> float:
    """The re-anchoring's residual tangential ratio ``ρ_t`` (:func:`meshrepair.denoise.reproject
    .residual_tangential_ratio`) read at the default law's data weight: ``ρ_t √g``, ``g`` the
    factor of :func:`main_lambda` (``info["lambda_gain"]``). A data weight raised by ``g`` keeps
    the solve's result nearer the input, whose tangential offsets the
    prior does not remove, so the tangential part of the residual shrinks against its normal
    part by about ``1/√g``: the residual then reads "along the normals" for noise that is not,
    and the re-anchoring would slide the vertices towards the input's noisy tangential
    positions. ``√g`` undoes that shrinkage, so the re-anchoring decides as at the default
    law's weight."""
    return float(ratio) * float(np.sqrt(max(float(gain), 1.0)))


def applies(support_fraction: float, willmore: float, outside: float, impulsive: bool,
            rho: float) -> bool:
    """The gate of :func:`organic_lambda`: a mesh that is not a CAD part (crease support below
    :data:`meshrepair.denoise.rules.CAD_SUPPORT`), white noise (Willmore weight 1 *and* the
    correlation ratio ρ of :func:`meshrepair.denoise.scale.noise_scale` below :data:`RHO_WHITE`),
    the
    outside weight not raised (``w_out = 1``) and noise that is not impulsive."""
    from meshrepair.denoise.rules import CAD_SUPPORT

    return bool(ORGANIC_FIDELITY and np.isfinite(support_fraction)
                and support_fraction < CAD_SUPPORT and willmore == 1.0 and outside == 1.0
                and not impulsive and np.isfinite(rho) and rho < RHO_WHITE)


def reintegrate_allowed(tangential: float, impulsive: bool) -> bool:
    """Whether the re-integration from the input may run: the input's noise lies along the
    normals (``r_t <`` :data:`meshrepair.denoise.rules.TANGENTIAL_MAX`) or is impulsive. An
    unknown ratio (no probe) allows it (the earlier behaviour)."""
    from meshrepair.denoise.rules import TANGENTIAL_MAX

    if not ORGANIC_FIDELITY or impulsive or not np.isfinite(tangential):
        return True
    return bool(tangential < TANGENTIAL_MAX)
