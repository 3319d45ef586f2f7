"""Kernel of :mod:`meshrepair.modes`: mean shift of face normals over CSR face neighbourhoods.
The numpy twin is the reference (tests/test_modes.py checks them equal)."""

from __future__ import annotations

import numpy as np

from ._jit import HAVE_NUMBA, njit


def _np_mode_rows(indptr, indices, rows, N, area, C, sigma_c, sigma_s, iters):
    """Modes of the rows ``rows`` (row ``k`` of the CSR is face ``rows[k]``)."""
    n = len(rows)
    I = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
    J = np.asarray(indices, dtype=np.int64)
    f = rows[I]
    wc = area[J] * np.exp(-np.einsum("ij,ij->i", C[f] - C[J], C[f] - C[J]) / (2 * sigma_c**2))
    M = N[rows].copy()
    for _ in range(iters):
        d2 = np.einsum("ij,ij->i", M[I] - N[J], M[I] - N[J])
        w = wc * np.exp(-d2 / (2 * sigma_s**2))
        S = np.empty((n, 3))
        for k in range(3):
            S[:, k] = np.bincount(I, weights=w * N[J, k], minlength=n)
        nrm = np.linalg.norm(S, axis=1)
        ok = nrm > 0
        M[ok] = S[ok] / nrm[ok, None]
    return M


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_mode_rows(indptr, indices, rows, N, area, C, sigma_c, sigma_s, iters
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
                if nrm > 0:
                    m0 = s0 / nrm
                    m1 = s1 / nrm
                    m2 = s2 / nrm
            out[r, 0] = m0
            out[r, 1] = m1
            out[r, 2] = m2
        return out


def mode_rows(indptr, indices, rows, N, area, C, sigma_c, sigma_s, iters):
    """Compiled when numba is available, else the numpy twin."""
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_mode_rows(np.ascontiguousarray(indptr, dtype=np.int64),
                             np.ascontiguousarray(indices), rows,
                             np.ascontiguousarray(N, dtype=np.float64),
                             np.ascontiguousarray(area, dtype=np.float64),
                             np.ascontiguousarray(C, dtype=np.float64), float(sigma_c),
                             float(sigma_s), int(iters))
    return _np_mode_rows(indptr, indices, rows, N, area, C, sigma_c, sigma_s, iters)
