"""Synthetic damage for tests and benchmarks: geodesic discs, damaged regions, rigid motions,
exactly mirror-symmetric meshes, a triangulated grid plane and thrown-vertex (impulsive) noise.

These build the cut-and-repair cases of the test suite and of ``benchmarks/completion.py`` (a
region of a known mesh is damaged and repaired, and the result is compared with the original),
in the spirit of :func:`meshrepair.model.noise.add_noise`. Distances on the surface are shortest
paths
in the edge graph weighted by edge length (Dijkstra), an upper bound of the geodesic distance.
"""

from __future__ import annotations

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.geometry import mean_edge_length, vertex_normals

DAMAGES = ("dent", "spike", "noise", "flat")
"""The kinds of :func:`damage_region`."""


def edge_graph(V: np.ndarray, F: np.ndarray):
    """The mesh's edge graph weighted by edge length: a symmetric ``(nV, nV)`` scipy CSR matrix
    (for ``scipy.sparse.csgraph``)."""
    import scipy.sparse as sp

    from meshrepair.mesh.topology import edge_topology

    e = edge_topology(F, len(V)).edges
    w = np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    return sp.coo_matrix((np.r_[w, w], (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                         shape=(len(V), len(V))).tocsr()


def edge_graph_distances(V: np.ndarray, F: np.ndarray, sources, *,
                         limit: float = np.inf) -> np.ndarray:
    """Edge-graph distances from ``sources`` (a vertex index or a list of them).

    Parameters
    ----------
    V : (nV, 3) float64
    F : (nF, 3) int64
    sources : int or sequence of int
    limit : float
        Distances above ``limit`` are not explored and come back as ``inf``.

    Returns
    -------
    (nV,) float64 for one source, (len(sources), nV) for a list.
    """
    from scipy.sparse.csgraph import dijkstra

    return dijkstra(edge_graph(V, F), indices=sources, limit=limit)


def geodesic_disc(V: np.ndarray, F: np.ndarray, center: int, radius: float, *,
                  return_distances: bool = False):
    """Faces whose three vertices lie within ``radius`` (edge-graph distance) of ``center``.

    Returns
    -------
    faces : (k,) int64
        Indices into ``F``.
    d : (nV,) float64
        Only with ``return_distances``: the distances from ``center``, ``inf`` beyond 1.5 r.
    """
    d = edge_graph_distances(V, F, center, limit=1.5 * radius)
    faces = np.flatnonzero((d[F] <= radius).all(axis=1))
    return (faces, d) if return_distances else faces


def damage_region(V: np.ndarray, F: np.ndarray, faces: np.ndarray, d: np.ndarray,
                  radius: float, kind: str, *, seed: int = 0) -> np.ndarray:
    """A copy of ``V`` with the interior vertices of a disc region damaged.

    The region's boundary loop is left intact. With ``l`` the mean edge length and ``n`` the
    vertex normals: ``"dent"`` pushes vertex i in by ``2 l max(0, 1 - d_i / radius)`` along
    ``-n_i``; ``"spike"`` lifts the vertex nearest the centre by ``5 l``; ``"noise"`` adds
    isotropic Gaussian noise of deviation ``0.5 l``; ``"flat"`` projects the interior onto the
    least-squares plane of the boundary.

    Parameters
    ----------
    faces : (k,) int64
        The region, e.g. from :func:`geodesic_disc`; it must have one boundary loop.
    d : (nV,) float64
        Distances from the region's centre (as returned by :func:`geodesic_disc`).
    kind : {"dent", "spike", "noise", "flat"}
    """
    from meshrepair.mesh.topology import boundary_loops

    if kind not in DAMAGES:
        raise MeshRepairError(f"unknown damage {kind!r}: use one of {', '.join(DAMAGES)}")
    b = boundary_loops(F[faces], len(V))[0]
    inner = np.setdiff1d(np.unique(F[faces]), b)
    l = mean_edge_length(V, F)
    Vd = np.array(V, dtype=float, copy=True)
    if kind == "dent":
        N = vertex_normals(V, F)
        Vd[inner] -= (2 * l * np.clip(1 - d[inner] / radius, 0, 1))[:, None] * N[inner]
    elif kind == "spike":
        N = vertex_normals(V, F)
        c = inner[np.argmin(d[inner])]
        Vd[c] += 5 * l * N[c]
    elif kind == "noise":
        Vd[inner] += 0.5 * l * np.random.default_rng(seed).normal(size=(len(inner), 3))
    else:  # flat
        c = V[b].mean(axis=0)
        n = np.linalg.svd(V[b] - c)[2][2]
        Vd[inner] -= ((V[inner] - c) @ n)[:, None] * n
    return Vd


def random_rigid(seed: int, shift: float) -> np.ndarray:
    """A random rotation and a translation of typical length ``shift``, as a (4, 4) matrix."""
    from scipy.spatial.transform import Rotation

    T = np.eye(4)
    T[:3, :3] = Rotation.random(random_state=seed).as_matrix()
    T[:3, 3] = shift * np.random.default_rng(seed).normal(size=3)
    return T


def symmetrize(V: np.ndarray, F: np.ndarray, axis: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """An exactly mirror-symmetric mesh: the half of ``(V, F)`` on one side of the plane through
    the centroid normal to ``axis``, and its mirror image, welded on the plane."""
    import trimesh

    c = V.mean(axis=0)
    n = np.zeros(3)
    n[axis] = 1.0
    Vh, Fh = trimesh.intersections.slice_faces_plane(V, F, n, c)[:2]
    Vh = np.asarray(Vh, float).copy()
    Fh = np.asarray(Fh, np.int64)
    on = np.abs(Vh[:, axis] - c[axis]) < 1e-12
    Vh[on, axis] = c[axis]
    Vm = Vh.copy()
    Vm[:, axis] = 2 * c[axis] - Vm[:, axis]
    W = trimesh.Trimesh(np.vstack([Vh, Vm]), np.vstack([Fh, Fh[:, ::-1] + len(Vh)]),
                        process=False)
    W.merge_vertices(digits_vertex=10)
    W.remove_unreferenced_vertices()
    return np.asarray(W.vertices, float), np.asarray(W.faces, np.int64)


def grid_plane(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The unit grid of ``n × n`` vertices in the plane z = 0, each square cut along its diagonal.

    Returns
    -------
    V : (n², 3) float64, vertex ``i n + j`` at ``(j, i, 0)``
    F : (2 (n - 1)², 3) int64, faces ``(a, a + 1, a + n + 1)`` and ``(a, a + n + 1, a + n)``
    """
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    V = np.c_[x.ravel(), y.ravel(), np.zeros(n * n)]
    a = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    F = np.r_[np.c_[a, a + 1, a + n + 1], np.c_[a, a + n + 1, a + n]].astype(np.int64)
    return V, F


def impulsive_noise(V: np.ndarray, F: np.ndarray, frac: float, amp: float,
                    seed: int = 5) -> np.ndarray:
    """Impulsive noise of ``benchmarks/impulsive.py``: every vertex moves 0.1 mean edge lengths
    ``l`` (Gaussian) along its normal, and a fraction ``frac`` of them is thrown a further
    ``amp l`` (Gaussian) along it.

    Returns
    -------
    (nV, 3) float64, a new array
    """
    rng = np.random.default_rng(seed)
    length = mean_edge_length(V, F)
    N = vertex_normals(V, F)
    Vn = V + 0.1 * length * rng.normal(size=(len(V), 1)) * N
    idx = rng.random(len(V)) < frac
    Vn[idx] += (amp * length * rng.normal(size=(idx.sum(), 1))) * N[idx]
    return Vn


def cut_holes(V: np.ndarray, F: np.ndarray, radius: float, *, n_holes: int = 3, seed: int = 0,
              centres=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The cut protocol of the hole benchmarks: ``n_holes`` geodesic discs cut from a mesh.

    Centres are vertices drawn at random (``seed``) among those farther than ``2.5 radius``
    (edge-graph distance) from every centre drawn before, so the holes stay apart; every face
    with a corner within ``radius`` mean edge lengths of a centre is removed and the unused
    vertices are dropped.

    Parameters
    ----------
    radius : float
        Disc radius in mean edge lengths (``l̄``).
    centres : sequence of int, optional
        Vertex indices of the first centres (e.g. on a crease); the rest are drawn.

    Returns
    -------
    Vc, Fc : the cut mesh (vertices in their original order)
    removed : (r,) int64
        Indices into ``F`` of the removed faces (the ground truth of the holes).
    centres : (n_holes,) int64
        The centre vertices (input numbering).
    """
    if not (np.isfinite(radius) and radius > 0) or int(n_holes) < 1:
        raise MeshRepairError(f"cut_holes needs radius > 0 and n_holes >= 1, got {radius!r}, "
                              f"{n_holes!r}")
    le = mean_edge_length(V, F)
    rng = np.random.default_rng(seed)
    chosen = [int(c) for c in (centres or ())][:n_holes]
    far = np.ones(len(V), bool)
    inside = np.zeros(len(V), bool)
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    for i in range(n_holes):
        if i >= len(chosen):
            cand = np.flatnonzero(far & used)
            if len(cand) == 0:
                break
            chosen.append(int(rng.choice(cand)))
        d = edge_graph_distances(V, F, chosen[i], limit=2.5 * radius * le)
        inside |= d < radius * le
        far &= ~(d < 2.5 * radius * le)
    removed = inside[F].any(axis=1)
    Fk = F[~removed]
    keep = np.zeros(len(V), bool)
    keep[Fk.ravel()] = True
    vmap = np.cumsum(keep) - 1
    return (V[keep], vmap[Fk].astype(np.int64), np.flatnonzero(removed).astype(np.int64),
            np.asarray(chosen, np.int64))
