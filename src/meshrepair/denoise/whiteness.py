r"""The white-noise test of a result's residual: which of two noise models the data support.

The reading of :mod:`meshrepair.denoise.scale` compares the input's high-passes across scales
against a reference (the probe's result). On a finely curved surface at low noise the probe
also removes relief at two to three rings, and that relief reads as correlated noise
(``ρ > 1``) although the noise is white. The reading alone cannot tell the two apart; the
result of the white-noise model can. When the noise reads correlated, the plan therefore runs
the white-noise model first and keeps its result if its residual is what white noise of the
measured level leaves behind (the *method noise* of Buades, Coll and Morel: a good denoiser's
residual is noise, without structure). Otherwise the correlated-noise model runs on the input.

**The test.** With ``X`` the white model's result, ``Y`` the input, ``n_i`` the result's
vertex normals and ``l̄`` the input's mean edge length, the normal residual
``r_i = ⟨y_i − x_i, n_i⟩ / l̄`` and the umbrella average ``W = D⁻¹A`` of the edge graph give

.. math:: ρ_1 = \frac{\sum_i r_i (W r)_i}{\sum_i r_i^2}, \qquad
          q = \frac{\mathrm{rms}(r)}{\hat γ},

the residual's correlation with its one-ring average (Moran's I on the mesh graph) and its
level against the input's one-ring noise level ``γ̂``
(:func:`meshrepair.model.noise.noise_statistics`, exact for white noise). The residual passes
as white when

.. math:: ρ_1 \le ρ_{max} \quad\text{and}\quad q \le 1 .

* *Whiteness.* White noise ``η`` minus its smoothed version ``Sη`` is a high-pass, whose
  neighbours are uncorrelated or anti-correlated: ``ρ_1 ≤ 0`` up to the relief the model
  leaves in the residual. Noise correlated over ``ℓ ≥ 1`` rings keeps its long waves in the
  white model's result and its short ones in the residual, which then correlates with its
  neighbours. :data:`RHO1_MAX` sits between the two (``benchmarks/whiteness.py`` prints both
  populations).
* *Discrepancy.* A smoother that removes white noise of level ``γ̂`` and keeps the surface
  leaves a residual of level ``γ̂ (1 − p/N)^{1/2} < γ̂`` (``p`` the smoother's degrees of
  freedom). A residual above ``γ̂`` holds more than the white noise the one-ring level sees,
  i.e. noise at longer wavelengths (a scanner's) that the one-ring level underestimates.

Both are necessary conditions of the white model, so either failing sends the input to the
correlated model. The test costs one residual and one sparse product.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from meshrepair.mesh.geometry import vertex_normals

RHO1_MAX = 0.1
"""Largest one-ring correlation ρ₁ of a white model's residual that passes as white noise."""
LEVEL_MAX = 1.0
"""Largest residual level, in units of the input's one-ring noise level γ̂, that passes."""


@dataclass(frozen=True)
class WhiteTest:
    """The white-noise test of a residual (module docstring).

    Attributes
    ----------
    rho1 : one-ring correlation ρ₁ of the normal residual
    level_ratio : residual RMS over γ̂
    white : ``rho1 <= RHO1_MAX and level_ratio <= LEVEL_MAX``
    """

    rho1: float
    level_ratio: float
    white: bool


def white_residual(Y: np.ndarray, X: np.ndarray, F: np.ndarray, edges: np.ndarray,
                   gamma: float) -> WhiteTest:
    """Test whether ``Y − X`` is white noise of level ``gamma`` (module docstring).

    Parameters
    ----------
    Y : (n, 3) float64, the input
    X : (n, 3) float64, the white-noise model's result
    F : (m, 3) int64
    edges : (k, 2) int64, the mesh's unique edges
    gamma : the input's one-ring noise level, mean edge lengths

    Returns
    -------
    WhiteTest
    """
    n = len(Y)
    lbar = float(np.linalg.norm(Y[edges[:, 0]] - Y[edges[:, 1]], axis=1).mean())
    r = np.einsum("ij,ij->i", Y - X, vertex_normals(X, F)) / lbar
    i, j = edges[:, 0], edges[:, 1]
    A = sp.coo_matrix((np.ones(2 * len(edges)), (np.r_[i, j], np.r_[j, i])), shape=(n, n))
    deg = np.bincount(np.r_[i, j], minlength=n).astype(np.float64)
    Wr = (A.tocsr() @ r) / np.maximum(deg, 1.0)
    rr = float(r @ r)
    rho1 = float(r @ Wr) / rr if rr > 0 else 0.0
    ratio = float(np.sqrt(rr / n)) / gamma if gamma > 0 else float("inf")
    return WhiteTest(rho1=rho1, level_ratio=ratio,
                     white=bool(rho1 <= RHO1_MAX and ratio <= LEVEL_MAX))
