"""Fused per-element kernels of the hot loop, compiled with numba when it is installed.

Each kernel has a pure-numpy twin with identical results (checked in ``tests/test_kernels.py``);
the numpy path is used when numba is missing or ``MESHREPAIR_NO_NUMBA=1`` is set. Profiling showed
the V-subproblem energy/gradient (gather, cross, normalise, dot, scatter over faces) and the
edge gathers dominating an ADMM iteration; fusing them removes the temporaries (see
docs/performance.md).
"""

from __future__ import annotations

import os

import numpy as np

try:  # pragma: no cover - exercised through both paths in tests
    if os.environ.get("MESHREPAIR_NO_NUMBA", "") not in ("", "0"):
        raise ImportError
    from numba import njit as _numba_njit

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    HAVE_NUMBA = False

CACHE_DISABLED: list[str] = []
"""Kernels compiled without numba's on-disk cache (no writable cache location was found)."""


def njit(**options):
    """``numba.njit(**options)``; with ``cache=True`` the compiled kernel is kept in numba's
    on-disk cache (``__pycache__`` beside this file, else the user cache directory, else
    ``NUMBA_CACHE_DIR``), so a new process loads it instead of compiling it again (~1.5 ms per
    kernel instead of seconds). Where none of these is writable, numba refuses ``cache=True`` at
    import; the kernel is then compiled in each process instead (logged once)."""
    def deco(fn):
        if not options.get("cache"):
            return _numba_njit(**options)(fn)
        try:
            return _numba_njit(**options)(fn)
        except RuntimeError as exc:  # "cannot cache function ...: no locator available"
            if "cannot cache" not in str(exc):
                raise
            if not CACHE_DISABLED:
                import logging

                logging.getLogger(__name__).warning(
                    "numba found no writable cache directory (%s); compiled kernels are not "
                    "cached: each new process compiles them again. Set NUMBA_CACHE_DIR to a "
                    "writable directory to avoid this.", exc)
            CACHE_DISABLED.append(fn.__name__)
            return _numba_njit(**dict(options, cache=False))(fn)
    return deco

FASTMATH = {"contract", "arcp", "nsz", "reassoc"}
"""LLVM fast-math flags of the hot-loop kernels: fused multiply-add, reciprocals, reassociated
sums (vectorised reductions). Not ``nnan``/``ninf``: inputs are validated finite, and comparisons
stay IEEE. Results differ from the numpy twins by rounding only (tests/test_kernels.py); the
V-gradient kernel measured 15 % faster on fandisk (141 vs 165 µs); the PCG kernels
4 % slower, so they keep strict IEEE arithmetic."""


# ---------------------------------------------------------------------------------------------
# numpy reference implementations


def _np_venergy(V, F, z, V0, wfid):
    p0 = V[F[:, 0]]
    c = np.cross(V[F[:, 1]] - p0, V[F[:, 2]] - p0)
    q = np.maximum(np.sqrt(np.einsum("ij,ij->i", c, c)), 1e-300)
    d = V - V0
    return float(np.einsum("ij,ij->", z, c / q[:, None])) + 0.5 * float(
        np.einsum("i,ij,ij->", wfid, d, d))


def _np_venergy_grad(V, F, z, V0, wfid, S):
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    c = np.cross(p1 - p0, p2 - p0)
    q = np.maximum(np.sqrt(np.einsum("ij,ij->i", c, c)), 1e-300)
    n = c / q[:, None]
    zn = np.einsum("ij,ij->i", z, n)
    g = (z - zn[:, None] * n) / q[:, None]
    contrib = np.concatenate([np.cross(g, p2 - p1), np.cross(g, p0 - p2), np.cross(g, p1 - p0)])
    grad = S @ contrib
    d = V - V0
    grad += wfid[:, None] * d
    return float(zn.sum()) + 0.5 * float(np.einsum("i,ij,ij->", wfid, d, d)), grad


def _np_face_normals(V, F):
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n2 = np.sqrt(np.einsum("ij,ij->i", c, c))
    out = np.zeros_like(c)
    ok = n2 > 0
    out[ok] = c[ok] / n2[ok, None]
    return out


def _np_edge_lengths(V, E):
    d = V[E[:, 1]] - V[E[:, 0]]
    return np.sqrt(np.einsum("ij,ij->i", d, d))


def _np_grad_edges(N, l, fa, fb):
    return l[:, None] * (N[fa] - N[fb])


def _np_grad_edges_T(t, l, fa, fb, nF):
    w = l[:, None] * t
    out = np.empty((nF, t.shape[1]))
    for k in range(t.shape[1]):
        out[:, k] = np.bincount(fa, w[:, k], nF) - np.bincount(fb, w[:, k], nF)
    return out


# ---------------------------------------------------------------------------------------------
# numba kernels

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

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_venergy(V, F, z, V0, wfid):  # pragma: no cover - compiled
        e = 0.0
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
            q = np.sqrt(cx * cx + cy * cy + cz * cz)
            if q < 1e-300:
                q = 1e-300
            e += (z[m, 0] * cx + z[m, 1] * cy + z[m, 2] * cz) / q
        f = 0.0
        for v in range(V.shape[0]):
            w = wfid[v]
            if w != 0.0:
                dx = V[v, 0] - V0[v, 0]
                dy = V[v, 1] - V0[v, 1]
                dz = V[v, 2] - V0[v, 2]
                f += w * (dx * dx + dy * dy + dz * dz)
        return e + 0.5 * f

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_venergy_grad(V, F, z, V0, wfid, grad):  # pragma: no cover - compiled
        nV = V.shape[0]
        e = 0.0
        f = 0.0
        for v in range(nV):
            w = wfid[v]
            dx = V[v, 0] - V0[v, 0]
            dy = V[v, 1] - V0[v, 1]
            dz = V[v, 2] - V0[v, 2]
            grad[v, 0] = w * dx
            grad[v, 1] = w * dy
            grad[v, 2] = w * dz
            f += w * (dx * dx + dy * dy + dz * dz)
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            p0x, p0y, p0z = V[i, 0], V[i, 1], V[i, 2]
            p1x, p1y, p1z = V[j, 0], V[j, 1], V[j, 2]
            p2x, p2y, p2z = V[k, 0], V[k, 1], V[k, 2]
            ax, ay, az = p1x - p0x, p1y - p0y, p1z - p0z
            bx, by, bz = p2x - p0x, p2y - p0y, p2z - p0z
            cx = ay * bz - az * by
            cy = az * bx - ax * bz
            cz = ax * by - ay * bx
            q = np.sqrt(cx * cx + cy * cy + cz * cz)
            if q < 1e-300:
                q = 1e-300
            iq = 1.0 / q  # one division per face (six measured 1.3x slower)
            nx, ny, nz = cx * iq, cy * iq, cz * iq
            zx, zy, zz = z[m, 0], z[m, 1], z[m, 2]
            zn = zx * nx + zy * ny + zz * nz
            e += zn
            gx = (zx - zn * nx) * iq
            gy = (zy - zn * ny) * iq
            gz = (zz - zn * nz) * iq
            # corner i: g x (p2 - p1)
            ux, uy, uz = p2x - p1x, p2y - p1y, p2z - p1z
            grad[i, 0] += gy * uz - gz * uy
            grad[i, 1] += gz * ux - gx * uz
            grad[i, 2] += gx * uy - gy * ux
            # corner j: g x (p0 - p2)
            ux, uy, uz = p0x - p2x, p0y - p2y, p0z - p2z
            grad[j, 0] += gy * uz - gz * uy
            grad[j, 1] += gz * ux - gx * uz
            grad[j, 2] += gx * uy - gy * ux
            # corner k: g x (p1 - p0)
            grad[k, 0] += gy * az - gz * ay
            grad[k, 1] += gz * ax - gx * az
            grad[k, 2] += gx * ay - gy * ax
        return e + 0.5 * f

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_face_normals(V, F):  # pragma: no cover - compiled
        out = np.zeros((F.shape[0], 3))
        for m in range(F.shape[0]):
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
    def _nb_edge_lengths(V, E):  # pragma: no cover - compiled
        out = np.empty(E.shape[0])
        for e in range(E.shape[0]):
            a, b = E[e, 0], E[e, 1]
            dx = V[b, 0] - V[a, 0]
            dy = V[b, 1] - V[a, 1]
            dz = V[b, 2] - V[a, 2]
            out[e] = np.sqrt(dx * dx + dy * dy + dz * dz)
        return out

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_grad_edges(N, l, fa, fb):  # pragma: no cover - compiled
        out = np.empty((fa.shape[0], 3))
        for e in range(fa.shape[0]):
            a, b, w = fa[e], fb[e], l[e]
            out[e, 0] = w * (N[a, 0] - N[b, 0])
            out[e, 1] = w * (N[a, 1] - N[b, 1])
            out[e, 2] = w * (N[a, 2] - N[b, 2])
        return out

    @njit(cache=True)
    def _nb_grad_edges_T(t, l, fa, fb, nF):  # pragma: no cover - compiled
        out = np.zeros((nF, 3))
        for e in range(fa.shape[0]):
            a, b, w = fa[e], fb[e], l[e]
            for c in range(3):
                x = w * t[e, c]
                out[a, c] += x
                out[b, c] -= x
        return out


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_lap_matvec_dot(nb, W3, diag, X, out):  # pragma: no cover - compiled
        # out = A X in gather form with the per-face neighbour weights W3 (sequential reads);
        # returns <X, A X>
        s = 0.0
        for f in range(X.shape[0]):
            d = diag[f]
            x0, x1, x2 = X[f, 0], X[f, 1], X[f, 2]
            a0 = d * x0
            a1 = d * x1
            a2 = d * x2
            for k in range(3):
                we = W3[f, k]
                if we != 0.0:
                    g = nb[f, k]
                    a0 -= we * X[g, 0]
                    a1 -= we * X[g, 1]
                    a2 -= we * X[g, 2]
            out[f, 0] = a0
            out[f, 1] = a1
            out[f, 2] = a2
            s += x0 * a0 + x1 * a1 + x2 * a2
        return s

    @njit(cache=True)
    def _nb_pcg(nb, fe, w, c, B, X, rtol, maxiter):  # pragma: no cover - compiled
        # CG on the Kronecker system (A ⊗ I3) vec(X) = vec(B), A = DᵀD + c I with interior-edge
        # weights w: scalar alpha/beta from Frobenius products, so the iterates are exactly
        # equivariant under rotations of the columns. Jacobi preconditioner, Z = R / diag is
        # never stored; the direction update P = Z + beta P is made at the start of the next
        # iteration, so none is wasted after the last. (Fusing it into the product, recomputing
        # Z + beta P at each neighbour, measured 1.3x slower: the kernel is compute-bound there.)
        n = B.shape[0]
        W3 = np.zeros((n, 3))
        diag = np.empty(n)
        idg = np.empty(n)
        for f in range(n):
            d = 0.0
            for k in range(3):
                e = fe[f, k]
                if e >= 0:
                    W3[f, k] = w[e]
                    d += w[e]
            diag[f] = d + c
            idg[f] = 1.0 / diag[f]
        R = np.empty_like(B)
        AP = np.empty_like(B)
        _nb_lap_matvec_dot(nb, W3, diag, X, AP)
        bn = 0.0
        rz = 0.0
        rn = 0.0
        P = np.empty_like(B)
        for f in range(n):
            i = idg[f]
            for k in range(3):
                r = B[f, k] - AP[f, k]
                R[f, k] = r
                P[f, k] = r * i
                bn += B[f, k] * B[f, k]
                rz += r * r * i
                rn += r * r
        tol2 = rtol * rtol * max(bn, 1e-300)
        it = 0
        beta = 0.0
        while it < maxiter and rn > tol2:
            if it > 0:
                for f in range(n):
                    i = idg[f]
                    P[f, 0] = R[f, 0] * i + beta * P[f, 0]
                    P[f, 1] = R[f, 1] * i + beta * P[f, 1]
                    P[f, 2] = R[f, 2] * i + beta * P[f, 2]
            pap = _nb_lap_matvec_dot(nb, W3, diag, P, AP)
            if pap <= 0.0:
                break
            alpha = rz / pap
            rz_new = 0.0
            rn = 0.0
            for f in range(n):  # one accumulation per face and sum (short dependency chains)
                X[f, 0] += alpha * P[f, 0]
                X[f, 1] += alpha * P[f, 1]
                X[f, 2] += alpha * P[f, 2]
                r0 = R[f, 0] - alpha * AP[f, 0]
                r1 = R[f, 1] - alpha * AP[f, 1]
                r2 = R[f, 2] - alpha * AP[f, 2]
                R[f, 0] = r0
                R[f, 1] = r1
                R[f, 2] = r2
                rr = r0 * r0 + r1 * r1 + r2 * r2
                rz_new += rr * idg[f]
                rn += rr
            beta = rz_new / rz if rz > 0 else 0.0
            rz = rz_new
            it += 1
        return it


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_t_update(DN, rho1, sharp, a, beta1, w):  # pragma: no cover - compiled
        n = DN.shape[0]
        t = np.empty((n, 3))
        smooth_div = 1.0 / (beta1 + 2.0 * w)
        v = beta1 / (beta1 - a) if beta1 > a else 0.0
        zeta = np.sqrt(2.0 * a) / (beta1 - a) if beta1 > a else 0.0
        for e in range(n):
            r0 = beta1 * DN[e, 0] + rho1[e, 0]
            r1 = beta1 * DN[e, 1] + rho1[e, 1]
            r2 = beta1 * DN[e, 2] + rho1[e, 2]
            if sharp[e]:
                r0 /= beta1
                r1 /= beta1
                r2 /= beta1
                nr = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
                s = 0.0
                if nr > 0:
                    s = v - zeta / nr
                    s = min(max(s, 0.0), 1.0)
                t[e, 0] = s * r0
                t[e, 1] = s * r1
                t[e, 2] = s * r2
            else:
                t[e, 0] = r0 * smooth_div
                t[e, 1] = r1 * smooth_div
                t[e, 2] = r2 * smooth_div
        return t


def _np_vhess_diag(V, F, z, wfid):
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    c = np.cross(p1 - p0, p2 - p0)
    q2 = np.maximum(np.einsum("ij,ij->i", c, c), 1e-300)
    zn = np.sqrt(np.einsum("ij,ij->i", z, z))
    h = np.zeros(len(V))
    for k, (a, b) in enumerate(((p2, p1), (p0, p2), (p1, p0))):
        e2 = np.einsum("ij,ij->i", a - b, a - b)
        h += np.bincount(F[:, k], zn * e2 / q2, len(V))
    return h + wfid


if HAVE_NUMBA:

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_vhess_diag(V, F, z, wfid):  # pragma: no cover - compiled
        h = wfid.copy()
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
            q2 = max(cx * cx + cy * cy + cz * cz, 1e-300)
            zn = np.sqrt(z[m, 0] ** 2 + z[m, 1] ** 2 + z[m, 2] ** 2) / q2
            dx, dy, dz = V[k, 0] - V[j, 0], V[k, 1] - V[j, 1], V[k, 2] - V[j, 2]
            h[i] += zn * (dx * dx + dy * dy + dz * dz)
            h[j] += zn * (bx * bx + by * by + bz * bz)
            h[k] += zn * (ax * ax + ay * ay + az * az)
        return h


def vhess_diag(V, F, z, wfid):
    """A diagonal curvature scale of (26) per vertex: ``λ_i + Σ_m |z_m| |e_opp|² / (2 s_m)²``.

    The normal of face m turns by about ``|e_opp| / (2 s_m)`` per unit move of a corner, so sliver
    faces make their corners stiff; dividing the gradient by this scale lets the rest of the mesh
    keep a normal step (Jacobi-preconditioned descent).
    """
    if HAVE_NUMBA:
        return _nb_vhess_diag(V, F, z, wfid)
    return _np_vhess_diag(V, F, z, wfid)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_neighbor_sum(N, fa, fb):  # pragma: no cover - compiled
        S = np.zeros_like(N)
        for e in range(fa.shape[0]):
            a, b = fa[e], fb[e]
            for k in range(3):
                S[a, k] += N[b, k]
                S[b, k] += N[a, k]
        return S


def neighbor_sum(N, fa, fb):
    """``S[f] = Σ N[g]`` over the faces g sharing an interior edge with f, shape ``(nF, 3)``."""
    if HAVE_NUMBA:
        return _nb_neighbor_sum(N, fa, fb)
    S = np.zeros_like(N)
    for k in range(3):
        S[:, k] = np.bincount(fa, N[fb, k], len(N)) + np.bincount(fb, N[fa, k], len(N))
    return S


def venergy(V, F, z, V0, wfid):
    """Energy (26) up to a constant (see :class:`meshrepair.inner.VSubproblem`)."""
    if HAVE_NUMBA:
        return float(_nb_venergy(V, F, z, V0, wfid))
    return _np_venergy(V, F, z, V0, wfid)


def venergy_grad(V, F, z, V0, wfid, S=None):
    """Energy (26) and its gradient (28); ``S`` is the corner scatter matrix (numpy path)."""
    if HAVE_NUMBA:
        grad = np.empty_like(V)
        e = _nb_venergy_grad(V, F, z, V0, wfid, grad)
        return float(e), grad
    return _np_venergy_grad(V, F, z, V0, wfid, S)


def face_normals(V, F):
    """Unit face normals, zero rows for degenerate faces, shape ``(nF, 3)``."""
    if HAVE_NUMBA:
        return _nb_face_normals(V, F)
    return _np_face_normals(V, F)


def edge_lengths(V, E):
    """Lengths of edges ``E (nE, 2)``."""
    if HAVE_NUMBA:
        return _nb_edge_lengths(V, E)
    return _np_edge_lengths(V, E)


def grad_edges(N, l, fa, fb):
    """``l_e (N[fa_e] - N[fb_e])`` for interior edges, shape ``(nEi, 3)``."""
    if HAVE_NUMBA:
        return _nb_grad_edges(N, l, fa, fb)
    return _np_grad_edges(N, l, fa, fb)


def grad_edges_T(t, l, fa, fb, nF):
    """Transpose of :func:`grad_edges`, shape ``(nF, 3)``."""
    if HAVE_NUMBA:
        return _nb_grad_edges_T(t, l, fa, fb, nF)
    return _np_grad_edges_T(t, l, fa, fb, nF)


# ---------------------------------------------------------------------------------------------
# fused ADMM steps (one pass each; numpy twins below)


def _np_rhs(c, Nv, rho2, beta1, t, rho1, l, fa, fb):
    return c * Nv + rho2 / beta1 + _np_grad_edges_T(t - rho1 / beta1, l, fa, fb, len(Nv))


def _np_normalize_z(N, Nv, rho2, beta2):
    nn = np.sqrt(np.einsum("ij,ij->i", N, N))[:, None]
    N = np.divide(N, nn, out=Nv.copy(), where=nn > 0)
    return N, rho2 - beta2 * N


def _np_update_rho1(t, N, l, fa, fb, rho1, beta1):
    r = t - _np_grad_edges(N, l, fa, fb)
    rho1 -= beta1 * r
    return float(np.einsum("ij,ij->", r, r))


def _np_update_rho2(N, Nv, rho2, beta2):
    r = N - Nv
    rho2 -= beta2 * r
    return float(np.einsum("ij,ij->", r, r))


def _np_reg_energy(Nv, l, fa, fb, sharp, a, w):
    t = _np_grad_edges(Nv, l, fa, fb)
    nt = np.sqrt(np.einsum("ij,ij->i", t, t))
    mc = np.where(nt < np.sqrt(2.0 / a), -0.5 * a * nt * nt + np.sqrt(2.0 * a) * nt, 1.0)
    return float(np.where(sharp, mc, w * nt * nt).sum())


def _np_sqdist(A, B, wts):
    d = A - B
    if wts is None:
        return float(np.einsum("ij,ij->", d, d))
    return float(np.einsum("i,ij,ij->", wts, d, d))


if HAVE_NUMBA:

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_rhs(c, Nv, rho2, beta1, t, rho1, l, fa, fb):  # pragma: no cover - compiled
        B = np.empty_like(Nv)
        ib = 1.0 / beta1
        for f in range(Nv.shape[0]):
            for k in range(3):
                B[f, k] = c * Nv[f, k] + rho2[f, k] * ib
        for e in range(fa.shape[0]):
            a, b, w = fa[e], fb[e], l[e]
            for k in range(3):
                x = w * (t[e, k] - rho1[e, k] * ib)
                B[a, k] += x
                B[b, k] -= x
        return B

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_normalize_z(N, Nv, rho2, beta2):  # pragma: no cover - compiled
        z = np.empty_like(N)
        for f in range(N.shape[0]):
            q = np.sqrt(N[f, 0] ** 2 + N[f, 1] ** 2 + N[f, 2] ** 2)
            iq = 1.0 / q if q > 0 else 0.0
            for k in range(3):
                if q > 0:
                    N[f, k] *= iq
                else:
                    N[f, k] = Nv[f, k]
                z[f, k] = rho2[f, k] - beta2 * N[f, k]
        return N, z

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_update_rho1(t, N, l, fa, fb, rho1, beta1):  # pragma: no cover - compiled
        s = 0.0
        for e in range(fa.shape[0]):
            a, b, w = fa[e], fb[e], l[e]
            for k in range(3):
                r = t[e, k] - w * (N[a, k] - N[b, k])
                rho1[e, k] -= beta1 * r
                s += r * r
        return s

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_update_rho2(N, Nv, rho2, beta2):  # pragma: no cover - compiled
        s = 0.0
        for f in range(N.shape[0]):
            for k in range(3):
                r = N[f, k] - Nv[f, k]
                rho2[f, k] -= beta2 * r
                s += r * r
        return s

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_reg_energy(Nv, l, fa, fb, sharp, a, w):  # pragma: no cover - compiled
        knee = np.sqrt(2.0 / a)
        s2a = np.sqrt(2.0 * a)
        e = 0.0
        for i in range(fa.shape[0]):
            p, q, le = fa[i], fb[i], l[i]
            dx = le * (Nv[p, 0] - Nv[q, 0])
            dy = le * (Nv[p, 1] - Nv[q, 1])
            dz = le * (Nv[p, 2] - Nv[q, 2])
            n2 = dx * dx + dy * dy + dz * dz
            if sharp[i]:
                nt = np.sqrt(n2)
                e += (-0.5 * a * n2 + s2a * nt) if nt < knee else 1.0
            else:
                e += w * n2
        return e

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_sqdist(A, B, wts):  # pragma: no cover - compiled
        s = 0.0
        for i in range(A.shape[0]):
            d = 0.0
            for k in range(3):
                x = A[i, k] - B[i, k]
                d += x * x
            s += d * wts[i]
        return s


def rhs(c, Nv, rho2, beta1, t, rho1, l, fa, fb):
    """Right-hand side of (25): ``c Nv + ρ2/β1 + Dᵀ(t - ρ1/β1)``."""
    f = _nb_rhs if HAVE_NUMBA else _np_rhs
    return f(c, Nv, rho2, beta1, t, rho1, l, fa, fb)


def normalize_z(N, Nv, rho2, beta2):
    """Normalise N's rows (``Nv`` where N vanishes); return ``(N, ρ2 - β2 N)``."""
    f = _nb_normalize_z if HAVE_NUMBA else _np_normalize_z
    return f(N, Nv, rho2, beta2)


def update_rho1(t, N, l, fa, fb, rho1, beta1):
    """(20) in place; returns ``||t - DN||²``."""
    f = _nb_update_rho1 if HAVE_NUMBA else _np_update_rho1
    return float(f(t, N, l, fa, fb, rho1, beta1))


def update_rho2(N, Nv, rho2, beta2):
    """(21) in place; returns ``||N - 𝒩(V)||²``."""
    f = _nb_update_rho2 if HAVE_NUMBA else _np_update_rho2
    return float(f(N, Nv, rho2, beta2))


def reg_energy(Nv, l, fa, fb, sharp, a, w):
    """Regularisers of (6) on interior edges: MC where ``sharp``, ``w ||DN||²`` elsewhere."""
    f = _nb_reg_energy if HAVE_NUMBA else _np_reg_energy
    return float(f(Nv, l, fa, fb, sharp, float(a), float(w)))


def sqdist(A, B, wts=None):
    """``Σ_i wts_i ||A_i - B_i||²`` (all weights 1 when ``wts`` is None)."""
    if HAVE_NUMBA:
        return float(_nb_sqdist(A, B, np.ones(len(A)) if wts is None else wts))
    return _np_sqdist(A, B, wts)


# ---------------------------------------------------------------------------------------------
# connectivity kernels (setup of large meshes: one O(n) pass instead of sorts and graph builds)


def _np_group_halfedges(F, n_vertices):
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    code = np.minimum(he[:, 0], he[:, 1]) * np.int64(n_vertices) + np.maximum(he[:, 0], he[:, 1])
    return np.argsort(code, kind="stable")


def _np_union_find(n, a, b):
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    G = sp.coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(n, n))
    return connected_components(G.tocsr(), directed=False)[1].astype(np.int64)


def _np_face_area2_lmax2(V, F):
    e01 = V[F[:, 1]] - V[F[:, 0]]
    e12 = V[F[:, 2]] - V[F[:, 1]]
    e20 = V[F[:, 0]] - V[F[:, 2]]
    l2 = np.stack([np.einsum("ij,ij->i", e, e) for e in (e01, e12, e20)], axis=1)
    cross = np.cross(e01, -e20)
    return np.sqrt(np.einsum("ij,ij->i", cross, cross)), l2.max(axis=1)


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
            q = np.sqrt(vn[v, 0] ** 2 + vn[v, 1] ** 2 + vn[v, 2] ** 2)
            if q > 0:
                vn[v, 0] /= q
                vn[v, 1] /= q
                vn[v, 2] /= q
        return vn

    @njit(cache=True)
    def _nb_umbrella(V, E):  # pragma: no cover - compiled
        S = np.zeros((V.shape[0], 3))
        deg = np.zeros(V.shape[0])
        for e in range(E.shape[0]):
            a, b = E[e, 0], E[e, 1]
            for k in range(3):
                S[a, k] += V[b, k]
                S[b, k] += V[a, k]
            deg[a] += 1.0
            deg[b] += 1.0
        return S, deg

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


def _np_umbrella(V, E):
    idx = np.r_[E[:, 0], E[:, 1]]
    nb = np.r_[V[E[:, 1]], V[E[:, 0]]]
    S = np.stack([np.bincount(idx, nb[:, j], len(V)) for j in range(3)], axis=1)
    return S, np.bincount(idx, minlength=len(V)).astype(np.float64)


def vertex_normals(V, F):
    """Area-weighted unit vertex normals ``(nV, 3)`` (zero rows for unreferenced vertices)."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_vertex_normals(V, F)
    return _np_vertex_normals(V, F)


def umbrella(V, E):
    """Sum of the neighbours' positions ``(nV, 3)`` and the degree ``(nV,)`` over edges ``E``."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    E = np.ascontiguousarray(E, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_umbrella(V, E)
    return _np_umbrella(V, E)


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
