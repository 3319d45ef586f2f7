"""Kernels of :mod:`meshrepair.denoise.polish`: one bilateral normal-filter pass over a CSR face
neighbourhood, and the Sun et al. vertex steps towards given face normals ((26) with λ = 0).
Numpy twins are the reference (tests/test_polish.py checks them equal)."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import HAVE_NUMBA, njit


def _np_bilateral(indptr, indices, N, area, C, gate, sigma_c, sigma_s):
    nF = len(N)
    I = np.repeat(np.arange(nF, dtype=np.int64), np.diff(indptr))
    J = indices
    keep = gate[I]
    I, J = I[keep], J[keep]
    d2 = np.einsum("ij,ij->i", C[I] - C[J], C[I] - C[J])
    nd2 = np.einsum("ij,ij->i", N[I] - N[J], N[I] - N[J])
    w = area[J] * np.exp(-d2 / (2 * sigma_c**2) - nd2 / (2 * sigma_s**2))
    out = N.copy()
    S = np.empty((nF, 3))
    for k in range(3):
        S[:, k] = np.bincount(I, weights=w * N[J, k], minlength=nF)
    nrm = np.linalg.norm(S, axis=1)
    g = gate & (nrm > 0)
    out[g] = S[g] / nrm[g, None]
    return out


def _np_spread_rows(indptr, indices, N):
    nF = len(N)
    I = np.repeat(np.arange(nF, dtype=np.int64), np.diff(indptr))
    J = indices
    M = np.empty((nF, 3))
    for k in range(3):
        M[:, k] = np.bincount(I, weights=N[J, k], minlength=nF)
    M /= np.maximum(np.linalg.norm(M, axis=1, keepdims=True), 1e-300)
    dev = np.arccos(np.clip(np.einsum("ij,ij->i", N[J], M[I]), -1.0, 1.0)) ** 2
    cnt = np.maximum(np.diff(indptr), 1)
    return np.degrees(np.sqrt(np.bincount(I, weights=dev, minlength=nF) / cnt))


def _np_sun_steps(X, F, Nt, steps):
    X = np.array(X, dtype=np.float64, copy=True)
    nV = len(X)
    deg = np.maximum(np.bincount(F.ravel(), minlength=nV), 1).astype(np.float64)
    for _ in range(steps):
        C = X[F].mean(axis=1)
        D = np.zeros_like(X)
        for j in range(3):
            s = np.einsum("ij,ij->i", C - X[F[:, j]], Nt)
            for k in range(3):
                D[:, k] += np.bincount(F[:, j], weights=s * Nt[:, k], minlength=nV)
        X += D / deg[:, None]
    return X


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_bilateral(indptr, indices, N, area, C, gate, sigma_c, sigma_s):  # pragma: no cover
        nF = N.shape[0]
        out = N.copy()
        ic = 1.0 / (2.0 * sigma_c * sigma_c)
        isg = 1.0 / (2.0 * sigma_s * sigma_s)
        for f in range(nF):
            if not gate[f]:
                continue
            s0 = 0.0
            s1 = 0.0
            s2 = 0.0
            for p in range(indptr[f], indptr[f + 1]):
                g = indices[p]
                dx = C[f, 0] - C[g, 0]
                dy = C[f, 1] - C[g, 1]
                dz = C[f, 2] - C[g, 2]
                nx = N[f, 0] - N[g, 0]
                ny = N[f, 1] - N[g, 1]
                nz = N[f, 2] - N[g, 2]
                w = area[g] * np.exp(-(dx * dx + dy * dy + dz * dz) * ic
                                     - (nx * nx + ny * ny + nz * nz) * isg)
                s0 += w * N[g, 0]
                s1 += w * N[g, 1]
                s2 += w * N[g, 2]
            nrm = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
            if nrm > 0:
                out[f, 0] = s0 / nrm
                out[f, 1] = s1 / nrm
                out[f, 2] = s2 / nrm
        return out

    @njit(cache=True)
    def _nb_spread_rows(indptr, indices, N):  # pragma: no cover - compiled
        nF = N.shape[0]
        out = np.zeros(nF)
        for f in range(nF):
            m0 = 0.0
            m1 = 0.0
            m2 = 0.0
            for p in range(indptr[f], indptr[f + 1]):
                g = indices[p]
                m0 += N[g, 0]
                m1 += N[g, 1]
                m2 += N[g, 2]
            nrm = max(np.sqrt(m0 * m0 + m1 * m1 + m2 * m2), 1e-300)
            m0 /= nrm
            m1 /= nrm
            m2 /= nrm
            acc = 0.0
            for p in range(indptr[f], indptr[f + 1]):
                g = indices[p]
                c = N[g, 0] * m0 + N[g, 1] * m1 + N[g, 2] * m2
                c = min(1.0, max(-1.0, c))
                a = np.arccos(c)
                acc += a * a
            cnt = max(indptr[f + 1] - indptr[f], 1)
            out[f] = np.degrees(np.sqrt(acc / cnt))
        return out

    @njit(cache=True)
    def _nb_sun_steps(X, F, Nt, steps):  # pragma: no cover - compiled
        X = X.copy()
        nV = X.shape[0]
        nF = F.shape[0]
        deg = np.zeros(nV)
        for f in range(nF):
            for j in range(3):
                deg[F[f, j]] += 1.0
        for i in range(nV):
            if deg[i] < 1.0:
                deg[i] = 1.0
        D = np.zeros((nV, 3))
        for _ in range(steps):
            D[:] = 0.0
            for f in range(nF):
                a, b, c = F[f, 0], F[f, 1], F[f, 2]
                cx = (X[a, 0] + X[b, 0] + X[c, 0]) / 3.0
                cy = (X[a, 1] + X[b, 1] + X[c, 1]) / 3.0
                cz = (X[a, 2] + X[b, 2] + X[c, 2]) / 3.0
                n0, n1, n2 = Nt[f, 0], Nt[f, 1], Nt[f, 2]
                for j in range(3):
                    v = F[f, j]
                    s = (cx - X[v, 0]) * n0 + (cy - X[v, 1]) * n1 + (cz - X[v, 2]) * n2
                    D[v, 0] += s * n0
                    D[v, 1] += s * n1
                    D[v, 2] += s * n2
            for i in range(nV):
                X[i, 0] += D[i, 0] / deg[i]
                X[i, 1] += D[i, 1] / deg[i]
                X[i, 2] += D[i, 2] / deg[i]
        return X


def bilateral_pass(indptr, indices, N, area, C, gate, sigma_c, sigma_s):
    """``n'`` of :mod:`meshrepair.denoise.polish` on the rows of ``gate`` (the others keep
    ``N``)."""
    args = (np.ascontiguousarray(indptr, np.int64), np.ascontiguousarray(indices),
            np.ascontiguousarray(N, np.float64), np.ascontiguousarray(area, np.float64),
            np.ascontiguousarray(C, np.float64), np.ascontiguousarray(gate, np.bool_),
            float(sigma_c), float(sigma_s))
    return _nb_bilateral(*args) if HAVE_NUMBA else _np_bilateral(*args)


def spread_rows(indptr, indices, N):
    """Per row f of the CSR neighbourhood, the RMS angle (degrees) of ``N[g]`` to their
    normalised mean, ``s_f`` of :mod:`meshrepair.denoise.polish`."""
    args = (np.ascontiguousarray(indptr, np.int64), np.ascontiguousarray(indices),
            np.ascontiguousarray(N, np.float64))
    return _nb_spread_rows(*args) if HAVE_NUMBA else _np_spread_rows(*args)


def sun_steps(X, F, Nt, steps):
    """``steps`` Sun et al. vertex steps towards the face normals ``Nt`` (a new array)."""
    args = (np.ascontiguousarray(X, np.float64), np.ascontiguousarray(F, np.int64),
            np.ascontiguousarray(Nt, np.float64), int(steps))
    return _nb_sun_steps(*args) if HAVE_NUMBA else _np_sun_steps(*args)
