"""Connectivity kernels (setup of large meshes: one O(n) pass instead of sorts, scatters and
graph builds): half-edge grouping, union-find, the face-neighbour table of the solver, the
crease test of face pairs and Morton codes. Sparse patterns are in
:mod:`meshrepair._kernels.patterns`, per-element tables in :mod:`meshrepair._kernels.tables`.
Each has a numpy twin with equal results (``tests/test_kernels.py``)."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import HAVE_NUMBA, njit


def _np_group_halfedges(F, n_vertices):
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    code = np.minimum(he[:, 0], he[:, 1]) * np.int64(n_vertices) + np.maximum(he[:, 0], he[:, 1])
    return np.argsort(code, kind="stable")


def _np_union_find(n, a, b):
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    G = sp.coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(n, n))
    return connected_components(G.tocsr(), directed=False)[1].astype(np.int64)


def _np_morton(P, bits):
    lo = P.min(axis=0)
    span = max(float(np.ptp(P, axis=0).max()), 1e-300)
    q = ((P - lo) / span * (2**bits - 1)).astype(np.int64)
    code = np.zeros(len(P), np.int64)
    for b in range(bits):
        for d in range(3):
            code |= ((q[:, d] >> b) & 1) << (3 * b + d)
    return code


def _np_pair_order(lo, hi, n):
    return np.lexsort((hi, lo))


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_pair_order(lo, hi, n):  # pragma: no cover - compiled
        # counting sort by lo, then each bucket by hi (insertion sort; merge sort when long),
        # stably: the order of np.lexsort((hi, lo))
        m = lo.shape[0]
        start = np.zeros(n + 1, np.int64)
        for i in range(m):
            start[lo[i] + 1] += 1
        for v in range(n):
            start[v + 1] += start[v]
        pos = start[:-1].copy()
        order = np.empty(m, np.int64)
        for i in range(m):
            order[pos[lo[i]]] = i
            pos[lo[i]] += 1
        for v in range(n):
            s, e = start[v], start[v + 1]
            if e - s > 64:
                p = np.argsort(hi[order[s:e]], kind="mergesort")
                order[s:e] = order[s:e][p]
                continue
            for i in range(s + 1, e):
                h = order[i]
                key = hi[h]
                j = i - 1
                while j >= s and hi[order[j]] > key:
                    order[j + 1] = order[j]
                    j -= 1
                order[j + 1] = h
        return order


def pair_order(lo, hi, n):
    """The stable lexicographic order of the pairs ``(lo[i], hi[i])``, ``0 <= lo < n``: equal to
    ``np.lexsort((hi, lo))``, in O(len + n) for short buckets."""
    lo = np.ascontiguousarray(lo, dtype=np.int64)
    hi = np.ascontiguousarray(hi, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_pair_order(lo, hi, int(n))
    return _np_pair_order(lo, hi, int(n))


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_group_halfedges(F, n_vertices):  # pragma: no cover - compiled
        # the lower and upper vertex of each half-edge, then their stable pair order: the same
        # permutation as a stable argsort of lo * nV + hi
        nH = 3 * F.shape[0]
        lo = np.empty(nH, np.int64)
        hi = np.empty(nH, np.int64)
        for h in range(nH):
            f, k = h // 3, h % 3
            u, v = F[f, k], F[f, (k + 1) % 3]
            if u < v:
                lo[h], hi[h] = u, v
            else:
                lo[h], hi[h] = v, u
        return _nb_pair_order(lo, hi, n_vertices)

    @njit(cache=True)
    def _nb_edges_from_groups(F, order):  # pragma: no cover - compiled
        nH = order.shape[0]
        new = np.empty(nH, np.bool_)  # position i of the grouping starts a new edge
        n_e = 0
        plo, phi = -1, -1
        for i in range(nH):
            h = order[i]
            u, v = F[h // 3, h % 3], F[h // 3, (h % 3 + 1) % 3]
            lo, hi = min(u, v), max(u, v)
            new[i] = lo != plo or hi != phi
            if new[i]:
                n_e += 1
                plo, phi = lo, hi
        edges = np.empty((n_e, 2), np.int64)
        edge_he = np.full((n_e, 2), -1, np.int64)
        counts = np.zeros(n_e, np.int64)
        inv = np.empty(nH, np.int64)
        e = -1
        for i in range(nH):
            h = order[i]
            if new[i]:
                e += 1
                u, v = F[h // 3, h % 3], F[h // 3, (h % 3 + 1) % 3]
                edges[e, 0], edges[e, 1] = min(u, v), max(u, v)
                edge_he[e, 0] = h
            elif counts[e] == 1:
                edge_he[e, 1] = h
            counts[e] += 1
            inv[h] = e
        return edges, edge_he, inv, counts

    @njit(cache=True)
    def _nb_union(parent, x, y):  # pragma: no cover - compiled
        # the roots of x and y (path halving), the larger linked under the smaller: every
        # root is the smallest member of its set
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        while parent[y] != y:
            parent[y] = parent[parent[y]]
            y = parent[y]
        if x < y:
            parent[y] = x
        elif y < x:
            parent[x] = y

    @njit(cache=True)
    def _nb_union_find(n, a, b):  # pragma: no cover - compiled
        parent = np.arange(n)
        for i in range(a.shape[0]):
            _nb_union(parent, a[i], b[i])
        # roots are the smallest member: label components in order of their smallest member
        label = np.empty(n, np.int64)
        nc = 0
        for i in range(n):
            r = i
            while parent[r] != r:
                r = parent[r]
            parent[i] = r
            if r == i:
                label[i] = nc
                nc += 1
            else:
                label[i] = label[r]
        return label

    @njit(cache=True)
    def _nb_face_neighbour_table(fa, fb, n_faces):  # pragma: no cover - compiled
        nb = np.full((n_faces, 3), -1, np.int64)
        fe = np.full((n_faces, 3), -1, np.int64)
        fill = np.zeros(n_faces, np.int64)
        for side in range(2):  # all (fa -> fb) entries first, then (fb -> fa), edges ascending
            for e in range(fa.shape[0]):
                f, g = (fa[e], fb[e]) if side == 0 else (fb[e], fa[e])
                if fill[f] == 3:
                    return nb, fe, False
                nb[f, fill[f]] = g
                fe[f, fill[f]] = e
                fill[f] += 1
        return nb, fe, True

    @njit(cache=True)
    def _nb_creased(N, fa, fb, cos_th):  # pragma: no cover - compiled
        out = np.empty(fa.shape[0], np.bool_)
        for e in range(fa.shape[0]):
            a, b = fa[e], fb[e]
            out[e] = N[a, 0] * N[b, 0] + N[a, 1] * N[b, 1] + N[a, 2] * N[b, 2] < cos_th
        return out

    @njit(cache=True)
    def _nb_morton(P, bits):  # pragma: no cover - compiled
        n = P.shape[0]
        lo0, lo1, lo2 = P[0, 0], P[0, 1], P[0, 2]
        hi0, hi1, hi2 = lo0, lo1, lo2
        for i in range(n):
            lo0, hi0 = min(lo0, P[i, 0]), max(hi0, P[i, 0])
            lo1, hi1 = min(lo1, P[i, 1]), max(hi1, P[i, 1])
            lo2, hi2 = min(lo2, P[i, 2]), max(hi2, P[i, 2])
        span = max(max(hi0 - lo0, hi1 - lo1), max(hi2 - lo2, 1e-300))
        K = (1 << bits) - 1
        code = np.zeros(n, np.int64)
        for i in range(n):
            q0 = np.int64((P[i, 0] - lo0) / span * K)
            q1 = np.int64((P[i, 1] - lo1) / span * K)
            q2 = np.int64((P[i, 2] - lo2) / span * K)
            c = np.int64(0)
            for b in range(bits):
                c |= ((q0 >> b) & 1) << (3 * b)
                c |= ((q1 >> b) & 1) << (3 * b + 1)
                c |= ((q2 >> b) & 1) << (3 * b + 2)
            code[i] = c
        return code


def group_halfedges(F, n_vertices):
    """Half-edges ``3 f + k`` (``F[f, k] -> F[f, (k + 1) % 3]``) sorted by their undirected edge
    ``(min, max)``, ties in index order: equal to a stable argsort of ``min * nV + max``."""
    F = np.ascontiguousarray(F, dtype=np.int64)
    if F.size and (int(F.min()) < 0 or int(F.max()) >= n_vertices):
        raise ValueError("face indices out of range [0, n_vertices)")
    if HAVE_NUMBA:
        return _nb_group_halfedges(F, int(n_vertices))
    return _np_group_halfedges(F, n_vertices)


def edges_from_groups(F, order):
    """Unique edges ``(nE, 2)``, their first two half-edges ``3 f + k`` ``(nE, 2)`` (-1 if
    absent), the edge of every half-edge ``(3 nF,)`` and the face count of every edge, from the
    grouping of :func:`group_halfedges`."""
    if HAVE_NUMBA:
        return _nb_edges_from_groups(np.ascontiguousarray(F, dtype=np.int64), order)
    return _np_edges_from_groups(F, order)


def _np_edges_from_groups(F, order):
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    key = np.sort(he, axis=1)
    ks = key[order]
    new = np.empty(len(order), dtype=bool)
    new[:1] = True
    new[1:] = (ks[1:, 0] != ks[:-1, 0]) | (ks[1:, 1] != ks[:-1, 1])
    starts = np.flatnonzero(new)
    counts = np.diff(np.append(starts, len(order)))
    inv = np.empty(len(order), dtype=np.int64)
    inv[order] = np.cumsum(new) - 1
    first = order[starts]
    edge_he = np.full((len(starts), 2), -1, dtype=np.int64)
    edge_he[:, 0] = first
    two = counts >= 2
    edge_he[two, 1] = order[starts[two] + 1]
    return key[first], edge_he, inv, counts


def union_find(n, a, b):
    """Component label of each of ``n`` nodes linked by pairs ``(a[i], b[i])``; labels number the
    components in order of their smallest node (as scipy's ``connected_components``)."""
    a = np.ascontiguousarray(a, dtype=np.int64)
    b = np.ascontiguousarray(b, dtype=np.int64)
    if a.size and (min(int(a.min()), int(b.min())) < 0 or max(int(a.max()), int(b.max())) >= n):
        raise ValueError("node indices out of range [0, n)")
    if HAVE_NUMBA:
        return _nb_union_find(int(n), a, b)
    return _np_union_find(int(n), a, b)


def _np_face_neighbour_table(fa, fb, n_faces):
    src = np.r_[fa, fb]
    order = np.argsort(src, kind="stable")
    s_sorted = src[order]
    counts = np.bincount(s_sorted, minlength=n_faces)
    if len(order) and counts.max() > 3:
        return None, None, False
    starts = np.cumsum(counts) - counts
    slot = np.arange(len(order)) - np.repeat(starts, counts)
    nb = np.full((n_faces, 3), -1, dtype=np.int64)
    fe = np.full((n_faces, 3), -1, dtype=np.int64)
    nb[s_sorted, slot] = np.r_[fb, fa][order]
    fe[s_sorted, slot] = np.r_[np.arange(len(fa)), np.arange(len(fa))][order]
    return nb, fe, True


def face_neighbour_table(fa, fb, n_faces):
    """Per-face neighbours ``nb (nF, 3)`` across interior edges ``(fa[e], fb[e])`` and the edge
    ``fe (nF, 3)`` of each, ``-1`` padded; in the order of a stable sort of ``np.r_[fa, fb]``."""
    fa = np.ascontiguousarray(fa, dtype=np.int64)
    fb = np.ascontiguousarray(fb, dtype=np.int64)
    f = _nb_face_neighbour_table if HAVE_NUMBA else _np_face_neighbour_table
    nb, fe, ok = f(fa, fb, int(n_faces))
    if not ok:  # pragma: no cover - impossible for triangles
        raise ValueError("a face has more than three interior edges")
    return nb, fe


def creased(N, fa, fb, th_degrees):
    """Interior edges whose dihedral angle exceeds ``th_degrees``: ``<N[fa], N[fb]> < cos th``."""
    cos_th = float(np.cos(np.radians(th_degrees)))
    if HAVE_NUMBA:
        return _nb_creased(N, fa, fb, cos_th)
    return np.einsum("ij,ij->i", N[fa], N[fb]) < cos_th


def morton(P, bits=16):
    """Morton (Z-order) code of each point of ``P (n, 3)`` on a ``2**bits`` grid."""
    P = np.ascontiguousarray(P, dtype=np.float64)
    if HAVE_NUMBA:
        return _nb_morton(P, bits)
    return _np_morton(P, bits)
