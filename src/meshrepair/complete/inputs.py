"""Inputs of context-aware completion: the region to replace and the template patch (Sect. 5).

* the region ``T̄``: face indices, a boolean face mask or a vertex selection
  (:func:`region_from_vertices`), checked to be a topological disc (:func:`_region_loop`);
* the template ``P``: a patch with exactly one boundary loop, given as arrays, a mesh, or a face
  selection of a mesh (:func:`extract_patch`; then its *context*, the source mesh's faces around
  the selection, is kept for the alignment);
* a user placement (:func:`load_transform`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import boundary_loops, edge_topology

__all__ = ["extract_patch", "load_transform", "region_from_vertices"]


def _face_selection(sel, n_faces: int, what: str) -> np.ndarray:
    """Face indices (sorted, unique) from an index list or a boolean mask of length nF."""
    arr = np.asarray(sel)
    if arr.dtype == bool:
        if arr.shape != (n_faces,):
            raise MeshRepairError(f"{what}: a boolean face mask must have length {n_faces} (one "
                                  f"value per face), got shape {arr.shape}")
        return np.flatnonzero(arr).astype(np.int64)
    arr = arr.ravel()
    if arr.size and not (np.issubdtype(arr.dtype, np.integer)
                         or (np.issubdtype(arr.dtype, np.floating)
                             and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)))):
        raise MeshRepairError(f"{what}: expected integer face indices or a boolean face mask, "
                              f"got dtype {arr.dtype}")
    idx = arr.astype(np.int64)
    bad = (idx < 0) | (idx >= n_faces)
    if bad.any():
        raise MeshRepairError(f"{what}: {int(bad.sum())} face indices out of range "
                              f"[0, {n_faces - 1}] (e.g. {idx[bad][:5].tolist()})")
    return np.unique(idx)


def region_from_vertices(F: np.ndarray, vertices, n_vertices: int | None = None) -> np.ndarray:
    """Faces whose three vertices are all selected.

    Parameters
    ----------
    F : (nF, 3) int
    vertices : vertex indices, or a boolean / 0-1 mask of length ``n_vertices``, or a mask file
        (see :func:`meshrepair.io.read_vertex_mask`)
    n_vertices : int, optional (default ``F.max() + 1``)

    Returns
    -------
    (k,) int64 face indices
    """
    from meshrepair.io import read_vertex_mask

    F = np.asarray(F, dtype=np.int64)
    nV = int(F.max()) + 1 if n_vertices is None else int(n_vertices)
    mask = read_vertex_mask(vertices, nV)
    faces = np.flatnonzero(mask[F].all(axis=1)).astype(np.int64)
    if faces.size == 0:
        raise MeshRepairError(f"the vertex selection ({int(mask.sum())} vertices) contains no "
                              "face with all three vertices selected; select a connected patch "
                              "of vertices (the region is made of the faces they cover)")
    return faces


def extract_patch(V, F, faces) -> tuple[np.ndarray, np.ndarray]:
    """The sub-mesh made of some faces, with unreferenced vertices dropped.

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    faces : face indices or boolean face mask

    Returns
    -------
    V_P : (m, 3) float64, the used vertices in their original order
    F_P : (k, 3) int64
    """
    from meshrepair.mesh.array_contract import as_arrays

    V, F = as_arrays(V, F)
    idx = _face_selection(faces, len(F), "patch selection")
    if idx.size == 0:
        raise MeshRepairError("the patch selection is empty; select the template's faces")
    return _compact(V, F[idx])


def _compact(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The patch ``(V, F)`` on the vertices its faces use
    (:func:`meshrepair.mesh.topology.compact`)."""
    from meshrepair.mesh.topology import compact

    return compact(V, F)[1:]


def load_transform(path_or_array) -> np.ndarray:
    """A 4x4 transform from an array, a ``.npy`` file, or a text file of 16 numbers (row-major).

    A 3x4 matrix (12 numbers) is accepted too (last row ``0 0 0 1``).

    Returns
    -------
    (4, 4) float64
    """
    import os

    if isinstance(path_or_array, (str, os.PathLike)):
        from meshrepair.io import check_input_file

        p = check_input_file(path_or_array, "transform ")
        need = (f"transform file {str(path_or_array)!r} must hold 16 numbers (a 4x4 matrix, row "
                "by row, as text or a .npy array)")
        try:
            if str(p).lower().endswith(".npy"):
                vals = _numbers(np.load(p, allow_pickle=False), need)
            else:
                with open(p, encoding="utf-8") as fh:
                    text = fh.read()
                toks = text.replace(",", " ").replace("[", " ").replace("]", " ").split()
                vals = _numbers(toks, need)
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise MeshRepairError(f"cannot read transform file {str(path_or_array)!r}: "
                                  f"{getattr(exc, 'strerror', None) or exc}; {need}") from None
    else:
        vals = _numbers(path_or_array, "a transform must be a 4x4 (or 3x4) array of numbers")
    if vals.size == 12:
        vals = np.concatenate([vals, [0.0, 0.0, 0.0, 1.0]])
    if vals.size != 16 or not np.isfinite(vals).all():
        raise MeshRepairError(f"a transform must be 16 finite numbers (a 4x4 matrix), got "
                              f"{vals.size} values")
    T = vals.reshape(4, 4)
    if not np.allclose(T[3], [0, 0, 0, 1]):
        raise MeshRepairError(f"the last row of the transform must be 0 0 0 1 (an affine map), "
                              f"got {T[3].tolist()}")
    if abs(np.linalg.det(T[:3, :3])) < 1e-12:
        raise MeshRepairError("the transform's 3x3 part is singular; give an invertible "
                              "rigid/similarity transform")
    return T


def _numbers(values, need: str) -> np.ndarray:
    """``values`` as a flat float64 array, or MeshRepairError ``need``."""
    try:
        if np.iscomplexobj(values):
            raise TypeError("complex")
        return np.asarray(values, dtype=np.float64).ravel()
    except (ValueError, TypeError):
        raise MeshRepairError(need) from None


def _template_arrays(template) -> tuple[np.ndarray, np.ndarray]:
    from meshrepair.mesh.array_contract import as_arrays

    if template is None:
        raise MeshRepairError("a template patch is required: pass (V_P, F_P), a trimesh.Trimesh, "
                              "or (V, F, face_indices) selecting faces of a mesh")
    if isinstance(template, (tuple, list)) and len(template) == 3:
        Vs, Fs = as_arrays(template[0], template[1])
        idx = _face_selection(template[2], len(Fs), "template face selection")
        if idx.size == 0:
            raise MeshRepairError("the template face selection is empty")
        return _compact(Vs, Fs[idx])
    if isinstance(template, (tuple, list)) and len(template) == 2:
        VP, FP = as_arrays(template[0], template[1])
    else:
        VP, FP = as_arrays(template)
    if FP.ndim == 2 and FP.shape[0] and FP.shape[1] == 3 and FP.min() >= 0 and FP.max() < len(VP):
        return _compact(VP, FP)
    return VP, FP  # check_mesh explains what is wrong


def _template_context(template, rings: int) -> np.ndarray | None:
    """Positions of the source mesh's vertices within ``rings`` edge rings outside a template.

    Only a template given as ``(V_src, F_src, faces)`` (a piece of a mesh) has a context: the
    intact surface around it, which the alignment matches with the surface around the hole.
    Returns ``(k, 3)`` float64, or None (a bare patch, or no vertex around it).
    """
    from meshrepair.mesh.array_contract import as_arrays
    from meshrepair.mesh.topology import vertex_adjacency

    if not (isinstance(template, (tuple, list)) and len(template) == 3) or rings < 1:
        return None
    Vs, Fs = as_arrays(template[0], template[1])
    idx = _face_selection(template[2], len(Fs), "template face selection")
    inside = np.zeros(len(Vs), bool)
    inside[Fs[idx].ravel()] = True
    A = vertex_adjacency(edge_topology(Fs, len(Vs)).edges, len(Vs))
    reached = inside.copy()
    front = inside.astype(np.float64)
    for _ in range(int(rings)):
        new = (A @ front > 0) & ~reached
        if not new.any():  # the component is reached: more rings add nothing
            break
        reached |= new
        front = new.astype(np.float64)
    ctx = np.flatnonzero(reached & ~inside)
    return Vs[ctx].copy() if ctx.size else None


def _check_template(VP: np.ndarray, FP: np.ndarray) -> np.ndarray:
    """Validate the template and return its boundary loop."""
    from meshrepair.complete.stitch import degenerate_seam_error
    from meshrepair.mesh.validate import check_mesh

    rep = check_mesh(VP, FP, name="template")
    if rep.n_degenerate_faces:
        raise degenerate_seam_error(rep.n_degenerate_faces)
    if rep.n_pinched_vertices:
        raise MeshRepairError(f"template: {rep.n_pinched_vertices} non-manifold (pinched) "
                              "vertices; the template must be a manifold patch: split or clean "
                              "those vertices")
    if rep.n_components != 1:
        raise MeshRepairError(f"template: {rep.n_components} connected components; the template "
                              "must be one connected patch (keep the component you want)")
    loops = boundary_loops(FP, len(VP))
    if len(loops) == 0:
        raise MeshRepairError("template: it is closed (no boundary loop); the template must be a "
                              "patch with exactly one boundary loop: cut the part you need")
    if len(loops) > 1:
        raise MeshRepairError(f"template: {len(loops)} boundary loops (sizes "
                              f"{[len(x) for x in loops][:6]}); the template must have exactly "
                              "one boundary loop: fill its other holes or cut a disc-like part")
    return loops[0]


def _region_loop(V: np.ndarray, F: np.ndarray, faces: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Check the region is a disc; return ``b0`` (remaining orientation) and the removed mask."""
    from scipy.sparse.csgraph import connected_components

    nV, nF = len(V), len(F)
    if faces.size == 0:
        raise MeshRepairError("the region is empty; give the faces to replace, or hole=k to "
                              "complete an existing hole")
    if faces.size == nF:
        raise MeshRepairError("the region covers the whole mesh; nothing would be left to "
                              "attach the template to: select a smaller region")
    inreg = np.zeros(nF, bool)
    inreg[faces] = True
    topo = edge_topology(F, nV)
    f0, f1 = topo.edge_faces[:, 0], topo.edge_faces[:, 1]
    in0 = inreg[f0]
    in1 = np.where(f1 >= 0, inreg[np.maximum(f1, 0)], False)
    touch = (f1 < 0) & in0
    if touch.any():
        e = topo.edges[np.flatnonzero(touch)[0]]
        raise MeshRepairError(f"the region touches the mesh boundary ({int(touch.sum())} boundary "
                              f"edges, e.g. {e.tolist()}); the region must be surrounded by "
                              "remaining faces: shrink it, or fill the hole first")
    both = np.flatnonzero(in0 & in1)
    pos = -np.ones(nF, np.int64)
    pos[faces] = np.arange(faces.size)
    A = sp.coo_matrix((np.ones(both.size), (pos[f0[both]], pos[f1[both]])),
                      shape=(faces.size, faces.size))
    ncomp, lab = connected_components(A, directed=False)
    if ncomp > 1:
        sizes = np.sort(np.bincount(lab))[::-1]
        raise MeshRepairError(f"the region is not connected: {ncomp} edge-connected parts "
                              f"(sizes {sizes[:6].tolist()} faces); replace one part at a time")
    loops = boundary_loops(F[faces], nV)
    if len(loops) != 1:
        raise MeshRepairError(f"the region is not a disc: its boundary has {len(loops)} loops "
                              f"(sizes {[len(x) for x in loops][:6]}); select a region without "
                              "holes or handles (e.g. add the enclosed faces)")
    loop = loops[0]
    if len(np.unique(loop)) != len(loop):
        raise MeshRepairError("the region's boundary touches itself at a vertex (it is not a "
                              "simple loop); grow or shrink the region so its border is simple")
    vr = np.unique(F[faces])
    n_edges = int((in0 | in1).sum())
    chi = vr.size - n_edges + faces.size
    if chi != 1:
        raise MeshRepairError(f"the region is not a disc (Euler characteristic {chi}, a disc has "
                              "1): it contains a handle; select a smaller region")
    removed = np.zeros(nV, bool)
    removed[vr] = True
    removed[loop] = False
    if removed[F[~inreg]].any():
        raise MeshRepairError("the region's interior vertices are shared with remaining faces "
                              "(a pinched vertex); select a region whose border is simple")
    return loop[::-1].copy(), removed


