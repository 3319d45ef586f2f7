r"""The coarse-to-fine low-pass of the input, capped at the mesh's resolution.

:mod:`meshrepair.denoise.presmooth` low-passes the input of an organic mesh under heavy
white noise with ``k = clip(round((γ_k / γ_p)²), 0, 96)`` Taubin λ|μ pairs before the solve.
``k`` is read from the noise level alone, in mean edge lengths: the length that removes noise of
that level, whatever the mesh. What the filter takes from the *surface* depends on the
resolution: the filter acts on a fixed number of rings, and a ring of a coarse mesh is a large
part of the shape. On a mesh decimated to 1/4 of its faces (``benchmarks/resolution.py``,
``dec``) thin parts are a few rings wide, and the length read from the noise level alone rounds
them away: the error of the low-passed model then grows with every pair past a few.

**The filter's transfer.** With ``W`` the uniform umbrella operator, one λ|μ pair multiplies
an eigenvector of ``I − W`` of eigenvalue ``x`` by

.. math:: t(x) = (1 − λx)(1 − μx), \qquad λ = 0.5,\ μ = −0.53,

so ``k`` pairs by ``t(x)^k``. On a regular triangular lattice (six neighbours at unit distance)
a plane wave of wavelength ``Λ`` edge lengths along a lattice direction is such an eigenvector,
with

.. math:: x(Λ) = 1 − \tfrac13\bigl(\cos(2π/Λ) + 2\cos(π/Λ)\bigr) \;(≈ π²/Λ² \text{ for large } Λ).

**The rule.** The low-pass must not halve a wave as long as a fixed fraction of the shape's
size. With ``q`` the mesh's radius in mean edge lengths read on the probe (the robust first
result, whose edges the noise does not lengthen: on the resolution truths it reads the truth's
``q`` within 3 %, the noisy input 10-20 % less at γ0.5;
:func:`meshrepair.denoise.scalefree.radius_in_edges`), ``Λ_q = c_q q`` and

.. math:: k \le K_q = \Bigl\lfloor \frac{\ln 2}{-\ln t(x(Λ_q))} \Bigr\rfloor
          \quad (K_q = ∞ \text{ when } t(x(Λ_q)) \ge 1,\ \text{inside Taubin's pass band}),
          \qquad c_q = 0.44,

i.e. ``t(x(Λ_q))^k ≥ 1/2``. ``c_q`` is the smallest value (two digits) for which no mesh as
finely sampled as the coarsest full-resolution benchmark mesh (``q ≈ 14.7``) is ever capped:
``K_q(14.7) = 107 ≥ 96``, the low-pass's own cap (``c_q = 0.43``: 94). ``K_q`` falls steeply
with ``q``: 42 at q 12.3, 11 at q 9, 4-5 at q 7.1-7.4.

**After a capped low-pass the noise is read as white.** The low-pass's gate asks for white noise
(Willmore weight 1 on the input). A low-pass shortened by the cap leaves the noise's long
wavelengths, correlated by the filter, and the run on the low-passed mesh reads them so (probe
profile ρ 1.7-1.8) and takes the correlated-noise branch (Willmore weight up to 16,
:func:`meshrepair.denoise.rules.willmore_weight_from_scale`): a prior of ``w`` averages the
normals over about ``√w`` rings, the length the cap has just refused on this mesh. So the run
after a low-pass *shortened by the cap* (``K_q`` below the low-pass's ``k``) keeps the input's
white read,

.. math:: w = 1 \quad\text{when } K_q < k

(:func:`keep_white`). Where the cap does not act the run reads the noise of the low-passed mesh
as it is: on finely sampled meshes the filter's long-wavelength residue is correlated noise,
and the correlated branch removes it.

**Where the cap reads.** A surface without relief at the mesh's scale loses nothing to a long
low-pass, however coarse the mesh (a 642-vertex sphere, q ≈ 5, wants the full length). The
read of the curvature variation (:func:`meshrepair.denoise.coarse.curvature_roughness`,
``c = ‖h − W²h‖ / ‖h‖`` after 8 Taubin pairs, here on the probe) says which: the cap acts only
where ``c ≥ c_0 = 0.185``, the bound of a surface smooth at its resolution (icospheres read
0.10-0.15 on the probe at γ0.5-0.6, decimated organic meshes 0.28-0.30).

The cap reads lengths only in units of the mesh's own edge length: it is invariant under rigid
motions and uniform scaling.
"""

from __future__ import annotations

import numpy as np

COARSE_CAP = True
C_Q = 0.44


def lattice_eigenvalue(wavelength: float) -> float:
    """``x(Λ)`` of the module docstring: the eigenvalue of ``I − W`` of a plane wave of
    wavelength ``Λ`` (edge lengths) along a direction of the regular triangular lattice."""
    w = float(wavelength)
    return float(1.0 - (np.cos(2.0 * np.pi / w) + 2.0 * np.cos(np.pi / w)) / 3.0)


def pair_transfer(x: float, lam: float | None = None, mu: float | None = None) -> float:
    """``t(x) = (1 − λx)(1 − μx)``, one λ|μ pair's factor on an eigenvector of ``I − W``."""
    from meshrepair.denoise.lowpass import TAUBIN_LAM, TAUBIN_MU

    lam = TAUBIN_LAM if lam is None else float(lam)
    mu = TAUBIN_MU if mu is None else float(mu)
    return float((1.0 - lam * x) * (1.0 - mu * x))


def half_steps(wavelength: float) -> float:
    """The real ``k`` with ``t(x(Λ))^k = 1/2`` (``inf`` when ``t ≥ 1``: never halved)."""
    t = pair_transfer(lattice_eigenvalue(wavelength))
    if not 0.0 < t < 1.0:
        return float("inf") if t >= 1.0 else 0.0
    return float(np.log(2.0) / -np.log(t))


def max_presmooth_steps(q: float, max_steps: int) -> int:
    """``min(max_steps, K_q)`` of the module docstring, ``q`` the radius of the probe in mean
    edge lengths (``max_steps`` when switched off or ``q`` is not a positive finite number)."""
    q = float(q)
    if not COARSE_CAP or not np.isfinite(q) or not q > 0:
        return int(max_steps)
    k = half_steps(C_Q * q)
    return int(max_steps) if not np.isfinite(k) else int(min(int(max_steps), np.floor(k)))


def capped_steps(k: int, V_probe: np.ndarray, F: np.ndarray, edges: np.ndarray) -> int:
    """The low-pass length ``k`` capped at ``K_q``, ``q`` read on the probe's vertices ``V_probe``,
    when the probe's surface has relief at the mesh's resolution (module docstring:
    :func:`meshrepair.denoise.coarse.curvature_roughness` of the probe ``≥ C_0``; read only when
    ``K_q < k``)."""
    if k <= 0 or not COARSE_CAP:
        return int(k)
    from meshrepair.denoise.coarse import C_0, curvature_roughness
    from meshrepair.denoise.scalefree import radius_in_edges

    cap = max_presmooth_steps(radius_in_edges(V_probe, F, edges), int(k))
    if cap >= k or not curvature_roughness(V_probe, F, edges) >= C_0:
        return int(k)
    return int(cap)


KEEP_WHITE = True


def keep_white(willmore: float, capped: bool) -> float:
    """The Willmore weight read on the noise's scale, or 1 on the run after a low-pass that
    the cap shortened (module docstring: the input's white read is kept)."""
    return 1.0 if (KEEP_WHITE and capped) else float(willmore)
