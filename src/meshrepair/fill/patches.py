"""Index bookkeeping and measurements of the patches appended by the enclosing step: their vertex
and face blocks, dropping refused ones, intersections, seam angles across the loop, routed
crease edges."""

from __future__ import annotations

import logging

import numpy as np

from meshrepair.holes import HoleReport, self_intersections
from meshrepair.mesh.topology import edge_topology

log = logging.getLogger("meshrepair.fill")


def _ring_faces(F: np.ndarray, seed_vertices: np.ndarray, nV: int, rings: int) -> np.ndarray:
    """Faces within ``rings`` face-rings of the seed vertices, bool ``(nF,)``."""
    vm = np.zeros(nV, bool)
    vm[seed_vertices] = True
    fm = vm[F].any(axis=1)
    for _ in range(rings):
        vm[F[fm].ravel()] = True
        grown = vm[F].any(axis=1)
        if np.array_equal(grown, fm):  # the component is covered: more rings add nothing
            break
        fm = grown
    return fm


def _blocks(reports: list[HoleReport], nV: int, nF: int) -> dict[int, tuple[np.ndarray,
                                                                             np.ndarray]]:
    """New vertex and face index ranges of each filled hole (patches are appended in order)."""
    out = {}
    ov, of = nV, nF
    for rep in reports:
        if rep.status == "filled" and (rep.n_new_vertices or rep.n_new_faces):
            out[rep.index] = (np.arange(ov, ov + rep.n_new_vertices, dtype=np.int64),
                              np.arange(of, of + rep.n_new_faces, dtype=np.int64))
            ov += rep.n_new_vertices
            of += rep.n_new_faces
    return out


def _drop_patches(V1: np.ndarray, F1: np.ndarray, reports: list[HoleReport], nV: int, nF: int,
                  drop: dict[int, str]) -> tuple[np.ndarray, np.ndarray]:
    """Remove the patches of the holes in ``drop`` (index -> reason) and mark them skipped."""
    blocks = _blocks(reports, nV, nF)
    keepV = np.ones(len(V1), bool)
    keepF = np.ones(len(F1), bool)
    for i in drop:
        keepV[blocks[i][0]] = False
        keepF[blocks[i][1]] = False
    remap = np.cumsum(keepV) - 1
    for rep in reports:
        if rep.index in drop:
            rep.status, rep.reason = "skipped", drop[rep.index]
            rep.note = ""
            rep.n_new_vertices = rep.n_new_faces = 0
            rep.n_creases = 0
            rep.sharp_edges = np.empty((0, 2), np.int64)
        elif len(rep.sharp_edges):
            rep.sharp_edges = remap[rep.sharp_edges]
    return V1[keepV], remap[F1[keepF]]


def _intersecting(V: np.ndarray, F: np.ndarray, faces: np.ndarray,
                  ignore: np.ndarray | None = None, pairs: np.ndarray | None = None) -> int:
    """Face pairs involving ``faces`` that intersect, not counting faces marked in ``ignore``
    (``pairs``: precomputed pairs of a superset of ``faces``, filtered instead of recomputed)."""
    if pairs is None:
        pairs = self_intersections(V, F, faces)
    elif len(pairs):
        mine = np.zeros(len(F), bool)
        mine[faces] = True
        pairs = pairs[mine[pairs].any(axis=1)]
    if ignore is not None and len(pairs):
        pairs = pairs[~ignore[pairs].any(axis=1)]
    return len(pairs)


def _seam_angle(V: np.ndarray, F: np.ndarray, faces: np.ndarray, nF: int, ring: bool = False):
    """Mean dihedral angle (degrees) across the loop edges of the patch ``faces`` (edges between
    one of them and an original face); with ``ring``, also that of the original edges within 3
    rings of the patch."""
    from meshrepair.mesh.geometry import dihedral_angles, face_normals

    near_v = np.zeros(len(V), bool)
    near_v[F[faces].ravel()] = True
    reach = near_v.copy()
    for _ in range(4 if ring else 1):
        reach[F[reach[F].any(axis=1)].ravel()] = True
    fl = np.flatnonzero(reach[F].any(axis=1))
    Fl = F[fl]
    topo = edge_topology(Fl, len(V))
    ang = dihedral_angles(face_normals(V, Fl), topo)
    mine = np.isin(fl, faces)
    a, b = topo.edge_faces[:, 0], topo.edge_faces[:, 1]
    inner = b >= 0
    b = np.maximum(b, 0)
    seam_e = inner & (mine[a] != mine[b]) & (fl[np.where(mine[a], b, a)] < nF)
    seam = float(ang[seam_e].mean()) if seam_e.any() else 0.0
    if not ring:
        return seam
    ring_v = near_v.copy()
    for _ in range(3):
        ring_v[Fl[ring_v[Fl].any(axis=1)].ravel()] = True
    orig = (fl < nF) & ring_v[Fl].all(axis=1)
    sur = inner & orig[a] & orig[b]
    return seam, float(ang[sur].mean()) if sur.any() else 0.0


def _sharp_vertices(V: np.ndarray, F: np.ndarray, th: float, nV: int) -> np.ndarray:
    """(nV,) bool: vertices on an edge with dihedral angle above ``th``."""
    from meshrepair.mesh.geometry import face_normals, sharp_edge_mask

    topo = edge_topology(F, nV)
    m = sharp_edge_mask(face_normals(V, F), topo, th).astype(bool)
    out = np.zeros(nV, bool)
    out[topo.edges[m].ravel()] = True
    return out


def _crease_edges(reports: list[HoleReport]) -> np.ndarray:
    """All patch edges on routed creases, ``(q, 2)`` output vertex indices."""
    parts = [r.sharp_edges for r in reports if r.status == "filled" and len(r.sharp_edges)]
    return np.concatenate(parts) if parts else np.empty((0, 2), np.int64)


def _edge_ids(topo, pairs: np.ndarray, n: int) -> np.ndarray:
    """Indices in ``topo.edges`` of the vertex pairs ``(q, 2)`` (pairs that are no edge are
    dropped)."""
    if len(pairs) == 0:
        return np.empty(0, np.int64)
    e = np.sort(topo.edges, axis=1)
    code = e[:, 0] * np.int64(n) + e[:, 1]
    order = np.argsort(code)
    p = np.sort(np.asarray(pairs, np.int64), axis=1)
    want = p[:, 0] * np.int64(n) + p[:, 1]
    pos = np.clip(np.searchsorted(code[order], want), 0, len(code) - 1)
    hit = code[order][pos] == want
    return order[pos[hit]]


def _finite_rows(V: np.ndarray, Vsafe: np.ndarray, rows: np.ndarray, what: str) -> np.ndarray:
    """``V`` with the non-finite ``rows`` replaced by ``Vsafe`` (logged)."""
    bad = rows[~np.isfinite(V[rows]).all(axis=1)]
    if len(bad):
        log.warning("%s gave %d non-finite vertex positions; kept the previous ones", what,
                    len(bad))
        V = V.copy()
        V[bad] = Vsafe[bad]
    return V
