"""Tangential re-anchoring: the tangential part of the fidelity solved exactly after the solve.

The V-update (26) fits the face normals of V to the ADMM normals N. Face normals do not change,
to first order, when a vertex slides in its tangent plane, so the only force on the tangential
position of a vertex is the fidelity ``λ/2 ||V_i - V⁰_i||²`` with a small λ where the noise is
strong: the result *surface* S is right but its vertices drift along it (on impulsive noise
along the normals about ten times the input's own tangential error, and three times a
vertex-update method's such as NLLR, at the same normal error; docs/parameters.md).

Post-step. With the result surface S = S(V) held fixed (its shape is what the prior and the
normal fidelity decided), the fidelity restricted to S is minimised vertex by vertex:

.. math:: V_i^{new} = \\operatorname{argmin}_{p \\in S} \\tfrac12 \\|p - V^0_i\\|^2
          = \\pi_S(V^0_i),

the closest point of the data vertex on the result surface (the Huber fidelity of
:mod:`meshrepair.model.fidelity` has the same minimiser: it is increasing in ``||p - V⁰_i||``). On a
plane it is the orthogonal projection ``V⁰_i - ⟨V⁰_i - q, n⟩ n``; on a sphere of centre c and
radius r it is ``c + r (V⁰_i - c)/||V⁰_i - c||`` (tested). Only the tangential position of each
vertex changes, by at most its drift, so the shape of S is kept up to the resampling of a
piecewise-linear surface at new points.

Weights (a minimum-variance blend). The projection is not exact either: the data vertex sits
``d_i = ⟨V⁰_i - V_i, n_i⟩`` off S along the normal, and an angular error of S's normals tilts
its foot by about ``κ |d_i|``, jitter from vertex to vertex, to which the face normals (MSAE)
are very sensitive (0.05 mean edge lengths of random tangential jitter on exact positions raises
MSAE by about a quarter). The solve's own position has error variance ``σ²`` (its drift,
estimated by the mean squared shift ``||π_S(V⁰_i) - V_i||²`` over the vertices treated), the
projection ``κ² d_i²``; the blend of two independent estimates with the least variance is

.. math:: V_i^{new} = V_i + w_i (\\pi_S(V^0_i) - V_i), \\qquad
          w_i = \\frac{σ^2}{σ^2 + κ^2 d_i^2},

``κ = REANCHOR_KAPPA = 0.3`` (chosen on the design set, docs/parameters.md). Far-thrown impulses
(large ``|d_i|``) keep the solve's position.

When (:func:`residual_tangential_ratio`). The data's tangential positions are only worth
pulling towards when the noise lay along the normals. After the solve this shows in the residual
``r = V⁰ - V`` split along the result's vertex normals:

.. math:: ρ_t = \\sqrt{\\frac{\\sum_i \\|P_i r_i\\|^2}{\\sum_i ⟨r_i, n_i⟩^2}},

0.13-0.56 on every normal-direction and impulsive input of the shared set, 0.78-1.45 on
random-direction noise (measured in docs/parameters.md); the step runs when ρ_t < 0.6.

Tangential regularisation (:func:`tangential_smooth`). The blended targets
``T_i = V_i + w_i (π_S(V⁰_i) - V_i)`` still carry vertex-scale tangential jitter (the κ d_i tilt
of each foot, independent from vertex to vertex), while for noise along the normals the data's
tangential layout is right: the tangential part of the displacement ``Y - V⁰`` from the data is
smooth across vertices. So the targets are replaced by the minimiser over tangential moves of

.. math:: \\sum_i \\|Y_i - T_i\\|^2
          + μ \\sum_i \\|P_i \\big((Y - V^0)_i - (W_w (Y - V^0))_i\\big)\\|^2,

``P_i = I - n_i n_iᵀ`` the tangent projector at the solve's vertex normal and ``W_w`` the
neighbour mean weighted by the blend weights ``w_j`` (far-thrown impulses, ``w_j ≈ 0``, do not
enter their neighbours' means); its local (Jacobi) form is one implicit step of time μ of the
weighted umbrella flow of the displacement field,
``((1 + μ) I - μ W_w)(Y - V⁰) = T - V⁰`` tangentially, solved by the sweeps
``Y_i ← Y_i + P_i((T_i + μ (V⁰_i + (W_w (Y - V⁰))_i))/(1 + μ) - Y_i)`` (contraction factor
``μ/(1+μ)``) and put back on S by ``π_S``. On a plane it is the exact linear solve (tested); it
commutes with rotations, translations and uniform scaling. Turn-over guard in two levels: the
vertices of a face the smoothed step would reverse take the unsmoothed target ``T_i``, and if
that still reverses a face, the solve's position. ``μ = REANCHOR_MU`` (docs/parameters.md).

The search is local: a data vertex is near its result vertex (drift of a fraction of an edge),
so the candidates are the faces of the ``rings``-ring of the result vertex i and of the result
vertex nearest to ``V⁰_i``; every candidate triangle gets the exact point-triangle closest
point (Ericson, *Real-Time Collision Detection*, 5.1.5).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from meshrepair._kernels.closest import (  # noqa: F401  (re-exported)
    _np_closest_points_local,
    _vertex_faces,
    closest_point_triangles,
    local_search,
)
from meshrepair.mesh.topology import Topology


def closest_points_local(V: np.ndarray, F: np.ndarray, P: np.ndarray, *,
                         rings: int = 1, chunk: int = 200_000,
                         search: tuple[sp.csr_matrix, cKDTree] | None = None) -> np.ndarray:
    """Closest point of each ``P[i]`` on the mesh ``(V, F)`` among the faces near vertex i.

    Candidates of ``P[i]``: the faces of the ``rings``-ring of vertex i and of the vertex of V
    nearest to ``P[i]``. Exact when the true closest face is among them (``P[i]`` within about
    an edge of vertex i).

    Parameters
    ----------
    V : (nV, 3) float64, the surface
    F : (nF, 3) int64
    P : (nV, 3) float64, one query point per vertex
    rings : vertex rings of the candidate faces (≥ 1)
    chunk : vertices per batch (memory bound)
    search : :func:`local_search` of ``(V, F)``, optional (built when omitted)

    Returns
    -------
    (nV, 3) float64
    """
    V = np.asarray(V, dtype=np.float64)
    P = np.asarray(P, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if rings == 1:  # one compiled pass, the numpy loop below its twin (tested equal)
        from meshrepair._kernels.closest import closest_points_one_ring

        VF, tree = local_search(V, F) if search is None else search
        out = closest_points_one_ring(V, F, P, VF.indptr, VF.indices, tree.query(P)[1])
        if out is not None:
            return out
    return _np_closest_points_local(V, F, P, rings=rings, chunk=chunk, search=search)


REANCHOR_KAPPA = 0.3
"""``κ`` of the blend weights (module docstring)."""

REANCHOR_MU = 0.5
"""``μ`` of the tangential regularisation of the targets (module docstring)."""

REANCHOR_SWEEPS = 3
"""Jacobi sweeps of :func:`tangential_smooth` (residual factor ``(μ/(1+μ))³ ≈ 0.04``)."""


def tangential_smooth(T: np.ndarray, n: np.ndarray, F: np.ndarray, active: np.ndarray, *,
                      base: np.ndarray | None = None, weights: np.ndarray | None = None,
                      mu: float = 0.5, sweeps: int = REANCHOR_SWEEPS,
                      topo: Topology | None = None) -> np.ndarray:
    """Jacobi sweeps for ``((1 + μ) I - μ W_w)(Y - B) = T - B`` restricted to tangential moves.

    ``Y_i ← Y_i + P_i((T_i + μ (B_i + (W_w (Y - B))_i))/(1 + μ) - Y_i)`` on ``active``
    vertices, starting from ``Y = T``, with ``P_i = I - n_i n_iᵀ``, ``B`` the base (the data
    ``V⁰``; zero smooths the positions themselves) and ``W_w`` the mean over the edge neighbours
    weighted by ``weights`` (uniform by default); inactive vertices stay at ``T``. With ``n``
    constant (a plane) and many sweeps it is the exact solve of the linear system on the
    active rows.

    Parameters
    ----------
    T : (nV, 3) float64, the targets
    n : (nV, 3) float64, unit normals defining the tangent planes
    F : (nF, 3) int64
    active : (nV,) bool
    base : (nV, 3) float64, optional, ``B`` (default zeros)
    weights : (nV,) float64 >= 0, optional, the neighbour weights of ``W_w`` (default ones)
    mu : float >= 0, the implicit step's time (0 returns ``T``)
    sweeps : int >= 0
    topo : Topology, optional

    Returns
    -------
    (nV, 3) float64, a new array (not projected onto the surface)
    """
    T = np.asarray(T, dtype=np.float64)
    Y = T.copy()
    act = np.asarray(active, bool)
    if mu <= 0 or sweeps <= 0 or not act.any():
        return Y
    nV = len(T)
    if topo is None:
        from meshrepair.mesh.topology import edge_topology

        topo = edge_topology(np.asarray(F, dtype=np.int64), nV)
    B = np.zeros_like(T) if base is None else np.asarray(base, dtype=np.float64)
    c = np.ones(nV) if weights is None else np.asarray(weights, dtype=np.float64)
    e = topo.edges
    A = sp.coo_matrix((np.r_[c[e[:, 1]], c[e[:, 0]]], (np.r_[e[:, 0], e[:, 1]],
                                                          np.r_[e[:, 1], e[:, 0]])),
                      shape=(nV, nV)).tocsr()
    s = np.asarray(A.sum(axis=1)).ravel()
    W = (sp.diags(np.where(s > 0, 1.0 / np.where(s > 0, s, 1.0), 0.0)) @ A).tocsr()[act]
    has = s[act] > 0  # a vertex whose neighbours all weigh 0 keeps its own displacement
    na = np.asarray(n, dtype=np.float64)[act]
    Ta, Ba = T[act], B[act]
    for _ in range(int(sweeps)):
        Da = Y[act] - Ba
        M = np.where(has[:, None], W @ (Y - B), Da)
        d = (Ta + mu * (Ba + M)) / (1.0 + mu) - Y[act]
        d -= np.einsum("ij,ij->i", d, na)[:, None] * na
        Y[act] += d
    return Y


def reanchor(V: np.ndarray, V0: np.ndarray, F: np.ndarray, active: np.ndarray | None = None,
             *, kappa: float = REANCHOR_KAPPA, mu: float = REANCHOR_MU,
             topo: Topology | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The result with its vertices moved along the result surface towards the data's closest
    points: ``V_i + w_i (π_S(V⁰_i) - V_i)``, smoothed tangentially by :func:`tangential_smooth`
    and put back on S (see the module docstring).

    Parameters
    ----------
    V : (nV, 3) float64, the solve's result (the surface S)
    V0 : (nV, 3) float64, the fidelity data
    F : (nF, 3) int64
    active : (nV,) bool, the vertices to move (default all); boundary vertices of open meshes
        never move (their closest point can leave the border)
    kappa : ``κ`` of :func:`blend_weights` (0: the exact projection, ``w = 1``)
    mu : ``μ`` of :func:`tangential_smooth` (0: the targets unsmoothed)
    topo : Topology, optional (built when omitted)

    Returns
    -------
    V_new : (nV, 3) float64, a new array
    w : (nV,) float64, the weights used

    Notes
    -----
    The step slides vertices along S and must not turn a triangle over: the vertices of every
    face whose normal the step would reverse (``⟨n_f(V_new), n_f(V)⟩ < 0``) keep the solve's
    position, repeated until no face is reversed (the set of moving vertices shrinks each time,
    so this ends); a face turned over carries a normal error above 90°. A test on *local*
    folds instead (:func:`meshrepair.model.relax.locally_flipped_faces`) is wrong here: a
    scanned truth can have locally folded faces of its own, and the step restores some of
    them.
    """
    V = np.asarray(V, dtype=np.float64)
    V0 = np.asarray(V0, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    act = np.ones(len(V), bool) if active is None else np.asarray(active, bool).copy()
    if topo is None:
        from meshrepair.mesh.topology import edge_topology

        topo = edge_topology(F, len(V))
    if (~topo.interior).any():
        act[topo.edges[~topo.interior].ravel()] = False
    if not act.any():
        return V.copy(), np.zeros(len(V))
    search = local_search(V, F)  # one incidence and k-d tree for both projections
    X = closest_points_local(V, F, V0, search=search)
    w = (np.where(act, 1.0, 0.0) if kappa == 0
         else blend_weights(V, V0, X, F, act, kappa))
    from meshrepair import _kernels as _k

    n_old = _k.face_normals(np.ascontiguousarray(V), F)
    T = V + w[:, None] * (X - V)
    moving = w > 0
    Y = T
    if mu > 0:
        Y = tangential_smooth(T, _k.vertex_normals(np.ascontiguousarray(V), F), F, moving,
                              base=V0, weights=w, mu=mu, topo=topo)
        Y = np.where(moving[:, None], closest_points_local(V, F, Y, search=search), V)
    level = np.where(moving, 0 if mu > 0 else 1, 2)  # 0: smoothed, 1: T, 2: the solve's V
    while True:
        Vn = np.where((level == 0)[:, None], Y, np.where((level == 1)[:, None], T, V))
        bad = np.unique(F[np.einsum("ij,ij->i", _k.face_normals(Vn, F), n_old) < 0.0])
        bad = bad[level[bad] < 2]
        if len(bad) == 0:
            return Vn, np.where(level < 2, w, 0.0)
        level[bad] += 1  # these vertices fall back one level


def residual_tangential_ratio(V: np.ndarray, V0: np.ndarray, F: np.ndarray) -> float:
    """``ρ_t`` of the module docstring: rms tangential over rms normal part of ``V⁰ - V``
    along the vertex normals of ``V`` (0 when ``V⁰ = V``)."""
    from meshrepair import _kernels as _k

    V = np.ascontiguousarray(V, dtype=np.float64)
    n = _k.vertex_normals(V, np.asarray(F, dtype=np.int64))
    r = np.asarray(V0, dtype=np.float64) - V
    rn = np.einsum("ij,ij->i", r, n)
    rt = r - rn[:, None] * n
    den = float(np.einsum("i,i->", rn, rn))
    num = float(np.einsum("ij,ij->", rt, rt))
    if not den > 0:
        return 0.0 if num == 0 else float("inf")
    return float(np.sqrt(num / den))


def blend_weights(V: np.ndarray, V0: np.ndarray, X: np.ndarray, F: np.ndarray,
                  active: np.ndarray, kappa: float) -> np.ndarray:
    """``w_i = σ² / (σ² + κ² d_i²)`` on ``active`` vertices (0 elsewhere), with
    ``d_i = ⟨V⁰_i - V_i, n_i⟩`` and ``σ² = mean_active ||X_i - V_i||²`` (module docstring).

    Parameters
    ----------
    V : (nV, 3) the result, V0 : (nV, 3) the data, X : (nV, 3) ``π_S(V⁰)``
    F : (nF, 3) int64
    active : (nV,) bool
    kappa : float >= 0 (0 gives weight 1)

    Returns
    -------
    (nV,) float64 in [0, 1]
    """
    from meshrepair import _kernels as _k

    active = np.asarray(active, bool)
    w = np.zeros(len(V))
    if not active.any():
        return w
    V = np.ascontiguousarray(V, dtype=np.float64)
    n = _k.vertex_normals(V, np.asarray(F, dtype=np.int64))
    d = np.einsum("ij,ij->i", np.asarray(V0) - V, n)
    s2 = float(np.einsum("ij,ij->i", X - V, X - V)[active].mean())
    den = s2 + (kappa * d[active]) ** 2
    w[active] = np.where(den > 0, s2 / np.where(den > 0, den, 1.0), 0.0)
    return w
