"""Context-aware completion: replace a damaged region of a mesh with a template patch (Sect. 5).

Given a mesh ``M0 = (V0, T0)``, a region ``(V̄, T̄)`` bounded by a loop ``b0`` and a template patch
``P = (V_P, T_P)`` bounded by one loop ``b_P``, :func:`complete` builds

.. math:: V^{(0)} = (V_0 \\setminus \\bar V) \\cup V_P, \\qquad
          T^* = (T_0 \\setminus \\bar T) \\cup T_P

with the boundary vertices of ``b_P`` merged into those of ``b0``, and blends the two parts by
minimising energy (6) with the shared :class:`~meshrepair.solver.ADMMSolver`:

1. **Region.** Face indices ``T̄`` (main form), a vertex selection (the faces with all three
   vertices selected) or an existing hole (``hole=k``: ``T̄ = V̄ = ∅``). The region must be a
   topological disc: connected, one simple boundary loop, Euler characteristic 1, not touching
   the mesh boundary. ``b0`` follows the orientation of the remaining faces.
2. **Correspondence.** Both loops are resampled to the same number of points by arc length and
   the best cyclic shift and direction is found over all shifts at once
   (:func:`~meshrepair.correspondence.best_cyclic_alignment`).
3. **Alignment.** Rigid (or, with ``allow_scale=True``, similarity) Umeyama fit of ``b_P`` onto
   ``b0`` from that correspondence, refined by ICP of ``b_P`` against the polyline ``b0`` and a
   refit on the matched boundary vertices; when a region of faces is replaced, then by
   point-to-plane ICP of the template's boundary ring (``icp_rings`` rings) against the surface
   around the hole (remaining faces near ``b0`` plus the faces ``T̄`` being replaced). Or a
   user-given 4x4 ``transform`` (no automatic alignment).
4. **Suitable subdivision.** The two aligned loops are refined to a common sampling
   (:func:`~meshrepair.correspondence.align_loops`, a cyclic sequence alignment): each vertex
   is either matched with a vertex of the other loop or inserted on the other loop's edge at its
   projection, by splitting that edge and the face it belongs to (the template's, or the
   remaining mesh's face along ``b0``). Both loops then have the same number of vertices, and
   paired points are only the loops' normal offset apart.
5. **Stitching.** ``b_P``'s vertices are replaced by ``b0``'s; the gap between paired boundary
   points is spread harmonically over the template's first ``strip_rings`` rings (so the
   template's border faces do not fold); template faces with two boundary edges ("ears") are
   split first (they would become zero-area on collinear seam vertices); the template's faces
   are flipped when its loop runs the same way as ``b0`` (only with ``orientation="auto"``).
6. **Blending.** ``S_D = strip(b0)``: the vertices within ``strip_rings`` edge-rings of the seam
   on both sides. ``M_V = 0`` on it and 1 elsewhere; ``M_E`` on strip edges is forced smooth
   (``mode="smooth"``), sharp (``"sharp"``) or left to the dihedral threshold (``"adaptive"``),
   elsewhere the dihedral threshold decides. With ``fix_outside=True`` (default) the vertices
   outside the strip never move, and the solve runs on the band of ``strip_rings + 2`` rings
   around the seam, which gives the same result as solving on the whole mesh. The blending runs
   a fixed number of iterations (``iterations``): rule (35), measured over a band of mostly
   fixed vertices, would stop it after the first, tiny, warm-started step.

Vertex order of the result: the remaining vertices of the input in their original order
(``vertex_map[i]`` is the new index of input vertex ``i``, ``-1`` if it was removed), then the
vertices inserted on ``b0`` by the subdivision (if any), then the template's interior vertices
in template order. Faces: the remaining input faces in order (faces split at the seam are
replaced in place, their extra pieces appended), then the template's faces.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .correspondence import (
    align_loops,
    apply_transform,
    arc_length_parameters,
    best_cyclic_alignment,
    icp_loop_to_polyline,
    icp_to_surface,
    monotone_loop_match,
    resample_polyline,
    split_boundary_edges,
    umeyama,
)
from .errors import MeshRepairError
from .geometry import face_normals, sharp_edge_mask
from .solver import ADMMSolver, SolverOptions, Stage
from .topology import boundary_loops, edge_topology, vertex_adjacency

log = logging.getLogger(__name__)

__all__ = ["MODES", "CompletionResult", "complete", "extract_patch", "load_transform",
           "region_from_vertices"]

MODES = ("smooth", "sharp", "adaptive")
ORIENTATIONS = ("template", "auto")
ICP_MODES = ("auto", "surface", "boundary", "none")
_EDGE_FORCE = {"smooth": 0, "sharp": 1, "adaptive": -1}


@dataclass
class CompletionResult:
    """Result of :func:`complete`.

    Attributes
    ----------
    V : (nV, 3) float64, the completed and blended vertices
    F : (nF, 3) int64, ``T*``: remaining input faces, then template faces
    M_V : (nV,) float64, fidelity mask (0 on ``strip(b0)``, 1 elsewhere)
    M_E : (nE,) bool, the sharp-edge mask of the last solver stage (outside the solved band: the
        dihedral threshold on the result)
    edges : (nE, 2) int64, the edges ``M_E`` and ``edge_force`` refer to
    edge_force : (nE,) int8, the per-edge override given to the solver (-1, 0, 1)
    history : list of dict, one per ADMM iteration
    correspondence : dict
        ``shift``, ``reversed`` (template loop traversed against its own orientation: the
        orientation-consistent case), ``flipped`` (template faces flipped), ``n_hole`` and
        ``n_template`` (loop vertex counts before subdivision), ``n_seam`` (after),
        ``inserted_region`` / ``inserted_template`` (vertices added on each side), ``transform``
        (4x4 applied to the template), ``fit`` (``"rigid"``, ``"similarity"`` or ``"user"``),
        ``rms_before`` (RMS boundary distance with the template as given), ``rms_after`` (RMS
        distance of the final seam pairs after alignment), ``max_gap`` (largest such distance),
        ``rms_coarse``, ``icp`` (dict with the ICP target and RMS before / after, or None),
        ``size_ratio`` (template / hole loop length), ``rms_other_direction``, ``ears_split``.
    strip_vertices : (k,) int64, indices of ``strip(b0)`` (``S_D``) in the result
    template_vertices : (m,) int64, indices of the template's interior vertices in the result
    seam_vertices : (n,) int64, the seam loop ``b0`` (after subdivision) in the result, following
        the orientation of the remaining faces
    vertex_map : (nV_in,) int64, new index of each input vertex, -1 for removed vertices
    V_init : (nV, 3) float64, the stitched mesh before blending (``V^(0)``)
    fixed : (nV,) bool, vertices the solver was not allowed to move
    iterations : int
    stop_reason : str
    params : dict, the options used
    """

    V: np.ndarray
    F: np.ndarray
    M_V: np.ndarray
    M_E: np.ndarray
    edges: np.ndarray
    edge_force: np.ndarray
    history: list[dict] = field(default_factory=list)
    correspondence: dict = field(default_factory=dict)
    strip_vertices: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    template_vertices: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    seam_vertices: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    vertex_map: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    V_init: np.ndarray | None = None
    fixed: np.ndarray | None = None
    iterations: int = 0
    stop_reason: str = ""
    params: dict = field(default_factory=dict)

    @property
    def mesh(self):
        """The result as a ``trimesh.Trimesh`` (no processing, same vertex order)."""
        import trimesh

        return trimesh.Trimesh(self.V, self.F, process=False)


# ------------------------------------------------------------------------------------------------
# inputs
# ------------------------------------------------------------------------------------------------

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
    from .io import read_vertex_mask

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
    from .io import as_arrays

    V, F = as_arrays(V, F)
    idx = _face_selection(faces, len(F), "patch selection")
    if idx.size == 0:
        raise MeshRepairError("the patch selection is empty; select the template's faces")
    return _compact(V, F[idx])


def _compact(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    new = np.cumsum(used) - 1
    return V[used].copy(), new[F].astype(np.int64)


def load_transform(path_or_array) -> np.ndarray:
    """A 4x4 transform from an array or a text file of 16 numbers (row-major).

    A 3x4 matrix (12 numbers) is accepted too (last row ``0 0 0 1``).

    Returns
    -------
    (4, 4) float64
    """
    import os

    if isinstance(path_or_array, (str, os.PathLike)):
        from .io import check_input_file

        check_input_file(path_or_array, "transform ")
        try:
            with open(path_or_array, encoding="utf-8") as fh:
                text = fh.read()
        except OSError as exc:
            raise MeshRepairError(f"cannot read transform file {str(path_or_array)!r}: "
                                  f"{exc.strerror or exc}") from None
        toks = text.replace(",", " ").replace("[", " ").replace("]", " ").split()
        try:
            vals = np.array([float(t) for t in toks])
        except ValueError:
            raise MeshRepairError(f"transform file {str(path_or_array)!r} must hold 16 numbers "
                                  "(a 4x4 matrix, row by row)") from None
    else:
        vals = np.asarray(path_or_array, dtype=np.float64).ravel()
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


def _template_arrays(template) -> tuple[np.ndarray, np.ndarray]:
    from .io import as_arrays

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


def _check_template(VP: np.ndarray, FP: np.ndarray) -> np.ndarray:
    """Validate the template and return its boundary loop."""
    from .validate import check_mesh

    rep = check_mesh(VP, FP, name="template")
    if rep.n_degenerate_faces:
        raise MeshRepairError(
            f"stitching the template into the hole gives {rep.n_degenerate_faces} zero-area "
            "faces (template faces whose corners land on collinear seam vertices); subdivide the "
            "template near its boundary, or choose a slightly different region")
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


# ------------------------------------------------------------------------------------------------
# main entry point
# ------------------------------------------------------------------------------------------------

def complete(
    V,
    F=None,
    region=None,
    template=None,
    *,
    region_vertices=None,
    hole: int | None = None,
    transform=None,
    strip_rings: int = 2,
    mode: str = "adaptive",
    allow_scale: bool = False,
    max_size_ratio: float = 5.0,
    orientation: str = "template",
    icp: str | bool = "auto",
    icp_rings: int = 2,
    fix_outside: bool | None = None,
    denoise: bool = False,
    lam: float | None = None,
    th: float = 30.0,
    a: float = 10.0,
    iterations: int = 80,
    mask_update_every: int = 3,
    relax: float | None = None,
    tol: float = 1e-6,
    inner_solver: str = "armijo",
    callback: Callable[[dict], None] | None = None,
) -> CompletionResult:
    """Replace a region of a mesh with a template patch and blend the seam (paper Sect. 5).

    Parameters
    ----------
    V : (nV, 3) float array, or a ``trimesh.Trimesh`` / ``MeshData`` (then ``F`` is None)
    F : (nF, 3) int array
    region : face indices ``T̄`` to replace (or a boolean face mask of length nF). Give exactly
        one of ``region``, ``region_vertices`` and ``hole``.
    template : the patch ``P`` with exactly one boundary loop: ``(V_P, F_P)``, a
        ``trimesh.Trimesh`` / ``MeshData``, or ``(V_src, F_src, faces)`` selecting faces of a mesh
        (the same or another one).
    region_vertices : vertex selection (indices, boolean/0-1 mask or mask file); the region is
        the faces with all three vertices selected.
    hole : index of an existing boundary loop of the mesh (``topology.boundary_loops`` order,
        longest first) to complete; then nothing is removed.
    transform : (4, 4) array or a path to a text file with 16 numbers: applied to the template,
        automatic alignment is skipped (the cyclic correspondence is still searched).
    strip_rings : width of ``strip(b0)`` in edge rings on each side of the seam (>= 1; the paper
        asks for at least 2).
    mode : ``M_E`` on strip edges: ``"smooth"`` (Willmore: a smooth joint), ``"sharp"`` (MC
        penalty: a sharp joint) or ``"adaptive"`` (dihedral threshold ``th``).
    allow_scale : estimate a uniform scale too (similarity alignment) and accept any size ratio;
        otherwise the alignment is rigid and a template whose boundary length differs from the
        hole's by more than ``max_size_ratio`` is refused.
    max_size_ratio : see ``allow_scale``.
    orientation : ``"template"`` (trust the template's face orientation: its outside must be the
        mesh's outside) or ``"auto"`` (also try the opposite direction and flip the template's
        faces if that matches better; ambiguous for planar loops).
    icp : refinement of the automatic alignment. ``"boundary"``: ICP of ``b_P`` against the
        polyline ``b0``, then a refit on the matched boundary vertices. ``"surface"``: the same,
        then trimmed point-to-plane ICP of the template's vertices within ``icp_rings`` rings of
        ``b_P`` against the surface around the hole (the remaining faces within 3 rings of
        ``b0`` plus the region's faces ``T̄``, which are being replaced but still say where the
        surface was; the better of the two fits is kept). ``"auto"`` (default):
        ``"surface"`` when a region of faces is replaced, ``"boundary"`` for a hole. ``"none"``
        (or False): the coarse fit only.
    icp_rings : rings of template vertices used by the surface ICP (0: the boundary only).
    fix_outside : vertices outside the strip never move (default True; False with ``denoise``).
        The solve then runs only on the band of ``strip_rings + 2`` rings around the seam.
    denoise : solve on the whole mesh with the two-stage denoising schedule
        (:func:`meshrepair.denoise.default_stages`) and λ from the estimated noise, i.e. denoise
        the context while blending.
    lam : fidelity weight λ (default 1; with ``denoise`` from the noise estimate). It only acts
        on vertices outside the strip, so it has no effect when ``fix_outside`` is True.
    th : dihedral threshold (degrees) of the adaptive ``M_E``.
    a : MC non-convexity of the blending stage.
    iterations : iteration cap of the blending stage (or of the feature stage with ``denoise``).
    mask_update_every : refresh the adaptive ``M_E`` every this many iterations (0: never).
    relax : tangential relaxation weight per iteration (:class:`~meshrepair.solver.Stage`);
        default 0.2 in ``"smooth"`` mode (without it the edge-Willmore energy can fold a strip
        triangle to shorten an edge across a smoothed crease) and 0 otherwise.
    tol : rule (35) tolerance.
    inner_solver : V-subproblem solver of :class:`~meshrepair.solver.SolverOptions`.
    callback : called with each iteration's history entry.

    Returns
    -------
    CompletionResult
        The input arrays are never modified.

    Raises
    ------
    MeshRepairError
        Invalid mesh or template (non-manifold, not one boundary loop, several components), a
        region that is not a disc, sizes too different, a template that seems mirrored, a
        stitched result that is not manifold, or invalid options.
    """
    from .io import as_arrays
    from .validate import check_mesh

    # ---- options ------------------------------------------------------------------------------
    if mode not in MODES:
        raise MeshRepairError(f"mode must be one of {MODES}, got {mode!r}")
    if orientation not in ORIENTATIONS:
        raise MeshRepairError(f"orientation must be one of {ORIENTATIONS}, got {orientation!r}")
    from .options import check_bool, check_int, check_number

    strip_rings = check_int("strip_rings", strip_rings, low=1)
    iterations = check_int("iterations", iterations, low=0)
    max_size_ratio = check_number("max_size_ratio", max_size_ratio, low=1)
    lam = check_number("lam", lam, low=0, allow_none=True)
    if not (isinstance(th, (int, float, np.number)) and 0 < th < 180):
        raise MeshRepairError(f"th must be an angle in (0, 180) degrees, got {th}")
    a = check_number("a", a, low=0, low_open=True)
    tol = check_number("tol", tol, low=0, low_open=True)
    mask_update_every = check_int("mask_update_every", mask_update_every, low=0)
    allow_scale = check_bool("allow_scale", allow_scale)
    denoise = check_bool("denoise", denoise)
    if fix_outside is None:
        fix_outside = not denoise
    fix_outside = check_bool("fix_outside", fix_outside)
    if relax is None:
        relax = 0.2 if mode == "smooth" else 0.0
    relax = check_number("relax", relax, low=0, high=1)
    if icp is True:
        icp = "auto"
    if icp is False or icp is None:
        icp = "none"
    if icp not in ICP_MODES:
        raise MeshRepairError(f"icp must be one of {ICP_MODES} (or a bool), got {icp!r}")
    icp_rings = check_int("icp_rings", icp_rings, low=0)
    if callback is not None and not callable(callback):
        raise MeshRepairError(f"callback must be callable or None, got {type(callback).__name__}")

    # ---- inputs -------------------------------------------------------------------------------
    V, F = as_arrays(V, F)
    check_mesh(V, F, name="input mesh")
    nV, nF = len(V), len(F)
    given = [x is not None for x in (region, region_vertices, hole)]
    if sum(given) != 1:
        raise MeshRepairError("give exactly one of region (face indices), region_vertices (a "
                              "vertex selection) or hole (a boundary loop index)")
    if hole is not None:
        loops = boundary_loops(F, nV)
        if not loops:
            raise MeshRepairError("the mesh is closed (no hole); select the region to replace "
                                  "with region= or region_vertices=")
        if (isinstance(hole, bool) or not isinstance(hole, (int, np.integer, float))
                or not np.isfinite(hole) or int(hole) != hole or not 0 <= hole < len(loops)):
            raise MeshRepairError(f"hole must be an integer in [0, {len(loops) - 1}] (the mesh "
                                  f"has {len(loops)} boundary loops, longest first), got {hole}")
        b0 = loops[int(hole)]
        if len(np.unique(b0)) != len(b0):
            raise MeshRepairError(f"boundary loop {hole} passes twice through a vertex (a "
                                  "pinched hole); it cannot be stitched to one template loop")
        region_faces = np.zeros(0, np.int64)
        removed = np.zeros(nV, bool)
    else:
        if region is not None:
            region_faces = _face_selection(region, nF, "region")
        else:
            region_faces = region_from_vertices(F, region_vertices, nV)
        b0, removed = _region_loop(V, F, region_faces)

    icp_mode = icp if icp != "auto" else ("surface" if region_faces.size else "boundary")
    VP, FP = _template_arrays(template)
    bP = _check_template(VP, FP)
    T_user = None if transform is None else load_transform(transform)

    # ---- sizes --------------------------------------------------------------------------------
    A = V[b0]
    B_raw = VP[bP]
    B = B_raw if T_user is None else apply_transform(T_user, B_raw)
    L0 = arc_length_parameters(A)[1]
    LP = arc_length_parameters(B)[1]
    ratio = LP / L0
    if not allow_scale and not (1.0 / max_size_ratio <= ratio <= max_size_ratio):
        raise MeshRepairError(
            f"the template's boundary is {ratio:.3g} times as long as the hole's ({LP:.4g} vs "
            f"{L0:.4g}), beyond the allowed factor {max_size_ratio:g}: use a template of the "
            "hole's size, pass allow_scale=True to fit a uniform scale, or give a transform")
    if not allow_scale and T_user is None and not (2 / 3 <= ratio <= 1.5):
        log.warning("the template's boundary is %.3g times as long as the hole's and the "
                    "alignment is rigid; pass allow_scale=True to fit a uniform scale", ratio)

    # ---- coarse correspondence and alignment ----------------------------------------------------
    nA, nB = len(A), len(B)
    m = int(np.clip(max(nA, nB), 32, 1024))
    Ar = resample_polyline(A, m)
    Br = resample_polyline(B, m)
    fit = "none" if T_user is not None else ("similarity" if allow_scale else "rigid")
    cand = {rev: best_cyclic_alignment(Ar, Br, fit=fit, directions=(rev,))
            for rev in (True, False)}
    if orientation == "template":
        ca = cand[True]
        other = cand[False].rms
        radius = L0 / (2 * np.pi)
        if ca.rms > 0.02 * radius and other < 0.5 * ca.rms:
            raise MeshRepairError(
                f"the template's boundary matches the hole much better with the opposite "
                f"orientation (RMS {other:.3g} vs {ca.rms:.3g}): its faces seem inversely "
                "oriented (a mirrored template?). Flip them (F_P[:, ::-1]) or pass "
                "orientation='auto'")
    else:
        ca = min(cand.values(), key=lambda c: c.rms)
        other = cand[not ca.reversed].rms
    idx = ca.indices(m)
    rms_before = float(np.sqrt(np.mean(np.sum((Ar - resample_polyline(B_raw, m)[idx]) ** 2,
                                              axis=1))))
    icp_info = None
    if T_user is not None:
        T = T_user
    else:
        T = ca.transform
        if icp_mode in ("boundary", "surface"):
            dT, r0, r1 = icp_loop_to_polyline(apply_transform(T, Br), A, scale=allow_scale)
            icp_info = {"target": "boundary", "rms_before": r0, "rms_after": r1}
            T = dT @ T
    log.info("completion: hole loop %d vertices, template loop %d, %s fit, coarse RMS %.3g "
             "(other direction %.3g)", nA, nB, fit, ca.rms, other)

    # ---- suitable subdivision -------------------------------------------------------------------
    rev = ca.reversed
    flipped = not rev
    Fm = F[np.setdiff1d(np.arange(nF), region_faces)] if region_faces.size else F.copy()
    bseq = bP[::-1] if rev else bP

    def pair_match(T_: np.ndarray):
        Bt = apply_transform(T_, VP[bseq])
        if nA <= nB:
            jj, r = monotone_loop_match(A, Bt)
            return r, VP[bseq][jj], A
        jj, r = monotone_loop_match(Bt, A)
        return r, VP[bseq], A[jj]

    if icp_mode != "none" and T_user is None:  # refit on matched vertex pairs while it helps
        pair_rms, src, dst = pair_match(T)
        for _ in range(3):
            T2 = umeyama(src, dst, scale=allow_scale)
            r2, s2, d2 = pair_match(T2)
            if not r2 < pair_rms * (1 - 1e-6):
                break
            T, pair_rms, src, dst = T2, r2, s2, d2
    if icp_mode == "surface" and T_user is None:
        ring = _rings(edge_topology(FP, len(VP)), bP, icp_rings) <= icp_rings
        d_in = _rings(edge_topology(F, nV), b0, 3)
        tsel = d_in[F].min(axis=1) <= 3
        tsel[region_faces] = True
        dT, r0, r1 = icp_to_surface(apply_transform(T, VP[ring]), V, F[tsel], scale=allow_scale)
        icp_info = {"target": "surface", "boundary": icp_info, "rms_before": r0,
                    "rms_after": r1, "points": int(ring.sum()), "target_faces": int(tsel.sum())}
        T = dT @ T
    VPt = apply_transform(T, VP)
    la = align_loops(A, VPt[bseq])
    Vm, Fm, b0_2, new = split_boundary_edges(V, Fm, b0, la.params_A)
    ins_region = len(new)
    VP2, FP2, bP2, new = split_boundary_edges(VPt, FP, bP, _to_loop_params(la.params_B, rev))
    ins_template = len(new)
    VP2, FP2, n_ears = _split_ears(VP2, FP2, bP2)
    bseq2 = bP2[::-1] if rev else bP2
    match, rms_after = monotone_loop_match(Vm[b0_2], VP2[bseq2])
    pairs_t = bseq2[match]  # template vertex matched with b0_2[i]
    gap = Vm[b0_2] - VP2[pairs_t]
    max_gap = float(np.linalg.norm(gap, axis=1).max())
    # move the template's border so that b_P lands on b0 without folding its first faces
    VP2 = VP2 + _harmonic_displacement(VP2, FP2, pairs_t, gap, strip_rings)

    # ---- stitching ----------------------------------------------------------------------------
    keep = np.ones(len(Vm), bool)
    keep[:nV] = ~removed
    new_index = np.cumsum(keep) - 1
    new_index[~keep] = -1
    n_mesh = int(keep.sum())
    tmap = np.full(len(VP2), -1, dtype=np.int64)
    tmap[pairs_t] = new_index[b0_2]
    interior = tmap < 0
    tmap[interior] = n_mesh + np.arange(int(interior.sum()))
    FPn = tmap[FP2]
    if flipped:
        FPn = FPn[:, [0, 2, 1]]
    V_init = np.vstack([Vm[keep], VP2[interior]])
    F_star = np.vstack([new_index[Fm], FPn]).astype(np.int64)
    seam = new_index[b0_2]
    n_loops_in = len(boundary_loops(F, nV))
    try:
        rep = check_mesh(V_init, F_star, name="completed mesh", allow_degenerate=True)
    except MeshRepairError as exc:
        raise MeshRepairError(
            f"stitching the template into the hole gives an invalid mesh ({exc}); this happens "
            "when the template has faces or edges joining boundary vertices that the mesh "
            "already joins: subdivide the template near its boundary or enlarge the region"
        ) from None
    n_loops_out = len(boundary_loops(F_star, len(V_init)))
    expected = n_loops_in - (1 if hole is not None else 0)
    if n_loops_out != expected:
        log.warning("the completed mesh has %d boundary loops (input %d)", n_loops_out,
                    n_loops_in)
    if rep.n_degenerate_faces:
        raise MeshRepairError(
            f"stitching the template into the hole gives {rep.n_degenerate_faces} zero-area "
            "faces (template faces whose corners land on collinear seam vertices); subdivide the "
            "template near its boundary, or choose a slightly different region")
    if rep.n_pinched_vertices:
        log.warning("the completed mesh has %d pinched vertices", rep.n_pinched_vertices)
    log.info("stitched: %d vertices (%d inserted on b0, %d on b_P), %d faces, seam RMS %.3g",
             len(V_init), ins_region, ins_template, len(F_star), rms_after)

    # ---- masks --------------------------------------------------------------------------------
    nVs = len(V_init)
    topo = edge_topology(F_star, nVs)
    dist = _rings(topo, seam, strip_rings + 2)
    strip = dist <= strip_rings
    M_V = np.where(strip, 0.0, 1.0)
    fixed = ~strip if fix_outside else np.zeros(nVs, bool)

    def force_for(edges: np.ndarray, d: np.ndarray) -> np.ndarray:
        ef = np.full(len(edges), -1, np.int8)
        on = (d[edges[:, 0]] <= strip_rings) & (d[edges[:, 1]] <= strip_rings)
        ef[on] = _EDGE_FORCE[mode]
        return ef

    if denoise:
        from .denoise import default_stages, lambda_from_noise
        from .noise import estimate_noise

        stages = default_stages(feature_iters=int(iterations), a=a)
        lam_used = lambda_from_noise(estimate_noise(V_init, F_star)) if lam is None else lam
    else:
        stages = (Stage(a=a, eps=1.2, beta2_ratio=1.7, mask="adaptive", max_iter=int(iterations),
                        min_iter=int(iterations), relax=float(relax), name="blend"),)
        lam_used = 1.0 if lam is None else float(lam)
    opts = SolverOptions(lam=lam_used, th=th, stages=stages, tol=tol,
                         inner_solver=inner_solver, mask_update_every=mask_update_every)

    V_out = V_init.copy()
    M_E = sharp_edge_mask(face_normals(V_init, F_star), topo, th).astype(bool)
    edge_force = force_for(topo.edges, dist)
    history: list[dict] = []
    n_it, stop = 0, "no iterations"
    if iterations > 0 and strip.any():
        if fix_outside:
            fsel = (dist[F_star] <= strip_rings + 2).all(axis=1)
            loc = np.unique(F_star[fsel])
            g2l = np.full(nVs, -1, np.int64)
            g2l[loc] = np.arange(loc.size)
            F_loc = g2l[F_star[fsel]]
            topo_l = edge_topology(F_loc, loc.size)
            solver = ADMMSolver(F_loc, loc.size, M_V=M_V[loc],
                                edge_force=force_for(topo_l.edges, dist[loc]),
                                fixed=fixed[loc], options=opts, topo=topo_l)
            res = solver.solve(V_init[loc], V_init=V_init[loc], callback=callback)
            free = ~fixed[loc]
            V_out[loc[free]] = res.V[free]
            M_E = sharp_edge_mask(face_normals(V_out, F_star), topo, th).astype(bool)
            ge = loc[topo_l.edges]
            codes = topo.edges[:, 0] * np.int64(nVs) + topo.edges[:, 1]
            gi = np.searchsorted(codes, ge[:, 0] * np.int64(nVs) + ge[:, 1])
            M_E[gi] = res.M_E
        else:
            solver = ADMMSolver(F_star, nVs, M_V=M_V, edge_force=edge_force, fixed=fixed,
                                options=opts, topo=topo)
            res = solver.solve(V_init, V_init=V_init, callback=callback)
            V_out = res.V
            if fixed.any():
                V_out[fixed] = V_init[fixed]
            M_E = res.M_E
        history, n_it, stop = res.history, res.iterations, res.stop_reason

    vertex_map = new_index[:nV].copy()
    corr = {
        "shift": int(ca.shift),
        "reversed": bool(rev),
        "flipped": bool(flipped),
        "n_hole": int(nA),
        "n_template": int(nB),
        "n_seam": int(len(seam)),
        "inserted_region": int(ins_region),
        "inserted_template": int(ins_template),
        "transform": T.copy(),
        "fit": "user" if T_user is not None else fit,
        "rms_before": rms_before,
        "rms_coarse": float(ca.rms),
        "rms_other_direction": float(other),
        "icp": icp_info,
        "rms_after": float(rms_after),
        "max_gap": max_gap,
        "ears_split": int(n_ears),
        "size_ratio": float(ratio),
    }
    params = {"strip_rings": strip_rings, "mode": mode, "allow_scale": allow_scale,
              "max_size_ratio": max_size_ratio, "orientation": orientation, "icp": icp_mode,
              "fix_outside": bool(fix_outside), "denoise": denoise, "lam": lam_used, "th": th,
              "a": a, "iterations": int(iterations), "mask_update_every": mask_update_every,
              "relax": float(relax), "tol": tol, "inner_solver": inner_solver,
              "hole": None if hole is None else int(hole)}
    return CompletionResult(
        V=V_out,
        F=F_star,
        M_V=M_V,
        M_E=M_E,
        edges=topo.edges.copy(),
        edge_force=edge_force,
        history=history,
        correspondence=corr,
        strip_vertices=np.flatnonzero(strip).astype(np.int64),
        template_vertices=np.arange(n_mesh, nVs, dtype=np.int64),
        seam_vertices=seam.astype(np.int64),
        vertex_map=vertex_map.astype(np.int64),
        V_init=V_init,
        fixed=fixed,
        iterations=n_it,
        stop_reason=stop,
        params=params,
    )
