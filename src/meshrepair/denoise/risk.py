"""Stein's unbiased risk of a Taubin low-pass of the input, along the normals and of the
normals: the length of :mod:`meshrepair.denoise.coarse`'s low-pass is its minimiser.

**The risk.** ``T = (I - μL)(I - λL)`` is linear and acts on each coordinate alike, so ``S =
T^k`` is an ``n × n`` matrix applied to ``x``, ``y``, ``z``. With ``y = x + ε``, ``ε`` zero-mean
with the normal part of variance ``σ²`` per vertex and no correlation between vertices, and
``P`` the projection on the unit vertex normals ``n_i`` of ``S y`` (taken fixed),

.. math:: \\mathbb E\\,\\lVert P(Sy - x)\\rVert^2
          = \\mathbb E\\,\\lVert P(y - Sy)\\rVert^2 - nσ^2 + 2σ^2\\,\\mathrm{tr}\\,S

(expand ``Sy - x = (Sy - y) + ε``; ``E[(n_i·ε_i)(n_i·(Sε)_i)] = s_{ii} σ²``). So

.. math:: R(k) = \\sum_i \\bigl(n_i\\cdot(y - T^k y)_i\\bigr)^2 + 2σ^2\\,\\mathrm{tr}\\,T^k

is the risk up to a constant that does not depend on ``k`` (:func:`normal_risk`). ``tr T^k``
is Hutchinson's estimate ``tr S ≈ \\frac13 \\sum_c z_c^\\top S z_c`` over the three coordinates
of one fixed Rademacher field ``Z`` (the same ``Z`` for every length, so the differences
between lengths are read with a smaller variance than each risk).

**The risk of the normals** (:func:`risk_curve` with ``normals=True``, the length of the
coarse low-pass, :mod:`meshrepair.denoise.coarse`). A face's normal error is, to first order,
the gradient over the face of the error of the normal offsets. With ``G`` the edge-difference
operator (a row ``e_i − e_j`` per edge, ``GᵀG = L`` the graph Laplacian) the same expansion
gives ``E‖G P(Sy − x)‖² = E‖G P(y − Sy)‖² − σ² tr L + 2σ² tr(L S)``, so

.. math:: R_∇(k) = \\sum_{(i,j) \\in E} (r_i - r_j)^2 + 2σ^2\\,\\mathrm{tr}(L\\,T^k),
          \\qquad r = P(y - T^k y),

up to a constant, ``tr(L T^k) ≈ \\frac13 \\sum_c (L z_c)^\\top T^k z_c`` with the same ``Z``.
The results are judged by their normals (MSAE), and ``R(k)`` weighs an error of long
wavelength, which costs positions but hardly normals, like one of a few rings: on smooth
surfaces it asks for a shorter filter than the normals want (a torus and a rounded cube at
0.05 l̄: 14 and 19 pairs against 60 and more for the least MSAE; ``R_∇`` 60 and 60; on
scanned relief the two agree within a few pairs).

**The level** ``σ`` (:func:`normal_level`) is read from the input by one λ|μ pair, whose signal
part is small: ``σ̂² = \\lVert P_1 (y - Ty)\\rVert^2 / \\lVert (I - T)Z\\rVert_F^2 \\cdot 3``,
the normal residual of one pair over what that pair leaves of a unit white field (``P_1`` the
normals of ``Ty``). Against the truth's normal part of the noise it reads within 1 % on heavy
random-direction noise, where the one-ring estimate ``γ̂`` of the denoiser reads 17-20 % low:
too biased for a risk whose minimiser moves with ``σ²``.

Everything is in the input's units: the risk scales with ``ℓ̄²`` and its minimiser is invariant
to scale, rotation and translation.
"""

from __future__ import annotations

import numpy as np

PROBE_SEED = 0


def _probe(V: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The fixed Rademacher field ``Z`` (nV, 3), drawn in the canonical order of the vertices
    on ``edges`` (:mod:`meshrepair.mesh.probe`: a relabelled mesh gets the same ``Z`` on each
    vertex)."""
    from meshrepair.mesh.probe import probe_field
    from meshrepair.mesh.topology import used_vertices

    return probe_field(V, 3, seed=PROBE_SEED, kind="rademacher",
                       used=used_vertices(edges, len(V)))


def normal_level(V: np.ndarray, F: np.ndarray, edges: np.ndarray) -> float:
    """``σ̂`` of the module docstring: the level of the normal part of the noise.

    Parameters
    ----------
    V : (nV, 3) float64, the input ``y``
    F : (nF, 3) int64
    edges : (nE, 2) int64

    Returns
    -------
    float, in the input's units (not edge lengths)
    """
    from meshrepair.denoise.presmooth import presmooth
    from meshrepair.mesh.geometry import vertex_normals

    free = np.ones(len(V), bool)
    X = presmooth(V, edges, free, 1)
    rn = np.einsum("ij,ij->i", V - X, vertex_normals(X, F))
    Z = _probe(V, edges)
    fz = float(((Z - presmooth(Z, edges, free, 1)) ** 2).sum()) / 3.0
    return float(np.sqrt(float(rn @ rn) / fz)) if fz > 0 else 0.0


def normal_risk(V: np.ndarray, X: np.ndarray, F: np.ndarray, edges: np.ndarray, steps: int,
                sigma: float) -> float:
    """``R(k)`` of the module docstring for ``X = T^k V``.

    Parameters
    ----------
    V : (nV, 3) float64, the input ``y``
    X : (nV, 3) float64, ``T^k y``
    F : (nF, 3) int64
    edges : (nE, 2) int64
    steps : ``k``
    sigma : ``σ``, the level of the normal part of the noise (input units)

    Returns
    -------
    float
    """
    from meshrepair.denoise.presmooth import presmooth
    from meshrepair.mesh.geometry import vertex_normals

    rn = np.einsum("ij,ij->i", V - X, vertex_normals(X, F))
    Z = _probe(V, edges)
    tr = float((Z * presmooth(Z, edges, np.ones(len(V), bool), int(steps))).sum()) / 3.0
    return float(rn @ rn) + 2.0 * float(sigma) ** 2 * tr


def risk_curve(V: np.ndarray, F: np.ndarray, edges: np.ndarray, max_steps: int,
               sigma: float | None = None, *, normals: bool = False) -> np.ndarray:
    """``R(k)`` of the module docstring for every ``k = 0 … max_steps`` (``R(k)`` equals
    :func:`normal_risk` of ``T^k V``), the pairs applied one after the other to ``V`` and to
    the probe ``Z``; with ``normals`` the risk of the normals ``R_∇(k)`` instead.

    Parameters
    ----------
    V : (nV, 3) float64, the input ``y``
    F : (nF, 3) int64
    edges : (nE, 2) int64
    max_steps : the largest ``k``
    sigma : ``σ`` (input units); :func:`normal_level` of ``V`` when None
    normals : the risk of the normals ``R_∇`` (module docstring) instead of ``R``

    Returns
    -------
    (max_steps + 1,) float64
    """
    from meshrepair.denoise.lowpass import taubin_region, umbrella
    from meshrepair.mesh.geometry import vertex_normals

    V = np.asarray(V, dtype=np.float64)
    s2 = float(normal_level(V, F, edges) if sigma is None else sigma) ** 2
    free = np.ones(len(V), bool)
    W = umbrella(edges, len(V))  # built once for the 2 · max_steps single pairs below
    X, Z = V, _probe(V, edges)
    SZ = Z
    i, j = np.asarray(edges[:, 0]), np.asarray(edges[:, 1])
    if normals:  # L Z, L the graph Laplacian (G^T G, G the edge differences)
        dz = Z[i] - Z[j]
        Z = np.zeros_like(Z)
        np.add.at(Z, i, dz)
        np.add.at(Z, j, -dz)
    out = np.empty(int(max_steps) + 1)
    for k in range(int(max_steps) + 1):
        if k:
            X, SZ = taubin_region(X, edges, free, 1, W=W), taubin_region(SZ, edges, free, 1, W=W)
        rn = np.einsum("ij,ij->i", V - X, vertex_normals(X, F))
        if normals:
            rn = rn[i] - rn[j]
        out[k] = float(rn @ rn) + 2.0 * s2 * float((Z * SZ).sum()) / 3.0
    return out

