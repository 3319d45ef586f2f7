"""Per-face geometry kernels on the vertex positions: face normals (3) (and the multiplier
update (21) fused with them), face areas and longest edges, vertex normals, signed volume. The
V-subproblem (26) kernels are in :mod:`.venergy`."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import FASTMATH, HAVE_NUMBA, njit


def _np_face_normals(V, F):
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n2 = np.sqrt(np.einsum("ij,ij->i", c, c))
    out = np.zeros_like(c)
    ok = n2 > 0
    out[ok] = c[ok] / n2[ok, None]
    return out


if HAVE_NUMBA:

    @njit(cache=True, inline="always")
    def _tri(V, i, j, k):  # pragma: no cover - compiled
        """Edge vectors a = v_j - v_i, b = v_k - v_i and their cross product c = a x b."""
        ax = V[j, 0] - V[i, 0]
        ay = V[j, 1] - V[i, 1]
        az = V[j, 2] - V[i, 2]
        bx = V[k, 0] - V[i, 0]
        by = V[k, 1] - V[i, 1]
        bz = V[k, 2] - V[i, 2]
        return ax, ay, az, bx, by, bz, ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx

    @njit(cache=True, inline="always")
    def _unit_normal(V, i, j, k):  # pragma: no cover - compiled
        """Unit normal of the face (i, j, k) of ``V``, zero when degenerate."""
        ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
        q = np.sqrt(cx * cx + cy * cy + cz * cz)
        if q > 0:
            iq = 1.0 / q
            return cx * iq, cy * iq, cz * iq
        return 0.0, 0.0, 0.0

    # The kernels below call the inlined helpers above; numba's on-disk cache does not notice a
    # change of an inlined helper defined in another file, so every caller stays in this file
    # (meshrepair.model._fused only wraps the fused ones).

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_face_normals(V, F):  # pragma: no cover - compiled
        out = np.zeros((F.shape[0], 3))
        for m in range(F.shape[0]):
            # not _unit_normal: writing the zero rows too measured 3 % slower
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
            q = np.sqrt(cx * cx + cy * cy + cz * cz)
            if q > 0:
                iq = 1.0 / q
                out[m, 0] = cx * iq
                out[m, 1] = cy * iq
                out[m, 2] = cz * iq
        return out

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_normals_update_rho2(V, F, N, rho2, beta2):  # pragma: no cover - compiled
        # meshrepair.model._fused.normals_update_rho2: _nb_face_normals and the update (21)
        Nv = np.zeros((F.shape[0], 3))
        s = 0.0
        for m in range(F.shape[0]):
            c0, c1, c2 = _unit_normal(V, F[m, 0], F[m, 1], F[m, 2])
            Nv[m, 0] = c0
            Nv[m, 1] = c1
            Nv[m, 2] = c2
            r0 = N[m, 0] - c0
            r1 = N[m, 1] - c1
            r2 = N[m, 2] - c2
            rho2[m, 0] -= beta2 * r0
            rho2[m, 1] -= beta2 * r1
            rho2[m, 2] -= beta2 * r2
            s += r0 * r0 + r1 * r1 + r2 * r2
        return Nv, s


def face_normals(V, F):
    """Unit face normals, zero rows for degenerate faces, shape ``(nF, 3)``."""
    if HAVE_NUMBA:
        return _nb_face_normals(V, F)
    return _np_face_normals(V, F)


def _np_face_area2_lmax2(V, F):
    e01 = V[F[:, 1]] - V[F[:, 0]]
    e12 = V[F[:, 2]] - V[F[:, 1]]
    e20 = V[F[:, 0]] - V[F[:, 2]]
    l2 = np.stack([np.einsum("ij,ij->i", e, e) for e in (e01, e12, e20)], axis=1)
    cross = np.cross(e01, -e20)
    return np.sqrt(np.einsum("ij,ij->i", cross, cross)), l2.max(axis=1)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_face_area2_lmax2(V, F):  # pragma: no cover - compiled
        nF = F.shape[0]
        area2 = np.empty(nF)
        lmax2 = np.empty(nF)
        for m in range(nF):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
            dx, dy, dz = bx - ax, by - ay, bz - az
            area2[m] = np.sqrt(cx * cx + cy * cy + cz * cz)
            lmax2[m] = max(ax * ax + ay * ay + az * az, dx * dx + dy * dy + dz * dz,
                           bx * bx + by * by + bz * bz)
        return area2, lmax2

    @njit(cache=True)
    def _nb_vertex_normals(V, F):  # pragma: no cover - compiled
        vn = np.zeros((V.shape[0], 3))
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
            for v in (i, j, k):
                vn[v, 0] += cx
                vn[v, 1] += cy
                vn[v, 2] += cz
        for v in range(V.shape[0]):
            q = np.sqrt(vn[v, 0] * vn[v, 0] + vn[v, 1] * vn[v, 1] + vn[v, 2] * vn[v, 2])
            if q > 0:
                vn[v, 0] /= q
                vn[v, 1] /= q
                vn[v, 2] /= q
        return vn


def face_area2_lmax2(V, F):
    """Doubled area and squared longest side of every face, two ``(nF,)`` arrays."""
    if HAVE_NUMBA:
        return _nb_face_area2_lmax2(np.ascontiguousarray(V, dtype=np.float64),
                                    np.ascontiguousarray(F, dtype=np.int64))
    return _np_face_area2_lmax2(V, F)


def _np_vertex_normals(V, F):
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    c3 = np.repeat(c, 3, axis=0)
    idx = F.ravel()
    vn = np.stack([np.bincount(idx, c3[:, j], len(V)) for j in range(3)], axis=1)
    n = np.linalg.norm(vn, axis=1, keepdims=True)
    return np.divide(vn, n, out=np.zeros_like(vn), where=n > 0)


def vertex_normals(V, F):
    """Area-weighted unit vertex normals ``(nV, 3)`` (zero rows for unreferenced vertices)."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_vertex_normals(V, F)
    return _np_vertex_normals(V, F)


def _np_signed_volume(V, F, center):
    X = V - center
    a, b, c = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_signed_volume(V, F, center):  # pragma: no cover - compiled
        c0, c1, c2 = center[0], center[1], center[2]
        s = 0.0
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az = V[i, 0] - c0, V[i, 1] - c1, V[i, 2] - c2
            bx, by, bz = V[j, 0] - c0, V[j, 1] - c1, V[j, 2] - c2
            cx, cy, cz = V[k, 0] - c0, V[k, 1] - c1, V[k, 2] - c2
            s += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        return s / 6.0


def signed_volume(V, F, center):
    """Signed volume ``Σ_m a·(b×c) / 6`` of the faces with corners taken relative to
    ``center`` (3,) (the enclosed volume of a closed, consistently oriented mesh)."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    center = np.ascontiguousarray(center, dtype=np.float64)
    if HAVE_NUMBA:
        return float(_nb_signed_volume(V, F, center))
    return _np_signed_volume(V, F, center)


def _np_min_corner_cos(F, N, n_vertices):
    """Per vertex, the smallest cosine between an incident face normal ``N`` and the mean
    (``M = A_vf N`` over the incident faces, normalised) of them; 1 where no face is incident."""
    import scipy.sparse as sp

    F = np.asarray(F, dtype=np.int64)
    nF = len(F)
    Avf = sp.csr_matrix((np.ones(3 * nF), (F.ravel(), np.repeat(np.arange(nF), 3))),
                        shape=(n_vertices, nF))
    M = Avf @ N
    M /= np.maximum(np.linalg.norm(M, axis=1, keepdims=True), 1e-300)
    out = np.ones(n_vertices)
    for k in range(3):
        c = np.clip(np.einsum("ij,ij->i", N, M[F[:, k]]), -1.0, 1.0)
        np.minimum.at(out, F[:, k], c)
    return out


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_min_corner_cos(F, N, n_vertices):  # pragma: no cover - compiled
        M = np.zeros((n_vertices, 3))
        for m in range(F.shape[0]):
            for k in range(3):
                v = F[m, k]
                M[v, 0] += N[m, 0]
                M[v, 1] += N[m, 1]
                M[v, 2] += N[m, 2]
        for v in range(n_vertices):
            q = max(np.sqrt(M[v, 0] * M[v, 0] + M[v, 1] * M[v, 1] + M[v, 2] * M[v, 2]), 1e-300)
            M[v, 0] /= q
            M[v, 1] /= q
            M[v, 2] /= q
        out = np.ones(n_vertices)
        for m in range(F.shape[0]):
            for k in range(3):
                v = F[m, k]
                # (x0 y0 + x2 y2) + x1 y1: the order numpy's einsum sums three products
                # in, so the twins agree bit for bit
                c = (N[m, 0] * M[v, 0] + N[m, 2] * M[v, 2]) + N[m, 1] * M[v, 1]
                c = min(max(c, -1.0), 1.0)
                if c < out[v]:
                    out[v] = c
        return out


def min_corner_cos(F, N, n_vertices):
    """Per vertex, the smallest cosine between an incident face normal and the normalised sum
    of the incident face normals, ``(nV,)`` (1 for unreferenced vertices); the sums run over
    the faces in ascending order, as the sparse product ``A_vf N`` does."""
    F = np.ascontiguousarray(F, dtype=np.int64)
    N = np.ascontiguousarray(N, dtype=np.float64)
    if HAVE_NUMBA:
        return _nb_min_corner_cos(F, N, int(n_vertices))
    return _np_min_corner_cos(F, N, int(n_vertices))


def _np_folded(N, S, cos_max):
    sn = np.linalg.norm(S, axis=1)
    return np.einsum("ij,ij->i", N, S) <= cos_max * sn


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_folded(N, S, cos_max):  # pragma: no cover - compiled
        out = np.empty(N.shape[0], np.bool_)
        for f in range(N.shape[0]):
            s0, s1, s2 = S[f, 0], S[f, 1], S[f, 2]
            sn = np.sqrt((s0 * s0 + s1 * s1) + s2 * s2)  # numpy's norm order
            d = (N[f, 0] * s0 + N[f, 2] * s2) + N[f, 1] * s1  # numpy's einsum order
            out[f] = d <= cos_max * sn
        return out


def folded(N, S, cos_max):
    """``N_f · S_f <= cos_max |S_f|`` per face, ``(nF,)`` bool: the face normal against the sum
    ``S`` of its neighbours' normals (:func:`meshrepair.model.relax.locally_flipped_faces`)."""
    if HAVE_NUMBA:
        return _nb_folded(np.ascontiguousarray(N, dtype=np.float64),
                          np.ascontiguousarray(S, dtype=np.float64), float(cos_max))
    return _np_folded(N, S, cos_max)


def _np_face_centroids(V, F):
    return V[F].mean(axis=1)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_face_centroids(V, F):  # pragma: no cover - compiled
        # strict IEEE: ((v0 + v1) + v2) / 3, numpy's mean over the corners, bit for bit
        out = np.empty((F.shape[0], 3))
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            for c in range(3):
                out[m, c] = (V[i, c] + V[j, c] + V[k, c]) / 3.0
        return out


def face_centroids(V, F):
    """Centroid of every face, shape ``(nF, 3)``: ``V[F].mean(axis=1)`` without the
    ``(nF, 3, 3)`` gather (the same sums in the same order)."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_face_centroids(V, F)
    return _np_face_centroids(V, F)
