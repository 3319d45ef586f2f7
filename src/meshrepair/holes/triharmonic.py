"""Triharmonic (curvature-continuous) fairing of the new vertices, with two rings of the
surround as boundary data.

The thin plate of :func:`meshrepair.holes.fair_vertices` (``Σ_r A_r |(Δx)_r|²``) continues
position and tangent plane across the loop (G1). Its Euler-Lagrange equation is ``Δ²x = 0``; the
next order, ``Δ³x = 0``, also continues the curvature (G2; Botsch & Kobbelt 2004, "An intuitive
framework for real-time freeform modeling"; Jacobson et al. 2010 "Mixed finite elements for
variational surface modeling"). Here it is the minimiser over the free vertices of

    E(x) = Σ_{(i,j) ∈ E_R} w_ij |y_i - y_j|²,   y = Δx = A⁻¹ C x  (the mean-curvature normal),

plus ``SCREEN Σ_i (A_i / h²) |y_i|²`` (:data:`SCREEN`), the discrete Dirichlet energy
``∫ |∇(Δx)|²`` of the Laplacian (screened by a small thin-plate term), with ``w_ij`` the cotangent
weights, ``A`` barycentric areas, and ``E_R`` the edges between *valid* vertices within two rings
of the free set. A vertex is valid when its Laplacian is a full interior one (not on a remaining
open boundary) and it is not on a sharp crease (there the surface has no tangent plane and no
curvature: each side of a crease is faired on its own, as for the thin plate). Every vertex not
free is Dirichlet data, so the original vertices of the first two or three rings beyond the loop
enter the energy: the patch matches both the surround's tangent planes and its curvature. With
``curvature_target`` (the field ``κ n`` of the curvature-continuity fairing) the energy is
``Σ w_ij |(y_i - κ_i n_i) - (y_j - κ_j n_j)|²``.

The cotangent weights and areas are recomputed from the new positions and the system solved
again, ``iterations`` times.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair.holes._fairing_common import (
    _barycentric_areas,
    _free_mask,
    _laplacian,
    _usable_rows,
)
from meshrepair.holes._geom2d import _cotan_weights_2d

SCREEN = 0.05
"""Weight of the thin-plate term ``SCREEN Σ_i (A_i / h²) |y_i|²`` added to the energy (``h`` the
mean edge length): the screened triharmonic ``(-Δ + 1/ℓ²) Δx = 0`` with ``ℓ = h / √SCREEN ≈
4.5 h``. It pins the constant mode of ``y`` on a part of the patch that crease routes cut off
from the surround, and lets the surround's curvature fade over ``ℓ`` instead of carrying it
across a large hole. Chosen on the holes benchmark's design set (docs/holes.md): a larger
weight helps large holes and costs small ones, and 0.05 balances the two."""


def _rings(F: np.ndarray, seed: np.ndarray, nV: int, k: int) -> np.ndarray:
    """Ring distance (0..k) of every vertex from the ``seed`` mask over the faces; ``k+1``
    beyond."""
    d = np.full(nV, k + 1, np.int64)
    d[seed] = 0
    cur = seed.copy()
    for r in range(1, k + 1):
        touch = cur[F].any(axis=1)
        nxt = np.zeros(nV, bool)
        nxt[F[touch].ravel()] = True
        nxt &= d > r
        d[nxt] = r
        cur = cur | nxt
    return d


def fair_triharmonic(V: np.ndarray, F: np.ndarray, free: np.ndarray, *, iterations: int = 3,
                     exclude_rows: np.ndarray | None = None,
                     target: np.ndarray | None = None) -> np.ndarray:
    """Move the ``free`` vertices to the minimiser of the triharmonic energy (module docstring).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nV, 3) int
    free : (nV,) bool or int indices of the vertices to move
    iterations : int
        Recompute the cotangent weights from the new positions and solve again this many times.
    exclude_rows : (nV,) bool or int indices, optional
        Fixed vertices whose Laplacian is not used (vertices on sharp creases).
    target : (nV, 3) float, optional
        Target Laplacian ``κ n`` (curvature continuity); default zero.

    Returns
    -------
    (nV, 3) float64, a new array (only the free rows differ from ``V``).
    """
    from scipy.sparse.linalg import spsolve

    V, F, fm = _free_mask(V, F, free)
    nV = len(V)
    if not fm.any():
        return V
    d = _rings(F, fm, nV, 3)
    Floc = F[(d[F] <= 2).any(axis=1)]  # full 1-rings of every vertex within 2 rings
    valid = (d <= 2) & _usable_rows(F, nV, fm, exclude_rows)[0]
    R = np.flatnonzero(valid)
    u_idx = np.flatnonzero(fm)
    k_idx = np.flatnonzero(~fm)
    pos = -np.ones(nV, np.int64)
    pos[R] = np.arange(len(R))
    el = np.linalg.norm(V[Floc] - V[np.roll(Floc, 1, axis=1)], axis=2)
    h2 = float(np.mean(el)) ** 2
    for _ in range(max(1, iterations)):
        W = _cotan_weights_2d(V, Floc, nV)
        C = _laplacian(W)
        area = _barycentric_areas(V, Floc, nV)
        L = sp.diags(1.0 / np.maximum(area[R], 1e-300)) @ C[R]  # y_R = L x
        # Dirichlet energy of y over the edges between valid vertices (cotangent weights)
        Wr = W[R][:, R].tocoo()
        Wr = sp.csr_matrix((Wr.data, (Wr.row, Wr.col)), shape=(len(R), len(R)))
        K = _laplacian(Wr)
        if SCREEN > 0:
            # a region of the patch enclosed by crease routes has no valid surround vertex:
            # a constant y there costs nothing; a small thin-plate term pins it
            K = K + SCREEN * sp.diags(area[R] / h2)
        G = L[:, u_idx]
        b = L[:, k_idx] @ V[k_idx]
        if target is not None:
            b = b - target[R]
        A = (G.T @ K @ G).tocsc()
        rhs = -(G.T @ (K @ b))
        sol = np.asarray(spsolve(A, rhs)).reshape(len(u_idx), 3)
        if not np.isfinite(sol).all():
            break
        V[u_idx] = sol
    return V
