"""Whether the rest of a surface encloses the region a loop bounds: the generalized winding
number of the surface with every *other* loop capped.

For a closed surface the winding number ``w(p) = (1 / 4π) Σ_f Ω_f(p)`` (``Ω_f`` the signed
solid angle of face ``f`` seen from ``p``) is 1 inside and 0 outside. Cutting holes removes
their solid angle: a point inside then sees ``1 - Ω_holes(p) / 4π``. Capping every loop but
``i`` by a flat fan (triangles from the loop's centroid) and taking the largest ``|w|`` over
points just inside the surface measures how much of the view loop ``i`` alone takes away:

* a hole of a body that is closed apart from its holes: ``|w|`` close to 1 at points far from
  it (a hole the size of a statue's cut base: about 0.88);
* the border of an open scan or relief: the scan does not surround any point, ``|w|`` stays
  near 0.5-0.75 (a point just under the surface sees half of space through it, plus what the
  folds of the surface add).

Winding numbers are additive over faces, so ``w_i = w(surface) + Σ_j w(cap_j) - w(cap_i)`` for
every loop from one evaluation per cap. Cost: (points) × (faces of the component), with
:data:`N_SAMPLES` faces sampled per component, two depths and both sides.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from meshrepair.holes.detect import Hole

N_SAMPLES = 24
"""Faces of each component whose centroids, moved in along the face normal, are the points
where the winding number is evaluated."""

DEPTHS = (1.0, 4.0)
"""Depths (mean edge lengths) of the sample points below (and above: the orientation may be
inward) their face."""


def solid_angle_sum(V: np.ndarray, F: np.ndarray, P: np.ndarray,
                    chunk: int = 100_000) -> np.ndarray:
    """``(1 / 4π) Σ_f Ω_f(p)`` for every point of ``P`` (Van Oosterom and Strackee's formula of a
    triangle's signed solid angle), ``(len(P),)``; computed in blocks of at most ``chunk``
    (point, face) pairs (over the points, and over the faces of a mesh with more faces than
    that): about 170 bytes of temporaries per pair, 17 MB per block."""
    out = np.zeros(len(P))
    if len(F) == 0 or len(P) == 0:
        return out
    fstep = min(len(F), chunk)
    pstep = max(1, chunk // fstep)
    for f0 in range(0, len(F), fstep):
        Fb = F[f0:f0 + fstep]
        A0, B0, C0 = V[Fb[:, 0]], V[Fb[:, 1]], V[Fb[:, 2]]
        for s in range(0, len(P), pstep):
            p = P[s:s + pstep, None, :]
            a, b, c = A0[None] - p, B0[None] - p, C0[None] - p
            la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
            num = np.einsum("ijk,ijk->ij", a, np.cross(b, c))
            den = (la * lb * lc + np.einsum("ijk,ijk->ij", a, b) * lc
                   + np.einsum("ijk,ijk->ij", b, c) * la + np.einsum("ijk,ijk->ij", c, a) * lb)
            out[s:s + pstep] += 2.0 * np.arctan2(num, den).sum(axis=1)
    return out / (4.0 * np.pi)


def _cap(V: np.ndarray, loop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A flat fan closing ``loop`` (traversed backwards, as a filling face must), ``(Vc, Fc)``
    with the centroid as vertex 0."""
    k = len(loop)
    Vc = np.r_[V[loop].mean(axis=0)[None], V[loop]]
    j = np.arange(k)
    return Vc, np.c_[np.zeros(k, np.int64), (j + 1) % k + 1, j + 1]


def loop_enclosure(V: np.ndarray, F: np.ndarray, holes: Sequence[Hole]) -> dict[int, float]:
    """For every loop, the largest ``|w|`` of its component with every other loop capped (see
    the module docstring): close to 1 when the rest of the surface encloses the loop's region,
    about 0.5-0.75 for the border of an open surface.

    Parameters
    ----------
    V : (nV, 3) float64
    F : (nF, 3) int64
    holes : list of Hole, from :func:`meshrepair.holes.find_holes` on ``(V, F)``

    Returns
    -------
    dict of int to float
        Hole index -> enclosure in [0, ~1].
    """
    if not holes:
        return {}
    from meshrepair.mesh.geometry import face_normals, mean_edge_length
    from meshrepair.mesh.topology import connected_components

    _, comp = connected_components(F, len(V))
    fcomp = comp[F[:, 0]]
    le = mean_edge_length(V, F)
    N = face_normals(V, F)
    rng = np.random.default_rng(0)
    out: dict[int, float] = {}
    for c in sorted({h.component for h in holes}):
        mine = [h for h in holes if h.component == c]
        fc = np.flatnonzero(fcomp == c)
        idx = fc[rng.choice(len(fc), size=min(N_SAMPLES, len(fc)), replace=False)]
        cen = V[F[idx]].mean(axis=1)
        P = np.concatenate([cen + s * d * le * N[idx] for d in DEPTHS for s in (-1.0, 1.0)])
        w_all = solid_angle_sum(V, F[fc], P)
        caps = []
        for h in mine:
            Vc, Fc = _cap(V, h.vertices)
            caps.append(solid_angle_sum(Vc, Fc, P))
        w_all = w_all + np.sum(caps, axis=0)
        for h, wc in zip(mine, caps, strict=True):
            out[h.index] = float(np.abs(w_all - wc).max())
    return out
