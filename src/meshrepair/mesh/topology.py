"""Connectivity of a triangle mesh: unique edges, edge-face incidence, boundary loops, components.

Everything here depends only on the face array ``F`` (int64, shape ``(nF, 3)``) and is computed
once per connectivity; geometry lives in :mod:`meshrepair.mesh.geometry`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class Topology:
    """Edge structure of a triangle mesh.

    Attributes
    ----------
    n_vertices : int
    faces : (nF, 3) int64
    edges : (nE, 2) int64
        Unique undirected edges, ``edges[:, 0] < edges[:, 1]``.
    edge_faces : (nE, 2) int64
        The two faces incident to each edge; ``edge_faces[:, 0] < edge_faces[:, 1]`` for interior
        edges (the ordering of (4): ``+l`` on the lower face index), ``-1`` in column 1 for
        boundary edges. Non-manifold edges (more than two faces) are rejected by
        :func:`edge_topology`.
    face_edges : (nF, 3) int64
        ``face_edges[m, k]`` is the index of the edge ``(F[m, k], F[m, (k+1) % 3])``.
    edge_counts : (nE,) int64
        Number of faces incident to each edge (1 boundary, 2 interior, >2 non-manifold).

    Operators derived from the connectivity alone (vertex adjacency, umbrella operator, face
    adjacencies) are built once per topology by :func:`cached` and kept in ``_cache`` until
    :meth:`drop_cache`.
    """

    n_vertices: int
    faces: np.ndarray
    edges: np.ndarray
    edge_faces: np.ndarray
    face_edges: np.ndarray
    edge_counts: np.ndarray = field(repr=False)
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def drop_cache(self, keep: tuple = ()) -> None:
        """Forget the cached operators (:func:`cached`), except those whose key's first item
        is in ``keep``."""
        for k in [k for k in self._cache if k[0] not in keep]:
            del self._cache[k]

    @property
    def n_faces(self) -> int:
        return int(self.faces.shape[0])

    @property
    def n_edges(self) -> int:
        return int(self.edges.shape[0])

    @property
    def interior(self) -> np.ndarray:
        """(nE,) bool: edges with two incident faces."""
        return self.edge_faces[:, 1] >= 0

    @property
    def boundary(self) -> np.ndarray:
        """(nE,) bool: edges with exactly one incident face."""
        return self.edge_faces[:, 1] < 0


def edge_topology(F: np.ndarray, n_vertices: int | None = None) -> Topology:
    """Build the unique edges and the edge-face incidence of a triangle mesh.

    Parameters
    ----------
    F : (nF, 3) int array
    n_vertices : int, optional
        Number of vertices (default ``F.max() + 1``).

    Returns
    -------
    Topology
        Edges with more than two incident faces keep only their first two faces in
        ``edge_faces``; ``edge_counts`` records the true count so callers can detect them.
    """
    F = np.asarray(F, dtype=np.int64)
    nF = F.shape[0]
    if n_vertices is None:
        n_vertices = int(F.max()) + 1 if nF else 0
    from meshrepair._kernels import edge_tables

    # half-edges grouped by edge, faces ascending (a stable sort by the edge's vertex pair)
    return _topology_from_parts(F, n_vertices, *edge_tables(F, n_vertices))


def permuted_topology(topo: Topology, inv: np.ndarray, pf: np.ndarray,
                      faces: np.ndarray) -> Topology:
    """The topology of ``faces = inv[topo.faces][pf]`` (vertex ``v`` renumbered ``inv[v]``, face
    ``m`` the old face ``pf[m]``): equal to ``edge_topology(faces, topo.n_vertices)``, permuted
    from ``topo``'s tables (:func:`meshrepair._kernels.permuted_edges`) when no edge has more
    than two faces, built again otherwise."""
    if int(topo.edge_counts.max(initial=0)) > 2:
        return edge_topology(faces, topo.n_vertices)
    from meshrepair._kernels import permuted_edges

    edges, edge_faces, face_edges, counts = permuted_edges(
        topo.edges, topo.edge_faces, topo.face_edges, topo.edge_counts, inv, pf)
    return Topology(n_vertices=topo.n_vertices, faces=np.asarray(faces, dtype=np.int64),
                    edges=edges, edge_faces=edge_faces, face_edges=face_edges,
                    edge_counts=counts)


def _topology_from_parts(F: np.ndarray, n_vertices: int, edges: np.ndarray, edge_he: np.ndarray,
                         inv: np.ndarray, counts: np.ndarray) -> Topology:
    """A :class:`Topology` from the output of ``_kernels.edges_from_groups``."""
    nF = F.shape[0]
    edge_faces = edge_he // 3  # (floor division: an absent half-edge -1 gives face -1)
    return Topology(
        n_vertices=int(n_vertices),
        faces=F,
        edges=edges,
        edge_faces=edge_faces,
        face_edges=inv.reshape(nF, 3),
        edge_counts=counts,
    )


def cached(topo: Topology, key: tuple, build):
    """``build()`` for this topology, computed on the first call with ``key`` and kept on
    ``topo`` (a function of the connectivity only; callers do not modify the value)."""
    v = topo._cache.get(key)
    if v is None:
        v = topo._cache[key] = build()
    return v


def mask_key(mask: np.ndarray) -> bytes:
    """A digest of a boolean mask, for :func:`cached` keys of masked operators."""
    import hashlib

    m = np.ascontiguousarray(mask, dtype=bool)
    return hashlib.blake2b(np.packbits(m).tobytes() + str(m.shape).encode(),
                           digest_size=16).digest()


def adjacency(topo: Topology) -> sp.csr_matrix:
    """The symmetric 0/1 vertex adjacency of ``topo`` (the matrix of :func:`vertex_adjacency`,
    rows sorted), cached."""
    return cached(topo, ("adjacency",), lambda: vertex_adjacency(topo.edges, topo.n_vertices))


def umbrella_operator(topo: Topology) -> sp.csr_matrix:
    """``W = D⁻¹A``: the mean over the one-ring (isolated vertices: a zero row), cached. Its
    entries are stored as scipy's product ``diags(1 / deg) @ A`` stores them (each row's
    columns descending), so ``W @ X`` sums in the same order as that product's."""
    def build():
        from meshrepair._kernels import umbrella_entries

        A = adjacency(topo)
        data, indices = umbrella_entries(A.indptr, A.indices)  # each row of A reversed
        return sp.csr_matrix((data, indices, A.indptr), shape=A.shape)

    return cached(topo, ("umbrella",), build)


def vertex_adjacency(edges: np.ndarray, n_vertices: int) -> sp.csr_matrix:
    """Symmetric 0/1 vertex adjacency matrix, shape ``(nV, nV)``: canonical CSR (rows sorted,
    duplicate edges merged), built in one pass (:func:`meshrepair._kernels.edge_csr`)."""
    from meshrepair._kernels import edge_csr

    n = int(n_vertices)
    indptr, indices = edge_csr(edges, n)
    return sp.csr_matrix((np.ones(len(indices)), indices, indptr), shape=(n, n))


def vertex_face_incidence(F: np.ndarray, n_vertices: int) -> sp.csr_matrix:
    """Sparse ``(nV, nF)`` matrix with a 1 where vertex i is a corner of face m."""
    nF = F.shape[0]
    rows = F.ravel()
    cols = np.repeat(np.arange(nF), 3)
    return sp.csr_matrix((np.ones(3 * nF), (rows, cols)), shape=(n_vertices, nF))


def connected_components(F: np.ndarray, n_vertices: int) -> tuple[int, np.ndarray]:
    """Face-connected components (via shared vertices).

    Returns
    -------
    n : int
    labels : (nV,) int64
        Component label per vertex; unreferenced vertices get their own labels.
    """
    from meshrepair._kernels import union_find

    labels = union_find(n_vertices, np.r_[F[:, 0], F[:, 1]], np.r_[F[:, 1], F[:, 2]])
    n = int(labels.max()) + 1 if len(labels) else 0
    return int(n), labels.astype(np.int64)


def boundary_loops(F: np.ndarray, n_vertices: int | None = None) -> list[np.ndarray]:
    """Boundary loops as ordered vertex index arrays.

    Each loop follows the orientation of its faces (a boundary half-edge ``(u, v)`` of a face is
    followed by ``(v, w)``), so filling a loop with faces ``(v, u, ·)`` keeps the mesh consistently
    oriented. At a pinched vertex (several boundary loops through one vertex) the loops are split
    by choosing, at each vertex, the outgoing boundary half-edge in face-order; every boundary
    half-edge is used exactly once.

    Parameters
    ----------
    F : (nF, 3) int array
    n_vertices : int, optional

    Returns
    -------
    list of (k,) int64 arrays, longest first.
    """
    F = np.asarray(F, dtype=np.int64)
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    nv = int(F.max()) + 1 if n_vertices is None else n_vertices
    key = np.sort(he, axis=1)
    code = key[:, 0] * np.int64(nv) + key[:, 1]
    _, inv, counts = np.unique(code, return_inverse=True, return_counts=True)
    bhe = he[counts[inv] == 1]
    if len(bhe) == 0:
        return []
    # successor map: from each boundary half-edge (u, v) go to a boundary half-edge starting at v
    order = np.argsort(bhe[:, 0], kind="stable")
    starts_sorted = bhe[order, 0]
    used = np.zeros(len(bhe), dtype=bool)
    loops: list[np.ndarray] = []
    for s in range(len(bhe)):
        if used[s]:
            continue
        loop = []
        cur = s
        while not used[cur]:
            used[cur] = True
            u, v = bhe[cur]
            loop.append(u)
            lo = np.searchsorted(starts_sorted, v, side="left")
            hi = np.searchsorted(starts_sorted, v, side="right")
            nxt = -1
            for k in order[lo:hi]:
                if not used[k]:
                    nxt = k
                    break
            if nxt < 0:
                break
            cur = nxt
        loops.append(np.asarray(loop, dtype=np.int64))
    loops.sort(key=len, reverse=True)
    return loops


def used_vertices(index_rows: np.ndarray, n_vertices: int) -> np.ndarray:
    """(n_vertices,) bool, the vertices named in ``index_rows`` (faces (nF, 3) or edges (nE, 2)):
    those some face uses."""
    used = np.zeros(int(n_vertices), bool)
    used[np.asarray(index_rows).ravel()] = True
    return used


def compact(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mesh on the vertices its faces use: ``(idx, V[idx], F renumbered)``, ``idx`` the
    used vertices in increasing order (so the renumbering keeps every order: edges sorted by
    vertex stay sorted).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int, indices in ``[0, nV)``

    Returns
    -------
    idx : (k,) int64
    V_used : (k, 3), a copy
    F_used : (nF, 3) int64
    """
    idx = np.flatnonzero(used_vertices(F, len(V)))
    new = np.full(len(V), -1, np.int64)
    new[idx] = np.arange(len(idx))
    return idx, V[idx], new[np.asarray(F)]


def least_first(T: np.ndarray) -> np.ndarray:
    """Each triangle of ``T`` (t, 3) listed from its least vertex index by a cyclic shift, which
    keeps its orientation: one spelling of a face whatever vertex it was listed from."""
    T = np.asarray(T, dtype=np.int64).reshape(-1, 3)
    first = np.argmin(T, axis=1)[:, None]
    return np.take_along_axis(T, (first + np.arange(3)) % 3, axis=1)


def row_order(A: np.ndarray) -> np.ndarray:
    """Order of the rows of ``A`` (n, m), lexicographic with the first column first (a stable
    sort: equal rows keep their order)."""
    A = np.asarray(A)
    return np.lexsort(A.T[::-1]) if len(A) else np.arange(0)

