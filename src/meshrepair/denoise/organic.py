"""Organic finish: a one-ring bilateral normal guidance, then the vertices re-integrated from the
input.

On smooth organic surfaces (no CAD crease support) the converged solve leaves two kinds of error
that the non-local low-rank filter of Li et al. (NLLR, CGF 2018) does not: a residual ripple of
the face normals at the scale of one ring, and a tangential drift of the vertices the tangential
re-anchoring (:mod:`meshrepair.denoise.reproject`) could not take back (its turn-over guard and its
least-variance weights keep the solve's position where it is unsure). NLLR's own vertex update
is the classical one: a few Sun et al. (2007) steps from the *noisy input* towards the filtered
normals, so its vertices move almost only along the normals and keep the input's tangential
layout (on impulsive noise along the normals about half the tangential error of the solve's
vertices).

**Guidance filter** (:func:`guidance_filter`). ``K(f)`` are the faces sharing an edge with
``f`` that is not in the converged sharp-edge mask ``M_E``, and ``f`` itself (the neighbourhood
of :mod:`meshrepair.denoise.polish` with ``r = 1``, no flatness gate). Each pass is a bilateral
normal
filter (Zheng et al. 2011)

.. math:: n'_f = \\frac{\\sum_{g \\in K(f)} A_g\\, e^{-\\|c_f - c_g\\|^2 / 2σ_c^2}\\,
                       e^{-\\|n_f - n_g\\|^2 / 2σ_s^2}\\, n_g}{\\|\\cdot\\|},
          \\qquad σ_c = \\bar\\ell,\\; σ_s = 0.2,

followed by ``m = 10`` Sun et al. vertex steps towards ``n'``
(``x_i ← x_i + (1/|F_i|) Σ_{f ∋ i} n'_f ⟨n'_f, c_f − x_i⟩``, the V-subproblem (26) with λ = 0),
``p`` passes. A mesh whose face normals are all equal is a fixed point (the filter returns them,
and ``c_f − x_i`` lies in each face's plane).

**Re-integration from the input** (:func:`reintegrate`). With ``n_i`` the vertex normals of the
result ``V``, ``d_i = ⟨V⁰_i − V_i, n_i⟩`` the input's normal offset and ``s = 2 median_i |d_i|``,
the start

.. math:: Y^0_i = V_i + (I - n_i n_i^T)(V^0_i - V_i) + \\mathrm{clip}(d_i, -s, s)\\, n_i

is the input vertex with its normal offset from the result capped (a vertex thrown far along
the normal starts at most ``s`` off the result surface), then ``k`` Sun et al. steps towards the
face normals ``n*`` of the filtered result (above). Early-stopped gradient descent on
``E(x) = Σ_f Σ_{i ∈ f} ⟨n*_f, x_i − c_f⟩²`` from ``Y⁰`` is the implicit (Landweber)
regularisation of that least-squares fit towards its start, i.e. a fidelity to the input of
strength ``∼ 1/k``; ``k`` grows with the noise level
(:func:`meshrepair.denoise.rules.reintegrate_rule`).
The steps move each vertex only along the target normals of its faces, so its tangential
position stays the input's. The map commutes with rotations, translations and uniform scalings
(``s`` scales with the mesh, the steps are geometric).
"""

from __future__ import annotations

import numpy as np

from meshrepair.denoise.polish import (
    _neighbourhood_csr,
    _normals_areas,
    filter_normals,
    vertex_update,
)

GUIDANCE_SIGMA_S = 0.2
GUIDANCE_VSTEPS = 10
REINTEGRATE_CLIP = 2.0


def guidance_filter(V: np.ndarray, F: np.ndarray, sharp: np.ndarray, topo, *, passes: int,
                    sigma_s: float = GUIDANCE_SIGMA_S, steps: int = GUIDANCE_VSTEPS
                    ) -> np.ndarray:
    """The one-ring bilateral guidance of the module docstring, ``passes`` passes.

    Parameters
    ----------
    V : (nV, 3) float64, the solve's result
    F : (nF, 3) int64
    sharp : (nE,) bool, ``M_E`` on ``topo.edges`` (its edges bound the neighbourhoods)
    topo : Topology of the mesh
    passes : number of filter-and-move passes (0 returns a copy)
    sigma_s : range width σ_s of the normal kernel
    steps : Sun et al. vertex steps per pass

    Returns
    -------
    (nV, 3) float64, a new array
    """
    F = np.asarray(F, dtype=np.int64)
    X = np.array(V, dtype=np.float64, copy=True)
    if passes <= 0 or len(F) == 0:
        return X
    K = _neighbourhood_csr(topo, sharp, 1)
    le = float(np.linalg.norm(X[topo.edges[:, 0]] - X[topo.edges[:, 1]], axis=1).mean())
    gate = np.ones(len(F), bool)
    for _ in range(int(passes)):
        Nt = filter_normals(X, F, K, gate, sigma_c=le, sigma_s=sigma_s)
        X = vertex_update(X, F, Nt, steps)
    return X


def reintegration_start(V: np.ndarray, V0: np.ndarray, F: np.ndarray, *,
                        clip: float = REINTEGRATE_CLIP) -> np.ndarray:
    """``Y⁰`` of the module docstring: the input vertices with their normal offset from the
    result ``V`` capped at ``clip · median |d_i|`` (a new array)."""
    from meshrepair import _kernels as _k

    V = np.ascontiguousarray(V, dtype=np.float64)
    n = _k.vertex_normals(V, np.asarray(F, dtype=np.int64))
    R = np.asarray(V0, dtype=np.float64) - V
    d = np.einsum("ij,ij->i", R, n)
    s = clip * float(np.median(np.abs(d)))
    return V + R + (np.clip(d, -s, s) - d)[:, None] * n


def residual_level(V: np.ndarray, V0: np.ndarray, F: np.ndarray) -> float:
    """Robust level of the input's normal offsets from the result, in mean edge lengths of
    ``V0``: ``1.4826 median_i |⟨V⁰_i − V_i, n_i⟩| / ℓ̄`` (``n_i`` the vertex normals of ``V``;
    the MAD scaled to a standard deviation). For white noise along the normals that the solve
    removed it reads about the noise level γ̂ (:func:`meshrepair.denoise.rules.reintegrate_rule`
    compares the two)."""
    from meshrepair import _kernels as _k

    V = np.ascontiguousarray(V, dtype=np.float64)
    V0 = np.asarray(V0, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = _k.vertex_normals(V, F)
    d = np.einsum("ij,ij->i", V0 - V, n)
    e = np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]
    le = float(np.linalg.norm(V0[e[:, 0]] - V0[e[:, 1]], axis=1).mean())
    return float(1.4826 * np.median(np.abs(d)) / le) if le > 0 else 0.0


def reintegrate(V: np.ndarray, V0: np.ndarray, F: np.ndarray, target: np.ndarray, *,
                steps: int, clip: float = REINTEGRATE_CLIP) -> np.ndarray:
    """Re-integration of the module docstring.

    Parameters
    ----------
    V : (nV, 3) float64, the result whose vertex normals split the input's offsets
    V0 : (nV, 3) float64, the input (the data)
    F : (nF, 3) int64
    target : (nV, 3) float64, the mesh whose face normals are the targets ``n*``
    steps : Sun et al. steps ``k`` (0 returns the start ``Y⁰``)
    clip : the cap ``s`` in units of ``median |d_i|``

    Returns
    -------
    (nV, 3) float64, a new array
    """
    F = np.asarray(F, dtype=np.int64)
    Y = reintegration_start(V, V0, F, clip=clip)
    if steps <= 0:
        return Y
    Nt, _, _ = _normals_areas(np.asarray(target, dtype=np.float64), F)
    return vertex_update(Y, F, Nt, int(steps))
