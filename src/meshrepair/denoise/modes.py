"""Crease sharpening for correlated scanner noise: mode-seeking face normals, kept where the data
support them.

On correlated (scanner) noise the solve and the polish of :mod:`meshrepair.denoise.polish` leave the
planes flat but the creases *rounded* over a band of a few noise lengths (on a real scan the
faces 2-5 rings from the true creases keep about twice the normal error of a TGV result).
Their sharp-edge mask cannot catch them: no
single edge of a rounded band is creased. This step sharpens such bands at the scale of the
noise and keeps the change only where the input's own vertices are closer to it.

**Modes.** For a face ``f`` with neighbourhood ``K(f)`` (faces within ``r`` steps across edges
not in ``M_E``), the mode ``m_f`` is the fixed point of the mean shift (Comaniciu & Meer 2002)
on the unit sphere started at ``n_f``,

.. math:: m \\leftarrow \\frac{\\sum_{g \\in K(f)} A_g\\, W_c(\\|c_f - c_g\\|)\\,
                                W_s(\\|m - n_g\\|)\\, n_g}{\\|\\cdot\\|}, \\qquad
          W_c(d) = e^{-d^2 / 2σ_c^2},\\; W_s(d) = e^{-d^2 / 2σ_s^2},

``σ_c = r`` mean edge lengths, ``σ_s = 0.15``, at most 10 iterations (a face stops when a
step moves its normal by less than 1e-6). Each step is a step of gradient ascent of the
kernel density ``p(m) = Σ_g A_g W_c W_s(\\|m - n_g\\|)`` over the normals of ``K(f)``
(its value never decreases): a face of a rounded band, whose normal lies in the valley
between the two planes' peaks, moves towards the peak of its side; a face of a plane keeps
its normal; on a surface whose normals are spread evenly about ``n_f`` (a sphere, a cylinder
away from its ends) ``m_f ≈ n_f``.

**Basins.** A face takes its mode only when the modes of its edge neighbours are within
``cons`` (10°) of it (it lies inside one basin; the faces straddling a crease keep their
normals) and it is more than 2 rings from the mesh border (one-sided neighbourhoods). The
vertices then move to the target normals ``n'`` by the forward-backward steps of
:mod:`meshrepair.denoise.polish_fidelity` (a Sun et al. step, then the proximal map of the data
term),
30 per pass, ``passes`` passes: the candidate ``X`` descends

.. math:: E_s(x) = \\sum_f \\sum_{i \\in f} \\big(n'_f \\cdot (x_i - c_f)\\big)^2
          + \\frac{η_s}{2} \\sum_i \\|x_i - V^0_i\\|^2, \\qquad η_s = 0.007,

the energy the polish of :mod:`meshrepair.denoise.polish` descends (``η = 0.002``, 300 steps)
with the modes as the target normals. *Like with like*: the polish's data term pulls the
result ``V`` towards the data, and a candidate built by plain Sun steps (``η_s = 0``) lacks
that pull: it lies farther from ``V⁰`` even where its normals are better, and the data test
below would refuse it everywhere. With the data term in the candidate's own step both sides of
the test carry the same pull; ``η_s`` is larger than the polish's because the candidate has 60
steps, not 300.

**Data test.** ``X`` is kept per connected set ``S`` (through mesh edges) of the vertices it
moves by more than ``eps`` mean edge lengths, when it lowers the fidelity there,

.. math:: \\sum_{i \\in S} \\|V^0_i - X_i\\|^2 < \\sum_{i \\in S} \\|V^0_i - V_i\\|^2,

``V⁰`` the input, ``V`` the result before this step. A rounded crease lies off the data (the
prior pulled it inwards), its sharpened version lies on it; a smooth surface that the mean
shift would facet lies on the data already and its facets leave it, so they are refused:
under synthetic scanner-like noise a smooth organic surface keeps the result unchanged. The
test reads ``ρ_S = ⟨X − V, V⁰ − V⟩_S / ‖X − V‖²_S > 1/2``, the projection of the data's pull
on the candidate's move: where it fails the result is the unsharpened one, never worse.

**Flat support.** Under correlated noise the test is biased against ``X`` (the
result keeps low-frequency noise that the sharpened planes remove), so on a set whose
vertices lie mostly on flat faces of the result (``φ_S ≥ 0.45``, the polish's flatness gate
at half its threshold) ``ρ_S > 0.2`` suffices: :mod:`meshrepair.denoise.sharpen_decision` has the
maths and the margins.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair._kernels.modes import mode_rows, rings_rows

MODE_SIGMA_S = 0.15
MODE_ITERS = 10
MODE_CONSISTENCY = 10.0
MODE_BORDER_RINGS = 2
MODE_PASSES = 2
MODE_EPS = 0.01
MODE_ETA = 0.007
"""``η_s``: the data weight of the candidate's vertex step (forward-backward steps of
:mod:`meshrepair.denoise.polish_fidelity`; module docstring)."""
MODE_VSTEPS = 30
"""Vertex steps per pass of the candidate."""
MODE_RHO_FLAT = 0.2
"""``ρ_flat``: the data test's threshold on a flat-supported set (module docstring)."""
MODE_FLAT_SHARE = 0.45
"""``φ_min``: the share of a set's vertices on flat faces of the result that makes it
flat-supported (:mod:`meshrepair.denoise.sharpen_decision`)."""
MODE_FLAT_TAU = 0.5
"""The flatness threshold of the flat support, a fraction of the polish's ``τ_p``
(:func:`meshrepair.denoise.polish.flat_gate` at ``τ_p / 2``)."""
MODE_CHUNK = 20_000
"""Rows of the neighbourhood built and shifted at a time (memory ≈ chunk × |K(f)| indices)."""


def _face_adjacency(topo, sharp: np.ndarray) -> sp.csr_matrix:
    """``A``: faces sharing an interior edge not in ``sharp``."""
    ok = topo.interior & ~np.asarray(sharp, bool)
    fa, fb = topo.edge_faces[ok, 0], topo.edge_faces[ok, 1]
    nF = topo.n_faces
    return sp.csr_matrix((np.ones(2 * len(fa)), (np.r_[fa, fb], np.r_[fb, fa])), shape=(nF, nF))


def _normals_areas(X: np.ndarray, F: np.ndarray):
    a, b, c = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    cr = np.cross(b - a, c - a)
    dbl = np.linalg.norm(cr, axis=1)
    return cr / np.maximum(dbl, 1e-300)[:, None], 0.5 * dbl, (a + b + c) / 3.0


MODE_CACHE_PAIRS = 50_000_000
"""Neighbourhoods up to this many (estimated) pairs are built once and kept for every pass
(int32 indices: 200 MB); larger meshes rebuild them chunk by chunk in each pass."""


def _neighbourhood_chunks(A: sp.csr_matrix, rings: int, chunk: int):
    """Rows ``lo:hi`` of ``K = (I + A)^rings > 0`` as ``(lo, hi, indptr, indices)`` (a
    breadth-first search per face when numba is available)."""
    nF = A.shape[0]
    A = A.tocsr()
    for lo in range(0, nF, chunk):
        hi = min(nF, lo + chunk)
        yield (lo, hi) + tuple(rings_rows(A.indptr, A.indices, lo, hi, rings))


def mode_normals(X: np.ndarray, F: np.ndarray, A: sp.csr_matrix, rings: int, *,
                 sigma_c: float, sigma_s: float = MODE_SIGMA_S, iters: int = MODE_ITERS,
                 chunk: int = MODE_CHUNK, chunks: list | None = None) -> np.ndarray:
    """The modes ``m_f`` of the module docstring, ``(nF, 3)``.

    ``K(f)`` is row ``f`` of ``(I + A)^rings > 0``, built ``chunk`` rows at a time (or taken
    from ``chunks``, a list of :func:`_neighbourhood_chunks` items)."""
    F = np.asarray(F, dtype=np.int64)
    N, area, C = _normals_areas(np.asarray(X, dtype=np.float64), F)
    out = np.empty((len(F), 3))
    for lo, hi, indptr, indices in (chunks if chunks is not None
                                    else _neighbourhood_chunks(A, rings, chunk)):
        out[lo:hi] = mode_rows(indptr, indices, np.arange(lo, hi), N, area, C, sigma_c,
                               sigma_s, iters)
    return out


def basin_gate(M: np.ndarray, A: sp.csr_matrix, away: np.ndarray, cons: float) -> np.ndarray:
    """Faces whose edge neighbours' modes (adjacency ``A``) are all within ``cons`` degrees of
    their own, among the faces ``away``."""
    A = A.tocoo()
    dots = np.einsum("ij,ij->i", M[A.row], M[A.col])
    low = np.ones(len(M))
    np.minimum.at(low, A.row, dots)
    return away & (low > np.cos(np.radians(cons)))


def supported_by_data(V0: np.ndarray, V: np.ndarray, X: np.ndarray, edges: np.ndarray,
                      eps: float, *, flat: np.ndarray | None = None,
                      rho_flat: float = MODE_RHO_FLAT, share: float = MODE_FLAT_SHARE,
                      stats: dict | None = None) -> np.ndarray:
    """``(nV,) bool``: the vertices of the decision of the module docstring (moved by more
    than ``eps`` — an absolute length — in a connected set ``S`` with ``ρ_S > 1/2``, or, when
    ``flat`` (``(nV,) bool``, the vertices on a flat face of the result) is given, with
    ``ρ_S > rho_flat`` and ``φ_S ≥ share``). ``stats`` (optional) receives ``rho``, ``flat``
    and ``size`` of the largest set."""
    from meshrepair.denoise.sharpen_decision import set_statistics

    moved = np.linalg.norm(X - V, axis=1) > eps
    out = np.zeros(len(V), bool)
    if not moved.any():
        return out
    lab, rho, phi = set_statistics(V0, V, X, edges, moved, flat)
    keep = rho > 0.5
    if flat is not None:
        keep |= (rho > rho_flat) & (phi >= share)
    out[moved] = keep[lab[moved]]
    if stats is not None:
        big = int(np.argmax(np.bincount(lab[moved])))
        stats.update(rho=float(rho[big]), flat=float(phi[big]),
                     size=int(np.sum(lab[moved] == big)))
    return out


def sharpen(V: np.ndarray, V0: np.ndarray, F: np.ndarray, sharp: np.ndarray, topo, *,
            rings: int, passes: int = MODE_PASSES, sigma_s: float = MODE_SIGMA_S,
            cons: float = MODE_CONSISTENCY, eps: float = MODE_EPS, eta: float = MODE_ETA,
            flat: tuple[int, float] | None = None, stats: dict | None = None
            ) -> tuple[np.ndarray, float]:
    """The step of the module docstring.

    Parameters
    ----------
    V : (nV, 3) float64, the result so far
    V0 : (nV, 3) float64, the input (the fidelity data)
    F : (nF, 3) int64
    sharp : (nE,) bool, ``M_E`` on ``topo.edges`` (neighbourhoods do not cross it)
    topo : Topology of the mesh
    rings : ``r`` of ``K(f)``
    passes, sigma_s, cons : see the module docstring
    eps : the data test's motion threshold, mean edge lengths
    eta : float >= 0, the candidate's data weight per vertex step ``η_s`` (0: plain Sun
        steps)
    flat : ``(r_p, τ_p)``, optional: the polish's ring count and flatness threshold (degrees);
        the flat support is :func:`meshrepair.denoise.polish.flat_gate` on ``V`` at ``r_p`` rings
        and
        ``MODE_FLAT_TAU τ_p`` (:mod:`meshrepair.denoise.sharpen_decision`); None: the
        test
        ``ρ_S > 1/2`` alone
    stats : dict, optional, filled with the largest set's ``rho``, ``flat`` and ``size``

    Returns
    -------
    V : (nV, 3) float64, a new array
    kept : float, the fraction of the vertices the step moved
    """
    F = np.asarray(F, dtype=np.int64)
    V = np.asarray(V, dtype=np.float64)
    V0 = np.asarray(V0, dtype=np.float64)
    e = topo.edges
    le = float(np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1).mean())
    X = candidate(V, V0, F, sharp, topo, rings=rings, passes=passes, sigma_s=sigma_s,
                  cons=cons, eta=eta)
    fv = None
    if flat is not None:
        from meshrepair.denoise.sharpen_decision import flat_vertices

        fv = flat_vertices(V, F, sharp, topo, rings=int(flat[0]),
                           tau=MODE_FLAT_TAU * float(flat[1]))
    keep = supported_by_data(V0, V, X, e, eps * le, flat=fv, stats=stats)
    out = V.copy()
    out[keep] = X[keep]
    return out, float(keep.mean())


def candidate(V: np.ndarray, V0: np.ndarray, F: np.ndarray, sharp: np.ndarray, topo, *,
              rings: int, passes: int = MODE_PASSES, sigma_s: float = MODE_SIGMA_S,
              cons: float = MODE_CONSISTENCY, eta: float = MODE_ETA) -> np.ndarray:
    """The sharpened candidate ``X`` of the module docstring (modes, basins, ``passes``
    forward-backward vertex passes), before the data test; parameters as :func:`sharpen`."""
    from meshrepair.denoise.polish_fidelity import vertex_update_with_data

    F = np.asarray(F, dtype=np.int64)
    V = np.asarray(V, dtype=np.float64)
    V0 = np.asarray(V0, dtype=np.float64)
    e = topo.edges
    le = float(np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1).mean())
    A = _face_adjacency(topo, sharp)
    A1 = _face_adjacency(topo, np.zeros(topo.n_edges, bool))
    near = np.zeros(topo.n_faces, bool)
    near[topo.edge_faces[topo.boundary, 0]] = True
    for _ in range(MODE_BORDER_RINGS):
        near = near | ((A1 @ near.astype(np.float64)) > 0)
    X = V.copy()
    chunks = None
    if passes > 1 and topo.n_faces * 1.5 * (rings + 1) ** 2 <= MODE_CACHE_PAIRS:
        chunks = list(_neighbourhood_chunks(A, rings, MODE_CHUNK))
    for _ in range(passes):
        M = mode_normals(X, F, A, rings, sigma_c=rings * le, sigma_s=sigma_s, chunks=chunks)
        N, _, _ = _normals_areas(X, F)
        take = basin_gate(M, A1, ~near, cons)
        X = vertex_update_with_data(X, F, np.where(take[:, None], M, N), V0, eta=eta,
                                    steps=MODE_VSTEPS)
    return X
