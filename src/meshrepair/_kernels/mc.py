"""The minimax-concave penalty φ(t; a) of (7) and its proximal map, the closed form below (23),
as array functions: the kernels' numpy twins use them, :mod:`meshrepair.model.penalties` puts
them in the model."""

from __future__ import annotations

import numpy as np


def mc_penalty(t: np.ndarray | float, a: float) -> np.ndarray:
    """Minimax-concave penalty φ(t; a) of (7).

    Parameters
    ----------
    t : array_like, t >= 0
    a : float > 0, the non-convexity (``inf φ'' = -a``).

    Returns
    -------
    ndarray, same shape as ``t``: ``-a t²/2 + sqrt(2a) t`` for ``t < sqrt(2/a)``, else 1.
    """
    t = np.asarray(t, dtype=np.float64)
    return np.where(t < np.sqrt(2.0 / a), -0.5 * a * t * t + np.sqrt(2.0 * a) * t, 1.0)


def prox_mc(r: np.ndarray, a: float, alpha: float) -> np.ndarray:
    """Proximal map of ``φ(||·||; a)`` with weight ``alpha``: the closed form below (23).

    Minimises ``φ(||t||; a) + alpha/2 ||t - r||²`` row-wise for ``alpha > a`` (firm thresholding):
    ``t = min(max(v - ζ/||r||, 0), 1) r`` with ``v = α/(α-a)``, ``ζ = sqrt(2a)/(α-a)``.

    Parameters
    ----------
    r : (n, 3)
    a, alpha : float with alpha > a

    Returns
    -------
    (n, 3)
    """
    if not alpha > a:
        raise ValueError(f"prox_mc needs alpha > a for strong convexity (alpha={alpha}, a={a})")
    nr = np.sqrt(np.einsum("ij,ij->i", r, r))
    v = alpha / (alpha - a)
    zeta = np.sqrt(2.0 * a) / (alpha - a)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.clip(v - zeta / nr, 0.0, 1.0)
    s = np.where(nr > 0, s, 0.0)
    return s[:, None] * r
