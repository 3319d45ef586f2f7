"""Correlated noise that reads white: a band read of the noise's correlation.

The profile of :mod:`meshrepair.denoise.scale` compares *cumulative* high-passes ``I − W^k``
(``ρ = s_2/s_1``). Noise made by ``m = 2`` diffusion steps of white noise (correlation length
√2 rings) reads ``ρ ≈ 1.03-1.09`` there on a flat grid, as white noise does (0.96-1.0), and
1.07-1.12 on organic meshes: the profile gate of :mod:`meshrepair.denoise.corrlowpass`
(``ρ ≥ 1.4``) cannot see it. A *band* ratio has
more contrast. With ``W = D⁻¹A`` (umbrella averaging) take the two finest octaves

.. math:: B_0 = I - W, \\qquad B_1 = W - W^2 ,

and the white-normalised level of the normal component of each band

.. math:: b_a(X) = \\frac{1.4826\\,\\mathrm{MAD}\\langle (B_a X)_i, n_i\\rangle}{c_a\\,\\bar l},
          \\qquad c_a = 1.4826\\,\\mathrm{MAD}(B_a Z),

``Z`` i.i.d. unit normal (random probes on the mesh itself), so that white noise of level γ
reads ``b_a = γ`` in both bands. A field ``W^m Z`` (unit standard deviation) reads
``b_a = c_a(m)/c_a`` with ``c_a(m) = 1.4826 MAD(B_a W^m Z)``, and the band ratio

.. math:: β(m) = \\frac{c_1(m)/c_1}{c_0(m)/c_0}

rises with ``m``: 1, 1.22, 1.38, 1.59, 1.91 for m = 0, 1, 2, 3, 4 on a regular grid. The
surface's relief is removed as in :mod:`meshrepair.denoise.scale`: the levels of a reference ``R``
(the
probe's result: the shape without the fine noise) are subtracted in quadrature,
``b_a ← (b_a(V)² − b_a(R)²)^{1/2}``, with the input's vertex normals for ``V`` and the
reference's for ``R``. Only the two finest octaves are used: from ``W² − W⁴`` on the relief of
the shared organic meshes is as large as the noise or larger (0.58 against 0.51 at γ 0.4) and
the difference in quadrature is dominated by cross terms.

**Direction.** Noise in random directions (isotropic, white) also raises ``β`` (1.26-1.50 on
the design meshes: its tangential part leaks into the normal bands through the relief), so the
read also measures the tangential part of the noise. With ``P_i = I − n_i n_iᵀ`` (the
reference's normals) and ``t(X) = (\\mathrm{median}_i\\,\\|P_i (B_0 X)_i\\|^2 / 2)^{1/2} / \\bar l``
(per tangential component), the tangential excess of the input over the reference, relative to
its normal level,

.. math:: τ = \\frac{(t(V)^2 - t(R)^2)_+^{1/2}}{c_0\\, b_0}

reads ≈ 1 for isotropic noise (two tangential components each as large as the normal one) and
≈ 0 for noise along the normals (a scanner's depth noise); the mesh's own irregular sampling is
in both ``t(V)`` and ``t(R)`` and cancels. On the benchmark grid (docs/parameters.md) m = 2
fields read τ ≤ 0.27, random-direction white noise at ``γ̂ > 0.13`` τ ≥ 0.58.

Two decisions use this read, both through
:func:`meshrepair.denoise.corrlowpass.band_correlated`: the plan's correlated-noise model
(:func:`meshrepair.denoise.rules.willmore_weight_from_band`, tested against the white model by
:mod:`meshrepair.denoise.whiteness`) and branch 2 of the correlated low-pass
(:func:`meshrepair.denoise.corrlowpass.white_steps`). The plan reads it once, against the
probe's result, and the low-pass reuses that read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from meshrepair.denoise.scale import _mad_std, _sampled, model_probe
from meshrepair.mesh.geometry import vertex_normals
from meshrepair.mesh.topology import Topology

CANDIDATE_STEPS = (0, 1, 2, 3, 4, 6, 8, 12, 16)
N_SAMPLES = 20_000


@dataclass(frozen=True)
class BandRead:
    """Result of :func:`band_read`.

    Attributes
    ----------
    levels : (2,) white-normalised levels ``b_0, b_1`` of the noise (mean edge lengths)
    beta : ``b_1 / b_0`` (1 for white noise along the normals)
    tau : tangential excess ``τ`` (≈ 1 isotropic noise, ≈ 0 noise along the normals)
    steps : the ``m`` whose model ratio ``β(m)`` is nearest to ``β`` (in log)
    length : ``√m`` in mean edge lengths
    gamma : standard deviation of the noise at that scale ``b_0 · c_0 / c_0(m) · σ(W^m Z)``
    """

    levels: np.ndarray
    beta: float
    tau: float
    steps: int
    length: float
    gamma: float


def band_models(W, ok: np.ndarray, Z: np.ndarray):
    """``c_a(m)`` (rows: :data:`CANDIDATE_STEPS`, columns a = 0, 1) and ``σ(W^m Z)`` on the
    samples ``ok``, from one chain ``Z, WZ, W²Z, ...`` of the random probes ``Z``
    (:func:`meshrepair.denoise.scale.model_probe`, (nV, p)).

    Returns
    -------
    C : (len(CANDIDATE_STEPS), 2) float64
    S : (len(CANDIDATE_STEPS),) float64
    """
    P = [Z]
    for _ in range(max(CANDIDATE_STEPS) + 2):
        P.append(W @ P[-1])
    C = np.zeros((len(CANDIDATE_STEPS), 2))
    S = np.zeros(len(CANDIDATE_STEPS))
    for i, m in enumerate(CANDIDATE_STEPS):
        C[i, 0] = _mad_std(np.ascontiguousarray((P[m] - P[m + 1])[ok]), overwrite=True)
        C[i, 1] = _mad_std(np.ascontiguousarray((P[m + 1] - P[m + 2])[ok]), overwrite=True)
        S[i] = np.sqrt(np.mean(P[m][ok] ** 2))
    return C, S


def _bands(X: np.ndarray, n: np.ndarray, W, ok: np.ndarray):
    """``MAD-std <B_a X, n>`` for a = 0, 1 and the tangential level ``t(X)`` (unscaled)."""
    X1 = W @ X
    X2 = W @ X1
    B0 = X - X1
    b0n = np.einsum("ij,ij->i", B0, n)
    b1n = np.einsum("ij,ij->i", X1 - X2, n)
    return b0n[ok], b1n[ok], B0[ok]


def _tangential(B0_ok: np.ndarray, n_ok: np.ndarray) -> float:
    T = B0_ok - np.einsum("ij,ij->i", B0_ok, n_ok)[:, None] * n_ok
    return float(np.sqrt(np.median(np.einsum("ij,ij->i", T, T)) / 2.0))


def band_read(V: np.ndarray, F: np.ndarray, *, reference: np.ndarray | None = None,
              topo: Topology | None = None) -> BandRead:
    """The band read of the module docstring.

    Parameters
    ----------
    V : (nV, 3) float, the input
    F : (nF, 3) int
    reference : (nV, 3) float, optional, a denoised version of ``V`` (its levels are subtracted
        in quadrature; without it ``τ`` is the input's tangential level over its normal one)
    topo : Topology, optional

    Returns
    -------
    BandRead
    """
    V, F, topo, W, ok, lbar, order = _sampled(V, F, topo, 2)  # medians over an even subsample
    C, S = band_models(W, ok, model_probe(V, ok, order, N_SAMPLES))
    nV = vertex_normals(V, F)
    b0, b1, B0 = _bands(V, nV, W, ok)
    lev = np.array([_mad_std(b0, overwrite=True), _mad_std(b1, overwrite=True)])
    if reference is not None:
        R = np.asarray(reference, dtype=np.float64)
        nR = vertex_normals(R, F)
        r0, r1, BR = _bands(R, nR, W, ok)
        ref = np.array([_mad_std(r0, overwrite=True), _mad_std(r1, overwrite=True)])
        lev = np.sqrt(np.maximum(lev ** 2 - ref ** 2, 0.0))
        tR = _tangential(BR, nR[ok])
    else:
        nR, tR = nV, 0.0
    tV = _tangential(B0, nR[ok])
    lev = lev / (C[0] * lbar)
    if not lev[0] > 0:
        return BandRead(levels=lev, beta=1.0, tau=0.0, steps=0, length=0.0, gamma=0.0)
    beta = float(lev[1] / lev[0])
    tau = float(np.sqrt(max(tV * tV - tR * tR, 0.0)) / lbar / (C[0, 0] * lev[0]))
    model = np.log((C[:, 1] / C[0, 1]) / (C[:, 0] / C[0, 0]))
    i = int(np.argmin(np.abs(model - np.log(max(beta, 1e-6)))))
    gamma = float(lev[0] * C[0, 0] / C[i, 0] * S[i])
    m = CANDIDATE_STEPS[i]
    return BandRead(levels=lev, beta=beta, tau=tau, steps=int(m), length=float(np.sqrt(m)),
                    gamma=gamma)
