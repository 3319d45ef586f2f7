"""Connectivity kernels (setup of large meshes: one O(n) pass instead of sorts, scatters and
graph builds): half-edge grouping and edge tables, the tables of a renumbered mesh, union-find
and fans, face-neighbour tables, sparse patterns (symmetric, of sorted edges, of face sides, of a
product in scipy's order), the umbrella entries, crease test and ring growth, duplicate rows,
Morton codes and renumbered faces. Each has a numpy twin with equal results
(``tests/test_kernels.py``)."""

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


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_group_halfedges(F, n_vertices):  # pragma: no cover - compiled
        # bucket the half-edges by their lower vertex (counting sort), then sort each bucket by
        # the upper vertex, stably: the same permutation as a stable argsort of lo * nV + hi
        nH = 3 * F.shape[0]
        lo = np.empty(nH, np.int64)
        hi = np.empty(nH, np.int64)
        start = np.zeros(n_vertices + 1, np.int64)
        for h in range(nH):
            f, k = h // 3, h % 3
            u, v = F[f, k], F[f, (k + 1) % 3]
            if u < v:
                lo[h], hi[h] = u, v
            else:
                lo[h], hi[h] = v, u
            start[lo[h] + 1] += 1
        for i in range(n_vertices):
            start[i + 1] += start[i]
        pos = start[:-1].copy()
        order = np.empty(nH, np.int64)
        for h in range(nH):
            order[pos[lo[h]]] = h
            pos[lo[h]] += 1
        for v in range(n_vertices):
            s, e = start[v], start[v + 1]
            if e - s > 64:  # a high-valence vertex: stable merge sort of the bucket
                keys = hi[order[s:e]]
                p = np.argsort(keys, kind="mergesort")
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
    def _nb_union_find(n, a, b):  # pragma: no cover - compiled
        parent = np.arange(n)
        for i in range(a.shape[0]):
            x, y = a[i], b[i]
            while parent[x] != x:
                parent[x] = parent[parent[x]]
                x = parent[x]
            while parent[y] != y:
                parent[y] = parent[parent[y]]
                y = parent[y]
            if x != y:
                if x < y:
                    parent[y] = x
                else:
                    parent[x] = y
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
        K = 2**bits - 1
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


def _np_sym_csr(a, b, n, diag):
    import scipy.sparse as sp

    r = np.r_[a, b, np.arange(n)] if diag else np.r_[a, b]
    c = np.r_[b, a, np.arange(n)] if diag else np.r_[b, a]
    M = sp.coo_matrix((np.ones(len(r)), (r, c)), shape=(n, n)).tocsr()
    M.sum_duplicates()
    return M.indptr.astype(np.int64), M.indices.astype(np.int64)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_sym_csr(a, b, n, diag):  # pragma: no cover - compiled
        cnt = np.zeros(n + 1, np.int64)
        for i in range(a.shape[0]):
            cnt[a[i] + 1] += 1
            cnt[b[i] + 1] += 1
        if diag:
            for v in range(n):
                cnt[v + 1] += 1
        for v in range(n):
            cnt[v + 1] += cnt[v]
        fill = cnt[:-1].copy()
        idx = np.empty(cnt[n], np.int64)
        for i in range(a.shape[0]):
            idx[fill[a[i]]] = b[i]
            fill[a[i]] += 1
            idx[fill[b[i]]] = a[i]
            fill[b[i]] += 1
        if diag:
            for v in range(n):
                idx[fill[v]] = v
                fill[v] += 1
        # each row sorted (insertion sort: rows are short), duplicates dropped
        indptr = np.empty(n + 1, np.int64)
        indptr[0] = 0
        k = 0
        for v in range(n):
            s, t = cnt[v], cnt[v + 1]
            for i in range(s + 1, t):
                x = idx[i]
                j = i - 1
                while j >= s and idx[j] > x:
                    idx[j + 1] = idx[j]
                    j -= 1
                idx[j + 1] = x
            for i in range(s, t):
                if i == s or idx[i] != idx[i - 1]:
                    idx[k] = idx[i]
                    k += 1
            indptr[v + 1] = k
        return indptr, idx[:k].copy()


def sym_csr(a, b, n, diag=False):
    """The pattern ``(indptr, indices)`` of the symmetric ``n × n`` matrix with an entry at
    ``(a_i, b_i)`` and ``(b_i, a_i)`` (and ``(v, v)`` with ``diag``): rows sorted, duplicates
    merged, the canonical CSR scipy makes of the same entries, in one O(nnz) pass."""
    a = np.ascontiguousarray(a, dtype=np.int64)
    b = np.ascontiguousarray(b, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_sym_csr(a, b, int(n), bool(diag))
    return _np_sym_csr(a, b, int(n), bool(diag))


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


def _end_corner(h):
    """The next corner of the same face: the end of half-edge ``h = 3 f + k``."""
    return np.where(h % 3 == 2, h - 2, h + 1)


def _np_fan_counts(F, h1, h2, n_vertices):
    corner_vertex = F.ravel()
    # consistent orientation: h1 = u -> w, h2 = w -> u; link the corners of u, and of w
    a = np.concatenate([h1, _end_corner(h1)])
    b = np.concatenate([_end_corner(h2), h2])
    labels = _np_union_find(3 * F.shape[0], a, b)
    n_groups = int(labels.max()) + 1 if len(labels) else 0
    group_vertex = np.empty(n_groups, dtype=np.int64)
    group_vertex[labels] = corner_vertex
    return np.bincount(group_vertex, minlength=n_vertices)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_fan_counts(F, h1, h2, n_vertices):  # pragma: no cover - compiled
        n = 3 * F.shape[0]
        parent = np.arange(n)
        for i in range(h1.shape[0]):
            u1, w1 = h1[i], h1[i] - 2 if h1[i] % 3 == 2 else h1[i] + 1
            w2, u2 = h2[i], h2[i] - 2 if h2[i] % 3 == 2 else h2[i] + 1
            for t in range(2):
                x, y = (u1, u2) if t == 0 else (w1, w2)
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
        fans = np.zeros(n_vertices, np.int64)
        for c in range(n):
            if parent[c] == c:  # one root per group of corners
                fans[F[c // 3, c % 3]] += 1
        return fans


def fan_counts(F, h1, h2, n_vertices):
    """Number of fans at every vertex: the groups of its face corners linked across the
    interior edges, whose two half-edges ``3 f + k`` (``F[f, k] -> F[f, (k + 1) % 3]``, opposite
    directions) are ``h1[i]``, ``h2[i]``; ``(n_vertices,)`` int64, 0 for unreferenced vertices."""
    F = np.ascontiguousarray(F, dtype=np.int64)
    h1 = np.ascontiguousarray(h1, dtype=np.int64)
    h2 = np.ascontiguousarray(h2, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_fan_counts(F, h1, h2, int(n_vertices))
    return _np_fan_counts(F, h1, h2, int(n_vertices))


def _np_face_side_csr(face_edges, edge_faces, ok):
    return _np_sym_csr(edge_faces[ok, 0], edge_faces[ok, 1], face_edges.shape[0], True)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_face_side_csr(face_edges, edge_faces, ok):  # pragma: no cover - compiled
        nF = face_edges.shape[0]
        indptr = np.empty(nF + 1, np.int64)
        idx = np.empty(4 * nF, np.int64)
        buf = np.empty(4, np.int64)
        k = 0
        for f in range(nF):
            indptr[f] = k
            buf[0] = f
            m = 1
            for s in range(3):
                e = face_edges[f, s]
                if ok[e]:
                    g = edge_faces[e, 0]
                    buf[m] = edge_faces[e, 1] if g == f else g
                    m += 1
            for i in range(1, m):  # sorted, duplicates dropped
                x = buf[i]
                j = i - 1
                while j >= 0 and buf[j] > x:
                    buf[j + 1] = buf[j]
                    j -= 1
                buf[j + 1] = x
            for i in range(m):
                if i == 0 or buf[i] != buf[i - 1]:
                    idx[k] = buf[i]
                    k += 1
        indptr[nF] = k
        return indptr, idx[:k].copy()


def face_side_csr(face_edges, edge_faces, ok):
    """The pattern ``(indptr, indices)`` of ``I + A``, A the face adjacency across the edges
    of ``ok`` (interior edges with two faces): :func:`sym_csr` of their face pairs with the
    diagonal, built per face from its three edges (each face's row directly, no scatter).
    ``face_edges`` and ``edge_faces`` are a :class:`~meshrepair.mesh.topology.Topology`'s
    whose edges have at most two faces."""
    face_edges = np.ascontiguousarray(face_edges, dtype=np.int64)
    edge_faces = np.ascontiguousarray(edge_faces, dtype=np.int64)
    ok = np.ascontiguousarray(ok, dtype=np.bool_)
    if HAVE_NUMBA:
        return _nb_face_side_csr(face_edges, edge_faces, ok)
    return _np_face_side_csr(face_edges, edge_faces, ok)


def _np_permuted_edges(edges, edge_faces, face_edges, counts, inv, pf):
    a, b = inv[edges[:, 0]], inv[edges[:, 1]]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    pe = _np_pair_order(lo, hi, len(inv))
    enew = np.empty(len(pe), np.int64)
    enew[pe] = np.arange(len(pe))
    finv = np.empty(len(pf), np.int64)
    finv[pf] = np.arange(len(pf))
    ef = edge_faces[pe]
    f0 = finv[ef[:, 0]]
    f1 = np.where(ef[:, 1] >= 0, finv[np.maximum(ef[:, 1], 0)], -1)
    two = f1 >= 0
    ef_new = np.stack([np.where(two, np.minimum(f0, f1), f0), np.where(two, np.maximum(f0, f1),
                                                                        -1)], axis=1)
    return (np.stack([lo[pe], hi[pe]], axis=1), ef_new, enew[face_edges[pf]], counts[pe])


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_permuted_edges(edges, edge_faces, face_edges, counts, inv,
                           pf):  # pragma: no cover - compiled
        nE, nF = edges.shape[0], pf.shape[0]
        lo = np.empty(nE, np.int64)
        hi = np.empty(nE, np.int64)
        for e in range(nE):
            a, b = inv[edges[e, 0]], inv[edges[e, 1]]
            lo[e], hi[e] = min(a, b), max(a, b)
        pe = _nb_pair_order(lo, hi, inv.shape[0])
        finv = np.empty(nF, np.int64)
        for m in range(nF):
            finv[pf[m]] = m
        enew = np.empty(nE, np.int64)
        e_out = np.empty((nE, 2), np.int64)
        ef_out = np.empty((nE, 2), np.int64)
        c_out = np.empty(nE, np.int64)
        for i in range(nE):
            e = pe[i]
            enew[e] = i
            e_out[i, 0], e_out[i, 1] = lo[e], hi[e]
            f0 = finv[edge_faces[e, 0]]
            if edge_faces[e, 1] >= 0:
                f1 = finv[edge_faces[e, 1]]
                ef_out[i, 0], ef_out[i, 1] = min(f0, f1), max(f0, f1)
            else:
                ef_out[i, 0], ef_out[i, 1] = f0, -1
            c_out[i] = counts[e]
        fe_out = np.empty((nF, 3), np.int64)
        for m in range(nF):
            for k in range(3):
                fe_out[m, k] = enew[face_edges[pf[m], k]]
        return e_out, ef_out, fe_out, c_out


def permuted_edges(edges, edge_faces, face_edges, counts, inv, pf):
    """A topology's edge tables after renumbering its vertices (new vertex ``inv[v]`` is old
    vertex ``v``) and reordering its faces (new face ``m`` is old face ``pf[m]``, corners in the
    same order): ``(edges, edge_faces, face_edges, counts)`` as ``edge_topology`` builds them
    for the new faces when no edge has more than two faces (edges sorted by their new vertex
    pair, an interior edge's faces ascending), from the old tables instead of the half-edges."""
    args = [np.ascontiguousarray(x, dtype=np.int64)
            for x in (edges, edge_faces, face_edges, counts, inv, pf)]
    if HAVE_NUMBA:
        return _nb_permuted_edges(*args)
    return _np_permuted_edges(*args)


def _np_duplicate_rows(bits):
    h = (bits[:, 0] * np.uint64(0x9E3779B97F4A7C15)) ^ (
        bits[:, 1] * np.uint64(0xC2B2AE3D27D4EB4F)) ^ (bits[:, 2] * np.uint64(0x165667B19E3779F9))
    order = np.argsort(h, kind="stable")
    hs = h[order]
    same = hs[1:] == hs[:-1]
    if not same.any():
        return np.empty(0, dtype=np.int64)
    cand_mask = np.zeros(len(hs), dtype=bool)
    cand_mask[1:] |= same
    cand_mask[:-1] |= same
    cand = np.sort(order[cand_mask])
    rows = np.ascontiguousarray(bits[cand]).view(np.dtype((np.void, 24))).ravel()
    _, first = np.unique(rows, return_index=True)
    is_first = np.zeros(len(cand), dtype=bool)
    is_first[first] = True  # np.unique returns the first occurrence; cand is ascending
    return cand[~is_first]


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_duplicate_rows(bits):  # pragma: no cover - compiled
        n = bits.shape[0]
        size = 1
        while size < 2 * n:
            size *= 2
        mask = np.uint64(size - 1)
        table = np.full(size, -1, np.int64)  # open addressing, linear probing
        dup = np.zeros(n, np.bool_)
        for i in range(n):
            h = (bits[i, 0] * np.uint64(0x9E3779B97F4A7C15)) ^ (
                bits[i, 1] * np.uint64(0xC2B2AE3D27D4EB4F)) ^ (
                bits[i, 2] * np.uint64(0x165667B19E3779F9))
            s = (h ^ (h >> np.uint64(29))) & mask
            while True:
                j = table[s]
                if j < 0:
                    table[s] = i
                    break
                if bits[j, 0] == bits[i, 0] and bits[j, 1] == bits[i, 1] and \
                        bits[j, 2] == bits[i, 2]:
                    dup[i] = True
                    break
                s = (s + np.uint64(1)) & mask
        return np.flatnonzero(dup)


def duplicate_rows(bits):
    """Ascending indices of the rows of ``bits`` ``(n, 3)`` uint64 equal to an earlier row."""
    bits = np.ascontiguousarray(bits, dtype=np.uint64)
    if HAVE_NUMBA:
        return _nb_duplicate_rows(bits)
    return _np_duplicate_rows(bits)


def _np_creased_edges(N, edge_faces, cos_th):
    ie = np.flatnonzero(edge_faces[:, 1] >= 0)
    m = np.zeros(len(edge_faces), bool)
    m[ie] = np.einsum("ij,ij->i", N[edge_faces[ie, 0]], N[edge_faces[ie, 1]]) < cos_th
    return m


def _np_grow(act, e):
    out = act.copy()
    out[e[act[e[:, 0]], 1]] = True
    out[e[act[e[:, 1]], 0]] = True
    return out


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_creased_edges(N, edge_faces, cos_th):  # pragma: no cover - compiled
        out = np.zeros(edge_faces.shape[0], np.bool_)
        for e in range(edge_faces.shape[0]):
            a, b = edge_faces[e, 0], edge_faces[e, 1]
            if b >= 0:
                out[e] = N[a, 0] * N[b, 0] + N[a, 1] * N[b, 1] + N[a, 2] * N[b, 2] < cos_th
        return out

    @njit(cache=True)
    def _nb_grow(act, e):  # pragma: no cover - compiled
        out = act.copy()
        for i in range(e.shape[0]):
            a, b = e[i, 0], e[i, 1]
            if act[a]:
                out[b] = True
            if act[b]:
                out[a] = True
        return out


def creased_edges(N, edge_faces, th_degrees):
    """``(nE,) bool``: the edges with two faces (``edge_faces[:, 1] >= 0``) whose normals ``N``
    differ by more than ``th_degrees``: :func:`creased` over every interior edge, one pass."""
    cos_th = float(np.cos(np.radians(th_degrees)))
    N = np.ascontiguousarray(N, dtype=np.float64)
    edge_faces = np.ascontiguousarray(edge_faces, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_creased_edges(N, edge_faces, cos_th)
    return _np_creased_edges(N, edge_faces, cos_th)


def grow(act, e):
    """``act`` ``(nV,) bool`` and the vertices one edge of ``e`` ``(k, 2)`` away from it."""
    act = np.ascontiguousarray(act, dtype=np.bool_)
    e = np.ascontiguousarray(e, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_grow(act, e)
    return _np_grow(act, e)


def _np_umbrella_entries(indptr, indices):
    deg = np.diff(indptr)
    row = np.repeat(np.arange(len(deg)), deg)
    # entry k of row r is entry indptr[r] + indptr[r + 1] - 1 - k of A: rows reversed
    src = (indptr[:-1] + indptr[1:] - 1)[row] - np.arange(len(row))
    return np.repeat(1.0 / np.maximum(deg, 1.0), deg), indices[src]


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_umbrella_entries(indptr, indices):  # pragma: no cover - compiled
        n = indptr.shape[0] - 1
        data = np.empty(indices.shape[0])
        out = np.empty_like(indices)
        for r in range(n):
            s, e = indptr[r], indptr[r + 1]
            w = 1.0 / max(float(e - s), 1.0)
            for k in range(e - s):
                data[s + k] = w
                out[s + k] = indices[e - 1 - k]
        return data, out


def umbrella_entries(indptr, indices):
    """The values ``1 / deg`` and the column indices, each row reversed, of ``W = D⁻¹A`` for the
    CSR pattern ``(indptr, indices)`` of A (the storage of
    :func:`meshrepair.mesh.topology.umbrella_operator`)."""
    if HAVE_NUMBA:
        return _nb_umbrella_entries(np.asarray(indptr), np.asarray(indices))
    return _np_umbrella_entries(np.asarray(indptr), np.asarray(indices))


def _np_edge_tables(F, n_vertices):
    return _np_edges_from_groups(F, _np_group_halfedges(F, n_vertices))


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_edge_tables(F, n_vertices):  # pragma: no cover - compiled
        # the grouping of _nb_group_halfedges carrying each half-edge's upper vertex along (the
        # buckets and the edge scan then read it in order, not through F), then the tables of
        # _nb_edges_from_groups
        nF = F.shape[0]
        nH = 3 * nF
        lo = np.empty(nH, np.int64)
        hi = np.empty(nH, np.int64)
        start = np.zeros(n_vertices + 1, np.int64)
        for f in range(nF):
            for k in range(3):
                u, v = F[f, k], F[f, k + 1 if k < 2 else 0]
                h = 3 * f + k
                if u < v:
                    lo[h], hi[h] = u, v
                else:
                    lo[h], hi[h] = v, u
                start[lo[h] + 1] += 1
        for i in range(n_vertices):
            start[i + 1] += start[i]
        pos = start[:-1].copy()
        order = np.empty(nH, np.int64)
        key = np.empty(nH, np.int64)
        for h in range(nH):
            p = pos[lo[h]]
            order[p] = h
            key[p] = hi[h]
            pos[lo[h]] += 1
        n_e = 0
        for v in range(n_vertices):
            s, e = start[v], start[v + 1]
            if e - s > 64:  # a high-valence vertex: stable merge sort of the bucket
                p = np.argsort(key[s:e], kind="mergesort")
                order[s:e] = order[s:e][p]
                key[s:e] = key[s:e][p]
            else:
                for i in range(s + 1, e):
                    h, kk = order[i], key[i]
                    j = i - 1
                    while j >= s and key[j] > kk:
                        order[j + 1] = order[j]
                        key[j + 1] = key[j]
                        j -= 1
                    order[j + 1] = h
                    key[j + 1] = kk
            for i in range(s, e):
                if i == s or key[i] != key[i - 1]:
                    n_e += 1
        edges = np.empty((n_e, 2), np.int64)
        edge_he = np.full((n_e, 2), -1, np.int64)
        counts = np.zeros(n_e, np.int64)
        inv = np.empty(nH, np.int64)
        c = -1
        for v in range(n_vertices):
            for i in range(start[v], start[v + 1]):
                h = order[i]
                if i == start[v] or key[i] != key[i - 1]:
                    c += 1
                    edges[c, 0], edges[c, 1] = v, key[i]
                    edge_he[c, 0] = h
                elif counts[c] == 1:
                    edge_he[c, 1] = h
                counts[c] += 1
                inv[h] = c
        return edges, edge_he, inv, counts


def edge_tables(F, n_vertices):
    """``edges_from_groups(F, group_halfedges(F, n_vertices))`` in one compiled pass: the
    unique edges, their first two half-edges, the edge of every half-edge and the face count
    of every edge."""
    F = np.ascontiguousarray(F, dtype=np.int64)
    if F.size and (int(F.min()) < 0 or int(F.max()) >= n_vertices):
        raise ValueError("face indices out of range [0, n_vertices)")
    if HAVE_NUMBA:
        return _nb_edge_tables(F, int(n_vertices))
    return _np_edge_tables(F, int(n_vertices))


def _np_interior_edges(edges, edge_faces):
    ie = np.flatnonzero(edge_faces[:, 1] >= 0)
    return (ie, np.ascontiguousarray(edges[ie]), np.ascontiguousarray(edge_faces[ie, 0]),
            np.ascontiguousarray(edge_faces[ie, 1]))


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_interior_edges(edges, edge_faces):  # pragma: no cover - compiled
        n = 0
        for e in range(edge_faces.shape[0]):
            if edge_faces[e, 1] >= 0:
                n += 1
        ie = np.empty(n, np.int64)
        E = np.empty((n, 2), np.int64)
        fa = np.empty(n, np.int64)
        fb = np.empty(n, np.int64)
        i = 0
        for e in range(edge_faces.shape[0]):
            if edge_faces[e, 1] >= 0:
                ie[i] = e
                E[i, 0], E[i, 1] = edges[e, 0], edges[e, 1]
                fa[i], fb[i] = edge_faces[e, 0], edge_faces[e, 1]
                i += 1
        return ie, E, fa, fb


def interior_edges(edges, edge_faces):
    """The interior edges (``edge_faces[:, 1] >= 0``) ascending, their vertex pairs and their
    two faces: ``(ie, edges[ie], edge_faces[ie, 0], edge_faces[ie, 1])``, contiguous."""
    edges = np.ascontiguousarray(edges, dtype=np.int64)
    edge_faces = np.ascontiguousarray(edge_faces, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_interior_edges(edges, edge_faces)
    return _np_interior_edges(edges, edge_faces)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_sorted_edge_csr(edges, n):  # pragma: no cover - compiled
        # edges unique, lo < hi, in lexicographic order: row v is the lower ends of the edges
        # whose upper end is v (in edge order: ascending), then the upper ends of its own edges
        # (one contiguous block: ascending); no sort, one scattered write per edge
        m = edges.shape[0]
        for e in range(m):
            if edges[e, 0] >= edges[e, 1] or (e > 0 and (
                    edges[e, 0] < edges[e - 1, 0] or (edges[e, 0] == edges[e - 1, 0]
                                                      and edges[e, 1] <= edges[e - 1, 1]))):
                return np.zeros(n + 1, np.int64), np.zeros(0, np.int64), False
        n_hi = np.zeros(n, np.int64)
        n_lo = np.zeros(n, np.int64)
        for e in range(m):
            n_lo[edges[e, 0]] += 1
            n_hi[edges[e, 1]] += 1
        indptr = np.empty(n + 1, np.int64)
        indptr[0] = 0
        for v in range(n):
            indptr[v + 1] = indptr[v] + n_lo[v] + n_hi[v]
        fill = indptr[:-1].copy()
        idx = np.empty(2 * m, np.int64)
        for e in range(m):
            b = edges[e, 1]
            idx[fill[b]] = edges[e, 0]
            fill[b] += 1
        e = 0
        for v in range(n):
            for k in range(n_lo[v]):
                idx[fill[v] + k] = edges[e + k, 1]
            e += n_lo[v]
        return indptr, idx, True


def edge_csr(edges, n):
    """``sym_csr(edges[:, 0], edges[:, 1], n)`` for the edges of a
    :class:`~meshrepair.mesh.topology.Topology` (unique, ``lo < hi``, lexicographic order: the
    rows come out sorted without a sort); any other ``edges`` go to :func:`sym_csr`."""
    edges = np.ascontiguousarray(edges, dtype=np.int64)
    if HAVE_NUMBA:
        indptr, idx, ok = _nb_sorted_edge_csr(edges, int(n))
        if ok:
            return indptr, idx
    return sym_csr(edges[:, 0], edges[:, 1], n)


def _np_renumbered_faces(F, inv, pf):
    return inv[F][pf]


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_renumbered_faces(F, inv, pf):  # pragma: no cover - compiled
        out = np.empty((pf.shape[0], 3), np.int64)
        for m in range(pf.shape[0]):
            f = pf[m]
            out[m, 0], out[m, 1], out[m, 2] = inv[F[f, 0]], inv[F[f, 1]], inv[F[f, 2]]
        return out


def renumbered_faces(F, inv, pf):
    """``inv[F][pf]``: the faces in the order ``pf``, vertex ``v`` renumbered ``inv[v]``."""
    F = np.ascontiguousarray(F, dtype=np.int64)
    inv = np.ascontiguousarray(inv, dtype=np.int64)
    pf = np.ascontiguousarray(pf, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_renumbered_faces(F, inv, pf)
    return _np_renumbered_faces(F, inv, pf)


def _np_face_neighbours(face_edges, edge_faces):
    inner = edge_faces[:, 1] >= 0
    return _np_face_neighbour_table(edge_faces[inner, 0], edge_faces[inner, 1],
                                    face_edges.shape[0])[:2]


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_face_neighbours(face_edges, edge_faces):  # pragma: no cover - compiled
        # per face from its three edges: first the interior edges where it is the lower face,
        # then those where it is the upper one, each ascending (the order of
        # _nb_face_neighbour_table's two passes), no scattered writes
        nE, nF = edge_faces.shape[0], face_edges.shape[0]
        pos = np.full(nE, -1, np.int64)
        n = 0
        for e in range(nE):
            if edge_faces[e, 1] >= 0:
                pos[e] = n
                n += 1
        nb = np.full((nF, 3), -1, np.int64)
        fe = np.full((nF, 3), -1, np.int64)
        lo = np.empty(3, np.int64)
        up = np.empty(3, np.int64)
        for f in range(nF):
            a = b = 0
            for k in range(3):
                e = face_edges[f, k]
                if pos[e] >= 0:
                    if edge_faces[e, 0] == f:
                        lo[a] = e
                        a += 1
                    else:
                        up[b] = e
                        b += 1
            for i in range(1, a):
                x = lo[i]
                j = i - 1
                while j >= 0 and lo[j] > x:
                    lo[j + 1] = lo[j]
                    j -= 1
                lo[j + 1] = x
            for i in range(1, b):
                x = up[i]
                j = i - 1
                while j >= 0 and up[j] > x:
                    up[j + 1] = up[j]
                    j -= 1
                up[j + 1] = x
            for i in range(a):
                nb[f, i] = edge_faces[lo[i], 1]
                fe[f, i] = pos[lo[i]]
            for i in range(b):
                nb[f, a + i] = edge_faces[up[i], 0]
                fe[f, a + i] = pos[up[i]]
        return nb, fe


def face_neighbours(face_edges, edge_faces):
    """:func:`face_neighbour_table` of the interior edges of a topology whose edges have at
    most two faces (``edge_faces[:, 1] >= 0``; ``fe`` indexes the interior edges in order),
    gathered per face from its three edges."""
    face_edges = np.ascontiguousarray(face_edges, dtype=np.int64)
    edge_faces = np.ascontiguousarray(edge_faces, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_face_neighbours(face_edges, edge_faces)
    return _np_face_neighbours(face_edges, edge_faces)


def _np_product_pattern(ap, aj, bp, bj, n_col, work):
    import scipy.sparse as sp

    A = sp.csr_matrix((np.ones(len(aj)), aj, ap), shape=(len(ap) - 1, n_col))
    B = sp.csr_matrix((np.ones(len(bj)), bj, bp), shape=(n_col, n_col))
    C = A @ B
    return C.indptr.astype(np.int64), C.indices.astype(np.int64)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_product_pattern(ap, aj, bp, bj, n_col, work):  # pragma: no cover - compiled
        # scipy's csr_matmat (SMMP) on positive values: per row, the columns in the reverse
        # order of their first appearance; ``work`` (n_col,) all -1, left so
        n_row = ap.shape[0] - 1
        cap = 0
        for jj in range(ap[n_row]):
            cap += bp[aj[jj] + 1] - bp[aj[jj]]
        cp = np.empty(n_row + 1, np.int64)
        cj = np.empty(cap, np.int64)
        cp[0] = 0
        nnz = 0
        for i in range(n_row):
            head = -2
            length = 0
            for jj in range(ap[i], ap[i + 1]):
                j = aj[jj]
                for kk in range(bp[j], bp[j + 1]):
                    k = bj[kk]
                    if work[k] == -1:
                        work[k] = head
                        head = k
                        length += 1
            for _ in range(length):
                cj[nnz] = head
                nnz += 1
                t = head
                head = work[head]
                work[t] = -1
            cp[i + 1] = nnz
        return cp, cj[:nnz].copy()


def product_pattern(ap, aj, bp, bj, n_col, work=None):
    """The pattern ``(indptr, indices)`` of the product of two CSR patterns with positive
    values, ``A (n × n_col) @ B (n_col × n_col)``, in the order scipy's product stores it (so
    sums over its rows add in the same order). ``work``: an ``(n_col,)`` int64 array of -1 to
    reuse across calls (returned so)."""
    if work is None:
        work = np.full(int(n_col), -1, np.int64)
    args = [np.asarray(x) for x in (ap, aj, bp, bj)]  # (int32 or int64: scipy's, unconverted)
    if HAVE_NUMBA:
        return _nb_product_pattern(*args, int(n_col), work)
    return _np_product_pattern(*args, int(n_col), work)
