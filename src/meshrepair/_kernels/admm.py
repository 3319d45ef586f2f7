"""Kernels of the ADMM steps: the fused PCG of the N-subproblem, the t update (shrinkage of
(19)), the right-hand side, the z normalisation, the multiplier updates, the regulariser energy of
(6), weighted squared distances."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import FASTMATH, HAVE_NUMBA, njit
from meshrepair._kernels.edges import _np_grad_edges, _np_grad_edges_T

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
            q = np.sqrt(N[f, 0] * N[f, 0] + N[f, 1] * N[f, 1] + N[f, 2] * N[f, 2])
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

    @njit(cache=True, inline="always")
    def _edge_reg(Nv, p, q, le, sharp, a, w, knee, s2a):  # pragma: no cover - compiled
        """Regulariser of (6) on one interior edge: the MC penalty of ``|t|`` where ``sharp``,
        else ``w |t|²``, with ``t = le (Nv[p] - Nv[q])``, ``knee = sqrt(2 / a)``,
        ``s2a = sqrt(2 a)``."""
        dx = le * (Nv[p, 0] - Nv[q, 0])
        dy = le * (Nv[p, 1] - Nv[q, 1])
        dz = le * (Nv[p, 2] - Nv[q, 2])
        n2 = dx * dx + dy * dy + dz * dz
        if sharp:
            nt = np.sqrt(n2)
            return (-0.5 * a * n2 + s2a * nt) if nt < knee else 1.0
        return w * n2

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_reg_energy(Nv, l, fa, fb, sharp, a, w):  # pragma: no cover - compiled
        knee = np.sqrt(2.0 / a)
        s2a = np.sqrt(2.0 * a)
        e = 0.0
        for i in range(fa.shape[0]):
            e += _edge_reg(Nv, fa[i], fb[i], l[i], sharp[i], a, w, knee, s2a)
        return e

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_lengths_reg_energy(V, E, Nv, fa, fb, sharp, a, w):  # pragma: no cover - compiled
        # meshrepair.model._fused.lengths_reg_energy: the edge lengths and _nb_reg_energy in one pass  # noqa: E501
        l = np.empty(E.shape[0])
        knee = np.sqrt(2.0 / a)
        s2a = np.sqrt(2.0 * a)
        e = 0.0
        for i in range(E.shape[0]):
            u, v = E[i, 0], E[i, 1]
            dx = V[v, 0] - V[u, 0]
            dy = V[v, 1] - V[u, 1]
            dz = V[v, 2] - V[u, 2]
            le = np.sqrt(dx * dx + dy * dy + dz * dz)
            l[i] = le
            e += _edge_reg(Nv, fa[i], fb[i], le, sharp[i], a, w, knee, s2a)
        return l, e

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
