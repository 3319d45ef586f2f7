"""Heavy-noise polish: a crease-bounded bilateral normal filter on the flat patches of a CAD part.

After the feature stage the sharp-edge mask ``M_E`` has converged, but on heavy noise (γ̂ >
0.33) the planar patches of a CAD part keep a ripple of a few degrees away from the creases.
This step filters
the result's face normals over a neighbourhood that never crosses ``M_E`` and only on faces
whose neighbourhood is already flat, then moves the vertices to the filtered normals.

**Neighbourhood.** ``A`` is the face adjacency across the interior edges *not* in ``M_E``;
``K(f)`` the faces within ``r`` steps of ``A`` (``(I + A)^r``, so a crease of ``M_E`` bounds it).

**Flatness gate.** With the result's normals ``n_g`` and their mean ``m_f`` over ``K(f)``,

.. math:: s_f = \\Big(\\frac{1}{|K(f)|} \\sum_{g \\in K(f)} \\angle(n_g, m_f)^2\\Big)^{1/2},
          \\qquad G = \\{f : s_f < τ\\},

computed once, on the input of this step. Faces outside ``G`` (curved patches, blends, small
features whose curvature within ``r`` rings is larger than τ) keep their normals.

**Filter** (Zheng et al. 2011, bilateral normal filtering), for ``f ∈ G``:

.. math:: n'_f = \\frac{\\sum_{g \\in K(f)} A_g W_c(\\|c_f - c_g\\|) W_s(\\|n_f - n_g\\|) n_g}
                      {\\|\\cdot\\|},
          \\quad W_c(d) = e^{-d^2 / 2σ_c^2},\\; W_s(d) = e^{-d^2 / 2σ_s^2},

``A_g`` the face area, ``c`` the centroids, ``σ_c = r`` mean edge lengths, ``σ_s = 0.35``.

**Vertex update** (Sun et al. 2007): gradient steps on
``E(x) = Σ_f Σ_{i ∈ f} (n'_f · (x_i − c_f))²`` (the V-subproblem (26) with λ = 0 and the
filtered normals as ``N``), each ``x_i ← x_i + (1/|F_i|) Σ_{f ∋ i} n'_f (n'_f · (c_f − x_i))``,
20 per filter pass, ``passes`` passes. A mesh whose faces already have the normals ``n'`` is a
fixed point (``c_f − x_i`` lies in the face's plane). With ``data`` and ``eta > 0`` each step
is followed by the prox of a data term (:mod:`meshrepair.denoise.polish_fidelity`; what
:func:`meshrepair.denoise` does).

Defaults: ``r = 4``, ``τ = 5°``, ``passes = 10`` (:func:`meshrepair.denoise.api.polish_rule`
scales them with the noise's correlation length); chosen on the benchmark grid
(docs/parameters.md).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

POLISH_RINGS = 4
POLISH_TAU = 5.0
POLISH_SIGMA_S = 0.35
POLISH_PASSES = 10
POLISH_VSTEPS = 20


def _neighbourhood(topo, sharp: np.ndarray, rings: int) -> tuple[np.ndarray, np.ndarray]:
    """Pairs ``(f, g)``, ``g ∈ K(f)``: faces within ``rings`` steps across non-sharp edges,
    sorted by ``f`` then ``g`` (the CSR order of ``K``)."""
    K = _neighbourhood_csr(topo, sharp, rings)
    I = np.repeat(np.arange(K.shape[0], dtype=np.int64), np.diff(K.indptr))
    return I, K.indices.astype(np.int64)


NEIGHBOURHOOD_CHUNK = 100_000
"""Rows of ``K`` built at a time: the sparse products then stay small on million-face meshes
(``K`` itself is kept with int32 column indices and boolean entries, ≈ 5 bytes per pair; about
30 pairs per face at r = 4, 60 at r = 6)."""


def _neighbourhood_csr(topo, sharp: np.ndarray, rings: int) -> sp.csr_matrix:
    """``K = (I + A)^r > 0`` as a boolean CSR matrix with sorted rows (module docstring)."""
    nF = topo.n_faces
    ok = topo.interior & ~np.asarray(sharp, bool)
    fa, fb = topo.edge_faces[ok, 0], topo.edge_faces[ok, 1]
    A = sp.csr_matrix((np.ones(2 * len(fa)), (np.r_[fa, fb], np.r_[fb, fa])), shape=(nF, nF))
    counts, cols = [], []
    for lo in range(0, nF, NEIGHBOURHOOD_CHUNK):
        hi = min(nF, lo + NEIGHBOURHOOD_CHUNK)
        R = sp.csr_matrix((np.ones(hi - lo), (np.arange(hi - lo), np.arange(lo, hi))),
                          shape=(hi - lo, nF))
        for _ in range(rings):
            R = R + R @ A
            R.data[:] = 1.0
        R.sort_indices()
        counts.append(np.diff(R.indptr))
        cols.append(R.indices.astype(np.int32))
    indptr = np.r_[0, np.cumsum(np.concatenate(counts))].astype(np.int64)
    indices = np.concatenate(cols)
    return sp.csr_matrix((np.ones(len(indices), bool), indices, indptr), shape=(nF, nF))


def _normals_areas(X: np.ndarray, F: np.ndarray):
    a, b, c = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    cr = np.cross(b - a, c - a)
    dbl = np.linalg.norm(cr, axis=1)
    return cr / np.maximum(dbl, 1e-300)[:, None], 0.5 * dbl, (a + b + c) / 3.0


def _scatter(I: np.ndarray, w: np.ndarray, X: np.ndarray, n: int) -> np.ndarray:
    out = np.empty((n, X.shape[1]))
    for k in range(X.shape[1]):
        out[:, k] = np.bincount(I, weights=w * X[:, k], minlength=n)
    return out


def flat_gate(N: np.ndarray, I: np.ndarray, J: np.ndarray, tau: float) -> np.ndarray:
    """``s_f < τ`` (degrees) of the module docstring, for normals ``N (nF, 3)`` and pairs
    ``(I, J)`` of ``K`` (the numpy reference of :func:`flat_gate_csr`)."""
    nF = len(N)
    M = _scatter(I, np.ones(len(I)), N[J], nF)
    M /= np.maximum(np.linalg.norm(M, axis=1, keepdims=True), 1e-300)
    dev = np.arccos(np.clip(np.einsum("ij,ij->i", N[J], M[I]), -1.0, 1.0)) ** 2
    cnt = np.bincount(I, minlength=nF)
    s = np.degrees(np.sqrt(np.bincount(I, weights=dev, minlength=nF) / np.maximum(cnt, 1)))
    return s < tau


def flat_gate_csr(N: np.ndarray, K: sp.csr_matrix, tau: float) -> np.ndarray:
    """:func:`flat_gate` row by row over the CSR neighbourhood ``K`` (no per-pair arrays)."""
    from meshrepair._kernels.bilateral import spread_rows

    return spread_rows(K.indptr, K.indices, N) < tau


def filter_normals(X: np.ndarray, F: np.ndarray, K: sp.csr_matrix, gate: np.ndarray, *,
                   sigma_c: float, sigma_s: float = POLISH_SIGMA_S,
                   faces: tuple | None = None) -> np.ndarray:
    """One bilateral pass ``n'`` of the module docstring over the neighbourhood ``K`` (CSR,
    from :func:`_neighbourhood_csr`); faces outside ``gate`` keep their normals. ``faces``:
    ``_normals_areas(X, F)`` when already computed (several passes on the same ``X``)."""
    from meshrepair._kernels.bilateral import bilateral_pass

    N, area, C = _normals_areas(X, F) if faces is None else faces
    return bilateral_pass(K.indptr, K.indices, N, area, C, gate, sigma_c, sigma_s)


def vertex_update(X: np.ndarray, F: np.ndarray, Nt: np.ndarray, steps: int = POLISH_VSTEPS
                  ) -> np.ndarray:
    """Sun et al. steps towards face normals ``Nt`` (module docstring); returns a new array."""
    from meshrepair._kernels.bilateral import sun_steps

    return sun_steps(X, F, Nt, steps)


def polish(V: np.ndarray, F: np.ndarray, sharp: np.ndarray, topo, *, rings: int = POLISH_RINGS,
           tau: float = POLISH_TAU, passes: int = POLISH_PASSES, data: np.ndarray | None = None,
           eta: float = 0.0) -> tuple[np.ndarray, float]:
    """The heavy-noise polish of the module docstring.

    Parameters
    ----------
    V : (nV, 3) float64, the solve's result
    F : (nF, 3) int64
    sharp : (nE,) bool, ``M_E`` on ``topo.edges``
    topo : Topology of the mesh
    rings, tau, passes : ``r``, ``τ`` (degrees) and the number of filter passes
    data : (nV, 3) float64, optional, the fidelity data ``V⁰``; with ``eta > 0`` the vertex
        step keeps a data term (:mod:`meshrepair.denoise.polish_fidelity`)
    eta : float >= 0, its weight per step (0: the vertex step of the module docstring)

    Returns
    -------
    V : (nV, 3) float64, a new array
    gated : float, the fraction of faces in ``G``
    """
    F = np.asarray(F, dtype=np.int64)
    K = _neighbourhood_csr(topo, sharp, rings)
    N0, _, _ = _normals_areas(V, F)
    gate = flat_gate_csr(N0, K, tau)
    le = float(np.linalg.norm(V[topo.edges[:, 0]] - V[topo.edges[:, 1]], axis=1).mean())
    X = np.array(V, dtype=np.float64, copy=True)
    if not gate.any():
        return X, 0.0
    for _ in range(passes):
        Nt = filter_normals(X, F, K, gate, sigma_c=rings * le)
        if data is not None and eta > 0:
            from meshrepair.denoise.polish_fidelity import vertex_update_with_data

            X = vertex_update_with_data(X, F, Nt, data, eta=eta)
        else:
            X = vertex_update(X, F, Nt)
    return X, float(gate.mean())
