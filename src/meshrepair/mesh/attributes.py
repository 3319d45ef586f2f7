"""Values on new vertices and faces of a repaired mesh, from the values around them.

A repair (hole filling, inpainting, completion) keeps the original vertices and adds new ones
inside patches; per-vertex values such as colours or texture coordinates are known on the
original vertices and unknown on the new ones. They are extended by the same kind of fairing
the geometry gets, with ``L = D^-1 (D - W)`` the normalised Laplacian of the output mesh
(``W`` edge weights, ``D`` their row sums):

* ``"biharmonic"`` (default): ``(L^2)_uu x_u = -(L^2)_uk x_k``, the unknown values ``x_u``
  solve the thin-plate equation ``L^2 x = 0`` on the patch with the known values ``x_k`` of
  two rings around it fixed: values *and* their slope across the border continue into the
  patch, so a smooth field (a colour gradient) is followed rather than flattened. The result is
  clipped to the range of the known values (a thin plate may overshoot);
* ``"harmonic"``: ``L_uu x_u = -L_uk x_k`` (the border values only): each new value is a
  convex combination of its neighbours', so it never leaves the border's range, but a field is
  flattened towards the border's average in a large patch.

Both reproduce a field that is linear in the surface's (flat) parameterisation on a flat patch.
The weights are the cotangent weights ``w_ij = (cot a_ij + cot b_ij) / 2`` clamped at 0, plus a
small uniform weight ``eps * mean(w)`` so that every patch vertex is linked to its neighbours
even across degenerate triangles.

Per-face values (materials, face properties) on new faces are taken from a neighbouring face
that has one: a breadth-first walk over edge-adjacent faces from the kept faces
(:func:`propagate_faces`).

This module is pure numpy/scipy on (V, F) arrays; reading, writing and the choice of what is
interpolated are in :mod:`meshrepair.io.carry`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["METHODS", "harmonic_weights", "harmonic_extend", "propagate_faces", "nearest_known"]

METHODS = ("biharmonic", "harmonic")

_EPS_UNIFORM = 1e-3


def harmonic_weights(V: np.ndarray, F: np.ndarray):
    """Symmetric (nV, nV) edge weights: cotangent weights clamped at 0 plus a small uniform
    part (``1e-3`` of their mean) on every edge."""
    import scipy.sparse as sp

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    nV = len(V)
    if len(F) == 0:
        return sp.csr_matrix((nV, nV))
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = F[:, (k + 1) % 3], F[:, (k + 2) % 3], F[:, k]
        a, b = V[i] - V[o], V[j] - V[o]
        cross = np.linalg.norm(np.cross(a, b), axis=1)
        dot = np.einsum("ij,ij->i", a, b)
        with np.errstate(divide="ignore", invalid="ignore"):
            cot = np.where(cross > 1e-300, dot / cross, 0.0)
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * cot, 0.5 * cot]
    W = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(nV, nV))
    W.data = np.maximum(W.data, 0.0)
    r, c = np.concatenate(rows), np.concatenate(cols)
    U = sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(nV, nV))
    U.data[:] = 1.0
    mean = float(W.data.mean()) if W.nnz and W.data.max() > 0 else 1.0
    return (W + _EPS_UNIFORM * mean * U).tocsr()


def harmonic_extend(V: np.ndarray, F: np.ndarray, values: np.ndarray,
                    known: np.ndarray, method: str = "biharmonic") -> np.ndarray:
    """Extend values given on the ``known`` vertices to the others (module docstring).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    values : (nV,) or (nV, k) float
        Read on the known rows only.
    known : (nV,) bool
    method : {"biharmonic", "harmonic"}

    Returns
    -------
    (nV,) or (nV, k) float64
        ``values`` on the known rows; on the others the solution of the biharmonic or harmonic
        equation (module docstring). An unknown vertex in a component without any known vertex
        gets the mean of all known values (there is nothing around it to interpolate from).
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    vals = np.asarray(values, dtype=np.float64)
    flat = vals.ndim == 1
    X = vals.reshape(len(vals), -1).copy()
    known = np.asarray(known, dtype=bool)
    unk = np.flatnonzero(~known)
    if unk.size == 0:
        return X[:, 0] if flat else X
    if not known.any():
        X[unk] = 0.0
        return X[:, 0] if flat else X
    # only the unknown vertices and three rings of faces around them take part
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    near = ~known
    for _ in range(3):
        near = near.copy()
        near[F[near[F].any(axis=1)].ravel()] = True
    Fs = F[near[F].all(axis=1)]  # complete rings: the rows of L and L^2 used are exact
    sub = np.flatnonzero(near)
    local = np.full(len(V), -1, np.int64)
    local[sub] = np.arange(len(sub))
    Xs = _extend_local(V[sub], local[Fs], X[sub], known[sub], method, X[known])
    X[sub] = Xs
    return X[:, 0] if flat else X


def _extend_local(V: np.ndarray, F: np.ndarray, X: np.ndarray, known: np.ndarray, method: str,
                  X_all_known: np.ndarray) -> np.ndarray:
    import scipy.sparse as sp

    X = X.copy()
    unk = np.flatnonzero(~known)
    kn = np.flatnonzero(known)
    W = harmonic_weights(V, F)
    deg = np.asarray(W.sum(axis=1)).ravel()
    reach = _reaches_known(W[unk][:, unk], np.asarray(W[unk][:, kn].sum(axis=1)).ravel() > 0)
    X[unk] = X_all_known.mean(axis=0)
    if reach.any():
        from scipy.sparse.linalg import splu

        u = unk[reach]
        if method == "harmonic":
            A = (sp.diags(deg[u]) - W[u][:, u]).tocsc()
            rhs = W[u][:, kn] @ X[kn]
            X[u] = splu(A).solve(np.asarray(rhs))
        else:
            L = (sp.eye(len(V)) - sp.diags(1.0 / np.maximum(deg, 1e-300)) @ W).tocsr()
            rows = (L[u] @ L).tocsr()
            A = rows[:, u].tocsc()
            rhs = -(rows[:, kn] @ X[kn])
            X[u] = np.clip(splu(A).solve(np.asarray(rhs)), X_all_known.min(axis=0),
                           X_all_known.max(axis=0))
    return X


def _reaches_known(W_uu, touches: np.ndarray) -> np.ndarray:
    """Unknown vertices connected (through unknown vertices) to one touching a known vertex."""
    from scipy.sparse.csgraph import connected_components

    n, lab = connected_components(W_uu, directed=False)
    good = np.zeros(n, bool)
    good[lab[touches]] = True
    return good[lab]


def propagate_faces(F: np.ndarray, known: np.ndarray) -> np.ndarray:
    """For each face, the known face whose value it takes: itself if known, else (breadth-first
    over edge-adjacent faces) that of the first known face reached; -1 where none is reached.

    Parameters
    ----------
    F : (nF, 3) int
    known : (nF,) bool

    Returns
    -------
    (nF,) int64
    """
    import scipy.sparse as sp

    F = np.asarray(F, dtype=np.int64)
    nF = len(F)
    src = np.where(np.asarray(known, bool), np.arange(nF), -1).astype(np.int64)
    if nF == 0 or (src >= 0).all():
        return src
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    fid = np.tile(np.arange(nF), 3)
    order = np.lexsort((e[:, 1], e[:, 0]))
    e, fid = e[order], fid[order]
    same = (e[1:] == e[:-1]).all(axis=1)
    a, b = fid[:-1][same], fid[1:][same]
    A = sp.csr_matrix((np.ones(2 * len(a)), (np.r_[a, b], np.r_[b, a])), shape=(nF, nF))
    while True:
        todo = np.flatnonzero(src < 0)
        if todo.size == 0:
            break
        sub = A[todo]
        hit = sub.multiply((src >= 0).astype(np.float64)[None, :]).tocsr()
        hit.eliminate_zeros()
        hit.sort_indices()
        rows = np.flatnonzero(np.diff(hit.indptr))
        if rows.size == 0:
            break
        first = hit.indices[hit.indptr[rows]]  # the lowest-numbered known neighbour
        src[todo[rows]] = src[first]
    return src


def nearest_known(V: np.ndarray, known: np.ndarray) -> np.ndarray:
    """For every vertex, the index of the closest known vertex (Euclidean); itself if known."""
    from scipy.spatial import cKDTree

    known = np.asarray(known, bool)
    out = np.arange(len(V), dtype=np.int64)
    kn = np.flatnonzero(known)
    unk = np.flatnonzero(~known)
    if unk.size and kn.size:
        _, j = cKDTree(V[kn]).query(V[unk])
        out[unk] = kn[j]
    return out
