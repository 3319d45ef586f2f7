"""Fairing of the new vertices: membrane (order 1) or thin-plate / least-squares meshes
(order 2) with the surrounding ring as Dirichlet data."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import MeshRepairError
from ..topology import edge_topology
from ._geom2d import _cotan_weights_2d


def fair_vertices(V: np.ndarray, F: np.ndarray, free: np.ndarray, *, order: int = 2,
                  weights: str = "cotan", iterations: int = 1,
                  exclude_rows: np.ndarray | None = None) -> np.ndarray:
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

    Returns
    -------
    (nV, 3) float64, a new array (only the free rows differ from ``V``).
    """
    from scipy.sparse.linalg import spsolve

    V = np.array(V, dtype=np.float64, copy=True)
    F = np.asarray(F, dtype=np.int64)
    nV = len(V)
    fm = np.zeros(nV, bool)
    fm[np.asarray(free)] = True
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
    Floc = F[rows[F].any(axis=1)]
    topo = edge_topology(F, nV)
    on_bnd = np.zeros(nV, bool)
    on_bnd[topo.edges[topo.boundary].ravel()] = True
    rows &= ~(on_bnd & ~fm)
    if exclude_rows is not None:
        ex = np.zeros(nV, bool)
        ex[np.asarray(exclude_rows)] = True
        rows &= ~(ex & ~fm)
    r_idx = np.flatnonzero(rows)
    u_idx = np.flatnonzero(fm)
    for _ in range(max(1, iterations)):
        if weights == "cotan":
            W = _cotan_weights_2d(V, Floc, nV)
        else:
            e = np.sort(np.concatenate([Floc[:, [0, 1]], Floc[:, [1, 2]], Floc[:, [2, 0]]]),
                        axis=1)
            e = np.unique(e, axis=0)
            W = sp.csr_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]],
                                                      np.r_[e[:, 1], e[:, 0]])), shape=(nV, nV))
        C = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()
        if weights == "cotan":
            c = np.cross(V[Floc[:, 1]] - V[Floc[:, 0]], V[Floc[:, 2]] - V[Floc[:, 0]])
            area = np.zeros(nV)
            np.add.at(area, Floc.ravel(), np.repeat(np.linalg.norm(c, axis=1) / 6.0, 3))
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
        sol = spsolve(A, rhs)
        V[u_idx] = np.asarray(sol).reshape(len(u_idx), 3)
        if weights == "uniform":
            break
    return V
