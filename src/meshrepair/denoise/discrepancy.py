"""A discrepancy principle for the smooth prior's weight outside the crease-supported region.

:func:`meshrepair.denoise.rules.outside_weight` gives edge-Willmore the weight ``w_out = 6``
outside the crease-supported region C of a CAD part. A quadratic prior that strong is right
where the surface outside C is planar or of constant curvature at the scale of the noise, and
wrong where the curvature *changes* within a few rings (tangent blends between cylinders and
planes at low noise): there it takes signal away with the noise.

Morozov's discrepancy principle says when a regulariser is too strong: the residual of the
data, ``V⁰ - V``, then exceeds the noise. The level of the noise is not known exactly (the
estimate γ̂ of :mod:`meshrepair.model.noise` is a MAD of a Laplacian and reads 0.7-1.0 times the
residual of a perfect result), but the same mesh carries a reference measured on the same noise:
the crease-supported region C, where the MC model fits the creases and ``w_out`` does not act.
With ``n_i`` the result's vertex normals and the mean normal residuals

.. math::  r_{out} = \\frac{1}{|\\bar C|} \\sum_{i \\notin C} ((V^0_i - V_i) \\cdot n_i)^2,
           \\qquad
           r_{in} = \\frac{1}{|C|} \\sum_{i \\in C} ((V^0_i - V_i) \\cdot n_i)^2,

the weight is kept when ``q = r_out / r_in ≤ 1 + ε`` and otherwise lowered (``6 → 3 → 1``,
the first weight whose solve satisfies the test; 1 is the paper's prior, always accepted).
Only the normal part is used: the tangential anchor acts on C only, so the tangential
residuals of the two regions are not comparable. ε = 0.03 lies in the gap measured on the
benchmark grid (docs/parameters.md): q with ``w_out = 6`` reads 0.81-1.006 on the rows where 6
beats 1 and 1.047 on the row where it loses.
"""

from __future__ import annotations

import numpy as np

from meshrepair.mesh.geometry import edge_lengths, mean_edge_length, vertex_normals

DISCREPANCY = True
DISCREPANCY_TOL = 0.03
CLIP = 3.0
"""Squared residuals are capped at ``(3 γ̂)²``, so a few vertices far off do not decide."""
STRONG_IMPULSIVE = 1.45
"""Above this RMS / MAD ratio of the noise estimate the test is not read (thrown vertices read
1.49-2.35 on the shared and synthetic impulsive inputs, Gaussian noise 1.00-1.40)."""
FALLBACK_WEIGHTS = (3.0,)
"""Weights tried, in order, when ``w_out`` fails the test (the last is kept whatever its
ratio)."""


def normal_residuals(V0: np.ndarray, V: np.ndarray, F: np.ndarray,
                     edges: np.ndarray | None = None) -> np.ndarray:
    """Per vertex, ``((V⁰_i - V_i) · n_i)²`` in squared mean edge lengths of ``V⁰``, with
    ``n_i`` the area-weighted vertex normals of ``V``; shape ``(nV,)``. ``edges``: the unique
    edges of ``F`` in lexicographic order (``Topology.edges``) when known (no sort then)."""
    V0 = np.asarray(V0, dtype=np.float64)
    V = np.asarray(V, dtype=np.float64)
    el = (mean_edge_length(V0, F) if edges is None
          else float(edge_lengths(V0, np.asarray(edges)).mean()))
    d = np.einsum("ij,ij->i", V0 - V, vertex_normals(V, F)) / max(el, 1e-300)
    return d * d


def discrepancy_ratio(V0: np.ndarray, V: np.ndarray, F: np.ndarray,
                      inside: np.ndarray, clip: float | None = None,
                      edges: np.ndarray | None = None) -> float:
    """``q = r_out / r_in`` of the module docstring: the mean normal residual of the vertices
    outside ``inside`` (a boolean mask, the crease-supported region C) over that of the
    vertices in it, each squared residual capped at ``clip²`` (mean edge lengths; ``None``: no
    cap; ``edges`` as in :func:`normal_residuals`). NaN when either region is empty or the
    residual in C is zero."""
    inside = np.asarray(inside, dtype=bool)
    if inside.all() or not inside.any():
        return float("nan")
    r = normal_residuals(V0, V, F, edges)
    if clip is not None:
        r = np.minimum(r, float(clip) ** 2)
    r_in = float(r[inside].mean())
    if not r_in > 0.0:
        return float("nan")
    return float(r[~inside].mean() / r_in)


def applies(gamma: float, gamma_rms: float) -> bool:
    """Whether the test is read at all: not on strongly impulsive noise,
    ``γ̂_rms > 1.45 γ̂`` (:data:`STRONG_IMPULSIVE`), whose residuals are those of the thrown
    vertices, a few per region, whatever the weight."""
    return bool(DISCREPANCY and gamma_rms <= STRONG_IMPULSIVE * max(gamma, 1e-12))


def accept_weight(ratio: float, tol: float = DISCREPANCY_TOL) -> bool:
    """The discrepancy test ``q ≤ 1 + ε``; an undefined ratio (NaN) accepts."""
    return not (ratio > 1.0 + tol)


def lowered_weight(ratio: float) -> float | None:
    """The one lowered outside weight a call that already made its other main solve affords
    (the first of :data:`FALLBACK_WEIGHTS`) when the ratio read on its first solve fails
    :func:`accept_weight`; None when it passes (or no weight is listed)."""
    if accept_weight(ratio) or not FALLBACK_WEIGHTS:
        return None
    return FALLBACK_WEIGHTS[0]
