"""Boundary-loop correspondence for context-aware completion (paper Sect. 5).

Completion replaces a region of a mesh, bounded by a loop ``b0``, with a template patch bounded by
a loop ``b_P``. The paper assumes both loops are aligned and have the same number of vertices;
this module provides the pieces that make it so:

* arc-length parametrisation and resampling of polylines (:func:`arc_length_parameters`,
  :func:`resample_polyline`);
* splitting boundary edges of a mesh (and the faces they belong to) at given arc-length
  positions so that the mesh stays valid (:func:`split_boundary_edges`,
  :func:`uniform_split_params`, :func:`subdivide_loop`);
* rigid / similarity alignment of point sets (:func:`umeyama`) and the best cyclic shift and
  direction between two loops with the same vertex count, over all shifts at once with the FFT
  (:func:`best_cyclic_alignment`);
* re-exported from the modules that implement them: rigid transforms
  (:mod:`meshrepair.complete.rigid`),
  ICP against a loop or a surface (:mod:`meshrepair.complete.icp`), and the matching of loops with
  different vertex counts (:mod:`meshrepair.complete.loopmatch`).

Conventions: points are ``(n, 3)`` float64, 4x4 homogeneous transforms act on column vectors
(``p' = T[:3, :3] @ p + T[:3, 3]``). A loop is *closed*: vertex ``n - 1`` connects back to
vertex 0. Input arrays are never modified.
"""

from __future__ import annotations

import heapq
import logging
from dataclasses import dataclass

import numpy as np

from meshrepair.complete.icp import (  # noqa: F401  (re-exported: the public API of this module)
    _closest_on_triangles,
    _rotation_vector,
    closest_points_on_loop,
    closest_points_on_mesh,
    icp_loop_to_polyline,
    icp_to_surface,
)
from meshrepair.complete.loopmatch import LoopAlignment, align_loops, monotone_loop_match  # noqa: F401
from meshrepair.complete.rigid import _points, _rotation_from_svd, apply_transform, umeyama  # noqa: F401
from meshrepair.errors import MeshRepairError

log = logging.getLogger(__name__)

__all__ = [
    "CyclicAlignment",
    "LoopAlignment",
    "align_loops",
    "apply_transform",
    "arc_length_parameters",
    "best_cyclic_alignment",
    "closest_points_on_loop",
    "closest_points_on_mesh",
    "icp_to_surface",
    "icp_loop_to_polyline",
    "monotone_loop_match",
    "resample_polyline",
    "split_boundary_edges",
    "subdivide_loop",
    "umeyama",
    "uniform_split_params",
]

FITS = ("none", "rigid", "similarity")


# ------------------------------------------------------------------------------------------------
# polylines
# ------------------------------------------------------------------------------------------------



def arc_length_parameters(P: np.ndarray, *, closed: bool = True) -> tuple[np.ndarray, float]:
    """Cumulative arc length at each vertex of a polyline.

    Parameters
    ----------
    P : (n, 3) float
    closed : bool
        Include the closing edge ``P[n-1] -> P[0]`` in the total length.

    Returns
    -------
    s : (n,) float64
        Arc length from ``P[0]`` to each vertex (``s[0] = 0``).
    total : float
        Total length (with the closing edge if ``closed``).
    """
    P = _points(P)
    seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    total = float(s[-1] + (np.linalg.norm(P[0] - P[-1]) if closed else 0.0))
    return s, total


def resample_polyline(P: np.ndarray, n: int, *, closed: bool = True) -> np.ndarray:
    """Resample a polyline to ``n`` points equally spaced in arc length.

    Parameters
    ----------
    P : (m, 3) float
    n : int
        Number of output points (>= 2 open, >= 3 closed).
    closed : bool
        Closed loop: points at arc lengths ``k L / n``, ``k = 0..n-1`` (``P[0]`` kept).
        Open polyline: ``linspace(0, L, n)``, so both endpoints are kept.

    Returns
    -------
    (n, 3) float64
    """
    P = _points(P)
    n = int(n)
    if n < (3 if closed else 2) or len(P) < 2:
        raise MeshRepairError(f"cannot resample a polyline of {len(P)} points to {n} points")
    Q = np.vstack([P, P[:1]]) if closed else P
    s, total = arc_length_parameters(Q, closed=False)
    if not total > 0:
        raise MeshRepairError("the polyline has zero length; its points all coincide")
    t = np.arange(n) * (total / n) if closed else np.linspace(0.0, total, n)
    k = np.clip(np.searchsorted(s, t, side="right") - 1, 0, len(Q) - 2)
    seg = s[k + 1] - s[k]
    w = np.divide(t - s[k], seg, out=np.zeros_like(t), where=seg > 0)
    out = Q[k] + w[:, None] * (Q[k + 1] - Q[k])
    if not closed:
        out[-1] = P[-1]
    return out


def uniform_split_params(P: np.ndarray, n_target: int) -> list[np.ndarray]:
    """Where to split the edges of a closed loop to reach ``n_target`` vertices.

    Greedy: each extra vertex goes to the edge whose current pieces are longest, and an edge
    split ``k`` times is cut into ``k + 1`` equal pieces, so the arc-length spacing becomes as
    uniform as possible while every original vertex is kept.

    Parameters
    ----------
    P : (n, 3) float, loop vertices (edge ``i`` joins ``P[i]`` and ``P[(i+1) % n]``)
    n_target : int >= n

    Returns
    -------
    list of n arrays
        ``params[i]``: sorted fractions in (0, 1) along edge ``i``.
    """
    P = _points(P)
    n = len(P)
    extra = int(n_target) - n
    if extra < 0:
        raise MeshRepairError(f"cannot split a loop of {n} vertices down to {n_target} vertices")
    lengths = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    counts = np.zeros(n, dtype=np.int64)
    heap = [(-float(lengths[i]), i) for i in range(n)]
    heapq.heapify(heap)
    for _ in range(extra):
        _, i = heapq.heappop(heap)
        counts[i] += 1
        heapq.heappush(heap, (-float(lengths[i]) / (counts[i] + 1), i))
    return [np.arange(1, c + 1, dtype=np.float64) / (c + 1) for c in counts]


def split_boundary_edges(V: np.ndarray, F: np.ndarray, loop: np.ndarray,
                         params: list[np.ndarray]
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Insert vertices on the edges of a boundary loop, fanning the faces they belong to.

    Edge ``i`` of the loop is the boundary half-edge ``(loop[i], loop[i+1])`` of a face
    ``(u, v, w)`` (the loop must follow the face orientation, as
    :func:`meshrepair.mesh.topology.boundary_loops` returns it). Splitting it at fractions
    ``t_1 < ... < t_k`` adds vertices ``p_j = u + t_j (v - u)`` and replaces the face with the fan
    ``(u, p_1, w), (p_1, p_2, w), ..., (p_k, v, w)``: same orientation, same surface, a valid
    mesh. Faces that own two loop edges are handled (the edges are split one after the other).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    loop : (n,) int, a boundary loop following the face orientation
    params : list of n arrays of fractions in (0, 1) (empty arrays for edges not split)

    Returns
    -------
    V2 : (nV + k, 3) float64, new vertices appended after the old ones
    F2 : (nF + k, 3) int64, the split faces replaced in place, new faces appended
    loop2 : (n + k,) int64, the refined loop (old vertices keep their order)
    new_vertices : (k,) int64, indices of the inserted vertices in loop order
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    loop = np.asarray(loop, dtype=np.int64)
    n = len(loop)
    if len(params) != n:
        raise MeshRepairError(f"need one parameter array per loop edge ({n}), got {len(params)}")
    total = int(sum(len(p) for p in params))
    if total == 0:
        return V.copy(), F.copy(), loop.copy(), np.zeros(0, np.int64)
    he_face: dict[tuple[int, int], int] = {}
    for m, (a, b, c) in enumerate(F.tolist()):
        he_face[(a, b)] = m
        he_face[(b, c)] = m
        he_face[(c, a)] = m
    newV = [V]
    Fl = F.tolist()
    nxt = len(V)
    loop2: list[int] = []
    new_vertices: list[int] = []
    for i in range(n):
        u, v = int(loop[i]), int(loop[(i + 1) % n])
        loop2.append(u)
        t = np.sort(np.asarray(params[i], dtype=np.float64).ravel())
        if t.size == 0:
            continue
        if (t <= 0).any() or (t >= 1).any() or (np.diff(t) <= 0).any():
            raise MeshRepairError(f"split fractions of loop edge {i} must be distinct and in "
                                  f"(0, 1), got {t.tolist()}")
        m = he_face.get((u, v))
        if m is None:
            raise MeshRepairError(f"({u}, {v}) is not a boundary half-edge of the mesh: the loop "
                                  "must follow the face orientation (use topology.boundary_loops)")
        face = Fl[m]
        k = face.index(u)
        w = face[(k + 2) % 3]
        P = V[u] + t[:, None] * (V[v] - V[u])
        idx = list(range(nxt, nxt + len(t)))
        nxt += len(t)
        newV.append(P)
        chain = [u, *idx, v]
        del he_face[(u, v)]
        for j in range(len(chain) - 1):
            tri = [chain[j], chain[j + 1], w]
            if j == 0:
                Fl[m] = tri
                fm = m
            else:
                Fl.append(tri)
                fm = len(Fl) - 1
            he_face[(tri[0], tri[1])] = fm
            he_face[(tri[1], tri[2])] = fm
            he_face[(tri[2], tri[0])] = fm
        loop2.extend(idx)
        new_vertices.extend(idx)
    return (np.vstack(newV), np.asarray(Fl, dtype=np.int64), np.asarray(loop2, np.int64),
            np.asarray(new_vertices, np.int64))


def subdivide_loop(V: np.ndarray, F: np.ndarray, loop: np.ndarray, n_target: int
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Split the edges of a boundary loop until it has ``n_target`` vertices (uniformly).

    Combines :func:`uniform_split_params` and :func:`split_boundary_edges`; see there.
    """
    V = np.asarray(V, dtype=np.float64)
    return split_boundary_edges(V, F, loop, uniform_split_params(V[np.asarray(loop)], n_target))


# ------------------------------------------------------------------------------------------------
# alignment
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CyclicAlignment:
    """Result of :func:`best_cyclic_alignment`.

    Attributes
    ----------
    shift : int
    reversed : bool
        Vertex ``i`` of ``A`` corresponds to ``B[(i + shift) % n]`` (not reversed) or to
        ``B[(shift - i) % n]`` (reversed).
    transform : (4, 4) float64, maps ``B`` onto ``A`` (identity for ``fit="none"``).
    rms : float, RMS distance ``|A_i - T B_sigma(i)|`` at the optimum.
    rms_other_direction : float, best RMS with the other direction (inf if not tried).
    """

    shift: int
    reversed: bool
    transform: np.ndarray
    rms: float
    rms_other_direction: float = float("inf")

    def indices(self, n: int) -> np.ndarray:
        """(n,) int64: the index into ``B`` matched with each vertex of ``A``."""
        i = np.arange(n)
        return ((self.shift - i) if self.reversed else (self.shift + i)) % n


def _shift_covariances(A: np.ndarray, B: np.ndarray, reverse: bool) -> np.ndarray:
    """``H[s] = sum_i A_i B_sigma_s(i)^T`` for all shifts ``s`` (``(n, 3, 3)``), via the FFT."""
    n = len(A)
    fa = np.fft.rfft(A, axis=0)
    fb = np.fft.rfft(B, axis=0)
    if reverse:  # sigma(i) = s - i: circular convolution
        prod = fa[:, :, None] * fb[:, None, :]
    else:  # sigma(i) = s + i: circular correlation
        prod = np.conj(fa)[:, :, None] * fb[:, None, :]
    return np.fft.irfft(prod, n=n, axis=0)


def best_cyclic_alignment(A: np.ndarray, B: np.ndarray, *, fit: str = "rigid",
                          directions: tuple[bool, ...] = (False, True)) -> CyclicAlignment:
    """Best cyclic shift and direction between two closed loops with the same vertex count.

    For every shift ``s`` and each direction in ``directions`` (``False`` forward, ``True``
    reversed) the optimal transform of ``fit`` is computed in closed form, and the pair with the
    least sum of squared distances is returned. All ``n`` cross-covariances come from one FFT per
    direction and the 3x3 SVDs are batched: O(n log n + n) work.

    Parameters
    ----------
    A : (n, 3) float, target loop
    B : (n, 3) float, loop to be matched onto ``A``
    fit : ``"none"`` (loops already aligned: plain squared distances), ``"rigid"`` (rotation and
        translation) or ``"similarity"`` (also a uniform scale).
    directions : which directions to try.

    Returns
    -------
    CyclicAlignment
    """
    A = _points(A, "loop A")
    B = _points(B, "loop B")
    if fit not in FITS:
        raise MeshRepairError(f"fit must be one of {FITS}, got {fit!r}")
    if A.shape != B.shape or len(A) < 3:
        raise MeshRepairError(f"both loops need the same number (>= 3) of vertices, got {len(A)} "
                              f"and {len(B)}; resample one first")
    if not directions:
        raise MeshRepairError("at least one direction must be tried")
    n = len(A)
    best: dict[bool, tuple[float, int, np.ndarray]] = {}
    for rev in directions:
        if fit == "none":
            H = _shift_covariances(A, B, rev)
            res = (A * A).sum() + (B * B).sum() - 2.0 * np.trace(H, axis1=1, axis2=2)
            s = int(np.argmin(res))
            best[rev] = (max(float(res[s]), 0.0), s, np.eye(4))
            continue
        muA, muB = A.mean(axis=0), B.mean(axis=0)
        Ac, Bc = A - muA, B - muB
        H = _shift_covariances(Ac, Bc, rev)
        U, sig, Vt = np.linalg.svd(H)
        _, d = _rotation_from_svd(U, Vt)
        tr = sig[:, 0] + sig[:, 1] + d * sig[:, 2]
        sa, sb = float((Ac * Ac).sum()), float((Bc * Bc).sum())
        res = sa - tr**2 / sb if fit == "similarity" else sa + sb - 2.0 * tr
        s = int(np.argmin(res))
        idx = ((s - np.arange(n)) if rev else (s + np.arange(n))) % n
        T = umeyama(B[idx], A, scale=fit == "similarity")
        best[rev] = (max(float(res[s]), 0.0), s, T)
    def exact_rms(rev: bool) -> float:  # the FFT residual loses digits by cancellation
        _, s, T = best[rev]
        idx = ((s - np.arange(n)) if rev else (s + np.arange(n))) % n
        return float(np.sqrt(np.mean(np.sum((apply_transform(T, B[idx]) - A) ** 2, axis=1))))

    rev = min(best, key=lambda r: best[r][0])
    _, s, T = best[rev]
    other = [exact_rms(r) for r in best if r != rev]
    return CyclicAlignment(shift=s, reversed=bool(rev), transform=T, rms=exact_rms(rev),
                           rms_other_direction=other[0] if other else float("inf"))
