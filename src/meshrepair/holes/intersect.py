"""Triangle-triangle intersection tests of patches against the mesh."""

from __future__ import annotations

import itertools

import numpy as np


def _seg_tri(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray,
             tol: float) -> np.ndarray:
    """Row-wise: does segment pq cross triangle abc (Möller-Trumbore, closed, tolerance tol)."""
    d = q - p
    e1 = b - a
    e2 = c - a
    hv = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, hv)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(np.cross(e1, e2), axis=1)
    ok = np.abs(det) > 1e-12 * np.maximum(scale, 1e-300)
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = p - a
    u = inv * np.einsum("ij,ij->i", s, hv)
    qv = np.cross(s, e1)
    v = inv * np.einsum("ij,ij->i", d, qv)
    t = inv * np.einsum("ij,ij->i", e2, qv)
    return ok & (u >= -tol) & (v >= -tol) & (u + v <= 1 + tol) & (t >= -tol) & (t <= 1 + tol)


PAIR_BLOCK = 100_000
"""Candidate face pairs tested at once by :func:`self_intersections` (the tests hold about 1 kB
of temporaries per pair: blocks bound the memory whatever the number of candidates)."""

QUERY_BLOCK = 20_000
"""Query faces whose candidate pairs :func:`self_intersections` gathers at once."""


def _pair_hits(V: np.ndarray, F: np.ndarray, a: np.ndarray, b: np.ndarray,
               tol: float) -> np.ndarray:
    """Row-wise: do faces ``F[a]`` and ``F[b]`` intersect other than along their shared vertices
    or edge (the tests of :func:`self_intersections`)."""
    Fa, Fb = F[a], F[b]
    shared = (Fa[:, :, None] == Fb[:, None, :])
    n_sh = shared.any(axis=2).sum(axis=1)
    hit = np.zeros(len(a), bool)
    # no shared vertex: 6 segment-triangle tests
    m0 = np.flatnonzero(n_sh == 0)
    if len(m0):
        A, B = V[Fa[m0]], V[Fb[m0]]
        h0 = np.zeros(len(m0), bool)
        for k in range(3):
            h0 |= _seg_tri(A[:, k], A[:, (k + 1) % 3], B[:, 0], B[:, 1], B[:, 2], tol)
            h0 |= _seg_tri(B[:, k], B[:, (k + 1) % 3], A[:, 0], A[:, 1], A[:, 2], tol)
        hit[m0] = h0
    # one shared vertex: the opposite edges
    m1 = np.flatnonzero(n_sh == 1)
    if len(m1):
        sa = shared[m1].any(axis=2)  # which corner of a is shared
        sb = shared[m1].any(axis=1)
        ka = np.argmax(sa, axis=1)
        kb = np.argmax(sb, axis=1)
        r = np.arange(len(m1))
        A, B = V[Fa[m1]], V[Fb[m1]]
        pa, qa = A[r, (ka + 1) % 3], A[r, (ka + 2) % 3]
        pb, qb = B[r, (kb + 1) % 3], B[r, (kb + 2) % 3]
        # strict parameters so the shared vertex itself does not count
        h1 = _seg_tri(pa, qa, B[:, 0], B[:, 1], B[:, 2], -tol)
        h1 |= _seg_tri(pb, qb, A[:, 0], A[:, 1], A[:, 2], -tol)
        hit[m1] = h1
    # shared edge: folded faces
    m2 = np.flatnonzero(n_sh == 2)
    if len(m2):
        na = np.cross(V[Fa[m2, 1]] - V[Fa[m2, 0]], V[Fa[m2, 2]] - V[Fa[m2, 0]])
        nb = np.cross(V[Fb[m2, 1]] - V[Fb[m2, 0]], V[Fb[m2, 2]] - V[Fb[m2, 0]])
        cosang = np.einsum("ij,ij->i", na, nb) / np.maximum(
            np.linalg.norm(na, axis=1) * np.linalg.norm(nb, axis=1), 1e-300)
        hit[m2] = cosang < -np.cos(np.radians(0.1))
    return hit


def self_intersections(V: np.ndarray, F: np.ndarray, faces: np.ndarray | None = None, *,
                       tol: float = 1e-9) -> np.ndarray:
    """Pairs of faces that intersect other than along their shared vertices or edge.

    Faces without a common vertex intersect when an edge of one crosses the other; faces sharing
    one vertex when the opposite edge of one crosses the other; faces sharing an edge when they
    are folded onto each other (dihedral angle within 0.1° of 180°). Candidate pairs come from a
    k-d tree on face centroids. Exactly coplanar overlaps of faces without a shared element are
    not detected (they do not occur in practice).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    faces : (q,) int, optional
        Only pairs involving at least one of these faces are tested (default: all faces).
    tol : float
        Relative tolerance of the barycentric and segment-parameter tests (touching counts).

    Returns
    -------
    (n, 2) int64 face index pairs, ``pairs[:, 0] < pairs[:, 1]``.
    """
    from scipy.spatial import cKDTree

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    q_faces = np.arange(len(F)) if faces is None else np.unique(np.asarray(faces, np.int64))
    if len(q_faces) == 0 or len(F) < 2:
        return np.empty((0, 2), np.int64)
    cen = V[F].mean(axis=1)
    rad = np.linalg.norm(V[F] - cen[:, None, :], axis=2).max(axis=1)
    # candidate pairs: centroids closer than the sum of the circumradii. Faces are put in classes
    # of radius within a factor 2, one k-d tree per class, each queried with the query face's
    # radius plus the class's largest: tight even when a few faces are much larger than the rest
    # (a coarse patch over a big hole made the single-radius search generate 10^7 candidates)
    med = max(float(np.median(rad)), 1e-300)
    cls = np.floor(np.log2(np.maximum(rad, 1e-300) / med)).astype(np.int64)
    cls = np.clip(cls, -8, None)
    qset = np.zeros(len(F), bool)
    qset[q_faces] = True
    classes = [(np.flatnonzero(cls == c)) for c in np.unique(cls)]
    trees = [(members, cKDTree(cen[members]), float(rad[members].max())) for members in classes]
    found = []
    # query faces in blocks, so the candidate pairs of one block (lists, tests) bound the memory
    for q0 in range(0, len(q_faces), QUERY_BLOCK):
        qb = q_faces[q0:q0 + QUERY_BLOCK]
        for members, tree, rmax in trees:
            lists = tree.query_ball_point(cen[qb], r=rad[qb] + rmax)
            counts = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(lists))
            if counts.sum() == 0:
                continue
            a = np.repeat(qb, counts)
            b = members[np.fromiter(itertools.chain.from_iterable(lists), dtype=np.int64,
                                    count=int(counts.sum()))]
            del lists
            # each (query face, face) pair is found once; a pair of two query faces twice
            keep = (a != b) & (~qset[b] | (a < b))
            a, b = np.minimum(a[keep], b[keep]), np.maximum(a[keep], b[keep])
            close = np.linalg.norm(cen[a] - cen[b], axis=1) <= rad[a] + rad[b]
            a, b = a[close], b[close]
            for s0 in range(0, len(a), PAIR_BLOCK):
                s1 = min(s0 + PAIR_BLOCK, len(a))
                hit = _pair_hits(V, F, a[s0:s1], b[s0:s1], tol)
                if hit.any():
                    found.append(np.c_[a[s0:s1][hit], b[s0:s1][hit]])
    if not found:
        return np.empty((0, 2), np.int64)
    pairs = np.concatenate(found).astype(np.int64)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
