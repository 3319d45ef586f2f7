"""A full-step low-pass that keeps the input's vertex layout.

The full Taubin low-passes of :mod:`meshrepair.denoise.presmooth` (on the input) and
:mod:`meshrepair.denoise.coarse` (on the result) move every vertex towards its neighbours'
centroid, along the surface as well as across it. The shape they reach is what wins MSAE; the
tangential part of the move is what costs E_V: it slides the vertices along the surface towards the
umbrella operator's preferred (uniform) layout, away from the input's. For noise along the
normals the input's layout *is* the truth's, and the filter turns a tangential error of 0 into
0.17-0.32 mean edge lengths, about twice the normal error left.

**The step** (:func:`keep_layout`): keep the low-passed *surface*, resample it at the reference
layout. With ``X = T^k A`` the filter's result, ``R`` the reference (the run's input), ``n_i`` the
vertex normals of ``X`` and ``P_i = I − n_i n_iᵀ``, the return field is the tangential part of
the way back,

.. math:: d_i = P_i (R_i - X_i),

(optionally) low-passed by ``j`` half-steps of the umbrella operator ``W``, each put back in the
tangent planes, ``d ← P(½ (d + W d))``, and the new vertices are the closest points on the
piecewise-linear surface ``X`` of the tangent-plane targets:

.. math:: Y_i = \\pi_X\\bigl(X_i + d_i\\bigr).

``π_X`` (:func:`meshrepair.denoise.reproject.closest_points_local`: the faces of the one-ring of i
and
of the vertex nearest to the target) keeps every vertex on the surface the filter found (its
shape, hence its MSAE, up to the resampling of a piecewise-linear surface at new points).
Only the tangential position changes, by at most the way back. On a plane ``X`` it is the
orthogonal projection ``Y_i = R_i − ⟨R_i − X_i, n⟩ n`` (``j = 0``): the reference's layout
exactly. A fixed point: ``R = X`` gives ``Y = X``. It commutes with rotations, translations and
uniform scaling (tested). Vertices the filter did not move (``free`` false) do not move.

*Guard.* Resampling may turn or crush a face (two targets landing on the same edge of ``X``):
the vertices of every face of ``Y`` whose normal is more than 60° from the same face of ``X``,
or whose area is below a fifth of it, take ``X``'s position, repeated until none is left.

**Smoothing of the return field** (:func:`return_smoothing`). For noise along the normals
(tangential ratio ``r_t < 0.65``, :data:`meshrepair.denoise.rules.TANGENTIAL_MAX`, the gate of
:mod:`meshrepair.denoise.lowpass`) the reference's layout is exact: ``j = 0``. For noise in random
directions the reference layout carries white tangential noise ``σ``, and ``d = −b + σ`` with
``b`` the filter's own layout error: the half-steps average the white part out and keep what is
common to neighbours; ``j = J_RANDOM = 3`` is the least smoothing that kept MSAE within 1 % on
every benchmark row it was chosen on (docs/parameters.md).

*Where it runs.* On the full step of :func:`meshrepair.denoise.coarse.coarse_lowpass` (the
reference is the run's input) and on the low-passed input before the coarse-to-fine run
(:mod:`meshrepair.denoise.run`; the reference is the input). That run reads its noise level
and tangential ratio on the low-passed mesh *before* the resampling (``read_from``): on the
input's layout the tangential ratio would see the clean mesh's own layout irregularity over a
tiny normal residual (4.6-12 against 0.4-1.3) and send the run down other branches. Not on
the correlated-noise low-pass of :mod:`meshrepair.denoise.corrlowpass`: there the resampling
raised the error on the held-out correlated-noise rows (docs/parameters.md).
"""

from __future__ import annotations

import numpy as np

LAYOUT_KEEP = True
J_RANDOM = 3
GUARD_COS = 0.5
GUARD_AREA = 0.2
GUARD_ROUNDS = 10
PRESMOOTH_KEEP = True


def return_smoothing(tangential: float) -> int:
    """``j`` of the module docstring: 0 for noise along the normals (``r_t < 0.65``, NaN reads
    as along the normals), :data:`J_RANDOM` otherwise."""
    from meshrepair.denoise.rules import TANGENTIAL_MAX

    t = float(tangential)
    return 0 if not np.isfinite(t) or t < TANGENTIAL_MAX else int(J_RANDOM)


def _face_frames(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    a = np.linalg.norm(c, axis=1)
    return c / np.maximum(a, 1e-300)[:, None], a


def keep_layout(X: np.ndarray, R: np.ndarray, F: np.ndarray, edges: np.ndarray, *,
                smooth: int = 0, free: np.ndarray | None = None) -> np.ndarray:
    """``Y = π_X(X + d)`` of the module docstring, with the guard; a new array.

    Parameters
    ----------
    X : (nV, 3) float64, the low-passed vertices (the surface kept)
    R : (nV, 3) float64, the reference layout (the run's input)
    F : (nF, 3) int64
    edges : (nE, 2) int64, the mesh's edges (for the return field's smoothing)
    smooth : ``j``, half-steps ``d ← P(½ (d + W d))`` of the return field
    free : (nV,) bool or None, the vertices the filter moved (None: all)

    Returns
    -------
    (nV, 3) float64
    """
    from meshrepair.denoise.lowpass import umbrella
    from meshrepair.denoise.reproject import closest_points_local
    from meshrepair.mesh.geometry import vertex_normals

    X = np.asarray(X, dtype=np.float64)
    R = np.asarray(R, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = vertex_normals(X, F)

    def tangent(v):
        return v - np.einsum("ij,ij->i", v, n)[:, None] * n

    d = tangent(R - X)
    if free is not None:
        d[~np.asarray(free, dtype=bool)] = 0.0
    if smooth > 0:
        W = umbrella(edges, len(X))
        for _ in range(int(smooth)):
            d = tangent(0.5 * (d + W @ d))
            if free is not None:
                d[~np.asarray(free, dtype=bool)] = 0.0
    Y = closest_points_local(X, F, X + d)
    if free is not None:
        Y[~np.asarray(free, dtype=bool)] = X[~np.asarray(free, dtype=bool)]
    nX, aX = _face_frames(X, F)
    for _ in range(GUARD_ROUNDS):
        nY, aY = _face_frames(Y, F)
        bad = (np.einsum("ij,ij->i", nY, nX) < GUARD_COS) | (aY < GUARD_AREA * aX)
        if not bad.any():
            break
        idx = np.unique(F[bad].ravel())
        Y[idx] = X[idx]
    return Y


def apply(X: np.ndarray, R: np.ndarray | None, F: np.ndarray | None, edges: np.ndarray,
          tangential: float, free: np.ndarray | None = None) -> np.ndarray:
    """The one-line call of the low-passes: :func:`keep_layout` with ``j`` from
    :func:`return_smoothing` when :data:`LAYOUT_KEEP` and a reference and faces are given,
    else ``X`` unchanged."""
    if not LAYOUT_KEEP or R is None or F is None:
        return X
    return keep_layout(X, R, F, edges, smooth=return_smoothing(tangential), free=free)
