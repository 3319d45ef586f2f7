"""Fused passes of the hot loop, compiled with numba when present.

The preconditioned Armijo V-descent (26).

:func:`meshrepair.inner.solve_armijo` needs, per call, the energy, gradient (28) and Jacobi
scale of (26) at the start point, then per descent step the direction ``d = -D⁻¹ ∇J`` with its
slope, and per backtracking trial the energy at ``V + s d``. Done with separate kernels and numpy
expressions that is one face pass for the energy-gradient, one more for the scale, and per trial
a numpy temporary ``V + s d`` plus one energy pass. Here:

* :func:`venergy_grad_hdiag`: energy, gradient and the scale of ``vhess_diag`` in one face pass
  (same arithmetic as ``_kernels.venergy_grad`` and ``_kernels.vhess_diag``: results equal);
* :func:`descent_direction`: ``d = -g / max(h, h_min)`` and ``⟨g, -d⟩`` in one vertex pass;
* :func:`venergy_trial`: writes ``V + s d`` into a reused buffer and evaluates (26) there, in one
  vertex pass and one face pass.

The ADMM loop's relative change of V (rule (35)) is :func:`rel_change`: one pass, no
temporaries. :func:`normals_update_rho2` computes the normals of the new V and the multiplier
update (21) in one face pass; :func:`lengths_reg_energy` the new edge lengths and the
regulariser of (6) (the history energy) in one edge pass.

Each kernel has a numpy twin (``tests/test_kernels.py`` checks they agree).
"""

from __future__ import annotations

import numpy as np

from . import _kernels as _k
from ._kernels import FASTMATH, HAVE_NUMBA, _np_venergy, _np_venergy_grad, _np_vhess_diag

if HAVE_NUMBA:
    from ._kernels import njit

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_venergy_grad_hdiag(V, F, z, V0, wfid, grad, h):  # pragma: no cover - compiled
        nV = V.shape[0]
        f = 0.0
        for v in range(nV):
            w = wfid[v]
            dx = V[v, 0] - V0[v, 0]
            dy = V[v, 1] - V0[v, 1]
            dz = V[v, 2] - V0[v, 2]
            grad[v, 0] = w * dx
            grad[v, 1] = w * dy
            grad[v, 2] = w * dz
            h[v] = w
            f += w * (dx * dx + dy * dy + dz * dz)
        e = 0.0
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
            c2 = cx * cx + cy * cy + cz * cz
            q = np.sqrt(c2)
            if q < 1e-300:
                q = 1e-300
            iq = 1.0 / q
            nx, ny, nz = cx * iq, cy * iq, cz * iq
            zx, zy, zz = z[m, 0], z[m, 1], z[m, 2]
            zn = zx * nx + zy * ny + zz * nz
            e += zn
            gx = (zx - zn * nx) * iq
            gy = (zy - zn * ny) * iq
            gz = (zz - zn * nz) * iq
            ux, uy, uz = p2x - p1x, p2y - p1y, p2z - p1z
            grad[i, 0] += gy * uz - gz * uy
            grad[i, 1] += gz * ux - gx * uz
            grad[i, 2] += gx * uy - gy * ux
            wx, wy, wz = p0x - p2x, p0y - p2y, p0z - p2z
            grad[j, 0] += gy * wz - gz * wy
            grad[j, 1] += gz * wx - gx * wz
            grad[j, 2] += gx * wy - gy * wx
            grad[k, 0] += gy * az - gz * ay
            grad[k, 1] += gz * ax - gx * az
            grad[k, 2] += gx * ay - gy * ax
            # the Jacobi scale of _kernels.vhess_diag (same expressions)
            q2 = max(c2, 1e-300)
            s = np.sqrt(zx ** 2 + zy ** 2 + zz ** 2) / q2
            h[i] += s * (ux * ux + uy * uy + uz * uz)
            h[j] += s * (bx * bx + by * by + bz * bz)
            h[k] += s * (ax * ax + ay * ay + az * az)
        return e + 0.5 * f

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_descent_direction(g, h, h_min, d):  # pragma: no cover - compiled
        s = 0.0
        for v in range(g.shape[0]):
            hv = h[v]
            if hv < h_min:
                hv = h_min
            hinv = 1.0 / hv
            for k in range(3):
                x = -g[v, k] * hinv
                d[v, k] = x
                s -= g[v, k] * x
        return s

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_venergy_trial(V, d, step, out, F, z, V0, wfid):  # pragma: no cover - compiled
        f = 0.0
        for v in range(V.shape[0]):
            x0 = V[v, 0] + step * d[v, 0]
            x1 = V[v, 1] + step * d[v, 1]
            x2 = V[v, 2] + step * d[v, 2]
            out[v, 0] = x0
            out[v, 1] = x1
            out[v, 2] = x2
            w = wfid[v]
            if w != 0.0:
                dx = x0 - V0[v, 0]
                dy = x1 - V0[v, 1]
                dz = x2 - V0[v, 2]
                f += w * (dx * dx + dy * dy + dz * dz)
        e = 0.0
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax = out[j, 0] - out[i, 0]
            ay = out[j, 1] - out[i, 1]
            az = out[j, 2] - out[i, 2]
            bx = out[k, 0] - out[i, 0]
            by = out[k, 1] - out[i, 1]
            bz = out[k, 2] - out[i, 2]
            cx = ay * bz - az * by
            cy = az * bx - ax * bz
            cz = ax * by - ay * bx
            q = np.sqrt(cx * cx + cy * cy + cz * cz)
            if q < 1e-300:
                q = 1e-300
            e += (z[m, 0] * cx + z[m, 1] * cy + z[m, 2] * cz) / q
        return e + 0.5 * f

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_rel_change(A, B):  # pragma: no cover - compiled
        num = 0.0
        den = 0.0
        for i in range(A.shape[0]):
            for k in range(3):
                x = A[i, k] - B[i, k]
                num += x * x
                den += B[i, k] * B[i, k]
        return np.sqrt(num / max(den, 1e-300))

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_normals_update_rho2(V, F, N, rho2, beta2):  # pragma: no cover - compiled
        Nv = np.zeros((F.shape[0], 3))
        s = 0.0
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax = V[j, 0] - V[i, 0]
            ay = V[j, 1] - V[i, 1]
            az = V[j, 2] - V[i, 2]
            bx = V[k, 0] - V[i, 0]
            by = V[k, 1] - V[i, 1]
            bz = V[k, 2] - V[i, 2]
            c0 = ay * bz - az * by
            c1 = az * bx - ax * bz
            c2 = ax * by - ay * bx
            q = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
            if q > 0:
                iq = 1.0 / q
                c0 *= iq
                c1 *= iq
                c2 *= iq
            else:
                c0 = c1 = c2 = 0.0
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

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_lengths_reg_energy(V, E, Nv, fa, fb, sharp, a, w):  # pragma: no cover - compiled
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
            p, q = fa[i], fb[i]
            tx = le * (Nv[p, 0] - Nv[q, 0])
            ty = le * (Nv[p, 1] - Nv[q, 1])
            tz = le * (Nv[p, 2] - Nv[q, 2])
            n2 = tx * tx + ty * ty + tz * tz
            if sharp[i]:
                nt = np.sqrt(n2)
                e += (-0.5 * a * n2 + s2a * nt) if nt < knee else 1.0
            else:
                e += w * n2
        return l, e


def normals_update_rho2(V, F, N, rho2, beta2):
    """Unit face normals ``Nv`` of ``V`` (zero rows for degenerate faces) and the multiplier
    update (21) ``ρ2 -= β2 (N - Nv)`` in place; returns ``(Nv, ||N - Nv||²)``."""
    if HAVE_NUMBA:
        Nv, s = _nb_normals_update_rho2(V, F, N, rho2, float(beta2))
        return Nv, float(s)
    Nv = _k.face_normals(V, F)
    return Nv, _k.update_rho2(N, Nv, rho2, beta2)


def lengths_reg_energy(V, E, Nv, fa, fb, sharp, a, w):
    """Lengths of the interior edges ``E`` of ``V`` and the regulariser of (6) there (see
    ``_kernels.reg_energy``); returns ``(l, energy)``."""
    if HAVE_NUMBA:
        l, e = _nb_lengths_reg_energy(V, E, Nv, fa, fb, sharp, float(a), float(w))
        return l, float(e)
    l = _k.edge_lengths(V, E)
    return l, _k.reg_energy(Nv, l, fa, fb, sharp, a, w)


def _np_rel_change(A, B):
    d = A - B
    return float(np.sqrt(np.einsum("ij,ij->", d, d) / max(np.einsum("ij,ij->", B, B), 1e-300)))


def rel_change(A, B):
    """``||A - B||_F / ||B||_F`` (rule (35) with ``A = V^(k+1)``, ``B = V^(k)``)."""
    f = _nb_rel_change if HAVE_NUMBA else _np_rel_change
    return float(f(A, B))


def _np_venergy_grad_hdiag(V, F, z, V0, wfid, S):
    e, g = _np_venergy_grad(V, F, z, V0, wfid, S)
    return e, g, _np_vhess_diag(V, F, z, wfid)


def _np_descent_direction(g, h, h_min, d):
    d[:] = -g * (1.0 / np.maximum(h, h_min))[:, None]
    return -float(np.einsum("ij,ij->", g, d))


def _np_venergy_trial(V, d, step, out, F, z, V0, wfid):
    np.add(V, step * d, out=out)
    return _np_venergy(out, F, z, V0, wfid)


def venergy_grad_hdiag(V, F, z, V0, wfid, S=None):
    """Energy (26), gradient (28) ``(nV, 3)`` and the Jacobi scale ``(nV,)`` of
    ``_kernels.vhess_diag``, in one face pass; ``S`` is the corner scatter matrix (numpy path)."""
    if HAVE_NUMBA:
        grad = np.empty_like(V)
        h = np.empty(len(V))
        e = _nb_venergy_grad_hdiag(V, F, z, V0, wfid, grad, h)
        return float(e), grad, h
    return _np_venergy_grad_hdiag(V, F, z, V0, wfid, S)


def descent_direction(g, h, h_min, d):
    """``d = -g / max(h, h_min)`` (per vertex, written into ``d``); returns ``⟨g, -d⟩ ≥ 0``."""
    f = _nb_descent_direction if HAVE_NUMBA else _np_descent_direction
    return float(f(g, h, float(h_min), d))


def venergy_trial(V, d, step, out, F, z, V0, wfid):
    """Write ``V + step d`` into ``out`` and return the energy (26) there."""
    f = _nb_venergy_trial if HAVE_NUMBA else _np_venergy_trial
    return float(f(V, d, float(step), out, F, z, V0, wfid))
