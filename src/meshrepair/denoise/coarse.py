"""A longer low-pass where the surface is smooth at the mesh's resolution.

On an organic mesh with white noise the defaults end with a short low-pass
(:mod:`meshrepair.denoise.lowpass`, ``k = round((γ̂/0.13)²)`` pairs) because a longer one smooths
away the fine relief of scanned surfaces. A surface sampled finely with respect to its
*curvature variation* (a smooth subdivision-like surface) has no such relief: its mean
curvature changes over many rings, so an isotropic filter at the noise's length only removes
noise there.

**The read** (sampling density of the curvature field). With ``W`` the uniform umbrella operator,
``T`` one full Taubin λ|μ pair (:mod:`meshrepair.denoise.lowpass`), ``X = T^m V`` the result after
``m = 8`` such pairs and ``n`` the vertex normals of ``X``, the two-step curvature proxy and its
variation are

.. math::  h = \\langle X - W^2 X,\\; n\\rangle, \\qquad
           c = \\frac{\\lVert h - W^2 h\\rVert_2}{\\lVert h\\rVert_2},

a dimensionless ratio (invariant to scaling, rotation and translation of the mesh; 0 on a
sphere of uniform sampling, where ``h`` is constant, and growing towards √2 as ``h`` becomes
white): how much the curvature changes from a two-ring neighbourhood to the next relative to
its own size, at the scale of the filter ``T^m`` (√m rings). The ``m`` pairs remove what
the solve and the earlier finishes left of the noise, which otherwise decides ``c``: read on
the result itself (``m = 0``) it varies with the noise level and with how much the finishes
smoothed. The read is made at the scale of the low-pass it decides on,
``m = max(m_0, k)`` with ``m_0 = 8`` and ``k`` the least-risk length below: the question is
whether the surface is smooth at the length the filter would have, and a result that kept
noise of a few rings (more of it when the noise has a tangential part, which the prior does
not remove) reads rough at ``m_0`` pairs although the surface is smooth at ``k``. Where the
risk asks for no more than ``m_0`` pairs (low noise) the read is the ``m_0``-pair one. After
these pairs ``c`` reads within about ±0.02 of the clean surface's own value across noise
levels; smooth surfaces read about 0.06-0.18, scanned relief 0.19-0.39.

**The gate** (:func:`gated`): an organic mesh (crease support below
:data:`meshrepair.denoise.rules.CAD_SUPPORT`, outside weight 1) with white, non-impulsive noise
(Willmore weight 1), λ and the Willmore weight read from the input (not set by the user), the
raw input at hand, and ``c < c_0 = 0.185`` (chosen on the benchmark grid, docs/parameters.md).
In the coarse-to-fine run (:mod:`meshrepair.denoise.presmooth`) the noise model is the raw
input's (white, non-impulsive: that run's own gate), not the reading of the filtered noise of
the low-passed input, and the risk below is read on the raw input.

**The length** (:func:`least_risk_steps`) is the one whose low-pass of the *input* has the least
estimated risk of its normals: with ``T`` one λ|μ pair, ``y`` the input, ``r = P(y − T^k y)``
the residual along the normals and ``R_∇(k)`` Stein's unbiased estimate of the risk of the
gradient of the normal offsets, which is to first order the error of the face normals
(:func:`meshrepair.denoise.risk.risk_curve` with ``normals=True``, ``L`` the graph
Laplacian, the noise level σ̂ read there by one pair),

.. math:: k = \\arg\\min_{0 \\le k \\le K_{max}} R_∇(k),
          \\qquad R_∇(k) = \\sum_{(i,j) \\in E} (r_i - r_j)^2
          + 2σ̂^2\\,\\mathrm{tr}(L\\,T^k), \\qquad K_{max} = 40.

The risk of the positions, ``Σ_i r_i² + 2σ̂² tr T^k``, weighs an error of long wavelength (which
costs positions but hardly normals) like one of a few rings and asks for shorter filters on
smooth surfaces than the normals want (module docstring of ``risk``).

The model's result ``X`` is then filtered by the same ``k`` pairs, ``T^k X``. In the
coarse-to-fine run (:mod:`meshrepair.denoise.presmooth`) the model ran on ``T^{k_p} y``: the risk
is read on the raw input ``y`` and the result gets ``max(0, k − k_p)`` pairs, so the two
low-passes together are ``T^k`` (the λ|μ pairs commute). Where the surface is smooth at the
mesh's resolution the linear filter at its best length is close to the best
estimate of the surface, and the model's result keeps part of the noise's mid frequencies
(bumps of a few rings) that the filter removes: the filter's length is then set by the noise
level *and* by how much shape the surface has at that length, which ``R_∇(k)`` reads from the
input and which a rule in γ̂ alone does not. The gate ``c < c_0`` is needed: on scanned relief
the model's result is already better than any ``T^k y``, and a further ``T^k`` on it only
removes relief, while ``R_∇(k)`` (a risk of the filter on the input, not of ``T^k X``) still
has its minimum at a few pairs.

The step is ``k`` full λ|μ pairs (:func:`meshrepair.denoise.lowpass.taubin_region`) on every
vertex, after the organic finish (as in :mod:`meshrepair.denoise.presmooth`, the probe's short
"crease" chains on an organic mesh are noise, so none is kept fixed). When the noise lies along
the normals at a low level (``r_t < 0.65`` and ``γ̂ ≤ 0.13``, the gates of
:mod:`meshrepair.denoise.lowpass`; :func:`normal_only`) the input's tangential layout is exact
and the solve left no drift: the pairs' total displacement is then projected on the vertex
normals of the surface they start from, so the vertex error E_V does not grow. (Projecting each
pair's step on the normals of the current surface instead degrades beyond a pair or two: the
normals of the partly filtered surface steer each later step.) Otherwise the filtered surface is
resampled at the input's vertex layout (:mod:`meshrepair.denoise.layoutkeep`).
"""

from __future__ import annotations

import numpy as np

COARSE = True  # switch of the low-pass
C_0 = 0.185  # c_0: curvature variation below which the surface is smooth at its resolution
READ_STEPS = 8  # m_0: the fewest λ|μ pairs applied before the read of c
MAX_STEPS = 40  # K_max: the longest low-pass the risk is read for


def curvature_roughness(V: np.ndarray, F: np.ndarray, edges: np.ndarray, *,
                        steps: int = READ_STEPS) -> float:
    """``c = ‖h − W²h‖ / ‖h‖`` of the module docstring on ``T^steps V`` (NaN on a flat mesh,
    ``h = 0``).

    Parameters
    ----------
    V : (nV, 3) float64
    F : (nF, 3) int64
    edges : (nE, 2) int64, the mesh's edges
    steps : full Taubin pairs applied before the read (``m``; 0 reads ``V`` itself)

    Returns
    -------
    float
    """
    from meshrepair.denoise.lowpass import taubin_region, umbrella
    from meshrepair.mesh.geometry import vertex_normals

    V = np.asarray(V, dtype=np.float64)
    if steps > 0:
        V = taubin_region(V, edges, np.ones(len(V), bool), int(steps))
    W = umbrella(edges, len(V))
    n = vertex_normals(V, F)
    h = np.einsum("ij,ij->i", V - W @ (W @ V), n)
    den = float(np.linalg.norm(h))
    if not den > 0:
        return float("nan")
    return float(np.linalg.norm(h - W @ (W @ h)) / den)


def gated(*, support_fraction: float, outside: float, willmore: float, impulsive: bool,
          lowpassed: bool = False) -> bool:
    """The gate of the module docstring without the read ``c``: an organic mesh with white,
    non-impulsive noise, and the raw input at hand (not ``lowpassed`` without it)."""
    from meshrepair.denoise.rules import CAD_SUPPORT

    if not COARSE or impulsive or lowpassed or outside != 1.0 or willmore != 1.0:
        return False
    return bool(support_fraction < CAD_SUPPORT)


def least_risk_steps(V: np.ndarray, F: np.ndarray, edges: np.ndarray, *,
                     before: int = 0) -> int:
    """``k − k_p``, ``k = argmin_{0 ≤ k ≤ K_max + k_p} R_∇(k)`` of the module docstring on the
    raw input ``V`` (``k_p`` = ``before``, the pairs already applied to the model's input),
    at least 0."""
    from meshrepair.denoise.risk import risk_curve

    k = int(np.argmin(risk_curve(V, F, edges, MAX_STEPS + int(before), normals=True)))
    return max(0, k - int(before))


def read_steps(k: int) -> int:
    """``m = max(m_0, k)``: the λ|μ pairs applied before the read of ``c`` (module docstring)."""
    return max(READ_STEPS, int(k))


def coarse_read(V: np.ndarray, X: np.ndarray, F: np.ndarray, edges: np.ndarray, *,
                before: int = 0, **gate) -> tuple[float, int]:
    """``(c, k)`` of the module docstring: ``k`` the least-risk length of the raw input ``V``
    less the ``before`` pairs already applied (:func:`least_risk_steps`), ``c`` the curvature
    variation of the model's result ``X`` read after ``max(m_0, k)`` pairs, and the pairs to
    apply, ``k`` when ``c < c_0`` and 0 otherwise; ``(NaN, 0)`` outside the gate
    (:func:`gated` with the keywords ``gate``)."""
    if not gated(**gate):
        return float("nan"), 0
    k = least_risk_steps(V, F, edges, before=before)
    c = curvature_roughness(X, F, edges, steps=read_steps(k))
    return c, (k if np.isfinite(c) and c < C_0 else 0)


def normal_only(tangential: float, gamma: float) -> bool:
    """Noise along the normals (``r_t < 0.65``) at a low level (``γ̂ ≤ 0.13``): the low-pass's
    displacement is projected on the vertex normals (:func:`coarse_lowpass`)."""
    from meshrepair.denoise.lowpass import TANGENTIAL_GAMMA
    from meshrepair.denoise.rules import TANGENTIAL_MAX

    return bool(np.isfinite(tangential) and tangential < TANGENTIAL_MAX
                and gamma <= TANGENTIAL_GAMMA)


FOLD_RINGS = 2


def free_vertices(V: np.ndarray, F: np.ndarray, topo, rings: int = FOLD_RINGS) -> np.ndarray:
    """The vertices the low-pass may move: all but those of faces still folded in ``V``
    (:func:`meshrepair.model.relax.locally_flipped_faces`) and ``rings`` rings around them (an
    umbrella step across a fold spreads it)."""
    from meshrepair.mesh.topology import adjacency
    from meshrepair.model.relax import locally_flipped_faces

    folded = locally_flipped_faces(V, topo)
    fixed = np.zeros(len(V), bool)
    if folded.any():
        fixed[np.asarray(F)[folded].ravel()] = True
        A = adjacency(topo)
        for _ in range(int(rings)):
            fixed = fixed | (A @ fixed.astype(np.float64) > 0)
    return ~fixed


def coarse_lowpass(V: np.ndarray, F: np.ndarray, topo, steps: int, *, normal: bool,
                   unfold: bool = True, reference: np.ndarray | None = None,
                   layout: np.ndarray | None = None,
                   tangential: float = float("nan")) -> np.ndarray:
    """``steps`` full λ|μ pairs of :func:`meshrepair.denoise.lowpass.taubin_region`; with
    ``normal`` their total displacement ``d_i`` is then projected on the vertex normals ``n_i``
    of the surface they start from, ``X_i = V_i + (n_i·d_i) n_i``; a new array.

    With ``unfold`` the faces folded in ``V`` are first unfolded
    (:func:`meshrepair.denoise.folds.unfold_result`, which ``denoise`` runs after the finish
    anyway, with the same per-cluster check against ``reference``, the robust probe's result:
    a fold the probe holds too is kept): the filter then acts on the unfolded surface, as it
    would after the unfolding, on every vertex: a filter across folded faces spreads the fold,
    and the folds the probe holds too are not features on a surface that is smooth at the
    mesh's resolution. Without ``unfold`` (the folds ``denoise`` keeps on purpose after the
    re-integration from the input) the faces folded in ``V`` and :data:`FOLD_RINGS` rings
    around them do not move (:func:`free_vertices`). With ``layout`` (the run's input) the full
    step's surface is resampled at that layout (:func:`meshrepair.denoise.layoutkeep.apply`,
    which reads ``tangential``, r_t); the normal-only step keeps the layout already.
    """
    from meshrepair.denoise.folds import unfold_result
    from meshrepair.denoise.layoutkeep import apply as keep_layout
    from meshrepair.denoise.lowpass import taubin_region

    if unfold:
        V, _ = unfold_result(V, topo, reference)
        free = np.ones(len(V), bool)
    else:
        free = free_vertices(V, F, topo)
    X = taubin_region(V, topo.edges, free, int(steps))
    if normal:
        from meshrepair.mesh.geometry import vertex_normals

        n = vertex_normals(V, F)
        return V + np.einsum("ij,ij->i", X - V, n)[:, None] * n
    return keep_layout(X, layout, F, topo.edges, tangential, free)
