"""The damaged region of :func:`meshrepair.fill.inpaint`: its vertex mask from a specification
(:func:`region_mask`) and the faces removed for it, so that the holes it opens are bounded by
simple loops."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import edge_topology


def region_mask(V: np.ndarray, region) -> np.ndarray:
    """Per-vertex bool mask of a region specification.

    Parameters
    ----------
    V : (nV, 3) float
    region : one of
        * a bool array of length nV (or a 0/1 array of length nV);
        * integer vertex indices;
        * ``("sphere", center, radius)``: vertices with ``|v - center| <= radius``;
        * ``("box", lo, hi)``: vertices with ``lo <= v <= hi`` component-wise (a list
          ``["sphere", center, radius]`` is read as the tuple);
        * a path to a mask file (:func:`meshrepair.io.read_vertex_mask`).

    Returns
    -------
    (nV,) bool
    """
    V = np.asarray(V, dtype=np.float64)
    nV = len(V)
    if isinstance(region, list) and region and isinstance(region[0], str):
        region = tuple(region)  # ["sphere", c, r] as ("sphere", c, r)
    if isinstance(region, tuple) and len(region) >= 1 and isinstance(region[0], str):
        kind = region[0].lower()
        try:
            if kind == "sphere" and len(region) == 3:
                c = np.asarray(region[1], dtype=np.float64).reshape(3)
                r = float(region[2])
                if not (np.isfinite(c).all() and np.isfinite(r) and r > 0):
                    raise ValueError
                return np.linalg.norm(V - c, axis=1) <= r
            if kind == "box" and len(region) == 3:
                lo = np.asarray(region[1], dtype=np.float64).reshape(3)
                hi = np.asarray(region[2], dtype=np.float64).reshape(3)
                if not (np.isfinite(lo).all() and np.isfinite(hi).all() and (lo <= hi).all()):
                    raise ValueError
                return ((V >= lo) & (V <= hi)).all(axis=1)
        except (ValueError, TypeError):
            pass
        raise MeshRepairError(
            f"invalid region {region!r}: use ('sphere', (x, y, z), radius > 0) or "
            "('box', (x0, y0, z0), (x1, y1, z1)) with x0 <= x1, y0 <= y1, z0 <= z1")
    import os

    from meshrepair.io import read_vertex_mask

    if isinstance(region, (str, os.PathLike)):  # a mask file (.ply, .npy or indices as text)
        return read_vertex_mask(region, nV)
    try:
        arr = np.asarray(region)
    except ValueError:
        arr = None
    if arr is None or arr.dtype == object:
        raise MeshRepairError(
            f"invalid region of type {type(region).__name__}: give a per-vertex bool mask, vertex "
            "indices, a mask file, ('sphere', (x, y, z), radius) or ('box', lo, hi)")
    return read_vertex_mask(arr, nV)


def _remove_region(F: np.ndarray, nV: int, vmask: np.ndarray, max_rounds: int = 20,
                   protect: np.ndarray | None = None) -> tuple[np.ndarray, list[str]]:
    """Faces to remove for a damaged vertex region, bool ``(nF,)``, and notes.

    Removed: every face with a corner in the region; then, repeatedly, kept faces left with two
    or three boundary edges next to the removed ones (dangling ears) and all faces around a vertex
    the removal left pinched (its remaining faces form several fans), so the holes are bounded by
    simple loops; finally kept pieces that the removal cut off and that are smaller than the
    removed area around them (islands inside the region). Faces marked in ``protect`` (bool
    ``(nF,)``) are never removed.
    """
    from meshrepair.mesh.validate import check_mesh  # noqa: F401  (validated by the caller)

    keep_always = np.zeros(len(F), bool) if protect is None else np.asarray(protect, bool)
    removed = vmask[F].any(axis=1) & ~keep_always
    notes: list[str] = []
    n_ear = n_pinch = n_island = 0
    for _ in range(max_rounds):
        changed = False
        keep = np.flatnonzero(~removed)
        if len(keep) == 0:
            break
        topo = edge_topology(F[keep], nV)
        nb = topo.boundary[topo.face_edges].sum(axis=1)
        # ears next to the removed region: kept faces with >= 2 boundary edges that were interior
        touch = np.zeros(nV, bool)
        touch[F[removed].ravel()] = True
        ear = (nb >= 2) & touch[F[keep]].any(axis=1) & ~keep_always[keep]
        if ear.any():
            removed[keep[ear]] = True
            n_ear += int(ear.sum())
            changed = True
            continue
        pinched = _pinched(F[keep], nV) & touch
        if pinched.any():
            sel = pinched[F[keep]].any(axis=1) & ~keep_always[keep]
            if not sel.any():
                break
            removed[keep[sel]] = True
            n_pinch += int(sel.sum())
            changed = True
            continue
        if not changed:
            break
    # islands: kept components cut off by the removal and smaller than the removed area
    from meshrepair.mesh.topology import connected_components

    keep = np.flatnonzero(~removed)
    if len(keep):
        n0, lab0 = connected_components(F, nV)
        n1, lab1 = connected_components(F[keep], nV)
        if n1 > n0:
            comp_of_face = lab1[F[keep, 0]]
            sizes = np.bincount(comp_of_face, minlength=n1)
            orig_of_comp = np.zeros(n1, np.int64)
            orig_of_comp[comp_of_face] = lab0[F[keep, 0]]
            n_removed_orig = np.bincount(lab0[F[removed, 0]], minlength=n0)
            for oc in np.unique(orig_of_comp):
                parts = np.flatnonzero((orig_of_comp == oc) & (sizes > 0))
                if len(parts) <= 1:
                    continue
                biggest = parts[np.argmax(sizes[parts])]
                for p in parts:
                    if p != biggest and sizes[p] < n_removed_orig[oc]:
                        sel = (comp_of_face == p) & ~keep_always[keep]
                        removed[keep[sel]] = True
                        n_island += int(sel.sum())
    if n_ear:
        notes.append(f"{n_ear} dangling faces next to the region removed")
    if n_pinch:
        notes.append(f"{n_pinch} faces around vertices the removal left pinched removed")
    if n_island:
        notes.append(f"{n_island} faces of islands cut off inside the region removed")
    return removed, notes


def _pinched(F: np.ndarray, nV: int) -> np.ndarray:
    """(nV,) bool: vertices whose faces form more than one fan."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components as cc

    nF = len(F)
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    # corner (f, k) sits at vertex F[f, k]; half-edge 3f+k goes F[f,k] -> F[f,k+1]
    key = np.sort(he, axis=1)
    code = key[:, 0] * np.int64(nV) + key[:, 1]
    order = np.argsort(code, kind="stable")
    cs = code[order]
    same = np.flatnonzero(cs[1:] == cs[:-1])
    h1, h2 = order[same], order[same + 1]

    def end_corner(h):
        return h - h % 3 + (h % 3 + 1) % 3

    a = np.r_[h1, end_corner(h1)]
    b = np.r_[end_corner(h2), h2]
    G = coo_matrix((np.ones(len(a)), (a, b)), shape=(3 * nF, 3 * nF))
    n, lab = cc(G.tocsr(), directed=False)
    gv = np.empty(n, np.int64)
    gv[lab] = F.ravel()
    return np.bincount(gv, minlength=nV) > 1


def resolve_region(region, attribute: str | None, n_vertices: int):
    """The ``region`` argument of :func:`meshrepair.inpaint` from :func:`inpaint_options`'s
    ``region``: a mask file read with :func:`meshrepair.io.read_vertex_mask`, or a sphere/box
    tuple."""
    from meshrepair.io.masks import read_vertex_mask

    if region is None:
        raise MeshRepairError("inpaint needs a region: --region FILE, --sphere or --box")
    if isinstance(region, (str, Path)):
        return read_vertex_mask(region, n_vertices, attribute=attribute)
    kind, a, b = region
    return (kind, tuple(a), b if kind == "sphere" else tuple(b))
