"""Validation of user meshes at the boundary of every public function.

:func:`check_mesh` inspects a vertex array ``V`` and a face array ``F`` and either refuses the
mesh with a :class:`~meshrepair.errors.MeshRepairError` whose message says what is wrong and how
to fix it, or returns a :class:`MeshReport` describing it. Everything is vectorised numpy or one
compiled O(n) pass of :mod:`meshrepair._kernels` (the edge tables of the half-edges, the fans of
the vertices, a hash of the positions, union-find components; each with a numpy twin); there is
no Python loop over vertices, edges or faces (1-2 s of CPU at 1.18M vertices:
docs/performance.md).

Decisions, in the order the checks run (the first refusal wins):

=====================================  =========  =================================================
case                                   decision   notes
=====================================  =========  =================================================
V or F not numeric / not an array      refuse     says what was given
no vertices, or no faces               refuse     "empty mesh"; a point cloud (no faces) is not
                                                  a surface: reconstruct one first
V not of shape ``(nV, 3)``             refuse     states expected and given shape
F not of shape ``(nF, 3)``             refuse     quads / polygons: triangulate first
F not integer-valued (e.g. 0.5)        refuse     integral floats (``2.0``) are accepted
                                                  (converted), booleans are refused
NaN / inf in V                         refuse     count and first vertex indices
|coordinate| > 1e50, extent < 1e-50    refuse     the factor to rescale by (COORDINATE_RANGE)
face index negative or >= nV           refuse     valid range, offending range, first faces
repeated index in a face ([3, 3, 5])   refuse     count, first faces; remove those faces
edge in more than 2 faces              refuse     count, first edges; split / clean the mesh
interior edge with both faces          refuse     inconsistent orientation: re-orient, e.g.
traversing it the same way                        ``trimesh.repair.fix_winding``
zero-area faces (see below)            refuse     count, first faces, the fix; with
                                                  ``allow_degenerate=True`` only a warning
duplicated vertex positions            warn       kept (legitimate along seams); counted
pinched (non-manifold) vertices        warn       counted (vertex whose faces form > 1 fan)
unreferenced vertices                  warn       kept unchanged by the solvers; counted
several connected components           info       counted; the solvers handle them
open boundaries                        ok         counted (number of boundary loops)
=====================================  =========  =================================================

A face is *zero-area* (degenerate) when its doubled area ``|(v1 - v0) x (v2 - v0)|`` is at most
``DEGENERATE_SHAPE_TOL`` (1e-12) times the square of its own longest edge (collinear or
coincident corners: scale-free, independent of the rest of the mesh) or at most
``DEGENERATE_SCALE_TOL`` (1e-14) times the squared mean edge length of the mesh (a face that is
negligible at the scale of the mesh). Both tests are scale invariant.

Boundary loops are counted as connected components of the boundary edges (two holes that touch
at a pinched vertex count as one loop), which is cheap to compute for any mesh size.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from meshrepair._kernels import (
    duplicate_rows,
    edge_lengths,
    edge_tables,
    face_area2_lmax2,
    fan_counts,
    union_find,
)
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.array_contract import (
    _MAX_LISTED,
    _as_face_array,
    _as_vertex_array,
    _check_shapes,
    _first,
    check_arrays,  # noqa: F401  (re-exported)
)
from meshrepair.mesh.topology import Topology, _topology_from_parts, connected_components

logger = logging.getLogger(__name__)

__all__ = [
    "DEGENERATE_SCALE_TOL",
    "DEGENERATE_SHAPE_TOL",
    "MeshReport",
    "check_mesh",
]

DEGENERATE_SHAPE_TOL = 1e-12
"""Doubled face area relative to its longest edge squared below which a face is degenerate."""

DEGENERATE_SCALE_TOL = 1e-14
"""Doubled face area relative to the mean edge length squared below which a face is degenerate."""

COORDINATE_RANGE = (1e-50, 1e50)
"""The faces' extent (bounding-box diagonal of the vertices they use) is at least the first
value and every coordinate at most the second in magnitude: the geometry squares areas (the
fourth power of a length) and sums them, which overflows above about 1e75 and loses every
digit below about 1e-75; a mesh outside the range is refused with the factor to rescale by."""

@dataclass(frozen=True)
class MeshReport:
    """What :func:`check_mesh` found in a mesh it accepted.

    Attributes
    ----------
    name : str
        The name used in messages.
    n_vertices, n_faces, n_edges : int
        Counts (edges are unique undirected edges).
    n_components : int
        Face-connected components (vertices shared = connected); unreferenced vertices are not
        counted.
    n_boundary_loops : int
        Connected components of boundary edges (0 for a closed mesh).
    n_boundary_edges : int
        Edges with exactly one incident face.
    n_duplicate_vertices : int
        Vertices whose position equals that of a vertex with a lower index.
    n_unreferenced : int
        Vertices used by no face.
    n_pinched_vertices : int
        Vertices whose incident faces form more than one fan.
    n_degenerate_faces : int
        Zero-area faces (non-zero only when ``allow_degenerate=True``).
    is_closed : bool
        True when there is no boundary edge.
    mean_edge_length : float
        Mean length of the unique edges.
    """

    name: str
    n_vertices: int
    n_faces: int
    n_edges: int
    n_components: int
    n_boundary_loops: int
    n_boundary_edges: int
    n_duplicate_vertices: int
    n_unreferenced: int
    n_pinched_vertices: int
    n_degenerate_faces: int
    is_closed: bool
    mean_edge_length: float

    def summary(self) -> str:
        """One-paragraph human-readable description of the mesh.

        Returns
        -------
        str
        """
        def plural(n: int, word: str, words: str | None = None) -> str:
            return f"{n} {word if n == 1 else (words or word + 's')}"

        parts = [
            plural(self.n_vertices, "vertex", "vertices"),
            plural(self.n_faces, "face"),
            plural(self.n_edges, "edge"),
            plural(self.n_components, "component"),
        ]
        if self.is_closed:
            parts.append("closed")
        else:
            parts.append(
                f"open ({plural(self.n_boundary_loops, 'boundary loop')}, "
                f"{plural(self.n_boundary_edges, 'boundary edge')})"
            )
        parts.append(f"mean edge length {self.mean_edge_length:.6g}")
        notes = []
        if self.n_duplicate_vertices:
            notes.append(f"{self.n_duplicate_vertices} duplicate vertices")
        if self.n_unreferenced:
            notes.append(f"{self.n_unreferenced} unreferenced vertices")
        if self.n_pinched_vertices:
            notes.append(f"{self.n_pinched_vertices} pinched vertices")
        if self.n_degenerate_faces:
            notes.append(f"{self.n_degenerate_faces} zero-area faces")
        text = f"{self.name}: " + ", ".join(parts)
        if notes:
            text += "; warnings: " + ", ".join(notes)
        return text


def _duplicate_vertex_count(V: np.ndarray) -> tuple[int, np.ndarray]:
    """Number of vertices repeating an earlier position, and the first such vertex indices.

    Exact comparison (``-0.0 == 0.0``) of the coordinates' bits in a hash table
    (:func:`meshrepair._kernels.duplicate_rows`, O(n)).
    """
    W = np.ascontiguousarray(V + 0.0)  # -0.0 -> 0.0
    dups = duplicate_rows(W.view(np.uint64).reshape(-1, 3))
    return int(len(dups)), dups


def _pinched_vertices(F: np.ndarray, n_vertices: int, he_first: np.ndarray,
                      he_second: np.ndarray) -> np.ndarray:
    """Boolean (nV,) mask of vertices whose faces form more than one fan.

    Nodes are face corners ``3 * f + k``; the two faces of each interior edge link their corners
    at the edge's two end vertices. The number of connected corner groups at a vertex is its
    number of fans (:func:`meshrepair._kernels.fan_counts`). ``he_first``/``he_second`` are the
    two (oppositely oriented) half-edges of each interior edge, as indices ``3 * f + k`` of
    half-edge ``F[f, k] -> F[f, (k + 1) % 3]``.
    """
    return fan_counts(F, he_first, he_second, n_vertices) > 1


def _boundary_loop_count(bedges: np.ndarray) -> int:
    """Connected components of the boundary-edge graph."""
    if len(bedges) == 0:
        return 0
    verts, local = np.unique(bedges.ravel(), return_inverse=True)
    local = local.reshape(-1, 2)
    return int(union_find(len(verts), local[:, 0], local[:, 1]).max()) + 1


def check_mesh(V: np.ndarray, F: np.ndarray, *, name: str = "mesh",
               allow_degenerate: bool = False) -> MeshReport:
    """Validate a triangle mesh; refuse unusable input, warn about suspicious input.

    See the module docstring for the decision taken in each case.

    Parameters
    ----------
    V : (nV, 3) array_like of float
        Vertex positions.
    F : (nF, 3) array_like of int
        Triangle vertex indices (0-based). Integral floats are accepted.
    name : str, optional
        Name of the mesh used in messages (e.g. ``"input mesh"`` or a file name).
    allow_degenerate : bool, optional
        If True, zero-area faces only produce a warning instead of an error.

    Returns
    -------
    MeshReport
        Counts and flags of the accepted mesh.

    Raises
    ------
    MeshRepairError
        If the mesh cannot be processed; the message names the problem, the first offending
        elements and a fix.
    """
    return _check_mesh(V, F, name=name, allow_degenerate=allow_degenerate)[0]


def _check_mesh(V, F, *, name: str = "mesh", allow_degenerate: bool = False,
                quiet: bool = False, replaced: np.ndarray | None = None
                ) -> tuple[MeshReport, Topology]:
    """:func:`check_mesh`, also returning the edge topology it built (reused by callers);
    ``quiet``: the warnings are not logged (a caller that already checked the user's arrays
    and now checks a renumbered copy of them); ``replaced``: (nF,) bool, faces the caller
    removes and rebuilds (an inpainted region): degenerate ones among them are accepted."""
    warn = (lambda *args: None) if quiet else logger.warning
    V = _as_vertex_array(V, name)
    F = _as_face_array(F, name)
    _check_shapes(V, F, name)
    nV, nF = V.shape[0], F.shape[0]

    # --- finite coordinates -------------------------------------------------------------------
    finite = np.isfinite(V).all(axis=1)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise MeshRepairError(
            f"{name}: {len(bad)} of {nV} vertices have NaN or infinite coordinates (first "
            f"vertices: {_first(bad)}); remove or fix them before repairing"
        )

    big = float(np.abs(V).max()) if nV else 0.0
    if big > COORDINATE_RANGE[1]:
        raise MeshRepairError(
            f"{name}: coordinates up to {big:.3g} in magnitude; the solvers work with coordinates "
            f"up to {COORDINATE_RANGE[1]:g} (areas are fourth powers of lengths): rescale the "
            f"mesh (e.g. V * {COORDINATE_RANGE[1] / big / 10:.0e}) and scale the result back")

    # --- index range ------------------------------------------------------------------------
    fmin, fmax = int(F.min()), int(F.max())
    if fmin < 0 or fmax >= nV:
        bad = np.flatnonzero(((F < 0) | (F >= nV)).any(axis=1))
        raise MeshRepairError(
            f"{name}: face indices out of range: valid range is [0, {nV - 1}] for {nV} vertices, "
            f"got indices in [{fmin}, {fmax}] ({len(bad)} faces affected, first faces: "
            f"{_first(bad)}); indices are 0-based and must not be negative"
        )

    # --- repeated indices in a face -----------------------------------------------------------
    rep = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    if rep.any():
        bad = np.flatnonzero(rep)
        raise MeshRepairError(
            f"{name}: {len(bad)} faces have repeated vertex indices (first faces: {_first(bad)}, "
            f"e.g. face {int(bad[0])} = {F[bad[0]].tolist()}); remove them, e.g. "
            "F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])]"
        )

    used = np.bincount(F.ravel(), minlength=nV) > 0  # also counts the unreferenced, below
    if nF:
        ext = float(np.linalg.norm(V[used].max(axis=0) - V[used].min(axis=0)))
        if 0.0 < ext < COORDINATE_RANGE[0]:
            raise MeshRepairError(
                f"{name}: the faces span only {ext:.3g} (bounding-box diagonal); the solvers "
                f"need at least {COORDINATE_RANGE[0]:g} (areas are fourth powers of lengths): "
                f"rescale the mesh (e.g. V * {10 * COORDINATE_RANGE[0] / ext:.0e}) and scale the "
                "result back")

    # --- edges --------------------------------------------------------------------------------
    # half-edge h = 3 f + k runs F[f, k] -> F[f, (k + 1) % 3]
    edges, edge_he, he_edge, counts = edge_tables(F, nV)
    nE = len(edges)

    nonman = counts > 2
    if nonman.any():
        bad = np.flatnonzero(nonman)
        listed = ", ".join(
            f"({edges[e, 0]}, {edges[e, 1]}) in {counts[e]} faces" for e in bad[:_MAX_LISTED]
        )
        raise MeshRepairError(
            f"{name}: {len(bad)} non-manifold edges (shared by more than 2 faces; first: "
            f"{listed}); split or clean the mesh first, e.g. remove duplicated faces and "
            "split non-manifold edges (pymeshlab 'meshing_repair_non_manifold_edges')"
        )

    # --- orientation --------------------------------------------------------------------------
    interior = counts == 2
    h1 = edge_he[interior, 0]
    h2 = edge_he[interior, 1]
    Fr = F.ravel()
    same_dir = Fr[h1] == Fr[h2]
    if same_dir.any():
        bad = np.flatnonzero(interior)[same_dir]
        listed = ", ".join(
            f"({edges[e, 0]}, {edges[e, 1]}) in faces {h1[same_dir][i] // 3} and "
            f"{h2[same_dir][i] // 3}"
            for i, e in enumerate(bad[:_MAX_LISTED])
        )
        raise MeshRepairError(
            f"{name}: inconsistent face orientation: {len(bad)} interior edges are traversed in "
            f"the same direction by both adjacent faces (first: {listed}); re-orient the faces "
            "consistently, e.g. trimesh.repair.fix_winding(mesh) or "
            "trimesh.repair.fix_normals(mesh) (a non-orientable surface cannot be repaired)"
        )

    # --- zero-area faces ----------------------------------------------------------------------
    area2, lmax2 = face_area2_lmax2(V, F)  # doubled area, squared longest side
    mean_len = float(edge_lengths(V, edges).mean())
    degenerate = (area2 <= DEGENERATE_SHAPE_TOL * lmax2) | (
        area2 <= DEGENERATE_SCALE_TOL * mean_len**2)
    if replaced is not None:  # the damage the caller replaces may hold degenerate faces
        degenerate &= ~np.asarray(replaced, bool)
    n_degenerate = int(degenerate.sum())
    if n_degenerate:
        bad = np.flatnonzero(degenerate)
        msg = (
            f"{name}: {n_degenerate} zero-area (degenerate) faces with collinear or coincident "
            f"corners (first faces: {_first(bad)})"
        )
        if not allow_degenerate:
            raise MeshRepairError(
                msg + "; remove or collapse them first (e.g. trimesh "
                "mesh.update_faces(mesh.nondegenerate_faces()), pymeshlab "
                "'meshing_remove_null_faces')"
            )
        warn("%s; proceeding because allow_degenerate=True", msg)

    # --- warnings and counts ------------------------------------------------------------------
    n_dup, dups = _duplicate_vertex_count(V)
    if n_dup:
        warn(
            "%s: %d vertices duplicate the position of another vertex (first: %s); they are kept "
            "(legitimate along seams) but are not connected to each other", name, n_dup,
            _first(dups))

    n_unref = int(nV - used.sum())
    if n_unref:
        warn(
            "%s: %d unreferenced vertices (used by no face; first: %s); they are kept unchanged",
            name, n_unref, _first(np.flatnonzero(~used)))

    pinched = _pinched_vertices(F, nV, h1, h2)
    n_pinched = int(pinched.sum())
    if n_pinched:
        warn(
            "%s: %d non-manifold (pinched) vertices whose faces form more than one fan (first: "
            "%s); processing continues", name, n_pinched, _first(np.flatnonzero(pinched)))

    _, labels = connected_components(F, nV)
    n_comp = int(len(np.unique(labels[used])))
    if n_comp > 1:
        logger.info("%s: %d connected components", name, n_comp)

    boundary = counts == 1
    bedges = edges[boundary]
    n_loops = _boundary_loop_count(bedges)

    return MeshReport(
        name=name,
        n_vertices=int(nV),
        n_faces=int(nF),
        n_edges=int(nE),
        n_components=n_comp,
        n_boundary_loops=n_loops,
        n_boundary_edges=int(len(bedges)),
        n_duplicate_vertices=n_dup,
        n_unreferenced=n_unref,
        n_pinched_vertices=n_pinched,
        n_degenerate_faces=n_degenerate,
        is_closed=bool(len(bedges) == 0),
        mean_edge_length=mean_len,
    ), _topology_from_parts(F, nV, edges, edge_he, he_edge, counts)
