"""Correlated noise on smooth organic meshes: a low-pass at the noise's scale.

Spatially correlated noise (scanner noise: bumps ``ℓ`` rings wide) on an organic mesh is read by
the multi-scale profile of :mod:`meshrepair.denoise.scale` (``ρ = s_2/s_1`` well above 1,
correlation
length ``ℓ = √m``), but such noise usually reads a tangential ratio ``r_t ≥ 0.65`` (its
high-passed normal part is small), so the Willmore weight stays 1 and the schedule treats it as
white: the one-ring low-pass of :mod:`meshrepair.denoise.lowpass` (``k = 1-2`` pairs) and the
one-ring
guidance of :mod:`meshrepair.denoise.organic` act at the wrong scale and leave the bumps (about
half of the noisy input's MSAE is left under synthetic ``correlated_noise`` with m = 4,
γ = 0.5).

**The step.** Taubin's λ|μ filter (1995, :func:`meshrepair.denoise.lowpass.taubin_region`, full
step,
λ = 0.5, μ = −0.53) on the finished result, every vertex except those of faces still folded
and two rings around them (:func:`meshrepair.denoise.coarse.free_vertices`). On the eigenvalue
``x ∈ [0, 2]`` of ``I − W`` one pair has the transfer ``t(x) = (1 − λx)(1 − μx)``: 1 at
``x = 0``, no shrinkage in the pass band ``x < 1/λ + 1/μ``, < 1 above, so ``k`` pairs remove
the wavelengths below ≈ √k rings. Bumps of correlation length ``ℓ`` and one-ring level ``γ̂``
(the MAD level of :func:`meshrepair.model.noise.noise_statistics`, which reads the part of the bump
that changes over one ring) carry a slope ``≈ γ̂`` per ring over ``ℓ`` rings, an amplitude
``≈ ℓ γ̂``; the filter's width is taken proportional to it (the diffusion time to ``(ℓγ̂)²``,
as :mod:`meshrepair.denoise.lowpass` does with ``γ̂`` for white noise):

.. math:: k = \\mathrm{clip}\\bigl(\\mathrm{round}((ℓ\\,γ̂ / γ_q)^2),\\, 0,\\, K_{max}\\bigr),
          \\qquad γ_q = 0.02,\\ K_{max} = 160.

**The gate** (:func:`corr_steps`): an organic mesh (crease support below
:data:`meshrepair.denoise.rules.CAD_SUPPORT`, outside weight 1), not impulsive, the probe's
profile correlated, ``ρ ≥ ρ_0 = 1.4`` (white Gaussian inputs read 0.83-1.12, low white noise
on irregular meshes up to 1.35, real scanner noise about 1.22), and the one-ring level above
``γ_0 = 0.095``: below it the solve has already taken the roughness and what is left is mostly
the surface's own relief, which a long low-pass removes (rows reading γ̂ 0.068-0.084 lose from
the first pairs, rows reading 0.102-0.110 gain). Values chosen on the benchmark grid
(docs/parameters.md).
The readings are those of the first run (the input), also when the coarse-to-fine run of
:mod:`meshrepair.denoise.presmooth` follows; the step then acts on that run's result.

**Branch 2: correlated noise that reads white.** Noise correlated over ``√2``
rings reads ``ρ ≤ 1.12`` (as white noise does) but a band ratio ``β = b_1/b_0 ≈ 1.4``
(:mod:`meshrepair.denoise.corrwhite`: the finest two octaves ``I − W``, ``W − W²`` of the input
minus the
probe's result, white-normalised). Where branch 1 does not fire, on the same organic,
non-impulsive meshes, the step also runs when

.. math:: γ̂ > γ_1 = 0.13, \\qquad m̂ ≥ 1, \\qquad τ < τ_0 = 0.45,

with ``k = clip(round((ℓ_β γ̂ / γ_q)²), 0, K_max)``, ``ℓ_β = √m̂`` the band read's own length:
``m̂`` is the ``m`` whose white-model ratio ``β(m)`` is nearest to the measured ``β`` in log
(:func:`meshrepair.denoise.corrwhite.band_read`, the models made on the mesh itself). The
correlation test and the length are one read: the step runs when the noise is nearer a field of
one diffusion step or more than white noise, ``β ≥ (β(0) β(1))^{1/2}`` (≈ 1.10 on a regular
grid, where ``β(1) = 1.22``), and a read of ``m̂ = 0`` gives ``k = 0`` by itself. White noise
along the normals reads β 0.96-1.07 at ``γ̂ > 0.13`` on the benchmark meshes, m = 2 fields
1.16-1.39; ``τ < τ₀`` keeps noise in random directions out (it raises ``β`` too, through
its tangential part: 1.26-1.50, but reads τ ≥ 0.58, the m = 2 fields ≤ 0.27); ``γ₁`` keeps low
white noise out, where the relief's cross terms dominate ``b_1`` (γ = 0.1 rows read γ̂ 0.08-0.12
and β up to 1.40; m = 2 fields at γ ≥ 0.3 read γ̂ ≥ 0.15). ``γ_1`` and ``τ_0`` were chosen on
the benchmark grid (docs/parameters.md). The band read costs a few sparse products and is
computed only where the other conditions of branch 2 hold.

**The same read chooses the noise model.** Where branch 2's reading holds
(:func:`band_correlated`) the plan also carries a correlated-noise model of weight
``w = clip(4 m̂, 1, 16)`` (:func:`meshrepair.denoise.rules.willmore_weight_from_band`), run when
the white model's result fails the white-noise test of :mod:`meshrepair.denoise.whiteness`.
The white result is the one low-passed here, so its residual holds the noise's longer waves
and fails the test where the read is right; where the low-pass removed relief instead, the
residual is the input's white noise and the white result is kept.
"""

from __future__ import annotations

import numpy as np

CORR_LOWPASS = True
RHO_0 = 1.4
GAMMA_0 = 0.095
GAMMA_Q = 0.02
MAX_STEPS = 160
CORR_WHITE = True  # branch 2: correlated noise that reads white
GAMMA_1 = 0.13
TAU_0 = 0.45


def _organic(gamma, support_fraction, outside, impulsive) -> bool:
    from meshrepair.denoise.rules import CAD_SUPPORT

    if not CORR_LOWPASS or impulsive or outside != 1.0:
        return False
    vals = (gamma, support_fraction)
    return all(np.isfinite(v) for v in vals) and support_fraction < CAD_SUPPORT


def band_gate(gamma: float, *, support_fraction: float, outside: float,
              impulsive: bool) -> bool:
    """Whether branch 2 needs the band read at all (organic, not impulsive, ``γ̂ > γ_1``)."""
    return bool(CORR_WHITE and _organic(gamma, support_fraction, outside, impulsive)
                and gamma > GAMMA_1)


def band_correlated(gamma: float, tau: float, steps: int) -> bool:
    """Branch 2's reading of correlated noise: ``γ̂ > γ_1``, ``τ < τ_0`` and a band read
    nearest a model of ``m̂ ≥ 1`` diffusion steps (module docstring; NaN never fires). The
    same reading gives the plan its correlated-noise model
    (:func:`meshrepair.denoise.rules.willmore_weight_from_band`)."""
    if not CORR_WHITE or not all(np.isfinite(v) for v in (gamma, tau)):
        return False
    return bool(gamma > GAMMA_1 and tau < TAU_0 and steps >= 1)


def white_steps(gamma: float, tau: float, length: float) -> int:
    """Branch 2: ``k = clip(round((ℓ_β γ̂/γ_q)²), 0, K_max)`` when ``γ̂ > γ_1`` and ``τ < τ_0``
    (module docstring), with ``ℓ_β = √m̂`` the band read's length (0 for a read nearest white
    noise, which gives ``k = 0``); 0 otherwise (NaN never fires)."""
    if not (np.isfinite(length) and band_correlated(gamma, tau, round(float(length) ** 2))):
        return 0
    return int(np.clip(round((float(length) * float(gamma) / GAMMA_Q) ** 2), 0, MAX_STEPS))


def corr_steps(gamma: float, rho: float, length: float, *, support_fraction: float,
               outside: float, impulsive: bool) -> int:
    """λ|μ pairs ``k = clip(round((ℓ γ̂/γ_q)²), 0, K_max)`` of the module docstring (branch 1);
    0 when the gate does not fire (NaN readings never fire)."""
    from meshrepair.denoise.rules import CAD_SUPPORT

    if not CORR_LOWPASS or impulsive or outside != 1.0:
        return 0
    vals = (gamma, rho, length, support_fraction)
    if not all(np.isfinite(v) for v in vals) or not support_fraction < CAD_SUPPORT:
        return 0
    if not (rho >= RHO_0 and gamma > GAMMA_0):
        return 0
    return int(np.clip(round((float(length) * float(gamma) / GAMMA_Q) ** 2), 0, MAX_STEPS))


def corr_lowpass(V: np.ndarray, F: np.ndarray, topo, steps: int) -> np.ndarray:
    """``steps`` full λ|μ pairs on every vertex not on or near a folded face; a new array.

    Parameters
    ----------
    V : (nV, 3) float64, the finished result
    F : (nF, 3) int64
    topo : the edge topology of ``F``
    steps : λ|μ pairs (0 returns a copy)

    Returns
    -------
    (nV, 3) float64
    """
    from meshrepair.denoise.coarse import free_vertices
    from meshrepair.denoise.lowpass import taubin_region

    V = np.array(V, dtype=np.float64)
    if steps <= 0:
        return V
    return taubin_region(V, topo.edges, free_vertices(V, F, topo), int(steps))


def apply(V_out: np.ndarray, F: np.ndarray, topo, gamma: float, info: dict,
          impulsive: bool, V_in: np.ndarray | None = None,
          probe: np.ndarray | None = None, band=None) -> np.ndarray:
    """The rule on ``denoise``'s result from the first run's readings in ``info``; records
    ``corr_lowpass_steps`` (and branch 2's ``band_beta``, ``band_tau``, ``band_length``, NaN
    where the band read was not needed) in ``info`` and returns the (new or same) vertices.
    ``V_in`` (the input) and ``probe`` (the probe's result) feed branch 2's band read;
    ``band``: that read, already made by the plan (:func:`meshrepair.denoise.corrwhite.band_read`
    of the same input and probe), used instead of reading again."""
    kw = dict(support_fraction=info.get("support_fraction", float("nan")),
              outside=info.get("outside_weight", 1.0), impulsive=impulsive)
    k = corr_steps(gamma, info.get("noise_rho", float("nan")),
                   info.get("noise_length", float("nan")), **kw)
    info.update(band_beta=float("nan"), band_tau=float("nan"), band_length=float("nan"))
    if not k and V_in is not None and probe is not None and band_gate(gamma, **kw):
        from meshrepair.denoise.corrwhite import band_read

        br = band if band is not None else band_read(V_in, F, reference=probe, topo=topo)
        info.update(band_beta=br.beta, band_tau=br.tau, band_length=br.length)
        k = white_steps(gamma, br.tau, br.length)
    info["corr_lowpass_steps"] = k
    return corr_lowpass(V_out, F, topo, k) if k else V_out


RECORDED = ("corr_lowpass_steps", "band_beta", "band_tau", "band_length")
"""The keys :func:`apply` records in ``info``."""
