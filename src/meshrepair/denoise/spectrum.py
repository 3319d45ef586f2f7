"""The noise reading: level and spatial scale of the noise from a spectrum across scales.

**Operator.** ``W = D⁻¹A`` is the umbrella (random-walk) averaging of the edge graph; ``t``
steps of it diffuse over a radius of about ``√t`` edges. It is built once and every quantity
below is a power of it applied to the positions.

**Bands.** For the dyadic times ``t ∈`` :data:`BANDS` the band-pass

.. math:: H_t = W^t (I - W^t)^2

has, in the eigenbasis ``W φ = μ φ``, the transfer ``μ^t (1 - μ^t)^2``: it peaks at the
wavelength ``≈ √t`` edges and has a *double* zero at ``μ = 1`` (the smooth part), so a surface
whose shape is locally a low-order polynomial contributes ``O(t² Δ² V)`` instead of the
``O(t Δ V)`` (mean curvature) of a plain difference of low-passes. Its normal component, with
the normals ``n^{(t)}`` of the low-passed surface ``W^t V`` (the band's own scale), is

.. math:: u_t = \\langle H_t V, n^{(t)} \\rangle , \\qquad
          E_t = W^{2t} (u_t^2) ,

``E_t`` being the local energy averaged over the band's neighbourhood. The band's reading is a
low quantile of the local energy over the interior vertices (those farther from the boundary
than the band's support)

.. math:: e_t = \\sqrt{Q_q(E_t)} / \\bar l , \\qquad q = \\text{:data:`QUANTILE`}.

Noise is stationary, so its local energy is the same everywhere; the surface's own relief is
not (flat or uniformly curved parts have none, features a lot), so the low quantile keeps the
noise and rejects most of the relief.

**Noise model.** Noise along the normals ``η = σ \\bar l \\, W^m Z / \\mathrm{std}(W^m Z)`` with
``Z`` i.i.d. standard normal: white for ``m = 0``, and of Gaussian correlation
``C(r) ≈ \\exp(-r^2 / 2ℓ^2)`` with ``ℓ = √m`` edges otherwise (``W^{2m}`` is the kernel of a
random walk with ``m`` steps per side). Its band readings are ``e_t = σ g_t(m)`` with

.. math:: g_t(m) = \\sqrt{Q_q\\big(W^{2t} (H_t W^m Z)^2\\big)} / \\mathrm{std}(W^m Z) ,

computed once, by :func:`band_gains`, on a periodic regular triangular grid (valence 6, no
boundary, seeded probes): a table that does not depend on the input, so no random probe follows the
vertex order. The gains of the umbrella walk on the meshes' own connectivity
differ by a few per cent (irregular valence).

**Fit.** The surface adds a relief ``r_t ≥ 0`` that grows with the band's scale; it is modelled
as a power ``r_t = a (t/t_0)^b``. Energies add in quadrature,

.. math:: e_t^2 ≈ σ^2 g_t(m)^2 + a^2 (t/t_0)^{2b} ,

and for every ``(m, b)`` on the grids :data:`CANDIDATE_STEPS` × :data:`RELIEF_POWERS` the two
non-negative amplitudes ``(σ², a²)`` minimise the relative squared misfit
``Σ_t (1 - \\text{model}_t / e_t^2)^2`` (non-negative least squares). The reading is the
``(σ, ℓ = √m)`` of the best fit. ``white_evidence`` is the misfit of the best white model
(``m = 0``) over the misfit of the best one: 1 when white noise explains the spectrum as well as
any correlated model, large when it does not.

**Mean edge length.** Noise along the normals lengthens the edges (``E‖d‖² = l² + 2σ²`` for
white noise), so ``l̄`` is the mean length of the edges projected on the tangent planes of
``W^4 V`` (:func:`tangent_edge_length`).

**Range and limits.** Lengths are read up to 4 edges (:data:`CANDIDATE_STEPS`); the level is that
of the quietest part of the surface (the quantile), which is the RMS for stationary noise and
less for noise whose strength varies over the surface. Where the surface's own relief at a
band's scale exceeds the noise there (correlations of several edges on a coarse organic mesh)
the noise cannot be told from the shape and is under-read.

Everything is in mean-edge-length units and invariant to rotation, uniform scale and the vertex
order (up to rounding: sums over a vertex's neighbours in another order); the reading is
deterministic.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from scipy.optimize import nnls

BANDS = (1, 2, 4, 8, 16, 32)
"""Diffusion times ``t`` of the band-passes ``W^t (I - W^t)^2`` (wavelength ≈ √t edges)."""
CANDIDATE_STEPS = (0, 1, 2, 4, 8, 16)
"""Diffusion steps ``m`` of the noise models (correlation length ``√m`` edges): those whose band
gains peak within :data:`BANDS`. A longer correlation reads as ``ℓ̂ = 4`` with the level of its
part within the bands (the rising edge of a longer model's gains looks like relief and cannot be
told from it)."""
RELIEF_POWERS = tuple(np.round(np.arange(0.0, 3.01, 0.25), 2))
"""Exponents ``b`` of the relief model ``a (t/t_0)^b``."""
QUANTILE = 0.1
"""Quantile of the local band energy read over the surface (rejects the relief, keeps noise)."""
CORRELATED_LENGTH = 1.0
"""A reading with ``ℓ̂`` above this many edges is called correlated: a correlation of one edge
is the sampling scale itself, which the mesh cannot tell from white noise."""
MIN_SAMPLES = 64
"""A band is read only where at least this many vertices lie beyond its boundary margin."""
LENGTH_STEPS = 4
"""Diffusion steps of the surface whose normals give the tangent planes of the edge length (one
of :data:`BANDS`, whose chain passes there)."""
GRID_SIZE = 160
"""Side of the periodic calibration grid (25,600 vertices)."""


@dataclass(frozen=True)
class NoiseReading:
    """Result of :func:`read_noise` (all lengths in mean edge lengths).

    Attributes
    ----------
    level : σ̂, standard deviation of the noise along the normals
    length : ℓ̂ = √m, correlation length of the noise (0 for white noise)
    correlated : ``length > CORRELATED_LENGTH``
    white_evidence : misfit of the best white model / misfit of the best model (≥ 1)
    relief_power : exponent ``b`` of the fitted relief
    bands : diffusion times ``t`` of the bands read
    energies : band readings ``e_t``
    model : the fitted ``(σ² g_t(m)² + a² (t/t_0)^{2b})^{1/2}``
    mean_edge : the mean edge length ``l̄`` in the input's units
    """

    level: float
    length: float
    correlated: bool
    white_evidence: float
    relief_power: float
    bands: tuple
    energies: np.ndarray
    model: np.ndarray
    mean_edge: float


def umbrella_operator(edges: np.ndarray, n: int) -> sp.csr_matrix:
    """``W = D⁻¹ A`` of the edge graph (isolated vertices keep a zero row)."""
    i = np.r_[edges[:, 0], edges[:, 1]]
    j = np.r_[edges[:, 1], edges[:, 0]]
    A = sp.csr_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
    deg = np.asarray(A.sum(axis=1)).ravel()
    return (sp.diags(1.0 / np.maximum(deg, 1.0)) @ A).tocsr()


def _powers(W, X, need: set) -> dict:
    """``{j: W^j X}`` for ``j`` in ``need`` (one chain of products)."""
    out, P = {}, X
    for j in range(max(need) + 1):
        if j:
            P = W @ P
        if j in need:
            out[j] = P
    return out


def _needed(ts) -> set:
    need = {0}
    for t in ts:
        need |= {t, 2 * t, 3 * t}
    return need


def _local_quantile(W, u2: np.ndarray, t: int, mask: np.ndarray) -> float:
    """``Q_q(W^{2t} u²)`` over the rows in ``mask`` (columns of ``u2`` pooled)."""
    E = u2
    for _ in range(2 * t):
        E = W @ E
    return float(np.quantile(E[mask], QUANTILE))


def grid_torus(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A periodic ``n × n`` regular triangular grid: ``(edges, n_vertices)`` of the torus."""
    idx = np.arange(n * n).reshape(n, n)
    right = np.roll(idx, -1, axis=1)
    down = np.roll(idx, -1, axis=0)
    diag = np.roll(right, -1, axis=0)
    e = np.concatenate([np.c_[idx.ravel(), right.ravel()], np.c_[idx.ravel(), down.ravel()],
                        np.c_[idx.ravel(), diag.ravel()]])
    return np.sort(e, axis=1), n * n


@lru_cache(maxsize=1)
def band_gains() -> np.ndarray:
    """``g_t(m)`` (rows :data:`CANDIDATE_STEPS`, columns :data:`BANDS`) on the calibration grid:
    two seeded probe columns of :data:`GRID_SIZE`² i.i.d. normals, computed once per process."""
    edges, n = grid_torus(GRID_SIZE)
    W = umbrella_operator(edges, n)
    Z = np.random.default_rng(20261202).normal(size=(n, 2))
    need = set()
    for m in CANDIDATE_STEPS:
        need |= {m + j for j in _needed(BANDS)}
    P = _powers(W, Z, need)
    everyone = np.ones(n, bool)
    G = np.zeros((len(CANDIDATE_STEPS), len(BANDS)))
    for i, m in enumerate(CANDIDATE_STEPS):
        s = float(np.sqrt(np.mean(P[m] ** 2)))
        for k, t in enumerate(BANDS):
            h = P[m + t] - 2.0 * P[m + 2 * t] + P[m + 3 * t]
            G[i, k] = np.sqrt(_local_quantile(W, h * h, t, everyone)) / s
    return G


def _boundary_hops(edges: np.ndarray, boundary_vertices: np.ndarray, n: int) -> np.ndarray:
    """Edge-graph hop distance of every vertex to the boundary (``inf`` on closed meshes)."""
    if not boundary_vertices.any():
        return np.full(n, np.inf)
    from scipy.sparse.csgraph import dijkstra

    A = sp.csr_matrix((np.ones(2 * len(edges)), (np.r_[edges[:, 0], edges[:, 1]],
                                                 np.r_[edges[:, 1], edges[:, 0]])), shape=(n, n))
    return dijkstra(A, indices=np.flatnonzero(boundary_vertices), min_only=True, unweighted=True)


def tangent_edge_length(d: np.ndarray, normals: np.ndarray, edges: np.ndarray) -> float:
    """Mean length of the edge vectors ``d`` projected on the tangent planes
    ``n̄ = (n_a + n_b)/‖n_a + n_b‖`` of the low-passed surface: noise along the normals
    lengthens the edges (``E‖d‖² = l² + 2σ²`` for white noise), the projection does not."""
    nb = normals[edges[:, 0]] + normals[edges[:, 1]]
    nb /= np.maximum(np.linalg.norm(nb, axis=1, keepdims=True), 1e-300)
    d = d - np.einsum("ij,ij->i", d, nb)[:, None] * nb
    return float(np.linalg.norm(d, axis=1).mean())


def _bands_of(W, X: np.ndarray, ts):
    """Yield ``(t, W^t X, H_t X)`` for the ascending times ``ts``, walking the chain
    ``X, WX, W²X, ...`` once and keeping only the powers a later band still needs."""
    todo = sorted(ts)
    keep: dict[int, np.ndarray] = {}
    P = X
    for j in range(3 * todo[-1] + 1):
        if j:
            P = W @ P
        if any(j in (t, 2 * t) for t in todo):
            keep[j] = P
        while todo and 3 * todo[0] == j:
            t = todo.pop(0)
            yield t, keep[t], keep[t] - 2.0 * keep[2 * t] + P
            for k in [k for k in keep if not any(k in (s, 2 * s) for s in todo)]:
                del keep[k]


def band_energies(V: np.ndarray, F: np.ndarray, field: np.ndarray | None = None):
    """The band readings ``e_t`` of the module docstring; with ``field`` (nV,) the readings of
    that scalar field on the mesh (``u_t = H_t field``: a known displacement without the relief).

    Returns
    -------
    ts : tuple of the diffusion times read (bands without enough interior vertices are left out)
    e : (len(ts),) float64, ``e_t`` in mean edge lengths
    lbar : float, the mean edge length
    """
    from meshrepair.mesh.geometry import vertex_normals
    from meshrepair.mesh.topology import edge_topology

    topo = edge_topology(F, len(V))
    edges = topo.edges
    n = len(V)
    W = umbrella_operator(edges, n)
    bnd = np.zeros(n, bool)
    bnd[edges[topo.boundary].ravel()] = True
    hops = _boundary_hops(edges, bnd, n)
    used = np.zeros(n, bool)
    used[F.ravel()] = True
    X = V if field is None else np.asarray(field, dtype=np.float64)
    ts, e = [], []
    nl = None
    for t, Pt, h in _bands_of(W, X, BANDS):
        if field is None and t == LENGTH_STEPS:
            nl = vertex_normals(Pt, F)
        mask = used & (hops > 3.0 * np.sqrt(5.0 * t))  # beyond the band's support (5t steps)
        if mask.sum() < MIN_SAMPLES:
            continue
        u = h if field is not None else np.einsum("ij,ij->i", h, vertex_normals(Pt, F))
        ts.append(t)
        e.append(np.sqrt(_local_quantile(W, u * u, t, mask)))
    if nl is None:
        nl = vertex_normals(_powers(W, V, {LENGTH_STEPS})[LENGTH_STEPS], F)
    lbar = tangent_edge_length(V[edges[:, 1]] - V[edges[:, 0]], nl, edges)
    return tuple(ts), np.asarray(e) / lbar, lbar


def fit_spectrum(ts, e: np.ndarray):
    """The best ``(σ, m, b)`` of the module docstring's fit; returns
    ``(sigma, m, b, white_evidence, model)``."""
    G = band_gains()[:, [BANDS.index(t) for t in ts]]
    tt = np.asarray(ts, dtype=np.float64) / ts[0]
    e2 = np.maximum(e * e, 1e-300)
    best = (np.inf, 0.0, 0, 0.0, 0.0)
    white = np.inf
    for i, m in enumerate(CANDIDATE_STEPS):
        for b in RELIEF_POWERS:
            A = np.c_[G[i] ** 2, tt ** (2 * b)] / e2[:, None]
            x, _ = nnls(A, np.ones(len(ts)))
            r = float(np.sum((A @ x - 1.0) ** 2))
            if m == 0:
                white = min(white, r)
            if r < best[0] - 1e-12:
                best = (r, float(x[0]), m, float(b), float(x[1]))
    r, s2, m, b, a2 = best
    model = np.sqrt(s2 * G[CANDIDATE_STEPS.index(m)] ** 2 + a2 * tt ** (2 * b))
    evidence = float(white / r) if r > 0 else (1.0 if white == 0 else np.inf)
    return float(np.sqrt(s2)), int(m), float(b), evidence, model


def read_noise(V, F, *, field: np.ndarray | None = None) -> NoiseReading:
    """Read the level and the correlation length of the noise of ``(V, F)`` (module docstring).

    Parameters
    ----------
    V : (nV, 3) float, vertex positions (not modified)
    F : (nF, 3) int, triangles
    field : (nV,) float, optional: read this scalar field laid on the mesh (for instance the
        normal component of a known displacement) instead of the positions' normal component

    Returns
    -------
    NoiseReading
    """
    from meshrepair.errors import MeshRepairError
    from meshrepair.mesh.array_contract import check_arrays

    V, F = check_arrays(V, F, name="read_noise mesh")
    if field is not None:
        field = np.asarray(field, dtype=np.float64)
        if field.shape != (len(V),) or not np.isfinite(field).all():
            raise MeshRepairError(f"field must be {len(V)} finite values, one per vertex; got "
                                  f"shape {field.shape}")
    ts, e, lbar = band_energies(V, F, field)
    if len(ts) < 3 or not lbar > 0:
        raise MeshRepairError(
            f"read_noise needs at least 3 bands of at least {MIN_SAMPLES} interior vertices; this "
            f"mesh ({len(V)} vertices) gives {len(ts)}: it is too small or almost all boundary")
    sigma, m, b, evidence, model = fit_spectrum(ts, e)
    length = float(np.sqrt(m))
    return NoiseReading(level=sigma, length=length, correlated=length > CORRELATED_LENGTH,
                        white_evidence=evidence, relief_power=b, bands=ts, energies=e,
                        model=model, mean_edge=lbar)
