"""Reflective symmetry of a mesh from its intact surface, and the mirrored template of a region.

Symmetric completion (``complete(V, F, region, template="mirror")``) replaces a damaged region
with the mirror image of its intact counterpart on the other side of the mesh's symmetry plane.

**Detection** (:func:`detect_symmetry`). Only the intact surface ``S`` (the mesh without the
region's faces) is used. Candidate planes: the three principal planes of ``S`` through its area
centroid (eigenvectors of the area-weighted covariance of the face centroids), then those of the
whole mesh (removing the region breaks the symmetry of ``S``'s frame; two close eigenvalues can
turn its axes far from the plane). Each candidate
plane ``(n, p)``, reflection ``M(x) = x - 2 ((x - p) . n) n``, is refined by alternating

1. trimmed point-to-plane ICP (:func:`~meshrepair.complete.icp.icp_to_surface`) of the mirrored
samples
   ``M(x_i)`` against ``S``, which gives a rigid ``T`` with ``T M(x_i)`` on ``S``;
2. the plane of the pairs ``(x_i, y_i = T M(x_i))``, which are mirror images of each other for
   an exact symmetry: ``n`` the principal direction of ``x_i - y_i`` (the eigenvector of
   ``sum (x_i - y_i)(x_i - y_i)^T``), ``p`` the mean midpoint ``(x_i + y_i) / 2``.

The **residual** of a plane is the mean distance from the mirrored intact vertices to ``S``, in
mean edge lengths ``l``, leaving out the vertices whose image falls into a ball around the region
(their counterpart is the region that was removed). The best candidate is returned.

**Counterpart** (:func:`mirror_template`). Each vertex of the hole's loop ``b0`` is mirrored and
snapped to the nearest intact vertex; consecutive snapped vertices are joined by shortest edge
paths, which gives a closed cut on the other side. The faces reached from the mirror image of the
region's centre without crossing the cut form the counterpart; the template is that piece of the
mirrored mesh ``(M(V), F[:, ::-1])`` (faces flipped: a reflection inverts orientation), with its
own context rings for the alignment (:mod:`meshrepair.complete.alignment`).
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp

from meshrepair.complete.icp import closest_points_on_mesh, icp_to_surface
from meshrepair.complete.rigid import apply_transform, reflection
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.geometry import mean_edge_length
from meshrepair.mesh.topology import edge_topology

log = logging.getLogger(__name__)

__all__ = ["detect_symmetry", "mirror_template"]


def _principal_frame(V: np.ndarray, F: np.ndarray, degenerate: float = 0.1
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Area centroid and candidate normals: the principal axes, plus, for two eigenvalues within
    ``degenerate`` (relative) of each other, directions every 15 degrees in their eigenspace
    (there the axes eigh returns are arbitrary, while a mirror normal is still in that plane)."""
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    A = 0.5 * np.linalg.norm(c, axis=1)
    C = V[F].mean(axis=1)
    cm = (A[:, None] * C).sum(0) / A.sum()
    X = C - cm
    w, U = np.linalg.eigh((A[:, None] * X).T @ X)
    dirs = [U[:, k] for k in range(3)]
    for i in range(3):
        for j in range(i + 1, 3):
            if abs(w[i] - w[j]) <= degenerate * max(w[i], w[j], 1e-300):
                for t in np.radians(np.arange(15.0, 180.0, 15.0)):
                    if not np.isclose(t, np.pi / 2):
                        dirs.append(np.cos(t) * U[:, i] + np.sin(t) * U[:, j])
    return cm, np.array(dirs)


def _plane_from_pairs(X: np.ndarray, Y: np.ndarray, n_prev: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    D = X - Y
    _, U = np.linalg.eigh(D.T @ D)
    n = U[:, -1]
    if n @ n_prev < 0:
        n = -n
    return n, 0.5 * (X + Y).mean(axis=0)


def detect_symmetry(V, F, exclude_faces=None, *, loop=None, samples: int = 3000,
                    iterations: int = 8, seed: int = 0, exhaustive: bool = False) -> dict:
    """The mesh's best mirror plane, found and measured on the surface outside ``exclude_faces``.

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    exclude_faces : face indices or a boolean face mask (e.g. a damaged region), optional
    loop : (k,) int, optional, the excluded region's (or a hole's) boundary loop: mirrored
        vertices falling in a ball around it are left out of the residual (default: the
        excluded faces' vertices)
    samples : int, number of intact vertices used (a fixed random subset)
    iterations : int, refinement rounds per candidate plane
    seed : int, of the subset
    exhaustive : refine every candidate (default: stop at the first exact plane, residual below
        1e-3 mean edge lengths); ``candidates`` then lists every refined plane

    Returns
    -------
    dict
        ``normal`` (3,), ``point`` (3,), ``offset`` (``normal . point``), ``residual`` (mean
        distance of the mirrored intact vertices to the intact surface, mean edge lengths),
        ``residual_p90`` (90th percentile), ``residual_max`` (largest), ``transform`` (4x4
        reflection), ``candidates`` (list of ``(normal, point, residual, residual_p90,
        residual_max)`` of the refined planes, best first, duplicates removed), ``unit`` (the
        mean edge length).
    """
    from meshrepair.complete.inputs import _face_selection
    from meshrepair.mesh.array_contract import as_arrays

    V, F = as_arrays(V, F)
    if int(samples) != samples or samples < 8:
        raise MeshRepairError(f"samples must be an integer >= 8, got {samples}")
    if int(iterations) != iterations or iterations < 0:
        raise MeshRepairError(f"iterations must be an integer >= 0, got {iterations}")
    ex = np.zeros(len(F), bool)
    if exclude_faces is not None:
        ex[_face_selection(exclude_faces, len(F), "exclude_faces")] = True
    Fi = F[~ex]
    if len(Fi) < 4:
        raise MeshRepairError("too little intact surface to look for a symmetry plane")
    unit = mean_edge_length(V, F)
    used = np.zeros(len(V), bool)
    used[Fi.ravel()] = True
    cand_v = np.flatnonzero(used)
    rng = np.random.default_rng(seed)
    if cand_v.size > samples:
        cand_v = np.sort(rng.choice(cand_v, int(samples), replace=False))
    X = V[cand_v]
    ball = None
    if ex.any() or loop is not None:  # a region, or a hole bounded by ``loop``
        ref = V[np.asarray(loop, np.int64)] if loop is not None else V[np.unique(F[ex])]
        c = ref.mean(axis=0)
        ball = (c, 1.2 * float(np.linalg.norm(ref - c, axis=1).max()) + unit)

    from scipy.spatial import cKDTree

    tree = cKDTree(V[Fi].mean(axis=1))

    def residual(n, p):
        Q = apply_transform(reflection(n, p), X)
        keep = np.ones(len(Q), bool)
        if ball is not None:
            keep = np.linalg.norm(Q - ball[0], axis=1) > ball[1]
        _, d, _ = closest_points_on_mesh(Q[keep], V, Fi, _tree=tree)
        return d / unit, keep

    cm, axes = _principal_frame(V, Fi)
    starts = [(a, cm) for a in axes]
    if ex.any():  # the whole mesh's frame too: the region breaks the intact part's symmetry
        cm2, axes2 = _principal_frame(V, F)
        starts += [(a, cm2) for a in axes2]
    first = [residual(n0, c0) for n0, c0 in starts]
    order = np.argsort([d.mean() for d, _ in first])  # refine the most promising first
    results = []
    for k in order:
        if not exhaustive and results and min(t[0] for t in results) < 1e-3:
            break  # an exact symmetry was found
        n0, c0 = starts[k]
        n, p = n0.copy(), c0.copy()
        d, keep = first[k]
        best = (float(d.mean()), n, p, d)
        for _ in range(int(iterations)):
            Q = apply_transform(reflection(n, p), X[keep])
            T, _, _ = icp_to_surface(Q, V, Fi, max_iter=4)
            n2, p2 = _plane_from_pairs(X[keep], apply_transform(T, Q), n)
            d2, keep2 = residual(n2, p2)
            if not d2.mean() < best[0] * (1 - 1e-4):
                break
            n, p, keep = n2, p2, keep2
            best = (float(d2.mean()), n, p, d2)
        results.append(best)
        log.debug("symmetry candidate %s: residual %.3g l", np.round(n0, 3), best[0])
    results.sort(key=lambda t: t[0])
    planes: list = []
    for t in results:  # distinct planes: normals more than 1 degree apart or offsets > 0.1 l
        if not any(abs(t[1] @ q[1]) > np.cos(np.radians(1.0))
                   and abs(abs(t[1] @ t[2]) - abs(q[1] @ q[2])) < 0.1 * unit for q in planes):
            planes.append(t)
    r, n, p, d = planes[0]
    return {"normal": n, "point": p, "offset": float(n @ p), "residual": r,
            "residual_p90": float(np.percentile(d, 90)), "residual_max": float(d.max()),
            "transform": reflection(n, p),
            "candidates": [(t[1].copy(), t[2].copy(), t[0], float(np.percentile(t[3], 90)),
                            float(t[3].max())) for t in planes],
            "unit": float(unit)}


def _edge_graph(V: np.ndarray, F: np.ndarray):
    topo = edge_topology(F, len(V))
    e = topo.edges
    w = np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    G = sp.coo_matrix((np.r_[w, w], (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                      shape=(len(V), len(V))).tocsr()
    return topo, G


def _inside_distance(V, F, inreg, b0, P) -> np.ndarray:
    """Signed distance of points ``P`` to the loop ``b0``, positive on the region's side."""
    from scipy.spatial import cKDTree

    from meshrepair.mesh.geometry import face_normals

    Fr = F[~inreg] if inreg.any() else F
    n = len(b0)
    a, b = b0, np.roll(b0, -1)
    he = {}
    for fi, (x, y, z) in enumerate(Fr.tolist()):
        he[(x, y)] = fi
        he[(y, z)] = fi
        he[(z, x)] = fi
    fidx = np.array([he.get((int(a[i]), int(b[i])), -1) for i in range(n)])
    N = face_normals(V, Fr)[np.maximum(fidx, 0)]
    inward = np.cross(V[b] - V[a], N)  # the remaining face is on the left of a -> b
    inward /= np.maximum(np.linalg.norm(inward, axis=1, keepdims=True), 1e-300)
    mid = 0.5 * (V[a] + V[b])
    _, j = cKDTree(mid).query(P)
    return np.einsum("ij,ij->i", P - mid[j], inward[j])


def _counterpart_faces(V, F, region_faces, b0, M, unit) -> np.ndarray:
    """Faces of ``F`` bounded by the cut through the mirror images of ``b0`` (see module doc)."""
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    topo, G = _edge_graph(V, F)
    inreg = np.zeros(len(F), bool)
    inreg[region_faces] = True
    intact_v = np.zeros(len(V), bool)
    intact_v[F[~inreg].ravel()] = True
    interior = np.zeros(len(V), bool)
    interior[F[inreg].ravel()] = True
    interior[b0] = False
    iv = np.flatnonzero(intact_v & ~interior)
    tree = cKDTree(V[iv])
    _, j = tree.query(apply_transform(M, V[b0]))
    u = iv[j]
    keep = np.r_[True, u[1:] != u[:-1]]
    u = u[keep]
    if len(u) > 1 and u[0] == u[-1]:
        u = u[:-1]
    if len(u) < 3:
        raise MeshRepairError("the mirror image of the region's boundary collapses to fewer than "
                              "3 vertices: the region is too small for template='mirror'")
    # prefer paths outside the mirror image of the region: where the mirrored tessellation has
    # no edge along b0 (a flipped diagonal), the counterpart then covers the hole (a tangential
    # gap) instead of missing a triangle of it
    G = G.tocoo()
    inside = _inside_distance(V, F, inreg, b0, apply_transform(M, 0.5 * (V[G.row] + V[G.col])))
    G = sp.csr_matrix((G.data * np.where(inside > 0.05 * unit, 10.0, 1.0), (G.row, G.col)),
                      shape=G.shape)
    cut = set()
    for k in range(len(u)):
        a, b = int(u[k]), int(u[(k + 1) % len(u)])
        lim = 10.0 * (4.0 * float(np.linalg.norm(V[a] - V[b])) + 2.0 * unit)
        dist, pred = dijkstra(G, indices=a, limit=lim, return_predecessors=True)
        if not np.isfinite(dist[b]):
            raise MeshRepairError("the mirror image of the region's boundary is not a connected "
                                  "path on the other side of the mesh; the region's counterpart "
                                  "cannot be cut out (is the region near a border or a thin "
                                  "part?)")
        x = b
        while x != a:
            y = int(pred[x])
            cut.add((min(x, y), max(x, y)))
            x = y
    # the centre of the region, mirrored, seeds the flood fill of faces not crossing the cut
    ref = V[b0].mean(axis=0) if not inreg.any() else np.median(V[np.unique(F[inreg])], axis=0)
    _, js = tree.query(apply_transform(M, ref[None, :]))
    seed_v = int(iv[js[0]])
    e = topo.edges
    codes = e[:, 0] * np.int64(len(V)) + e[:, 1]
    cut_codes = np.array(sorted(a * len(V) + b for a, b in cut), np.int64)
    blocked = np.isin(codes, cut_codes)
    f0, f1 = topo.edge_faces[:, 0], topo.edge_faces[:, 1]
    ok = (~blocked) & (f1 >= 0)
    Adj = sp.coo_matrix((np.ones(int(ok.sum())), (f0[ok], f1[ok])), shape=(len(F), len(F)))
    from scipy.sparse.csgraph import connected_components

    _, lab = connected_components(Adj, directed=False)
    seeds = np.flatnonzero((F == seed_v).any(axis=1))
    sizes = np.bincount(lab, minlength=lab.max() + 1)
    comp = min({int(lab[s]) for s in seeds}, key=lambda c_: sizes[c_])
    faces = np.flatnonzero(lab == comp)
    if faces.size > 0.5 * len(F):
        raise MeshRepairError("the mirror image of the region's boundary does not close a disc "
                              "on the other side of the mesh (the cut leaks); choose a region "
                              "whose mirror image is clear of creases and borders, or give a "
                              "template")
    if inreg[faces].any():
        raise MeshRepairError("the region's mirror image overlaps the region itself (the region "
                              "crosses or touches the symmetry plane): complete each half "
                              "separately, or give a template")
    return faces


def mirror_template(V, F, region_faces, b0, *, max_residual: float = 0.1) -> tuple[tuple, dict]:
    """The mirrored counterpart of a region as a template ``(M(V), F[:, ::-1], faces)``.

    Parameters
    ----------
    V, F : the mesh (with the damaged region still in it, or with a hole)
    region_faces : (k,) int64, the region's faces (empty for a hole)
    b0 : (n,) int64, the region's (or hole's) boundary loop
    max_residual : float, refuse when the symmetry residual (mean edge lengths) is larger

    Returns
    -------
    template : tuple, a face selection of the mirrored mesh (keeps its context rings)
    info : dict, :func:`detect_symmetry`'s result plus ``counterpart_faces`` (count)

    Raises
    ------
    MeshRepairError
        When the mesh is not symmetric enough (the residual is in the message), or when the
        counterpart cannot be cut out.
    """
    sym = detect_symmetry(V, F, region_faces, loop=b0)
    if not sym["residual"] <= max_residual:
        raise MeshRepairError(
            f"the mesh is not mirror-symmetric enough for template='mirror': the best plane "
            f"found (normal {np.round(sym['normal'], 3).tolist()}) leaves a symmetry residual of "
            f"{sym['residual']:.3g} mean edge lengths (mean distance of the mirrored intact "
            f"surface to itself; the limit max_symmetry_residual is {max_residual:g}). Give a "
            "template instead, or raise the limit if an approximate mirror image will do")
    try:
        faces = _counterpart_faces(V, F, region_faces, b0, sym["transform"], sym["unit"])
    except MeshRepairError as first_error:
        # the region may straddle this plane while the mesh has another one (a part with
        # several mirror planes): try the other symmetric-enough planes, best first
        faces = None
        allp = detect_symmetry(V, F, region_faces, loop=b0, exhaustive=True)
        for n, p, r, r90, rmax in allp["candidates"]:
            if r > max_residual or abs(n @ sym["normal"]) > np.cos(np.radians(1.0)):
                continue
            try:
                faces = _counterpart_faces(V, F, region_faces, b0, reflection(n, p),
                                           sym["unit"])
            except MeshRepairError:
                continue
            sym = {**sym, "normal": n, "point": p, "offset": float(n @ p), "residual": r,
                   "residual_p90": r90, "residual_max": rmax, "transform": reflection(n, p),
                   "candidates": allp["candidates"]}
            break
        if faces is None:
            raise first_error from None
    M = sym["transform"]
    VM = apply_transform(M, V)
    FM = np.ascontiguousarray(F[:, ::-1])
    info = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in sym.items()}
    info["counterpart_faces"] = int(faces.size)
    log.info("symmetric completion: plane n=%s through %s, residual %.3g l, counterpart %d "
             "faces", np.round(sym["normal"], 4), np.round(sym["point"], 4), sym["residual"],
             faces.size)
    return (VM, FM, faces), info
