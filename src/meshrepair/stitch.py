"""Stitching a template into a hole: ring distances, ears, harmonic spreading (Sect. 5).

Helpers of :func:`meshrepair.complete.complete` that work on the two meshes being joined:
edge-ring distances to a vertex set (:func:`_rings`), splitting template faces that own two
boundary edges (:func:`_split_ears`), spreading the seam gap over the template's first rings
(:func:`_harmonic_displacement`), and converting split fractions between a loop and its
reversed sequence (:func:`_to_loop_params`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .topology import edge_topology, vertex_adjacency


def _to_loop_params(params_seq: list[np.ndarray], reversed_seq: bool) -> list[np.ndarray]:
    """Convert split fractions given along a sequence to the loop's own edge order."""
    if not reversed_seq:
        return params_seq
    n = len(params_seq)
    out: list[np.ndarray] = [np.zeros(0)] * n
    for i, t in enumerate(params_seq):
        # sequence = loop[::-1]: its edge i is loop edge (n - 2 - i) % n traversed backwards
        out[(n - 2 - i) % n] = np.sort(1.0 - np.asarray(t))
    return out


def _rings(topo, seeds: np.ndarray, max_ring: int) -> np.ndarray:
    """Edge-ring distance of every vertex to ``seeds`` (``max_ring + 1`` beyond ``max_ring``)."""
    nV = topo.n_vertices
    A = vertex_adjacency(topo.edges, nV)
    dist = np.full(nV, max_ring + 1, dtype=np.int64)
    dist[seeds] = 0
    front = np.zeros(nV)
    front[seeds] = 1.0
    for r in range(1, max_ring + 1):
        reach = (A @ front > 0) & (dist > max_ring)
        dist[reach] = r
        front = reach.astype(np.float64)
    return dist


def _split_ears(V: np.ndarray, F: np.ndarray, loop: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, int]:
    """Split the inner edge of every face that owns two edges of the boundary ``loop``.

    Such an *ear* would become a zero-area face if its three boundary vertices were merged into
    three collinear seam vertices (which happens when ``b0``'s edges are subdivided). The inner
    edge ``(a, b)`` is split at its midpoint ``m`` and both faces containing it are split in two
    (``(a, b, c) -> (a, m, c), (m, b, c)``), which keeps the surface and the orientation.

    Returns
    -------
    V2, F2 : the patch with the new vertices appended
    n_split : number of ears split
    """
    n = len(loop)
    bedges = {(int(loop[i]), int(loop[(i + 1) % n])) for i in range(n)}
    Fl = F.tolist()
    he_face = {}
    for fi, (a, b, c) in enumerate(Fl):
        he_face[(a, b)] = fi
        he_face[(b, c)] = fi
        he_face[(c, a)] = fi
    ears = [fi for fi, (a, b, c) in enumerate(Fl)
            if ((a, b) in bedges) + ((b, c) in bedges) + ((c, a) in bedges) == 2]
    if not ears:
        return V, F, 0
    Vl = [V]
    nxt = len(V)
    for fi in ears:
        a, b, c = Fl[fi]
        he = [(a, b), (b, c), (c, a)]
        u, v = next(h for h in he if h not in bedges)  # the inner edge
        m = nxt
        nxt += 1
        Vl.append(0.5 * (V[u] + V[v])[None, :])
        for x, y in ((u, v), (v, u)):  # both faces on the edge
            fj = he_face.pop((x, y), None)
            if fj is None:
                continue
            f = Fl[fj]
            k = f.index(x)
            z = f[(k + 2) % 3]
            Fl[fj] = [x, m, z]
            Fl.append([m, y, z])
            fn = len(Fl) - 1
            he_face[(x, m)] = fj
            he_face[(m, z)] = fj
            he_face[(m, y)] = fn
            he_face[(y, z)] = fn
            he_face[(z, x)] = fj
    return np.vstack(Vl), np.asarray(Fl, dtype=np.int64), len(ears)


def _harmonic_displacement(V: np.ndarray, F: np.ndarray, loop: np.ndarray, disp: np.ndarray,
                           rings: int) -> np.ndarray:
    """Spread a displacement of the boundary ``loop`` over ``rings`` rings of a patch.

    The displacement is ``disp`` on the loop, 0 on the vertices more than ``rings`` rings away,
    and harmonic (uniform graph Laplacian) in between. Returns ``(nV, 3)``.
    """
    from scipy.sparse.linalg import spsolve

    topo = edge_topology(F, len(V))
    dist = _rings(topo, loop, rings + 1)
    D = np.zeros((len(V), 3))
    D[loop] = disp
    inner = np.flatnonzero((dist >= 1) & (dist <= rings))
    if inner.size == 0 or rings < 1:
        return D
    Adj = vertex_adjacency(topo.edges, len(V)).tocsr()
    deg = np.asarray(Adj.sum(axis=1)).ravel()
    L = (sp.diags(deg) - Adj).tocsr()
    L_ii = L[inner][:, inner].tocsc()
    rhs = -(L[inner] @ D)
    D[inner] = np.asarray(spsolve(L_ii, rhs)).reshape(-1, 3)
    return D
