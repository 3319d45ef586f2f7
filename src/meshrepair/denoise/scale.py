"""Multi-scale noise estimate: level and spatial correlation of the noise (scanner noise).

The one-ring estimator of :mod:`meshrepair.model.noise` sees only the part of the noise that changes
from a vertex to its neighbours. Scanner noise is spatially correlated (a depth camera's map is
smooth over several samples), so it reads far too low there. We look at the normal component of
the residual of ``k`` steps of umbrella averaging ``W`` (``W = D⁻¹A``, diffusion radius ≈ √k
rings)

.. math::  h^{(k)}_i = \\langle V_i - (W^k V)_i,\\; n_i \\rangle ,
           \\qquad s_k = \\frac{1.4826\\,\\mathrm{MAD}(h^{(k)})}{c_k(0)\\,\\bar l},

normalised by ``c_k(m)``, the RMS of ``(I - W^k) W^m Z`` for a unit-variance white field ``Z``
(measured on the mesh itself with random probes drawn in a canonical vertex order,
:mod:`meshrepair.mesh.probe`), so that i.i.d. noise of level γ reads
``s_k = γ`` at every ``k``. Noise made by ``m`` diffusion steps of white noise reads
``s_k ∝ c_k(m)/c_k(0)``, which grows with ``k``: the *profile* ``s_k / s_1`` identifies ``m``. A
clean curved surface also gives a residual growing with ``k`` (shrinkage), so the profile of a
reference (a first denoised result, which keeps the shape but not the fine noise) is subtracted
in quadrature: ``s_k² ← s_k²(input) − s_k²(reference)``.

The estimate returned is the ``m`` whose white-noise-model profile ``c_k(m)/c_k(0)`` best
matches the observed one (least squares in log, ``m ∈ {0, 1, 2, 3, 4, 6, 8, 12, 16}``), the
correlation length ``ℓ = √m`` in mean edge lengths, the correlation ratio ``ρ = s_2/s_1`` and the
noise level at that scale ``γ_m = s_1 · c_1(0)/c_1(m) · σ(W^m Z)`` (the standard deviation of the
correlated field, in mean edge lengths).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from meshrepair._kernels import edge_lengths_exact
from meshrepair._kernels.select import median_inplace
from meshrepair.mesh.geometry import vertex_normals
from meshrepair.mesh.probe import canonical_order, probe_field
from meshrepair.mesh.topology import Topology, edge_topology, umbrella_operator, used_vertices

SCALES = (1, 2, 4)
CANDIDATE_STEPS = (0, 1, 2, 3, 4, 6, 8, 12, 16)
MAX_SAMPLES = 100_000


@dataclass(frozen=True)
class NoiseScale:
    """Result of :func:`noise_scale`.

    Attributes
    ----------
    profile : (len(SCALES),) white-noise-normalised residual levels ``s_k`` (mean edge lengths)
    rho : ``s_2 / s_1`` (1 for i.i.d. noise, larger for correlated noise)
    steps : diffusion steps ``m`` of the best-matching correlated-noise model
    length : correlation length ``√m`` in mean edge lengths
    gamma : standard deviation of the noise at that scale, in mean edge lengths
    """

    profile: np.ndarray
    rho: float
    steps: int
    length: float
    gamma: float


def _umbrella_operator(topo: Topology) -> sp.csr_matrix:
    """``W = D⁻¹A`` of ``topo``, built once per topology (the readings share it)."""
    return umbrella_operator(topo)


def _interior_vertices(topo: Topology, rings: int, W: sp.csr_matrix,
                       used: np.ndarray | None = None) -> np.ndarray:
    """Vertices more than ``rings`` rings away from the boundary (one-sided averages), among
    the ``used`` ones (on an edge; default all): a vertex no face uses reads no noise."""
    bnd = np.zeros(topo.n_vertices, bool)
    bnd[topo.edges[topo.boundary].ravel()] = True
    if used is None:
        used = np.ones(topo.n_vertices, bool)
    near = bnd.astype(np.float64)
    for _ in range(rings):
        near = np.maximum(near, W @ near)
    ok = (near == 0) & used
    return ok if ok.sum() >= 16 else ~bnd & used


def _residual_levels(V, n, W, ks, ok) -> np.ndarray:
    out = []
    Vk = V
    k = 0
    for kk in ks:
        while k < kk:
            Vk = W @ Vk
            k += 1
        h = np.einsum("ij,ij->i", V - Vk, n)[ok]
        out.append(_mad_std(h, overwrite=True))
    return np.asarray(out)


def model_probe(V: np.ndarray, ok: np.ndarray, order: np.ndarray,
                n_samples: int = 20_000) -> np.ndarray:
    """The white field ``Z`` of the model profiles: enough standard-normal columns for about
    ``n_samples`` samples on ``ok`` (one column on a large mesh, at most 8: the MAD of that many
    samples is within ~1 % of its limit), drawn in the canonical vertex order ``order``
    (:mod:`meshrepair.mesh.probe`), so a relabelled mesh gets the same field on each vertex."""
    n_probe = int(np.clip(np.ceil(n_samples / max(int(ok.sum()), 1)), 1, 8))
    return probe_field(V, n_probe, order=order)


def _model_profiles(W, ks, ok, Z):
    """``c_k(m)`` (MAD-std of ``(I - W^k) W^m Z``) and ``σ(W^m Z)`` for the candidate ``m``,
    ``Z`` the (nV, p) white field of :func:`model_probe`."""
    C = np.zeros((len(CANDIDATE_STEPS), len(ks)))
    S = np.zeros(len(CANDIDATE_STEPS))
    # W^k (W^m Z) is the (m + k)-th term of the one chain Z, W Z, W² Z, ... (the same products
    # in the same order), so the chain is walked once: 20 sparse products instead of 52, and
    # only the candidates still within max(ks) steps are kept
    col = {kk: j for j, kk in enumerate(ks)}
    first = {mm: i for i, mm in enumerate(CANDIDATE_STEPS)}
    live: dict[int, tuple[int, np.ndarray]] = {}
    P = Z
    for n in range(max(CANDIDATE_STEPS) + max(ks) + 1):
        if n:
            P = W @ P
        P_ok = P[ok]
        for m, (i, Zm_ok) in list(live.items()):
            j = col.get(n - m)
            if j is not None:
                buf = np.subtract(Zm_ok, P_ok)
                C[i, j] = _mad_std(buf, overwrite=True)
            if n - m >= max(ks):
                del live[m]
        if n in first:
            i = first[n]
            S[i] = np.sqrt(np.mean(P_ok ** 2))
            live[n] = (i, P_ok)
    return C, S


def _pow(W, X, k):
    for _ in range(k):
        X = W @ X
    return X


def _mad_std(X: np.ndarray, overwrite: bool = False) -> float:
    """``1.4826 median|x - median(x)|`` over the entries of ``X`` (the value of numpy's two
    medians), on one scratch copy, or in ``X`` itself with ``overwrite`` (a contiguous float64
    array): the 27 model medians were most of :func:`noise_scale` with numpy's medians
    (copies, and the slow two-index partition :mod:`meshrepair._kernels.select` avoids)."""
    if overwrite and X.dtype == np.float64 and X.flags.c_contiguous:
        x = X.reshape(-1)
    else:
        x = np.array(X, dtype=np.float64).ravel()
    m = median_inplace(x)
    np.subtract(x, m, out=x)
    np.abs(x, out=x)
    return float(1.4826 * median_inplace(x))


def _sampled(V, F, topo, rings: int):
    """The inputs of a band read: float64 ``V``, int64 ``F``, the topology, the umbrella operator
    ``W``, the mask of vertices ``rings`` rings inside (an even subsample of at most
    :data:`MAX_SAMPLES`, every j-th one in the canonical order), the mean edge length ``ℓ̄`` and
    the canonical vertex order (:func:`meshrepair.mesh.probe.canonical_order`)."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if topo is None:
        topo = edge_topology(F, len(V))
    W = _umbrella_operator(topo)
    used = used_vertices(topo.edges, len(V))
    ok = _interior_vertices(topo, rings, W, used)
    order = canonical_order(V, used)
    idx = order[ok[order]]  # the interior vertices in the canonical order
    if len(idx) > MAX_SAMPLES:  # medians over an even subsample (every j-th interior vertex)
        ok = np.zeros_like(ok)
        ok[idx[:: int(np.ceil(len(idx) / MAX_SAMPLES))]] = True
    lbar = float(edge_lengths_exact(V, topo.edges).mean())
    return V, F, topo, W, ok, lbar, order


def noise_scale(V: np.ndarray, F: np.ndarray, *, reference: np.ndarray | None = None,
                topo: Topology | None = None) -> NoiseScale:
    """Level and correlation length of the noise of ``(V, F)`` (see the module docstring).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    reference : (nV, 3) float, optional, a denoised version of ``V`` whose residual profile
        (curvature shrinkage) is subtracted in quadrature.
    topo : Topology, optional

    Returns
    -------
    NoiseScale
    """
    ks = SCALES
    V, F, topo, W, ok, lbar, order = _sampled(V, F, topo, max(ks))
    if not ok.any():  # no vertex far enough inside (a few faces): nothing to read, white
        return NoiseScale(profile=np.zeros(len(ks)), rho=1.0, steps=0, length=0.0, gamma=0.0)
    C, S = _model_profiles(W, ks, ok, model_probe(V, ok, order))
    s = _residual_levels(V, vertex_normals(V, F), W, ks, ok)
    if reference is not None:
        R = np.asarray(reference, dtype=np.float64)
        b = _residual_levels(R, vertex_normals(R, F), W, ks, ok)
        s = np.sqrt(np.maximum(s * s - b * b, 0.0))
    s = s / (C[0] * lbar)  # white-noise normalised: i.i.d. noise reads γ at every k
    if not s[0] > 0:
        return NoiseScale(profile=s, rho=1.0, steps=0, length=0.0, gamma=0.0)
    obs = np.log(np.maximum(s / s[0], 1e-6))
    model = np.log((C / C[0]) / (C[:, :1] / C[0, 0]))
    i = int(np.argmin(((model - obs) ** 2).sum(axis=1)))
    m = CANDIDATE_STEPS[i]
    gamma = float(s[0] * C[0, 0] / C[i, 0] * S[i])
    return NoiseScale(profile=s, rho=float(s[1] / s[0]), steps=int(m), length=float(np.sqrt(m)),
                      gamma=gamma)


def correlated_noise(V: np.ndarray, F: np.ndarray, gamma: float, steps: int, *,
                     seed: int | None = 0, topo: Topology | None = None) -> np.ndarray:
    """Spatially correlated noise along the vertex normals, for tests and design.

    ``η = γ l̄ · W^m Z / σ(W^m Z)`` with ``Z`` i.i.d. standard normal and ``m = steps`` umbrella
    averaging steps (correlation length ≈ √m mean edge lengths); returns ``V + η n``.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if topo is None:
        topo = edge_topology(F, len(V))
    W = _umbrella_operator(topo)
    rng = np.random.default_rng(seed)
    z = _pow(W, rng.normal(size=len(V)), int(steps))
    z = z / max(np.std(z), 1e-300)
    e = topo.edges
    lbar = float(np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1).mean())
    return V + (gamma * lbar * z)[:, None] * vertex_normals(V, F)


def tangential_ratio(V: np.ndarray, F: np.ndarray, reference: np.ndarray, *,
                     topo: Topology | None = None) -> float:
    """How much of the noise lies in the tangent plane: ``≈ 0.1-0.5`` for noise along the
    normals, ``≳ 0.8`` for noise in random directions (measured in docs/parameters.md).

    With ``L = V - W V`` (umbrella Laplacian of the input) split along the vertex normals ``n``
    of ``reference`` (a denoised version: accurate normals) into ``L_n = <L, n>`` and the
    tangential rest ``L_t``, and the high-pass ``X - W X`` that removes the smooth part due to
    the sampling density of a clean mesh,

    .. math:: r_t = \\frac{\\sqrt{\\mathrm{median}\\,\\|L_t - W L_t\\|^2 / 2}}
                         {1.4826\\,\\mathrm{MAD}(L_n - W L_n)}

    (the tangential part has two components, hence the 2).
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if topo is None:
        topo = edge_topology(F, len(V))
    W = _umbrella_operator(topo)
    ok = _interior_vertices(topo, 2, W, used_vertices(topo.edges, len(V)))
    n = vertex_normals(np.asarray(reference, dtype=np.float64), F)
    L = V - W @ V
    ln = np.einsum("ij,ij->i", L, n)
    T = L - ln[:, None] * n
    R = (T - W @ T)[ok]
    den = _mad_std((ln - W @ ln)[ok])
    if not den > 0:
        return 0.0
    return float(np.sqrt(np.median(np.einsum("ij,ij->i", R, R)) / 2.0) / den)
