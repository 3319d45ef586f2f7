"""Fairing of the new vertices: membrane (order 1) or thin-plate / least-squares meshes
(order 2) with the surrounding ring as Dirichlet data."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair.errors import MeshRepairError
from meshrepair.holes._fairing_common import (
    _barycentric_areas,
    _free_mask,
    _laplacian,
    _usable_rows,
)
from meshrepair.holes._geom2d import _cotan_weights_2d

LIEPA_COT_RANGE = (0.3, 3.0)
"""Cotangent bounds (angles 18.4°-73.3°) of the thin-plate fairing of patches enclosed by
Liepa's triangulation (:mod:`meshrepair.fill.place`): its developed / mean-value layouts give
anisotropic triangles, whose exact cotangents make the fairing follow the triangulation rather
than the surround. Chosen on the holes benchmark (docs/holes.md, section 5)."""


def fair_vertices(V: np.ndarray, F: np.ndarray, free: np.ndarray, *, order: int = 2,
                  weights: str = "cotan", iterations: int = 1,
                  exclude_rows: np.ndarray | None = None,
                  curvature: bool = False,
                  curvature_exclude: np.ndarray | None = None,
                  cot_range: tuple[float, float] | None = None,
                  cot_faces: np.ndarray | None = None) -> np.ndarray:
    """Move the ``free`` vertices to a fair (harmonic or bi-Laplacian) position.

    ``order=2`` minimises ``sum_r A_r |(Δx)_r|²`` over the free vertices and their neighbours
    (``Δ = A⁻¹ C``, ``C`` the cotangent or umbrella weights, ``A`` barycentric areas) with all
    other vertices fixed: the free region continues position *and* tangent plane of the
    surrounding 1-ring (least-squares meshes / thin-plate fairing). ``order=1`` solves
    ``(Δx)_i = 0`` on the free vertices only (a membrane: minimal area for cotangent weights).
    Rows of vertices on a remaining open boundary are left out (their Laplacian is one-sided).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    free : (nV,) bool or int indices of the vertices to move
    order : 1 or 2
    weights : ``"cotan"`` (geometry-aware, from the current positions) or ``"uniform"``
        (umbrella; also regularises the vertex distribution)
    iterations : int
        Recompute the cotangent weights from the new positions and solve again this many times.
    exclude_rows : (nV,) bool or int indices, optional
        Fixed vertices whose Laplacian rows are left out of the energy (vertices on a sharp
        crease: the surface has no tangent plane there, so each side is faired on its own).
    curvature : bool
        ``order=2`` only: minimise ``sum_r A_r |(Δx)_r - κ_r n_r|²`` instead, with ``κ`` the
        signed mean curvature measured on the ring just outside the loop and harmonically
        interpolated over the patch, ``n_r`` the current vertex normal (curvature continuity:
        a sphere's hole is filled by the sphere, which the plain thin plate flattens).
    curvature_exclude : (nV,) bool or int indices, optional
        Vertices not used as curvature measurements (e.g. vertices on sharp edges).
    cot_range : (lo, hi), optional
        ``weights="cotan"`` only: clip every angle's cotangent to ``[lo, hi]`` in the fairing's
        Laplacian (bounds the weight of nearly degenerate or obtuse angles, which an
        anisotropic triangulation has: :data:`LIEPA_COT_RANGE`). The curvature measurement
        keeps the exact cotangents.
    cot_faces : (nF,) bool, optional
        With ``cot_range``: clip only the angles of these faces (default: all).

    Returns
    -------
    (nV, 3) float64, a new array (only the free rows differ from ``V``).
    """
    from scipy.sparse.linalg import spsolve

    V, F, fm = _free_mask(V, F, free)
    nV = len(V)
    if not fm.any():
        return V
    if order not in (1, 2):
        raise MeshRepairError(f"order must be 1 or 2, got {order}")
    if weights not in ("cotan", "uniform"):
        raise MeshRepairError(f"weights must be 'cotan' or 'uniform', got {weights!r}")
    # local mesh: faces touching the free vertices and their neighbours
    touch = fm[F].any(axis=1)
    rows = np.zeros(nV, bool)
    rows[F[touch].ravel()] = True
    if order == 1:
        rows = fm.copy()
    in_loc = rows[F].any(axis=1)
    Floc = F[in_loc]
    clip_loc = None
    if cot_range is not None:
        clip_loc = np.ones(len(Floc), bool) if cot_faces is None else \
            np.asarray(cot_faces, bool)[in_loc]
    ok, on_bnd = _usable_rows(F, nV, fm, exclude_rows)
    rows &= ok
    r_idx = np.flatnonzero(rows)
    u_idx = np.flatnonzero(fm)
    kappa = None
    if curvature and order == 2 and weights == "cotan":
        ex = np.zeros(nV, bool)
        for e_ in (exclude_rows, curvature_exclude):
            if e_ is not None:
                ex[np.asarray(e_)] = True
        kappa = _curvature_field(V, F, fm, rows, on_bnd, ex)
    for _ in range(max(1, iterations)):
        if weights == "cotan":
            W = _cotan_weights_2d(V, Floc, nV) if clip_loc is None else (
                _cotan_weights_2d(V, Floc[~clip_loc], nV)
                + _cotan_weights_2d(V, Floc[clip_loc], nV, cot_range))
        else:
            e = np.sort(np.concatenate([Floc[:, [0, 1]], Floc[:, [1, 2]], Floc[:, [2, 0]]]),
                        axis=1)
            e = np.unique(e, axis=0)
            W = sp.csr_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]],
                                                      np.r_[e[:, 1], e[:, 0]])), shape=(nV, nV))
        C = _laplacian(W)
        if weights == "cotan":
            area = _barycentric_areas(V, Floc, nV)
        else:
            area = np.ones(nV)
        k_idx = np.flatnonzero(~fm)
        if order == 1:
            A = C[u_idx][:, u_idx].tocsc()
            rhs = -(C[u_idx][:, k_idx] @ V[k_idx])
        else:
            Cr = C[r_idx]
            w = sp.diags(1.0 / np.maximum(area[r_idx], 1e-300))
            CU = Cr[:, u_idx]
            CK = Cr[:, k_idx]
            A = (CU.T @ w @ CU).tocsc()
            rhs = -(CU.T @ (w @ (CK @ V[k_idx])))
            if kappa is not None:
                n = _vertex_normals(V, Floc, nV)[r_idx]
                rhs = rhs + CU.T @ (kappa[r_idx, None] * n)
        sol = spsolve(A, rhs)
        V[u_idx] = np.asarray(sol).reshape(len(u_idx), 3)
        if weights == "uniform":
            break
    return V


def _vertex_normals(V: np.ndarray, F: np.ndarray, nV: int) -> np.ndarray:
    """Area-weighted unit vertex normals over the faces ``F`` (zero where no face)."""
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n = np.zeros((nV, 3))
    for k in range(3):
        np.add.at(n, F[:, k], c)
    ln = np.linalg.norm(n, axis=1, keepdims=True)
    return np.where(ln > 0, n / np.where(ln > 0, ln, 1.0), 0.0)


def _curvature_field(V, F, fm, rows, on_bnd, exclude_rows) -> np.ndarray:
    """Signed mean curvature ``κ = (Δx)·n`` (cotangent Laplacian over barycentric area) measured
    on the ring of original vertices just outside the loop, copied to the loop vertices (mean
    of their outside neighbours) and harmonically interpolated over the free vertices (uniform
    weights). Zero where there is no measurement."""
    from scipy.sparse.linalg import spsolve

    nV = len(V)
    loopv = rows & ~fm
    patchf = fm[F].any(axis=1)
    ex = np.zeros(nV, bool)
    if exclude_rows is not None:
        ex[np.asarray(exclude_rows)] = True
    # outside ring: original vertices sharing an original face with a loop vertex
    orig = F[~patchf]
    near = np.zeros(nV, bool)
    near[orig[loopv[orig].any(axis=1)].ravel()] = True
    ring = near & ~loopv & ~fm & ~on_bnd & ~ex
    kappa = np.zeros(nV)
    if not ring.any():
        return kappa
    Fr = orig[ring[orig].any(axis=1)]
    # the full 1-ring of every ring vertex must be original faces (true by construction unless
    # it touches the patch through a loop vertex, which only adds loop vertices as neighbours)
    W = _cotan_weights_2d(V, Fr, nV)
    C = _laplacian(W)
    area = _barycentric_areas(V, Fr, nV)
    ri = np.flatnonzero(ring)
    t = (C[ri] @ V) / np.maximum(area[ri], 1e-300)[:, None]
    n = _vertex_normals(V, Fr, nV)[ri]
    kappa[ri] = np.einsum("ij,ij->i", t, n)
    # loop vertices: mean over their outside-ring neighbours
    e = np.r_[orig[:, [0, 1]], orig[:, [1, 2]], orig[:, [2, 0]]]
    e = np.r_[e, e[:, ::-1]]
    sel = loopv[e[:, 0]] & ring[e[:, 1]]
    s = np.bincount(e[sel, 0], kappa[e[sel, 1]], minlength=nV)
    cnt = np.bincount(e[sel, 0], minlength=nV)
    known = ring.copy()
    lk = loopv & (cnt > 0)
    kappa[lk] = s[lk] / cnt[lk]
    known |= lk
    # harmonic interpolation over the patch graph (uniform weights), loop values as data
    Fp = F[patchf]
    if len(Fp) == 0:
        return kappa
    ep = np.unique(np.sort(np.r_[Fp[:, [0, 1]], Fp[:, [1, 2]], Fp[:, [2, 0]]], axis=1), axis=0)
    Wp = sp.csr_matrix((np.ones(2 * len(ep)), (np.r_[ep[:, 0], ep[:, 1]],
                                               np.r_[ep[:, 1], ep[:, 0]])), shape=(nV, nV))
    L = _laplacian(Wp)
    u = np.flatnonzero(fm)
    kn = np.flatnonzero(known & (np.asarray(Wp.sum(axis=1)).ravel() > 0))
    if len(u) == 0 or len(kn) == 0:
        return kappa
    A = L[u][:, u].tocsc()
    rhs = -(L[u][:, kn] @ kappa[kn])
    kappa[u] = np.asarray(spsolve(A, rhs)).ravel()
    return kappa
