"""A final low-pass step on the smooth region of organic meshes with white noise.

The ADMM of energy (6) with the edge-Willmore prior removes the vertex-scale noise of a smooth
surface but leaves its mid-frequency part (bumps of a few rings): on the synthetic noise (32) of
docs/comparison.md a tuned Taubin filter can beat the solve alone on smooth organic meshes, and
the same filter applied to the *result* lowers MSAE there (docs/parameters.md). For i.i.d.
(white) noise an isotropic low-pass at the right strength is close to optimal where the surface
is smooth; the strength must grow with the noise.

The step is Taubin's λ|μ filter (1995) with the uniform umbrella operator W, on the vertices
of the smooth region S only (those outside the crease-supported region C stay the boundary
condition, fixed):

.. math::  V \\leftarrow V + λ\\, P_S (W V - V), \\qquad
           V \\leftarrow V + μ\\, P_S (W V - V), \\qquad λ = 0.5,\\ μ = -0.53,

repeated ``k`` times, with ``P_S`` the restriction to S. One λ|μ pair has the transfer function
``(1 - λ x)(1 - μ x)`` on the eigenvalue ``x ∈ [0, 2]`` of ``I - W``: ≈ 1 on smooth shape
(x → 0), < 1 on the noise's high frequencies, so it does not shrink the surface (Taubin's
pass band ends at ``x_pb = 1/λ + 1/μ ≈ 0.113``; ``-μ > λ``).
``k`` pairs act as a filter of width ∝ √k rings; the width is taken proportional to the
noise level ``γ̂`` (mean edge lengths), i.e. the diffusion time to ``γ̂²``:

.. math::  k = \\max\\bigl(1, \\mathrm{round}((γ̂ / γ_1)^2)\\bigr), \\qquad γ_1 = 0.13,

so ``k = 1`` up to ``γ̂ ≈ 0.16``, 4 at ``γ̂ = 0.26``, 8 at ``γ̂ = 0.37``, capped at
:data:`MAX_STEPS`; γ_1 was chosen on the benchmark grid (docs/parameters.md): a smaller
γ_1 (a longer filter) smooths fine scanned relief away, 0.13 keeps it.
For noise along the normals (and at low noise) the displacement of each step is projected on
the vertex normals (:func:`normal_only`): the tangential layout is left to the solve and to
the re-anchoring of :mod:`meshrepair.denoise.reproject` that follows, so E_V does not grow (with the
full step it grows by up to 90 % at low noise).

It runs only where the model's smooth prior is the whole story: crease support on less than
:data:`meshrepair.denoise.rules.CAD_SUPPORT` of the edges (an organic mesh) and noise found
white (Willmore weight 1; correlated scanner noise has the polish of
:mod:`meshrepair.denoise.polish`).
Impulsive noise is included: the robust fidelity and the solve have removed the thrown vertices
by then, and ``γ̂`` (the MAD level) reads the Gaussian part.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

LOWPASS = True
GAMMA_1 = 0.13
TANGENTIAL_GAMMA = 0.13
MAX_STEPS = 12
TAUBIN_LAM = 0.5
TAUBIN_MU = -0.53


def steps_from_noise(gamma: float, gamma_1: float | None = None,
                     max_steps: int | None = None) -> int:
    """``k = clip(round((γ̂/γ_1)²), 1, MAX_STEPS)`` (module docstring)."""
    g1 = GAMMA_1 if gamma_1 is None else gamma_1
    cap = MAX_STEPS if max_steps is None else max_steps
    if not np.isfinite(gamma) or gamma <= 0:
        return 1
    return int(np.clip(round((float(gamma) / g1) ** 2), 1, cap))


def applies(support_fraction: float, willmore: float) -> bool:
    """The gate of the module docstring: an organic mesh (crease support below 20 % of the
    edges) with white noise (``w = 1``)."""
    from meshrepair.denoise.rules import CAD_SUPPORT

    return bool(LOWPASS and support_fraction < CAD_SUPPORT and willmore <= 1.0)


def normal_only(tangential: float, gamma: float, gamma_1: float | None = None) -> bool:
    """Whether the step moves the vertices along their normals only: unless the noise has a
    tangential part (``r_t ≥ 0.65``, :data:`meshrepair.denoise.rules.TANGENTIAL_MAX`) *and* is
    above the one-step level (``γ̂ > γ_1``). The umbrella operator also pulls each vertex
    tangentially towards its neighbours' centroid: that removes tangential noise but also the
    mesh's own irregular layout, a loss when the tangential noise is small."""
    from meshrepair.denoise.rules import TANGENTIAL_MAX

    g1 = TANGENTIAL_GAMMA if gamma_1 is None else gamma_1
    return not (tangential >= TANGENTIAL_MAX and gamma > g1)


def umbrella(edges: np.ndarray, n_vertices: int) -> sp.csr_matrix:
    """The uniform umbrella operator W (row i: the mean over the neighbours of i)."""
    e = np.asarray(edges, dtype=np.int64)
    A = sp.csr_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                      shape=(n_vertices, n_vertices))
    deg = np.asarray(A.sum(axis=1)).ravel()
    return sp.diags(1.0 / np.maximum(deg, 1.0)) @ A


def taubin_region(V: np.ndarray, edges: np.ndarray, free: np.ndarray, steps: int, *,
                  lam: float = TAUBIN_LAM, mu: float = TAUBIN_MU,
                  F: np.ndarray | None = None, W: sp.csr_matrix | None = None) -> np.ndarray:
    """``steps`` λ|μ pairs of the module docstring on the vertices ``free`` (boolean mask);
    the others do not move. With faces ``F`` each displacement is projected on the vertex
    normals of the current mesh (``d ← (d·n) n``): the tangential layout is kept (normal-only
    filtering, for noise along the normals). ``W``: :func:`umbrella` of ``edges`` when the
    caller already holds it (a loop of single pairs builds it once). Returns new ``(nV, 3)``
    float64 vertices (``V`` is not modified).
    """
    V = np.array(V, dtype=np.float64)
    free = np.asarray(free, dtype=bool)
    if steps <= 0 or not free.any():
        return V
    if W is None:
        W = umbrella(edges, len(V))
    m = free[:, None].astype(np.float64)

    def move(c):
        d = W @ V - V
        if F is not None:
            from meshrepair.mesh.geometry import vertex_normals

            n = vertex_normals(V, F)
            d = np.einsum("ij,ij->i", d, n)[:, None] * n
        return c * m * d

    for _ in range(int(steps)):
        V += move(lam)
        V += move(mu)
    return V
