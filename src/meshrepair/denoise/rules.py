"""The rules that read the input: every default of :func:`meshrepair.denoise` that is
computed from the mesh (noise level, its scale and direction, impulsiveness, the crease-supported
fraction), each written as maths with its threshold; the thresholds were chosen on the
benchmark grid (docs/parameters.md).

Pure functions of the statistics :mod:`meshrepair.model.noise`, :mod:`meshrepair.denoise.scale` and
:mod:`meshrepair.denoise.regions` compute; :mod:`meshrepair.denoise` applies them (and re-exports
them,
so ``meshrepair.denoise.api.outside_weight`` and the constants stay where they were).
"""

from __future__ import annotations

import numpy as np

LAMBDA_SCALE = 0.02
"""``c`` of ``λ = c / γ̂²``: the fidelity weight per squared mean edge length at unit noise."""
LAMBDA_MIN = 0.05
"""Smallest default λ: heavy noise still ties the result to its data."""
GAMMA_FLOOR = 1e-3
"""Noise level (mean edge lengths) below which γ̂ reads as this floor (a clean input)."""


LOWPASSED_LAMBDA_MAX = 1.0
"""Largest default λ of the run on a low-passed input (coarse-to-fine,
:mod:`meshrepair.denoise.presmooth`): its data's error against the surface is the filter's bias
plus the noise left, and the residual roughness γ̂ read on it measures only the latter."""


def lambda_from_noise(gamma: float, *, lowpassed: bool = False) -> float:
    """Default fidelity weight λ of (6): ``λ = max(c / max(γ̂, γ_0)², λ_min)``.

    The data term ``(λ/2)‖V − V⁰‖²`` is the negative log-likelihood of white Gaussian noise of
    level ``γ̂`` (mean edge lengths) up to the prior's scale, so the MAP weight grows as
    ``1/γ̂²``: low noise ties the result closely to its data, and a surface at low noise keeps
    the relief the prior would flatten. The floor ``λ_min`` keeps heavy noise tied to its data.
    On a low-passed input (``lowpassed``) γ̂ under-reads the data's error and λ is at most
    :data:`LOWPASSED_LAMBDA_MAX`. (The hole filler and the completion use the model's default
    :func:`meshrepair.model.schedule.lambda_from_noise`, capped at 1: their data are the
    patch's surround, not a noisy measurement.)"""
    g = max(float(gamma), GAMMA_FLOOR) if np.isfinite(gamma) else GAMMA_FLOOR
    lam = max(LAMBDA_SCALE / g ** 2, LAMBDA_MIN)
    return min(lam, LOWPASSED_LAMBDA_MAX) if lowpassed else lam

HEAVY_NOISE = 0.33
HEAVY_SLOPE = 600.0
"""Above this estimated level the robust stage grows by 600 iterations per unit of γ̂ (up to 120):
heavy noise is otherwise frozen in by the feature stage (measured in docs/parameters.md)."""


HEAVY_ROBUST_A = 0.25


def robust_a_from_noise(gamma: float) -> float:
    """Non-convexity of the robust stage: 0.5, or ``HEAVY_ROBUST_A`` above ``HEAVY_NOISE``."""
    return HEAVY_ROBUST_A if gamma > HEAVY_NOISE else 0.5


def robust_iters_from_noise(gamma: float, folded_fraction: float = 0.0) -> int:
    """Default length of the robust stage: ``clip(130 γ̂, 10, 40)``, or 40 when more than 1 % of
    the faces were folded over. ``denoise`` passes the larger of the MAD and RMS noise
    estimates, so impulsive noise (RMS above MAD) also gets the long stage.

    The robust stage removes noise but also rounds features the longer it runs: low noise
    wants a short stage (10 iterations at γ̂ = 0.1), noise near 0.3 mean edge lengths a long
    one (40); the slope 130 joins the two (docs/parameters.md). Random-direction noise reads
    about half its level along the normals but needs the long stage; the fold-overs it causes
    identify it.
    """
    if gamma > HEAVY_NOISE:
        return int(np.clip(round(40 + HEAVY_SLOPE * (gamma - HEAVY_NOISE)), 40, 120))
    if folded_fraction > 0.01:
        return 40
    return int(np.clip(round(130.0 * gamma), 10, 40))


TANGENTIAL_MAX = 0.65
"""Below this :func:`meshrepair.denoise.scale.tangential_ratio` the noise is taken to lie along the
normals (measured 0.08-0.47 on normal noise, 0.83-1.29 on random-direction noise) and the
crease-supported region gets the tangential anchor of
:func:`meshrepair.model.fidelity.tangential_anchor`."""


PROBE_MAX_ITERS = 120
PROBE_EARLY_STOP = True
"""Cap of the robust probe that decides the crease-supported region."""

FLAT_SPREAD_DEFAULT = 7.0
"""Crease-supported edges whose robust-probe normal spread is below this (degrees) get the
flat-TV prior (MC with ``a = FLAT_A``) in the feature stage instead of edge-Willmore."""
FLAT_A = 0.5

IMPULSIVE_RATIO = 1.3
"""Noise whose RMS level exceeds its robust (MAD) level by this factor is called impulsive: a
minority of vertices moved far. The RMS is the one without the surface's coherent relief
(:func:`meshrepair.model.noise.noise_statistics` with ``isolated``), so creases at low noise
do not count. Gaussian and scanner noise read 1.00-1.10 on the benchmark grid, impulsive noise
1.5-2.3, so 1.3 lies between the two groups."""


def is_impulsive(gamma: float, gamma_rms_isolated: float) -> bool:
    """``γ̂_rms,iso > 1.3 γ̂_MAD`` (see :data:`IMPULSIVE_RATIO`), with the RMS level of the
    noise without the surface's coherent relief."""
    return bool(gamma_rms_isolated > IMPULSIVE_RATIO * max(gamma, 1e-12))


def huber_from_noise(gamma_rms: float, impulsive: bool) -> float:
    """Default threshold δ of the robust fidelity (:mod:`meshrepair.model.fidelity`): ``2 γ̂_rms``
    for impulsive noise (:func:`is_impulsive`), 0 (the paper's quadratic fidelity)
    otherwise."""
    return 2.0 * gamma_rms if impulsive else 0.0


W_FULL = 16.0
"""The largest automatic Willmore weight (noise correlated over ``ℓ ≥ 2`` rings)."""


def willmore_weight_from_scale(rho: float, impulsive: bool = False,
                               tangential: float = 0.0) -> float:
    """Weight ``w`` of edge-Willmore from the noise correlation ratio ρ of
    :func:`meshrepair.denoise.scale.noise_scale` (``ρ = 1`` for i.i.d. noise):

    .. math:: w = \\mathrm{clip}(1 + 150(ρ - 1.12),\\, 1,\\, 16),

    1 for white noise (ρ ≤ 1.12; Gaussian noise reads 0.83-1.09 on the benchmark grid), 16 for
    scanner-like noise correlated over ≥ 2 rings (ρ ≥ 1.22).
    The quadratic prior ``w ||DN||²`` against the coupling ``β2 ||N - 𝒩(V)||²`` smooths the
    normals over about ``√(w/β2)`` rings, so a larger ``w`` acts at the scale of the noise.
    Impulsive noise raises ρ through its isolated spikes (w = 1), and so do noise with a
    tangential part and low noise on an irregular mesh (the tangential residual and the
    curvature left in the reference): the weight is raised only when the noise lies along the
    normals, ``tangential`` (:func:`meshrepair.denoise.scale.tangential_ratio`) < 0.65: white
    noise with a tangential part reads ρ 1.2-1.35 with ``r_t`` above 1, scanner noise ρ ≈ 1.22
    with ``r_t`` ≈ 0.3. Smooth synthetic correlated noise can read ``r_t ≥ 0.65`` (its
    high-passed normal part is small) and is then missed (docs/parameters.md).
    """
    if impulsive or tangential >= TANGENTIAL_MAX:
        return 1.0
    return float(np.clip(1.0 + 150.0 * (rho - 1.12), 1.0, W_FULL))


def willmore_weight_from_band(steps: int) -> float:
    """Weight ``w`` of edge-Willmore for correlated noise found by the band read of
    :mod:`meshrepair.denoise.corrwhite` (``m̂`` diffusion steps, correlation length
    ``ℓ = √m̂``) where the profile of :func:`willmore_weight_from_scale` reads white:

    .. math:: w = \\mathrm{clip}(W_{full}\\, ℓ^2 / 4,\\, 1,\\, W_{full})
              = \\mathrm{clip}(4 \\hat m,\\, 1,\\, 16).

    The prior smooths the normals over about ``√(w/β2)`` rings, so ``w ∝ ℓ²`` acts at the
    noise's own length; the constant is the profile rule's: its full weight 16 belongs to noise
    correlated over ``ℓ = 2`` rings (m = 4).
    """
    return float(np.clip(W_FULL * float(steps) / 4.0, 1.0, W_FULL))


CAD_SUPPORT = 0.2
CAD_WILLMORE = 6.0
"""Rule of :func:`outside_weight`: a mesh whose crease-supported region covers at least
``CAD_SUPPORT`` of its edges is a CAD part, and edge-Willmore outside that region gets the
weight ``CAD_WILLMORE`` (times ``w``) in the feature stage."""


def outside_weight(support_fraction: float, tangential: float) -> float:
    """Factor on edge-Willmore *outside* the crease-supported region C, feature stage only:

    .. math:: w_{out} = \\begin{cases} 6 & |C| / n_E \\ge 0.2 \\text{ and } r_t < 0.65 \\\\
                                       1 & \\text{otherwise.} \\end{cases}

    Outside C a CAD part is smooth patches (planes, cylinders, blends) far from its creases.
    The quadratic prior ``w ||t_e||²`` against the coupling ``β2 ||N - 𝒩(V)||²`` averages the
    normals over about ``√(w/β2)`` rings; with ``w = 1`` it leaves a ripple of a few degrees
    on the smooth patches, and ``w_out = 6`` averages over ≈ 1.5 rings more. It is quadratic,
    so it does not terrace the curved patches the flat-TV class would.

    The supported fraction separates the cases: CAD parts read 0.41-0.64 on the benchmark grid,
    organic meshes 0.04-0.10 (short left-over chains), so organic results do not change.
    Heavy noise on coarse organic meshes can read high; there C covers nearly everything and
    the factor acts on little. Noise not along the normals (``r_t ≥ 0.65``,
    :data:`TANGENTIAL_MAX`) keeps 1: there the support is not a set of creases.
    Thresholds chosen on the benchmark grid (docs/parameters.md).
    """
    if support_fraction >= CAD_SUPPORT and tangential < TANGENTIAL_MAX:
        return CAD_WILLMORE
    return 1.0


POLISH = True
"""Heavy noise on a CAD part gets the crease-bounded polish of :mod:`meshrepair.denoise.polish`."""


def polish_rule(gamma: float, outside: float, willmore: float, length: float
                ) -> tuple[int, float, int] | None:
    """Whether the result is polished (:mod:`meshrepair.denoise.polish`) and with which ring count
    ``r``, flatness threshold ``τ`` (degrees) and number of passes:

    .. math:: \\text{polish} \\iff (\\max(γ̂, γ̂_{rms}) > 0.33 \\wedge w_{out} > 1)
              \\vee w > 1, \\qquad
              r = \\mathrm{round}(4 \\max(1, ℓ)),\\; τ = 5° \\max(1, ℓ),\\;
              n_{pass} = \\mathrm{round}(10 \\max(1, ℓ^2)),

    heavy noise (:data:`HEAVY_NOISE`) on a CAD part with the noise along the normals (the
    rule of :func:`outside_weight`), or noise found correlated along the normals (``w > 1``,
    :func:`willmore_weight_from_scale`), with ``ℓ`` its correlation length (0 for white
    noise). A bump ``ℓ`` edges wide is averaged by a neighbourhood ``ℓ`` times wider; its
    residual slopes are larger (hence τ), and the filter-and-move passes diffuse, like the
    V-steps of :func:`inner_iters_from_scale`, over about ``ℓ²`` times as many passes.
    At moderate white noise the feature stage already leaves the flat patches within 2°, and
    the filter there moves crease vertices that are right; organic meshes and random-direction
    noise have no converged crease mask to bound it. Thresholds chosen on the benchmark grid
    (docs/parameters.md).
    """
    heavy = gamma > HEAVY_NOISE and outside > 1.0
    if not POLISH or not (heavy or willmore > 1.0):
        return None
    ell = max(1.0, float(length)) if willmore > 1.0 and np.isfinite(length) else 1.0
    return int(round(4 * ell)), 5.0 * ell, int(round(10 * ell * ell))


def inner_iters_from_scale(length: float, base: int = 3) -> int:
    r"""V-steps per ADMM iteration for noise correlated over ``ℓ`` mean edge lengths
    (:func:`meshrepair.denoise.scale.noise_scale`), used when the noise is found correlated (``w >
    1``):

    .. math:: n_{inner} = \mathrm{clip}(\mathrm{round}(3\, \max(1, ℓ^2)),\, 3,\, 12).

    The V-update (26) is solved by a few preconditioned gradient steps, each moving a vertex
    from its 1-ring: a bump of the vertices ``ℓ`` rings wide needs about ``ℓ²`` times as many
    local steps to follow the smoothed normals as a one-ring bump (diffusion). With correlated
    noise the vertices, not the prior, hold the low-frequency bumps in (the ADMM normals are
    smooth, the mesh's own normals are not), so the V-steps are the bottleneck. The probe is
    run again with the new count (the correlation is known only after a first probe): its
    better converged normals keep the crease chains. On i.i.d. noise more steps follow the
    noise as well, hence only for correlated noise (``w > 1``).
    """
    return int(np.clip(round(base * max(1.0, float(length) ** 2)), base, 12))


WARM_IMPULSIVE = True
WARM_IMPULSIVE_GAMMA = 0.15


def warm_start_from_probe(impulsive: bool, outside: float, gamma: float) -> bool:
    """Whether the main run starts from the robust probe's result instead of the input:

    .. math:: \\text{impulsive} \\wedge w_{out} > 1 \\wedge γ̂ > 0.15,

    impulsive noise (:func:`is_impulsive`) on a CAD part (the rule of :func:`outside_weight`)
    at a real noise level. The probe is an MC smoother on every edge: it removes the thrown
    vertices and keeps the creases, so the main run's robust stage starts without the spikes
    that otherwise pull the first feature iterations; the fidelity data are unchanged. Not on
    organic meshes (the probe's MC prior flattens their fine relief) and not at low noise
    (γ̂ ≤ 0.15, where Gaussian noise can read impulsive and the probe costs detail). Checked on
    synthetic impulsive noise (a fraction of the vertices thrown along the normals over 0.1 l̄
    Gaussian noise) held out from the choice (docs/parameters.md).
    """
    return bool(WARM_IMPULSIVE and impulsive and outside > 1.0 and gamma > WARM_IMPULSIVE_GAMMA)


ORGANIC = True
GUIDANCE_GAMMA_UNIT = 0.09
"""Noise level (mean edge lengths) per pass of the organic guidance filter."""


def guidance_rule(gamma: float, outside: float, willmore: float) -> int:
    """Passes ``p`` of the one-ring bilateral guidance of :mod:`meshrepair.denoise.organic`:

    .. math:: p = \\begin{cases} \\mathrm{clip}(\\mathrm{round}(γ̂ / 0.09), 1, 3) &
              w_{out} = 1 \\wedge w = 1 \\wedge γ̂ \\le 0.33 \\\\ 0 & \\text{otherwise,}
              \\end{cases}

    on meshes that are not CAD parts (the rule of :func:`outside_weight` does not fire), with
    white noise (the Willmore weight of :func:`willmore_weight_from_scale` is 1) that is not
    heavy (:data:`HEAVY_NOISE`; heavy noise on organic meshes is left to the solve). The
    residual one-ring ripple of the normals grows with the noise, hence one pass per 0.09 mean
    edge lengths of γ̂ (the MAD estimate): 1 pass at γ̂ ≈ 0.09, 2 at 0.18-0.2, 3 from 0.27.
    The unit was chosen on the benchmark grid (docs/parameters.md).
    """
    if not ORGANIC or outside != 1.0 or willmore != 1.0 or not gamma <= HEAVY_NOISE:
        return 0
    return int(np.clip(round(gamma / GUIDANCE_GAMMA_UNIT), 1, 3))


REINTEGRATE_RATIO = 0.16
REINTEGRATE_STEPS_PER_GAMMA = 18.0


REINTEGRATE_LEVEL = 0.7


def reintegrate_rule(passes: int, reanchored: bool, impulsive: bool, ratio_after: float,
                     gamma: float, level_ratio: float = 1.0) -> int:
    """Sun et al. steps ``k`` of the re-integration from the input
    (:mod:`meshrepair.denoise.organic`),
    0 for none:

    .. math:: k = \\max(2, \\mathrm{round}(18\\, γ̂)) \\quad\\text{when}\\quad p > 0 \\wedge
              \\text{re-anchored} \\wedge q \\ge 0.7 \\wedge
              (\\text{impulsive} \\vee ρ_t^{after} > 0.16),

    on the meshes the guidance filter runs on (``p > 0``, :func:`guidance_rule`), whose
    residual was found to lie along the normals (the re-anchoring of
    :mod:`meshrepair.denoise.reproject` ran: the input's tangential layout is right), whose input is
    the result plus white noise of the estimated level: ``q`` = the robust level of the input's
    normal offsets from the result (:func:`meshrepair.denoise.organic.residual_level`) over γ̂ reads
    0.77-0.93 where the solve removed white noise and 0.26-0.66 on correlated noise, which the
    one-ring γ̂ and the result both miss (restarting from that input would put the bumps
    back), and either

    * the noise is impulsive (:func:`is_impulsive`): most input vertices are nearly exact, so a
      few steps from the (capped) input keep them and fix the thrown ones; or
    * the tangential drift left *after* the re-anchoring is large,
      ``ρ_t^{after} = rms‖P(V⁰ − V)‖ / rms⟨V⁰ − V, n⟩`` above 0.16 (the re-anchoring's guards
      kept it): Gaussian noise where the step does not pay reads 0.11-0.14.

    ``k`` grows with the noise: the steps are the only regulariser of the fit (module docstring
    of :mod:`meshrepair.denoise.organic`), and more noise needs more of them (γ̂ ≈ 0.09 → 2,
    0.27 → 5). Thresholds chosen on the benchmark grid (docs/parameters.md).
    """
    if passes <= 0 or not reanchored or not level_ratio >= REINTEGRATE_LEVEL:
        return 0
    if not (impulsive or ratio_after > REINTEGRATE_RATIO):
        return 0
    return int(max(2, round(REINTEGRATE_STEPS_PER_GAMMA * gamma)))
SHARPEN = True
SHARPEN_FLAT_SUPPORT = True
"""True: the sharpening's decision also trusts a flat-supported set at ``ρ_S > 0.2``
(:mod:`meshrepair.denoise.sharpen_decision`); False: ``ρ_S > 1/2`` alone."""
SHARPEN_RINGS = 10
SHARPEN_MAX_RINGS = 14
"""Cap of ``r``: the work grows as ``r²`` per face (on 134k vertices the step alone takes
about 36 s at r = 17); 14 covers the correlation lengths ℓ ≤ 1.4 of scanner noise."""


def sharpen_rule(willmore: float, length: float, *, band_model: bool = False) -> int | None:
    """Whether the result's creases are sharpened (:mod:`meshrepair.denoise.modes`) and over how
    many
    rings ``r`` the mode-seeking neighbourhood reaches:

    .. math:: \\text{sharpen} \\iff w > 1, \\qquad
              r = \\min(\\mathrm{round}(10 \\max(1, ℓ)),\\, 14),

    noise found correlated along the normals (:func:`willmore_weight_from_scale`) with
    correlation length ``ℓ``. The solve smooths the normals of correlated noise over a few
    noise lengths (``w = 16``), so a crease comes out rounded over a band that grows with ℓ;
    the neighbourhood must reach the flat sides beyond the band on both sides (the polish's
    ``4 ℓ`` rings reach into it). The data test of :mod:`meshrepair.denoise.sharpen_decision`,
    not the radius, keeps smooth surfaces unchanged: without it the step also moves smooth
    surfaces under synthetic scanner-like noise (docs/parameters.md).

    Not on the band read's correlated model (``band_model``,
    :func:`willmore_weight_from_band`): that model runs on organic meshes only (crease support
    below :data:`CAD_SUPPORT`), where there is no crease to restore, and there the data test's
    margin is thin: on a smooth sphere it keeps mean-shift facets at ``ρ_S`` 0.51-0.53.
    """
    if not SHARPEN or band_model or not willmore > 1.0:
        return None
    ell = max(1.0, float(length)) if np.isfinite(length) else 1.0
    return int(min(round(SHARPEN_RINGS * ell), SHARPEN_MAX_RINGS))
