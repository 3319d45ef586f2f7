"""Kernel of :mod:`meshrepair.denoise.modes`: mean shift of face normals over CSR face
neighbourhoods.
The numpy twin is the reference (tests/test_modes.py checks them equal)."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import HAVE_NUMBA, njit

MODE_TOL2 = 1e-12
"""A row stops when its mean-shift step moves the unit normal by less than 1e-6 (squared)."""


def _np_mode_rows(indptr, indices, rows, N, area, C, sigma_c, sigma_s, iters):
    """Modes of the rows ``rows`` (row ``k`` of the CSR is face ``rows[k]``)."""
    n = len(rows)
    I = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
    J = np.asarray(indices, dtype=np.int64)
    f = rows[I]
    wc = area[J] * np.exp(-np.einsum("ij,ij->i", C[f] - C[J], C[f] - C[J]) / (2 * sigma_c**2))
    M = N[rows].copy()
    live = np.ones(n, bool)
    for _ in range(iters):
        d2 = np.einsum("ij,ij->i", M[I] - N[J], M[I] - N[J])
        w = wc * np.exp(-d2 / (2 * sigma_s**2))
        S = np.empty((n, 3))
        for k in range(3):
            S[:, k] = np.bincount(I, weights=w * N[J, k], minlength=n)
        nrm = np.linalg.norm(S, axis=1)
        ok = live & (nrm > 0)
        new = S[ok] / nrm[ok, None]
        moved = np.zeros(n, bool)
        moved[ok] = np.sum((new - M[ok]) ** 2, axis=1) >= MODE_TOL2
        M[ok] = new
        live &= moved  # a row whose step moved it less than the tolerance is converged
        if not live.any():
            break
    return M


def _np_rings_rows(adj_ptr, adj_idx, lo, hi, rings):
    """Rows ``lo:hi`` of ``(I + A)^rings > 0`` (``A`` the CSR adjacency), sorted indices."""
    import scipy.sparse as sp

    n = len(adj_ptr) - 1
    A = sp.csr_matrix((np.ones(len(adj_idx)), adj_idx, adj_ptr), shape=(n, n))
    R = sp.csr_matrix((np.ones(hi - lo), (np.arange(hi - lo), np.arange(lo, hi))),
                      shape=(hi - lo, n))
    for _ in range(rings):
        R = R + R @ A
        R.data[:] = 1.0
    R.sort_indices()
    return R.indptr.astype(np.int64), R.indices.astype(np.int32)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_rings_rows(adj_ptr, adj_idx, lo, hi, rings):  # pragma: no cover - compiled
        n = adj_ptr.shape[0] - 1
        stamp = np.full(n, -1, np.int64)
        queue = np.empty(n, np.int64)
        counts = np.zeros(hi - lo, np.int64)
        for sweep in range(2):
            if sweep == 1:
                indptr = np.zeros(hi - lo + 1, np.int64)
                for r in range(hi - lo):
                    indptr[r + 1] = indptr[r] + counts[r]
                indices = np.empty(indptr[-1], np.int32)
                stamp[:] = -1
            for f in range(lo, hi):
                stamp[f] = f + sweep * n
                queue[0] = f
                head = 0
                tail = 1
                for _ in range(rings):
                    end = tail
                    while head < end:
                        g = queue[head]
                        head += 1
                        for p in range(adj_ptr[g], adj_ptr[g + 1]):
                            h = adj_idx[p]
                            if stamp[h] != f + sweep * n:
                                stamp[h] = f + sweep * n
                                queue[tail] = h
                                tail += 1
                if sweep == 0:
                    counts[f - lo] = tail
                else:
                    a = indptr[f - lo]
                    srt = np.sort(queue[:tail])
                    for k in range(tail):
                        indices[a + k] = srt[k]
        return indptr, indices

    @njit(cache=True)
    def _nb_mode_rows(indptr, indices, rows, N, area, C, sigma_c, sigma_s, iters, tol2
                      ):  # pragma: no cover - compiled
        n = rows.shape[0]
        out = np.empty((n, 3))
        ic = 1.0 / (2.0 * sigma_c * sigma_c)
        isg = 1.0 / (2.0 * sigma_s * sigma_s)
        for r in range(n):
            f = rows[r]
            lo = indptr[r]
            hi = indptr[r + 1]
            wc = np.empty(hi - lo)
            for p in range(lo, hi):
                g = indices[p]
                dx = C[f, 0] - C[g, 0]
                dy = C[f, 1] - C[g, 1]
                dz = C[f, 2] - C[g, 2]
                wc[p - lo] = area[g] * np.exp(-(dx * dx + dy * dy + dz * dz) * ic)
            m0 = N[f, 0]
            m1 = N[f, 1]
            m2 = N[f, 2]
            for _ in range(iters):
                s0 = 0.0
                s1 = 0.0
                s2 = 0.0
                for p in range(lo, hi):
                    g = indices[p]
                    nx = m0 - N[g, 0]
                    ny = m1 - N[g, 1]
                    nz = m2 - N[g, 2]
                    w = wc[p - lo] * np.exp(-(nx * nx + ny * ny + nz * nz) * isg)
                    s0 += w * N[g, 0]
                    s1 += w * N[g, 1]
                    s2 += w * N[g, 2]
                nrm = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
                if not nrm > 0:
                    break
                d0 = s0 / nrm - m0
                d1 = s1 / nrm - m1
                d2 = s2 / nrm - m2
                m0 = s0 / nrm
                m1 = s1 / nrm
                m2 = s2 / nrm
                if d0 * d0 + d1 * d1 + d2 * d2 < tol2:
                    break
            out[r, 0] = m0
            out[r, 1] = m1
            out[r, 2] = m2
        return out


def rings_rows(adj_ptr, adj_idx, lo, hi, rings):
    """Compiled when numba is available, else the numpy twin."""
    if HAVE_NUMBA:
        return _nb_rings_rows(np.ascontiguousarray(adj_ptr, dtype=np.int64),
                              np.ascontiguousarray(adj_idx, dtype=np.int64), int(lo), int(hi),
                              int(rings))
    return _np_rings_rows(adj_ptr, adj_idx, lo, hi, rings)


def mode_rows(indptr, indices, rows, N, area, C, sigma_c, sigma_s, iters):
    """Compiled when numba is available, else the numpy twin."""
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_mode_rows(np.ascontiguousarray(indptr, dtype=np.int64),
                             np.ascontiguousarray(indices), rows,
                             np.ascontiguousarray(N, dtype=np.float64),
                             np.ascontiguousarray(area, dtype=np.float64),
                             np.ascontiguousarray(C, dtype=np.float64), float(sigma_c),
                             float(sigma_s), int(iters), MODE_TOL2)
    return _np_mode_rows(indptr, indices, rows, N, area, C, sigma_c, sigma_s, iters)
