"""Per-edge kernels: edge lengths, the edge difference operator ``l_e (N_a - N_b)`` (D = L D̄
of (4)) and its transpose, neighbour sums, the umbrella operator."""

from __future__ import annotations

import numpy as np

from meshrepair._kernels._jit import FASTMATH, HAVE_NUMBA, njit


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


if HAVE_NUMBA:

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


def _np_edge_lengths_exact(V, E):
    return np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1)


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_edge_lengths_exact(V, E):  # pragma: no cover - compiled
        # strict IEEE (no fused multiply-add): numpy's row norm bit for bit
        out = np.empty(E.shape[0])
        for e in range(E.shape[0]):
            a, b = E[e, 0], E[e, 1]
            dx = V[b, 0] - V[a, 0]
            dy = V[b, 1] - V[a, 1]
            dz = V[b, 2] - V[a, 2]
            out[e] = np.sqrt(dx * dx + dy * dy + dz * dz)
        return out


def edge_lengths_exact(V, E):
    """Lengths of edges ``E (nE, 2)``, ``sqrt((dx² + dy²) + dz²)`` in strict IEEE arithmetic (no
    fused multiply-add): bit for bit numpy's ``np.linalg.norm(d, axis=1)``, so a reading's mean
    edge length does not depend on numba."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    E = np.ascontiguousarray(E, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_edge_lengths_exact(V, E)
    return _np_edge_lengths_exact(V, E)


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


if HAVE_NUMBA:

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


def _np_umbrella(V, E):
    idx = np.r_[E[:, 0], E[:, 1]]
    nb = np.r_[V[E[:, 1]], V[E[:, 0]]]
    S = np.stack([np.bincount(idx, nb[:, j], len(V)) for j in range(3)], axis=1)
    return S, np.bincount(idx, minlength=len(V)).astype(np.float64)


def umbrella(V, E):
    """Sum of the neighbours' positions ``(nV, 3)`` and the degree ``(nV,)`` over edges ``E``."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    E = np.ascontiguousarray(E, dtype=np.int64)
    if HAVE_NUMBA:
        return _nb_umbrella(V, E)
    return _np_umbrella(V, E)
