"""Per-element table kernels of the set-up (one O(n) pass each): the edge tables of a mesh, the
fan counts and duplicate rows of its validation, the tables of a renumbered mesh (edges, faces,
interior edges), and the crease test and ring growth over all edges. Each has a numpy twin with
equal results (``tests/test_kernels.py``)."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import HAVE_NUMBA, njit
from meshrepair._kernels.connectivity import (
    _np_edges_from_groups,
    _np_group_halfedges,
    _np_pair_order,
    _np_union_find,
)

if HAVE_NUMBA:
    from meshrepair._kernels.connectivity import _nb_pair_order, _nb_union


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
            _nb_union(parent, u1, u2)
            _nb_union(parent, w1, w2)
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
