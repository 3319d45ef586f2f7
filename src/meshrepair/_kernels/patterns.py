"""Sparse-pattern kernels of the set-up (one O(n) pass each, entries in the order scipy stores
them, so every later product is bit-equal): the symmetric pattern of an edge list and of sorted
edges, the stable order of index pairs, the face-side pattern, the umbrella entries, the
face-neighbour table and the pattern of a product. Each has a numpy twin with equal results
(``tests/test_kernels.py``)."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import HAVE_NUMBA, njit
from meshrepair._kernels.connectivity import _np_face_neighbour_table


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


def _np_face_side_csr(face_edges, edge_faces, ok):
    return _np_sym_csr(edge_faces[ok, 0], edge_faces[ok, 1], face_edges.shape[0], True)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_sort_small(buf, m):  # pragma: no cover - compiled
        """Sort ``buf[:m]`` ascending in place (insertion sort: m ≤ 4 here)."""
        for i in range(1, m):
            x = buf[i]
            j = i - 1
            while j >= 0 and buf[j] > x:
                buf[j + 1] = buf[j]
                j -= 1
            buf[j + 1] = x

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
            _nb_sort_small(buf, m)  # sorted, duplicates dropped
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
            _nb_sort_small(lo, a)
            _nb_sort_small(up, b)
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
