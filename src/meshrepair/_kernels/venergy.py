"""Kernels of the V-subproblem (26): its energy, gradient (28) and Jacobi scale, and the fused
passes of the Armijo V-descent (:mod:`meshrepair.model._fused`) that share their loop bodies."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import FASTMATH, HAVE_NUMBA, njit


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

    # a copy of faces._tri (numba's on-disk cache does not notice a change of an inlined helper
    # defined in another file: each file keeps its own)
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
    def _face_energy(V, z, m, i, j, k):  # pragma: no cover - compiled
        """Term ``z_m · n_m`` of (26) of face m = (i, j, k) of ``V``."""
        ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
        q = np.sqrt(cx * cx + cy * cy + cz * cz)
        if q < 1e-300:
            q = 1e-300
        return (z[m, 0] * cx + z[m, 1] * cy + z[m, 2] * cz) / q

    @njit(cache=True, inline="always")
    def _fidelity_grad(V, V0, wfid, v, grad):  # pragma: no cover - compiled
        """Writes the fidelity gradient ``w_v (v - v0)`` into ``grad[v]``; returns
        ``w_v |v - v0|²``."""
        w = wfid[v]
        dx = V[v, 0] - V0[v, 0]
        dy = V[v, 1] - V0[v, 1]
        dz = V[v, 2] - V0[v, 2]
        grad[v, 0] = w * dx
        grad[v, 1] = w * dy
        grad[v, 2] = w * dz
        return w * (dx * dx + dy * dy + dz * dz)

    @njit(cache=True, inline="always")
    def _face_grad(V, i, j, k, zx, zy, zz, grad):  # pragma: no cover - compiled
        """Adds the gradient (28) of the term ``z · n`` of the face (i, j, k) into ``grad``;
        returns the term, ``|c|²`` (``c = a x b``) and the edge vectors ``u = p2 - p1``,
        ``a = p1 - p0``, ``b = p2 - p0`` (the Jacobi scale of :func:`vhess_diag` reuses them).
        The caller loads ``i, j, k`` and ``z``, before the ``grad`` stores."""
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
        iq = 1.0 / q  # one division per face (six measured 1.3x slower)
        nx, ny, nz = cx * iq, cy * iq, cz * iq
        zn = zx * nx + zy * ny + zz * nz
        gx = (zx - zn * nx) * iq
        gy = (zy - zn * ny) * iq
        gz = (zz - zn * nz) * iq
        # corner i: g x (p2 - p1)
        ux, uy, uz = p2x - p1x, p2y - p1y, p2z - p1z
        grad[i, 0] += gy * uz - gz * uy
        grad[i, 1] += gz * ux - gx * uz
        grad[i, 2] += gx * uy - gy * ux
        # corner j: g x (p0 - p2)
        wx, wy, wz = p0x - p2x, p0y - p2y, p0z - p2z
        grad[j, 0] += gy * wz - gz * wy
        grad[j, 1] += gz * wx - gx * wz
        grad[j, 2] += gx * wy - gy * wx
        # corner k: g x (p1 - p0)
        grad[k, 0] += gy * az - gz * ay
        grad[k, 1] += gz * ax - gx * az
        grad[k, 2] += gx * ay - gy * ax
        return zn, c2, ux, uy, uz, ax, ay, az, bx, by, bz

    # The kernels below call the inlined helpers above; numba's on-disk cache does not notice a
    # change of an inlined helper defined in another file, so every caller stays in this file
    # (meshrepair.model._fused only wraps the fused ones).

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_venergy(V, F, z, V0, wfid):  # pragma: no cover - compiled
        e = 0.0
        for m in range(F.shape[0]):
            e += _face_energy(V, z, m, F[m, 0], F[m, 1], F[m, 2])
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
        f = 0.0
        for v in range(V.shape[0]):
            f += _fidelity_grad(V, V0, wfid, v, grad)
        e = 0.0
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            e += _face_grad(V, i, j, k, z[m, 0], z[m, 1], z[m, 2], grad)[0]
        return e + 0.5 * f

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_venergy_grad_hdiag(V, F, z, V0, wfid, grad, h):  # pragma: no cover - compiled
        # meshrepair.model._fused.venergy_grad_hdiag: _nb_venergy_grad and _nb_vhess_diag in one pass  # noqa: E501
        f = 0.0
        for v in range(V.shape[0]):
            f += _fidelity_grad(V, V0, wfid, v, grad)
            h[v] = wfid[v]
        e = 0.0
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            zx, zy, zz = z[m, 0], z[m, 1], z[m, 2]
            zn, c2, ux, uy, uz, ax, ay, az, bx, by, bz = _face_grad(V, i, j, k, zx, zy, zz, grad)
            e += zn
            # the Jacobi scale of vhess_diag (same expressions)
            q2 = max(c2, 1e-300)
            s = np.sqrt(zx * zx + zy * zy + zz * zz) / q2
            h[i] += s * (ux * ux + uy * uy + uz * uz)
            h[j] += s * (bx * bx + by * by + bz * bz)
            h[k] += s * (ax * ax + ay * ay + az * az)
        return e + 0.5 * f

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_venergy_trial(V, d, step, out, F, z, V0, wfid):  # pragma: no cover - compiled
        # meshrepair.model._fused.venergy_trial: out = V + step d, then _nb_venergy(out, ...)
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
            e += _face_energy(out, z, m, F[m, 0], F[m, 1], F[m, 2])
        return e + 0.5 * f

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_venergy_grad_trial(V, d, step, out, F, z, V0, wfid, grad):  # pragma: no cover
        # meshrepair.model._fused.venergy_grad_trial: out = V + step d (as _nb_venergy_trial), then
        # _nb_venergy_grad(out, ...) into grad: the same values as the two calls
        f = 0.0
        for v in range(V.shape[0]):
            out[v, 0] = V[v, 0] + step * d[v, 0]
            out[v, 1] = V[v, 1] + step * d[v, 1]
            out[v, 2] = V[v, 2] + step * d[v, 2]
            f += _fidelity_grad(out, V0, wfid, v, grad)
        e = 0.0
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            e += _face_grad(out, i, j, k, z[m, 0], z[m, 1], z[m, 2], grad)[0]
        return e + 0.5 * f

    @njit(cache=True, fastmath=FASTMATH)
    def _nb_vhess_diag(V, F, z, wfid):  # pragma: no cover - compiled
        h = wfid.copy()
        for m in range(F.shape[0]):
            i, j, k = F[m, 0], F[m, 1], F[m, 2]
            ax, ay, az, bx, by, bz, cx, cy, cz = _tri(V, i, j, k)
            q2 = max(cx * cx + cy * cy + cz * cz, 1e-300)
            zn = np.sqrt(z[m, 0] * z[m, 0] + z[m, 1] * z[m, 1] + z[m, 2] * z[m, 2]) / q2
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


def venergy(V, F, z, V0, wfid):
    """Energy (26) up to a constant (see :class:`meshrepair.model.inner.VSubproblem`)."""
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
