"""Kernel of the tangential anchor (:func:`meshrepair.model.fidelity.tangential_anchor`): the
area-weighted vertex normals of ``V`` and the removal of the weighted tangential part of
``V - V⁰`` in one face pass and one vertex pass, with no numpy temporaries (it runs after every
V-step on CAD regions; 104 → 65 µs of CPU per call on a 4,610-vertex mesh, where the numpy
expressions were 5 % of a default denoise: docs/performance.md). Same arithmetic as
``_kernels.vertex_normals`` followed by the numpy expression of the twin, in the same order
(the dot product summed as numpy's ``einsum`` sums it): results equal bit for bit, so the
iterates of the solver do not change (a rounding-level change can move the MSAE of a
heavy-noise row by several per cent)."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import HAVE_NUMBA, njit


def _np_tangential_anchor(V, V0, F, weight):
    from meshrepair._kernels.faces import _np_vertex_normals

    n = _np_vertex_normals(V, F)
    d = V - V0
    dt = d - np.einsum("ij,ij->i", d, n)[:, None] * n
    return V - np.asarray(weight, dtype=np.float64)[:, None] * dt


if HAVE_NUMBA:
    from meshrepair._kernels.faces import _tri

    @njit(cache=True)
    def _anchor_vertex(V, V0, vn, s, v, w, out):  # pragma: no cover - compiled
        # out[v] = V[v] - w P (V[v] - V0[v]), P = I - n nᵀ, n = vn[s] / |vn[s]|
        q = np.sqrt(vn[s, 0] * vn[s, 0] + vn[s, 1] * vn[s, 1] + vn[s, 2] * vn[s, 2])
        n0, n1, n2 = vn[s, 0], vn[s, 1], vn[s, 2]
        if q > 0:
            n0 /= q
            n1 /= q
            n2 /= q
        d0 = V[v, 0] - V0[v, 0]
        d1 = V[v, 1] - V0[v, 1]
        d2 = V[v, 2] - V0[v, 2]
        dn = (d0 * n0 + d2 * n2) + d1 * n1  # numpy's einsum order: equal bit for bit
        out[v, 0] = V[v, 0] - w * (d0 - dn * n0)
        out[v, 1] = V[v, 1] - w * (d1 - dn * n1)
        out[v, 2] = V[v, 2] - w * (d2 - dn * n2)

    @njit(cache=True)
    def _nb_tangential_anchor(V, V0, F, weight):  # pragma: no cover - compiled
        nV = V.shape[0]
        vn = np.zeros((nV, 3))
        for m in range(F.shape[0]):  # the loop of _nb_vertex_normals
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
            for v in (i, j, k):
                vn[v, 0] += cx
                vn[v, 1] += cy
                vn[v, 2] += cz
        out = np.empty_like(V)
        for v in range(nV):
            _anchor_vertex(V, V0, vn, v, v, weight[v], out)
        return out


def anchor_support(F, weight):
    """The faces touching a vertex of non-zero ``weight`` (ascending) and the slot of each such
    vertex (``-1`` elsewhere): what :func:`tangential_anchor_on` reads, once per weight."""
    w = np.asarray(weight, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    on = w != 0.0
    faces = np.flatnonzero(on[F].any(axis=1)).astype(np.int64)
    verts = np.flatnonzero(on).astype(np.int64)
    slot = np.full(len(w), -1, np.int64)
    slot[verts] = np.arange(len(verts))
    return faces, verts, slot


def _np_tangential_anchor_on(V, V0, F, weight, faces, verts, slot):
    out = np.array(V, dtype=np.float64, copy=True)
    if len(verts) == 0:
        return out
    full = _np_tangential_anchor(V, V0, F[faces], weight)  # the skipped faces touch no vertex
    out[verts] = full[verts]                                 # of non-zero weight
    return out


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_tangential_anchor_on(V, V0, F, weight, faces, verts, slot
                                 ):  # pragma: no cover - compiled
        # _nb_tangential_anchor on the vertices of non-zero weight only: their normals summed
        # over their faces in the same (ascending) order; the others keep V (w = 0)
        vn = np.zeros((verts.shape[0], 3))
        for p in range(faces.shape[0]):
            m = faces[p]
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
            for v in (i, j, k):
                s = slot[v]
                if s >= 0:
                    vn[s, 0] += cx
                    vn[s, 1] += cy
                    vn[s, 2] += cz
        out = V.copy()
        for s in range(verts.shape[0]):
            v = verts[s]
            _anchor_vertex(V, V0, vn, s, v, weight[v], out)
        return out


def tangential_anchor_on(V, V0, F, weight, support):
    """:func:`tangential_anchor` with ``support = anchor_support(F, weight)``: the face pass
    only over the faces of the anchored vertices (the anchor acts on the CAD region C; the
    full pass took 43 ms per call, wall, in the loaded 1.18M-vertex profile). Equal to
    :func:`tangential_anchor`: the same sums in the same order on the anchored vertices, ``V``
    itself elsewhere (``w = 0``)."""
    faces, verts, slot = support
    if HAVE_NUMBA:
        return _nb_tangential_anchor_on(np.ascontiguousarray(V, dtype=np.float64),
                                        np.ascontiguousarray(V0, dtype=np.float64),
                                        np.ascontiguousarray(F, dtype=np.int64),
                                        np.ascontiguousarray(weight, dtype=np.float64),
                                        faces, verts, slot)
    return _np_tangential_anchor_on(V, V0, F, weight, faces, verts, slot)


def tangential_anchor(V, V0, F, weight):
    """``V - weight_i P_i (V_i - V⁰_i)`` with ``P_i = I - n_i n_iᵀ``, ``n_i`` the area-weighted
    unit vertex normal of ``V`` (a new ``(nV, 3)`` array)."""
    if HAVE_NUMBA:
        return _nb_tangential_anchor(np.ascontiguousarray(V, dtype=np.float64),
                                     np.ascontiguousarray(V0, dtype=np.float64),
                                     np.ascontiguousarray(F, dtype=np.int64),
                                     np.ascontiguousarray(weight, dtype=np.float64))
    return _np_tangential_anchor(V, V0, F, weight)
