"""Pieces shared by the fairings of the new vertices (:mod:`meshrepair.holes.fairing`,
:mod:`meshrepair.holes.triharmonic`): the free-vertex mask, the rows whose Laplacian may enter
the energy, the Laplacian ``C = diag(W 1) - W`` of a weight matrix and barycentric areas."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair.mesh.topology import edge_topology


def _free_mask(V, F, free) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(V, F, fm)``: a float64 copy of ``V``, ``F`` as int64 and the (nV,) bool mask of the
    ``free`` vertices (bool mask or indices)."""
    V = np.array(V, dtype=np.float64, copy=True)
    F = np.asarray(F, dtype=np.int64)
    fm = np.zeros(len(V), bool)
    fm[np.asarray(free)] = True
    return V, F, fm


def _usable_rows(F: np.ndarray, nV: int, fm: np.ndarray,
                 exclude_rows: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """``(ok, on_bnd)``: ``ok`` (nV,) bool is False on the fixed vertices whose Laplacian is left
    out of the energy (on a remaining open boundary, where it is one-sided, or in
    ``exclude_rows``); ``on_bnd`` marks the open-boundary vertices."""
    topo = edge_topology(F, nV)
    on_bnd = np.zeros(nV, bool)
    on_bnd[topo.edges[topo.boundary].ravel()] = True
    ok = ~(on_bnd & ~fm)
    if exclude_rows is not None:
        ex = np.zeros(nV, bool)
        ex[np.asarray(exclude_rows)] = True
        ok &= ~(ex & ~fm)
    return ok, on_bnd


def _laplacian(W: sp.spmatrix) -> sp.csr_matrix:
    """``C = diag(W 1) - W`` (CSR)."""
    return (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()


def _barycentric_areas(V: np.ndarray, F: np.ndarray, nV: int) -> np.ndarray:
    """(nV,) barycentric vertex areas (a third of the adjacent faces' areas) over ``F``."""
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    area = np.zeros(nV)
    np.add.at(area, F.ravel(), np.repeat(np.linalg.norm(c, axis=1) / 6.0, 3))
    return area
