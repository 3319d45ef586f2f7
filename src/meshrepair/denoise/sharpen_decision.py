"""The decision of the crease sharpening (:mod:`meshrepair.denoise.modes`): where the sharpened
candidate replaces the result, read from the data and from the result's flat support
(docs/parameters.md).

**Sets.** ``S`` runs over the connected sets (through mesh edges) of the vertices the
candidate ``X`` moves by more than ``ε`` from the result ``V``; ``V⁰`` is the input.

**Data statistic.** The position of the data along the segment from ``V`` to ``X``,

.. math:: ρ_S = \\frac{⟨X - V,\\, V^0 - V⟩_S}{\\|X - V\\|^2_S}
          = \\operatorname*{arg\\,min}_t \\sum_{i \\in S} \\|V^0_i - V_i - t (X_i - V_i)\\|^2,

so ``ρ_S > 1/2 ⟺ Σ_S ‖V⁰ − X‖² < Σ_S ‖V⁰ − V‖²`` (the plain data test). Under correlated
noise the test is biased against ``X``. Write the input ``V⁰ = T + n`` (truth ``T``), the
result ``V = T + b + P n`` (``b`` the rounding of the creases, ``P`` the low-pass share of the
noise the result keeps: the polish fits it through its data term) and take ``X = T`` (the
mode-seeking planes remove both). Then ``X − V = −b − P n``, ``V⁰ − V = −b + (I − P) n`` and,
for a symmetric ``P`` with eigenvalues in ``[0, 1]`` and noise of covariance ``σ² I``,

.. math:: \\mathbb{E}\\,ρ_S \\approx \\frac{\\|b\\|^2 - σ^2 \\operatorname{tr} P (I - P)}
                                   {\\|b\\|^2 + σ^2 \\operatorname{tr} P^2} < 1,

below 1/2 as soon as the noise the result keeps weighs as much as the rounding, negative when
it weighs more; a false facet ``f`` cut into a smooth surface (``V`` the truth) gives
``E ρ_S ≈ 0`` plus the share of ``f`` that the candidate's own data term fits. Against the
truth (docs/parameters.md): on CAD parts with scanner-like noise the candidate is closer to
the truth on every largest set while ``ρ_S`` reads −0.20 … 1.28 (a real scan of a
piecewise-flat object reads 0.500, on the knife edge of 1/2); on smooth organic meshes it is
farther and ``ρ_S`` reads −0.33 … 0.095, but 0.36-0.45 on a noisy sphere.

**Flat support.** ``G`` is the polish's flatness gate on ``V``
(:func:`meshrepair.denoise.polish.flat_gate`: faces whose neighbourhood of ``r_p`` rings across
edges
not in ``M_E`` has an rms normal spread below ``τ``) at half the polish's threshold,
``τ = τ_p / 2 = 2.5 max(1, ℓ)`` degrees, and ``φ_S`` the share of the vertices of ``S`` on a
face of ``G``. A piecewise-flat part (a CAD part, a scanned box) has most of its
vertices on flat faces; a coarse smooth surface few at the noise's scale (piecewise-flat
scans and CAD parts read 0.29-0.71, smooth organic meshes and a sphere 0.00-0.32; at ``τ_p``
itself the two groups overlap at 0.66-0.71, hence half the threshold). A finely sampled smooth
surface is flat at that scale too (0.51 at 134k vertices): ``φ`` is a prior, not a proof, and
such a surface is refused by ``ρ`` (−0.05 there).

**Decision.** ``X`` replaces ``V`` on ``S`` iff

.. math:: ρ_S > \\tfrac12 \\;\\vee\\; \\big(ρ_S > ρ_{flat} \\wedge φ_S ≥ φ_{min}\\big),
          \\qquad ρ_{flat} = 0.2,\\; φ_{min} = 0.45:

where the result is mostly flat the piecewise-flat model is trusted as soon as the data move
a fifth of the way from ``V`` towards ``X`` (the bias above), elsewhere the data must prefer
``X`` outright. The thresholds sit in the middle of the measured gaps: the piecewise-flat
scan reads ``ρ = 0.500, φ = 0.58`` (margins 0.30 and 0.13), a smooth real scan ``ρ = −0.33,
φ = 0.32`` (refused on both counts, margins 0.53 and 0.13), the smooth synthetic meshes
``ρ ≤ 0.095`` or ``φ ≤ 0.01`` (the sphere, ``ρ`` 0.36-0.45).
"""

from __future__ import annotations

import numpy as np

from meshrepair import _kernels as _k


def set_statistics(V0: np.ndarray, V: np.ndarray, X: np.ndarray, edges: np.ndarray,
                   moved: np.ndarray, flat: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sets ``S`` and their ``ρ_S``, ``φ_S`` (module docstring).

    Parameters
    ----------
    V0, V, X : (nV, 3) float64, the input, the result and the candidate
    edges : (nE, 2) int64
    moved : (nV,) bool, the vertices ``X`` moves by more than ``ε``
    flat : (nV,) bool, optional, the vertices on a face of ``G`` (None: ``φ_S = 0``)

    Returns
    -------
    lab : (nV,) int64, the set of each vertex (meaningful on ``moved``)
    rho : (nS,) float64, ``ρ_S`` (0 where ``‖X − V‖_S = 0``)
    phi : (nS,) float64, ``φ_S``
    """
    e = edges[moved[edges[:, 0]] & moved[edges[:, 1]]]
    lab = _k.union_find(len(V), np.ascontiguousarray(e[:, 0]), np.ascontiguousarray(e[:, 1]))
    n = int(lab.max()) + 1
    d = X - V
    num = np.bincount(lab[moved], np.einsum("ij,ij->i", d, V0 - V)[moved], minlength=n)
    den = np.bincount(lab[moved], np.einsum("ij,ij->i", d, d)[moved], minlength=n)
    rho = np.divide(num, den, out=np.zeros(n), where=den > 0)
    cnt = np.bincount(lab[moved], minlength=n)
    phi = np.zeros(n)
    if flat is not None:
        phi = np.bincount(lab[moved], np.asarray(flat, float)[moved], minlength=n)
        phi = np.divide(phi, cnt, out=np.zeros(n), where=cnt > 0)
    return lab, rho, phi


def flat_vertices(V: np.ndarray, F: np.ndarray, sharp: np.ndarray, topo, *, rings: int,
                  tau: float) -> np.ndarray:
    """``(nV,) bool``: the vertices on a face of the flatness gate ``G`` of
    :func:`meshrepair.denoise.polish.flat_gate` on ``V`` (``rings`` across edges not in ``sharp``,
    threshold ``tau`` degrees)."""
    from meshrepair.denoise.polish import _neighbourhood_csr, _normals_areas, flat_gate_csr

    F = np.asarray(F, dtype=np.int64)
    K = _neighbourhood_csr(topo, sharp, rings)
    N, _, _ = _normals_areas(np.asarray(V, dtype=np.float64), F)
    g = flat_gate_csr(N, K, tau)
    out = np.zeros(len(V), bool)
    out[F[g].ravel()] = True
    return out
