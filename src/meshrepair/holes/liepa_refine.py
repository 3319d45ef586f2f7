"""Refinement of Liepa's coarse triangulation to the target edge length on its own surface:
isometric development (or mean-value layout of a subdivision, both in
:mod:`meshrepair.holes.liepa_layout`), Triangle, lift by barycentric coordinates."""

from __future__ import annotations

import logging

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.holes._geom2d import Patch, _max_area_for, _orient_patch
from meshrepair.holes._triangle import MIN_ANGLE, steiner_cap, triangulate, triangulate_capped
from meshrepair.holes.liepa import min_weight_triangulation
from meshrepair.holes.liepa_layout import _locate, _mean_value_layout, _unfold

log = logging.getLogger(__name__)


STEINER_FACTOR = 8.0
"""Triangle may add at most this many times the expected number of patch vertices (layout
area over the target triangle area) as Steiner points; a layout needing more is given up."""

def _divided_folds(Q: np.ndarray, folds: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """The layout's points with each fold ``(i, j)`` divided into ``max(1, round(L / h))`` equal
    pieces (``L`` its length in the layout): ``(points (k + m, 2), segments (s, 2))``, the new
    points after the ``k`` loop vertices, in fold order."""
    k = len(Q)
    a, b = Q[folds[:, 0]], Q[folds[:, 1]]
    n = np.maximum(1, np.rint(np.linalg.norm(b - a, axis=1) / h)).astype(np.int64)
    extra, segs = [], []
    nxt = k
    for (i, j), p, q, m in zip(folds.tolist(), a, b, n.tolist(), strict=True):
        t = np.arange(1, m)[:, None] / m
        extra.append(p + t * (q - p))
        ids = np.r_[i, nxt + np.arange(m - 1), j]
        nxt += m - 1
        segs.append(np.c_[ids[:-1], ids[1:]])
    return np.concatenate([Q, *extra]), np.concatenate(segs).astype(np.int64)


def _refine_on_triangulation(k: int, S: np.ndarray, Ts: np.ndarray, Qs: np.ndarray, h: float, *,
                             isometric: bool, creases: np.ndarray | None = None,
                             conforming: bool = False
                             ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Remesh the triangulated surface ``(S, Ts)`` spanning a loop to edge length ``h``.

    ``S (n, 3)`` starts with the ``k`` loop vertices; ``Qs (n, 2)`` is a valid planar layout of
    ``Ts`` (every triangle positive, none overlapping) whose first ``k`` rows are a simple
    polygon containing the rest of the layout. Triangle meshes that polygon (no Steiner point on
    the loop, minimum angle :data:`MIN_ANGLE`) and every new vertex is mapped to 3-D by the affine
    map of the triangle of ``Ts`` containing it, so it lies on the surface. ``creases (q, 2)``
    (pairs of loop vertices: edges of ``Ts`` where it folds) stay edges of the result, so no new
    edge cuts across a fold and the new triangles lie on the surface too; other edges of ``Ts``
    do not, because fans of chords meeting at small angles at a loop vertex force tiny triangles
    there. Each fold is divided into ``round(L / h)`` equal pieces beforehand and Triangle may
    not split a segment further (``YY``): where folds fan out of a loop vertex at small angles,
    splitting them for the angle bound cascades into thousands of tiny triangles (Triangle's
    refinement near small input angles); with fixed pieces the triangles there are as thin as
    the fan but no smaller than its pieces. With ``conforming`` Triangle splits the folds for its
    angle bound instead (a patch much finer along the folds: the fallback of
    :func:`meshrepair.fill.fill_holes` when the divided patch, faired, intersects the surface).
    For an ``isometric`` layout the 3-D edge length is the 2-D one; otherwise the area bounds are
    corrected by the 2-D/3-D area ratio of each new triangle with two rounds of Triangle's
    refinement (``r``). The Steiner bound of the developed layout counts the points Triangle
    adds, not the fold points given to it.

    Returns
    -------
    (X (m, 3), T (t, 3), X2 (m, 2)), or None if Triangle changed the loop vertices.
    """
    Q = Qs[:k]
    segs = np.c_[np.arange(k), (np.arange(k) + 1) % k]
    pts, no_split = Q, ""
    if creases is not None and len(creases):
        cr = np.asarray(creases, dtype=np.int64).reshape(-1, 2)
        if conforming:
            segs = np.r_[segs, cr]
        else:
            pts, fold_segs = _divided_folds(Q, cr, h)
            segs = np.r_[segs, fold_segs]
            no_split = "Y"  # with the "Y" of opts: no Steiner point on any segment
    target = _max_area_for(h)

    def lift(X2):
        X = np.empty((len(X2), 3))
        X[:k] = S[:k]
        if len(X2) > k:
            owner, bc = _locate(Qs, Ts, X2[k:])
            X[k:] = np.einsum("ij,ijk->ik", bc, S[Ts[owner]])
        return X

    def areas(X, T):
        if X.shape[1] == 2:
            d1, d2 = X[T[:, 1]] - X[T[:, 0]], X[T[:, 2]] - X[T[:, 0]]
            return 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        return 0.5 * np.linalg.norm(np.cross(X[T[:, 1]] - X[T[:, 0]], X[T[:, 2]] - X[T[:, 0]]),
                                    axis=1)

    amax = target
    if not isometric:
        amax *= float(areas(Qs, Ts).sum()) / max(float(areas(S, Ts).sum()), 1e-300)
    opts = f"pYQq{MIN_ANGLE:g}"
    if isometric:
        # developed layout: Steiner points bounded at STEINER_FACTOR times the target count
        # (folds meeting a loop vertex at tiny angles can make Triangle's quality refinement run
        # away: a 105-loop gave 1.2 M triangles); reaching the bound gives the layout up (None),
        # and the caller falls back to the mean-value layout
        cap = int(STEINER_FACTOR * float(areas(Qs, Ts).sum()) / amax) + 4 * k + 100
        out = triangulate({"vertices": pts, "segments": segs}, opts + no_split + f"S{cap}",
                          max_area=amax)
    else:
        # mean-value layout: the last resort, capped too (a loop through a far-away vertex is a
        # sliver whose quality mesh is unbounded): past the cap, MeshRepairError; the two
        # refinement rounds share the cap of the first call
        cap = steiner_cap(Q, k, amax)
        out = triangulate_capped({"vertices": Q, "segments": segs}, opts, cap, max_area=amax)
    for _ in range(0 if isometric else 2):
        X2 = np.asarray(out["vertices"], dtype=np.float64)
        T = np.asarray(out["triangles"], dtype=np.int64)
        a2, a3 = areas(X2, T), areas(lift(X2), T)
        if (a3 <= 1.25 * target).all():
            break
        bound = np.where(a3 > 1.25 * target, a2 * target / np.maximum(a3, 1e-300), -1.0)
        out = triangulate_capped({"vertices": X2, "segments": out["segments"], "triangles": T,
                                  "triangle_max_area": bound}, f"r{opts}a",
                                 cap - (len(X2) - k))
    X2 = np.asarray(out["vertices"], dtype=np.float64)
    T = np.asarray(out.get("triangles", np.empty((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(T) == 0 or len(X2) < k or not np.allclose(X2[:k], Q) \
            or (isometric and len(X2) - len(pts) >= cap):
        return None
    return lift(X2), T, X2


def _subdivide(X: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """1-to-4 midpoint subdivision (old vertices keep their indices, midpoints appended)."""
    e = np.sort(np.r_[T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]], axis=1)
    uniq, inv = np.unique(e, axis=0, return_inverse=True)
    mid = len(X) + inv.reshape(3, -1).T  # (t, 3): midpoints of edges 01, 12, 20
    Xn = np.r_[X, 0.5 * (X[uniq[:, 0]] + X[uniq[:, 1]])]
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    ab, bc, ca = mid[:, 0], mid[:, 1], mid[:, 2]
    Tn = np.r_[np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]]
    return Xn, Tn


LIEPA_CREASE = 20.0
"""Chords of the minimum-weight triangulation folding by more than this (degrees) stay edges of
the refined patch (:func:`_refine_on_triangulation`). 30° or less was needed for the unfaired
patch of a hole across a CAD part's creases not to cut into the surface (45° was not enough);
the price is a few short edges (1-5 % below 0.1 of the target) where folds fan out of a loop
vertex."""


def _creases(P: np.ndarray, T: np.ndarray, min_deg: float) -> np.ndarray:
    """Interior edges ``(q, 2)`` of the triangulated polygon with a dihedral angle > min_deg."""
    k = len(P)
    n = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    e = np.r_[T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]
    f = np.tile(np.arange(len(T)), 3)
    key = np.sort(e, axis=1)
    code = key[:, 0] * k + key[:, 1]
    order = np.argsort(code, kind="stable")
    cs = code[order]
    same = np.flatnonzero(cs[1:] == cs[:-1])
    a, b = f[order[same]], f[order[same + 1]]
    cosang = np.einsum("ij,ij->i", n[a], n[b])
    keep = cosang < np.cos(np.radians(min_deg))
    return key[order[same]][keep]


def _enclose_liepa(P: np.ndarray, h: float, opposite: np.ndarray | None,
                   forbidden: np.ndarray | None, *, conforming: bool = False,
                   coarse: np.ndarray | None = None) -> Patch:
    """Liepa's triangulation of the loop, remeshed to edge length ``h`` on its own surface.

    1. :func:`min_weight_triangulation` (no interior vertices), or the caller's ``coarse``
       triangulation of the loop.
    2. A planar layout of it: the isometric development along its dual tree (:func:`_unfold`)
       when that does not overlap itself (no distortion at all); otherwise the coarse surface is
       subdivided 1-to-4 until its edges are at most ``2 h`` and laid out by Floater's
       mean-value embedding with the loop on the unit circle by arc length (a convex boundary:
       always valid, but anisotropic where the surface is far from developable).
    3. :func:`_refine_on_triangulation`: Triangle meshes the layout to the target size, keeping
       the folds of the coarse surface (:data:`LIEPA_CREASE`) as edges in the developed layout
       (divided into pieces of about ``h``; split by Triangle for its angle bound instead with
       ``conforming``), and every new vertex is placed on the coarse surface by the affine map
       of the triangle it falls in; with the developed layout the patch lies on the coarse
       surface up to the smaller folds, with the mean-value layout its vertices do.
    """
    k = len(P)
    if coarse is None:
        Tc = min_weight_triangulation(P, opposite=opposite, forbidden=forbidden)
    else:
        Tc = np.asarray(coarse, dtype=np.int64).reshape(-1, 3)
        if Tc.shape != (k - 2, 3) or Tc.min(initial=0) < 0 or Tc.max(initial=0) >= k:
            raise MeshRepairError(f"coarse must be a ({k - 2}, 3) triangulation of the {k}-loop "
                                  f"in local indices, got shape {Tc.shape}")
    Tc = _orient_patch(Tc, k)  # already backwards along the loop; checks it
    Q = _unfold(P, Tc)
    res = None
    layout = "developed"
    folds = _creases(P, Tc, LIEPA_CREASE)
    if Q is not None:
        res = _refine_on_triangulation(k, P, Tc, Q, h, isometric=True, creases=folds,
                                       conforming=conforming)
    if res is None:
        S, Ts = P, Tc
        # the target patch has about area / (√3/4 h²) triangles; subdividing beyond a few times
        # that only costs memory (a 565-loop reached 2.3 M triangles with 6 rounds)
        area = 0.5 * float(np.linalg.norm(np.cross(P[Tc[:, 1]] - P[Tc[:, 0]],
                                                   P[Tc[:, 2]] - P[Tc[:, 0]]), axis=1).sum())
        cap = 4 * max(area / (np.sqrt(3.0) / 4.0 * h * h), float(k))
        for _ in range(6):
            e = np.r_[Ts[:, [0, 1]], Ts[:, [1, 2]], Ts[:, [2, 0]]]
            if np.linalg.norm(S[e[:, 0]] - S[e[:, 1]], axis=1).max() <= 2.0 * h \
                    or 4 * len(Ts) > cap:
                break
            S, Ts = _subdivide(S, Ts)
        res = _refine_on_triangulation(k, S, Ts, _mean_value_layout(S, Ts, k), h,
                                       isometric=False)
        layout = "mean-value"
        folds = folds[:0]
    if res is None:
        raise MeshRepairError("the minimum-weight triangulation of the loop could not be remeshed "
                              "(Triangle changed the loop vertices)")
    X, T, X2 = res
    log.debug("liepa: %d-loop, %d coarse triangles, %s layout, %d triangles", k, len(Tc),
              layout, len(T))
    return Patch(X=X, T=_orient_patch(T, k), uv=X2, method="liepa", n_loop=k,
                 n_folds=len(folds))
