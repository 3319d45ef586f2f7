"""The length of the coarse-to-fine low-pass of the input where the surface carries relief at
its own scale.

:mod:`meshrepair.denoise.presmooth` low-passes a heavily noisy organic input by ``k`` full
Taubin λ|μ pairs before the solve, with ``k`` set by the noise level,

.. math:: k = \\mathrm{round}\\bigl((γ_k/γ_p)^2\\bigr),\\qquad
          γ_k = γ̂\\,\\sqrt{1 + w\\,\\min(r_t, 1)^2},\\quad w = 1,

γ̂ the level of the normal part of the noise and ``r_t`` its tangential ratio (≈ 1 for noise in
random directions): the *full* step moves the vertices tangentially too, and on a surface
whose curvature is resolved by the sampling the layout it pulls towards, the umbrella
operator's, is close to the truth's, so the tangential part of the noise is noise the filter
removes and lengthens it. On a surface that carries relief at the mesh's own scale that layout
is *not* the truth's: the tangential pull of the longer filter flattens the relief instead, and
the same γ̂ and r_t want a filter about half as long.

**The read** is the curvature variation of :func:`meshrepair.denoise.coarse.curvature_roughness`
taken on the
low-passed input itself, ``X = T^k V`` with the length above (the filter's own length, ∝ γ²,
removes the noise before the read; no extra pairs, ``m = 0``), with what the filter leaves of
the noise taken out (:func:`relief_read`):

.. math:: h = (I - W^2)X \\cdot n,\\quad r = (I - W^2)h,\\qquad
          h_ε = (I - W^2)T^k ε,\\quad r_ε = (I - W^2)h_ε,

.. math:: \\tilde c = \\sqrt{\\frac{\\max(\\lVert r\\rVert^2 - \\lVert r_ε\\rVert^2,\\ 0)}
          {\\lVert h\\rVert^2 - \\lVert h_ε\\rVert^2}},

``ε`` one white scalar field of standard deviation ``γ̂ ℓ̄`` per vertex (fixed seed; the
normal part of the noise as γ̂ reads it) run through the same ``k`` pairs. ``T`` and ``W`` act
on each coordinate alike, so ``h_ε`` and ``r_ε`` estimate the share of ``h`` and ``r`` that is
residual noise and not surface (uncorrelated with it: the energies add). Without the
correction, on a finely sampled surface, whose curvature per ring is small, the residual makes
up about a fifth of ``‖h‖²`` (1-5 % on the shared meshes at their own resolution) and the read
sees relief that is not there. The ratio is dimensionless, invariant to scale, rotation and
translation (``ε`` scales with ``ℓ̄``), and 0 on a uniformly sampled sphere. At γ 0.5-0.6
smooth surfaces read ≤ 0.18 and scanned relief ≥ 0.25 (docs/parameters.md).

**The rule** (:func:`tangential_weight`, :func:`heavy_length`): the weight of the tangential
part in γ_k falls from 1 to 0 as ``c̃`` goes from ``c_0`` to ``c_1``,

.. math:: w(c) = \\mathrm{clip}\\Bigl(\\frac{c_1 - c}{c_1 - c_0},\\ 0,\\ 1\\Bigr),
          \\qquad c_0 = 0.18,\\ c_1 = 0.26,

and the length is the coarse-to-fine law with that weight, the constant moving with it from
its γ_p (resolved curvature) to a larger γ_r (relief at the mesh's scale; a shorter filter for
the same level, since its normal part rounds that relief too):

.. math:: k' = \\mathrm{clip}\\Bigl(\\mathrm{round}\\Bigl(\\frac{γ̂^2\\,(1 + w\\min(r_t,1)^2)}
          {(γ_r + w\\,(γ_p - γ_r))^2}\\Bigr),\\ 0,\\ K_{max}\\Bigr),
          \\qquad γ_p = 0.044,\\ γ_r = 0.05,

so ``w = 1`` (``c̃ ≤ c_0``, or a NaN read) is the unweighted ``k`` exactly, and ``w = 0`` sets the
length by the normal part of the noise alone at the constant γ_r (``k' = (γ̂/γ_r)²``: ≈ 0.4 k
for random directions, ≈ 0.75 k for noise along the normals, whose ``r_t`` is 0.1-0.3). ``k' ≤
k`` always (both factors shrink with ``w``), and the low-passed input is ``T^{k'} V``.
"""

from __future__ import annotations

import numpy as np

HEAVY_LENGTH = True
C_0 = 0.18
C_1 = 0.26
GAMMA_R = 0.05
NOISE_SEED = 0


def relief_read(X: np.ndarray, F: np.ndarray, edges: np.ndarray, gamma: float,
                ell: float, steps: int) -> float:
    """``c̃`` of the module docstring on ``X = T^k V``: the ratio ``c`` of
    :func:`meshrepair.denoise.coarse.curvature_roughness` with the energy of a white normal field
    of level ``γ̂ ℓ̄`` run through the same ``k`` pairs taken out of both norms (NaN when nothing
    is left of ``‖h‖²``; ``γ̂ = 0`` gives ``c`` itself).

    Parameters
    ----------
    X : (nV, 3) float64, the low-passed input ``T^k V``
    F : (nF, 3) int64
    edges : (nE, 2) int64, the mesh's edges
    gamma : γ̂, the level of the normal part of the noise (mean edge lengths)
    ell : ℓ̄, the input's mean edge length
    steps : ``k``, the pairs that made ``X``

    Returns
    -------
    float
    """
    from meshrepair.denoise.lowpass import taubin_region, umbrella
    from meshrepair.mesh.geometry import vertex_normals
    from meshrepair.mesh.probe import probe_field
    from meshrepair.mesh.topology import used_vertices

    W = umbrella(edges, len(X))
    n = vertex_normals(X, F)
    h = np.einsum("ij,ij->i", X - W @ (W @ X), n)
    r = h - W @ (W @ h)
    hh, rr = float(h @ h), float(r @ r)
    if gamma > 0 and ell > 0:
        e = probe_field(X, seed=NOISE_SEED, used=used_vertices(edges, len(X)))
        e = e * (float(gamma) * ell)
        e = taubin_region(np.c_[e, e, e], edges, np.ones(len(X), bool), int(steps))[:, 0]
        hn = e - W @ (W @ e)
        rn = hn - W @ (W @ hn)
        hh, rr = hh - float(hn @ hn), rr - float(rn @ rn)
    if not hh > 0:
        return float("nan")
    return float(np.sqrt(max(rr, 0.0) / hh))


def tangential_weight(c: float, c0: float = C_0, c1: float = C_1) -> float:
    """``w(c)`` of the module docstring; 1 for a NaN read (a flat mesh)."""
    if not np.isfinite(c):
        return 1.0
    return float(np.clip((c1 - float(c)) / (c1 - c0), 0.0, 1.0))


def steps_at_weight(gamma: float, tangential: float, weight: float) -> int:
    """``k = clip(round((γ̂ √(1 + w min(r_t, 1)²) / γ_p(w))²), 0, K_max)``,
    ``γ_p(w) = γ_r + w (γ_p − γ_r)`` (the unweighted law at ``w = 1``: the length of
    :func:`meshrepair.denoise.presmooth.presmooth_steps`)."""
    from meshrepair.denoise.presmooth import GAMMA_P, MAX_STEPS, effective_level

    w = float(np.clip(weight, 0.0, 1.0))
    g = effective_level(gamma, tangential, w)
    gp = GAMMA_R + w * (GAMMA_P - GAMMA_R)
    return int(np.clip(round((g / gp) ** 2), 0, MAX_STEPS))


def heavy_length(V: np.ndarray, F: np.ndarray, edges: np.ndarray, gamma: float,
                 tangential: float, steps: int, *, Vk: np.ndarray | None = None
                 ) -> tuple[int, np.ndarray, float, float]:
    """The coarse-to-fine low-pass of the input with the length of the module docstring.

    Parameters
    ----------
    V : (nV, 3) float64, the input
    F : (nF, 3) int64
    edges : (nE, 2) int64, the mesh's edges
    gamma : γ̂, the level of the normal part of the noise
    tangential : r_t, its tangential ratio
    steps : the unweighted length ``k`` (``presmooth_steps``; > 0)
    Vk : (nV, 3) float64, optional, ``T^k V`` when the caller has it already (not modified)

    Returns
    -------
    k' : int, the length used (≤ ``steps``)
    Vp : (nV, 3) float64, ``T^{k'} V`` (a new array)
    c : float, the read ``c̃`` on ``T^k V``
    w : float, the weight of the tangential part
    """
    from meshrepair.denoise.presmooth import presmooth

    free = np.ones(len(V), bool)
    Vp = presmooth(V, edges, free, int(steps)) if Vk is None else Vk
    if not HEAVY_LENGTH:
        return int(steps), Vp, float("nan"), 1.0
    ell = float(np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1).mean())
    c = relief_read(Vp, F, edges, gamma, ell, int(steps))
    w = tangential_weight(c)
    k = min(int(steps), steps_at_weight(gamma, tangential, w))
    if k != int(steps):
        Vp = presmooth(V, edges, free, k)
    return k, Vp, float(c), w
