"""Holes of a triangle mesh: detection, selection and "trivial enclosing" (Sect. 5 of the paper).

A *hole* is a simple closed boundary loop. :func:`find_holes` takes the loops of
:func:`meshrepair.topology.boundary_loops` (which follow the face orientation) and splits a loop
that passes twice through a pinched vertex (two holes touching at one vertex) into simple loops,
so every hole visits each of its vertices once.

:func:`enclose_loop` builds the initial patch of one hole (the region ``S_D`` of the paper):

1. *2-D domain.* The loop is projected onto the plane orthogonal to its vector area (the plane it
   "looks through"); if that polygon is not simple (a loop folding over itself in that view, e.g.
   a band around a cylinder) the projection onto the least-squares plane is tried, and as a last
   resort the loop is mapped to the unit circle by cumulative arc length (a convex polygon, always
   valid).
2. *Triangulation.* Shewchuk's constrained Delaunay mesher (the ``triangle`` package) meshes the
   polygon with a minimum angle of 28° (``q``) and a maximum triangle area (``a``) chosen so that
   interior edges match the loop's mean edge length; ``Y`` forbids Steiner points on the boundary,
   so the patch boundary is exactly the loop.
3. *Embedding.* Interior vertices get the harmonic interpolation of the loop positions with the
   cotangent weights of the 2-D triangulation (linear precision: a planar loop gives back the
   planar triangulation). The patch traverses every loop edge in the opposite direction, so it is
   consistently oriented with the rest of the mesh.

``enclose_loop(P, method="liepa")`` is the fallback for loops no planar view serves (a reflex
spike of the surround poking into the hole, a hole straddling a sharp crease, a loop wrapping
round a thin wall): :func:`min_weight_triangulation` (Liepa 2003, as in CGAL's
``triangulate_hole`` and MeshLab) triangulates the loop without new vertices, minimising the
largest dihedral angle (against the faces on the loop edges too), then the area, by an O(k³)
dynamic program (numba kernel, numpy twin); that coarse surface is developed isometrically into
the plane (or, when the development overlaps itself, subdivided and laid out on the unit disc by
mean-value coordinates), meshed by Triangle to the edge length and every new vertex placed back on
the coarse surface, which follows the surrounding faces.

:func:`enclose_holes` encloses several holes of one mesh at once (appending the new vertices and
faces), removes chords that would duplicate an existing edge, fills an annulus when a loop is an
island inside another hole, and refuses patches that would intersect or lie on the surface.
:func:`fair_vertices` then moves the new vertices to a bi-Laplacian (least-squares-meshes /
thin-plate) position with the surrounding 1-ring as Dirichlet data, which continues the
surrounding curvature into the hole; the ADMM solve of :mod:`meshrepair.fill` refines it.
:func:`self_intersections` is an exact (up to round-off) triangle-triangle intersection test used
to check patches.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ._kernels import HAVE_NUMBA
from .errors import MeshRepairError
from .topology import boundary_loops, connected_components, edge_topology

if HAVE_NUMBA:
    from ._kernels import njit  # numba.njit, without the disk cache where none is writable

log = logging.getLogger(__name__)

__all__ = [
    "Hole",
    "HoleReport",
    "Patch",
    "enclose_holes",
    "enclose_loop",
    "fair_vertices",
    "find_holes",
    "min_weight_triangulation",
    "select_holes",
    "self_intersections",
]

MIN_ANGLE = 28.0
"""Minimum angle (degrees) asked of the 2-D constrained Delaunay triangulation."""

ENCLOSE_METHODS = ("auto", "liepa")
"""Ways :func:`enclose_loop` can triangulate a loop."""


# ------------------------------------------------------------------------------------------------
# detection and selection
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Hole:
    """A simple boundary loop of a mesh.

    Attributes
    ----------
    index : int
        Position in the list returned by :func:`find_holes` (longest loop first).
    vertices : (k,) int64
        Loop vertices in order; consecutive vertices (and last -> first) are boundary edges,
        traversed in the direction of their face, so a filling face must traverse them backwards.
    length : float
        Sum of the ``k`` edge lengths.
    pinched : bool
        True when a vertex of the loop also lies on another loop (a non-manifold, pinched boundary
        vertex).
    component : int
        Label of the connected component of the mesh the loop lies on.
    """

    index: int
    vertices: np.ndarray
    length: float
    pinched: bool = False
    component: int = 0

    @property
    def n_boundary(self) -> int:
        """Number of boundary vertices (= boundary edges) of the loop."""
        return int(len(self.vertices))


@dataclass
class HoleReport:
    """What happened to one hole.

    Attributes
    ----------
    index : int
        Hole index (see :func:`find_holes`).
    n_boundary : int
        Boundary vertices (= edges) of the loop.
    length : float
        Loop length (input units).
    status : str
        ``"filled"`` or ``"skipped"``.
    reason : str
        Why it was skipped, or how it was filled (e.g. ``"plane"``, ``"disc"``, ``"liepa"``,
        ``"annulus with hole 3"``; :func:`meshrepair.fill.fill_holes` appends ``", membrane"`` or
        ``", unfaired"`` when the faired patch intersected and the initial one was kept).
    n_new_vertices, n_new_faces : int
        Size of the patch (0 when skipped).
    loop : (k,) int64
        Loop vertices, numbered in the output mesh.
    n_intersections : int
        Face pairs of the final patch intersecting other faces (-1 when not checked).
    """

    index: int
    n_boundary: int
    length: float
    status: str
    reason: str = ""
    n_new_vertices: int = 0
    n_new_faces: int = 0
    loop: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64), repr=False)
    n_intersections: int = -1

    def as_dict(self) -> dict:
        """The report as plain Python values (for JSON logs)."""
        return {"index": self.index, "n_boundary": self.n_boundary, "length": self.length,
                "status": self.status, "reason": self.reason,
                "n_new_vertices": self.n_new_vertices, "n_new_faces": self.n_new_faces,
                "n_intersections": self.n_intersections}


def _split_simple(loop: list[int]) -> list[list[int]]:
    """Split a closed walk that repeats vertices into simple closed loops."""
    out: list[list[int]] = []
    stack = [list(loop)]
    while stack:
        cur = stack.pop()
        seen: dict[int, int] = {}
        split = False
        for pos, v in enumerate(cur):
            if v in seen:
                i = seen[v]
                stack.append(cur[i:pos])
                stack.append(cur[:i] + cur[pos:])
                split = True
                break
            seen[v] = pos
        if not split:
            out.append(cur)
    return [c for c in out if len(c) >= 3]


def find_holes(V, F=None) -> list[Hole]:
    """All boundary loops of a mesh as simple loops, longest (by length) first.

    Parameters
    ----------
    V : (nV, 3) float array, or a ``trimesh.Trimesh`` / ``MeshData`` (then ``F`` is omitted)
    F : (nF, 3) int array

    Returns
    -------
    list of Hole
        ``holes[i].index == i``; sorted by decreasing :attr:`Hole.length`. A loop through a pinched
        vertex is split there into simple loops (flagged :attr:`Hole.pinched`).

    Raises
    ------
    MeshRepairError
        For meshes :func:`meshrepair.validate.check_mesh` refuses (e.g. non-manifold edges).
    """
    from .io import as_arrays
    from .validate import check_mesh

    V, F = as_arrays(V, F)
    check_mesh(V, F, name="input mesh", allow_degenerate=True)
    return _find_holes(V, F)


def _find_holes(V: np.ndarray, F: np.ndarray) -> list[Hole]:
    loops = boundary_loops(F, len(V))
    simple: list[np.ndarray] = []
    for lp in loops:
        for s in _split_simple(lp.tolist()):
            simple.append(np.asarray(s, dtype=np.int64))
    if not simple:
        return []
    count = np.bincount(np.concatenate(simple), minlength=len(V))
    _, comp = connected_components(F, len(V))
    lengths = [float(np.linalg.norm(V[s] - V[np.roll(s, -1)], axis=1).sum()) for s in simple]
    order = sorted(range(len(simple)), key=lambda i: (-lengths[i], -len(simple[i]),
                                                      int(simple[i].min())))
    return [Hole(index=k, vertices=simple[i], length=lengths[i],
                 pinched=bool((count[simple[i]] > 1).any()), component=int(comp[simple[i][0]]))
            for k, i in enumerate(order)]


def _check_indices(name: str, idx: Sequence[int] | None, n: int) -> list[int]:
    if idx is None:
        return []
    if isinstance(idx, (int, np.integer)):
        idx = [int(idx)]
    out = []
    for i in idx:
        if isinstance(i, (bool, np.bool_)) or int(i) != i:
            raise MeshRepairError(f"{name} must hold integer hole indices, got {i!r}")
        i = int(i)
        if not 0 <= i < n:
            raise MeshRepairError(
                f"{name}: hole index {i} does not exist; the mesh has {n} boundary loops "
                f"(indices 0..{n - 1}, longest first; list them with find_holes or "
                "'meshrepair fill --list')" if n else
                f"{name}: hole index {i} does not exist; the mesh has no boundary loops")
        out.append(i)
    return out


def select_holes(holes: Sequence[Hole], *, max_hole_size: int | None = None,
                 keep_border: bool = False, exclude: Sequence[int] = (),
                 indices: Sequence[int] | None = None) -> dict[int, str]:
    """Decide which holes to fill.

    Parameters
    ----------
    holes : list of Hole, from :func:`find_holes`
    max_hole_size : int, optional
        Skip holes with more boundary vertices (= edges) than this.
    keep_border : bool
        Skip the longest loop (``holes[0]``): the intended open border of a scan or a model cut
        open (e.g. the base of a statue).
    exclude : sequence of int
        Hole indices never filled.
    indices : sequence of int, optional
        Fill only these holes (default: all).

    Returns
    -------
    dict of int to str
        Hole index -> reason for every hole that is *not* selected; the others are selected.

    Raises
    ------
    MeshRepairError
        For an index that does not exist or an invalid ``max_hole_size``.
    """
    n = len(holes)
    if max_hole_size is not None:
        if isinstance(max_hole_size, bool) or int(max_hole_size) != max_hole_size \
                or max_hole_size < 3:
            raise MeshRepairError(f"max_hole_size must be an integer >= 3 (boundary vertices of "
                                  f"the largest hole to fill), got {max_hole_size!r}")
    excl = set(_check_indices("exclude", exclude, n))
    only = None if indices is None else set(_check_indices("holes", indices, n))
    skipped: dict[int, str] = {}
    for h in holes:
        if keep_border and h.index == 0:
            skipped[h.index] = "kept as the mesh border (keep_border: longest loop)"
        elif h.index in excl:
            skipped[h.index] = "excluded"
        elif only is not None and h.index not in only:
            skipped[h.index] = "not selected"
        elif max_hole_size is not None and h.n_boundary > max_hole_size:
            skipped[h.index] = f"larger than max_hole_size ({h.n_boundary} > {max_hole_size})"
    return skipped


# ------------------------------------------------------------------------------------------------
# 2-D helpers
# ------------------------------------------------------------------------------------------------


def _polygon_is_simple(Q: np.ndarray) -> bool:
    """True when the closed 2-D polygon ``Q (k, 2)`` does not touch or cross itself."""
    k = len(Q)
    if k < 3:
        return False
    A = Q
    B = np.roll(Q, -1, axis=0)
    seg = B - A
    scale = float(np.abs(Q - Q.mean(axis=0)).max())
    if not scale > 0:
        return False
    lens = np.linalg.norm(seg, axis=1)
    if (lens <= 1e-9 * scale).any():
        return False
    eps = 1e-10 * scale * scale
    # adjacent segments must not fold back onto each other
    nxt = np.roll(seg, -1, axis=0)
    crs = seg[:, 0] * nxt[:, 1] - seg[:, 1] * nxt[:, 0]
    dot = np.einsum("ij,ij->i", seg, nxt)
    if ((np.abs(crs) <= eps) & (dot < 0)).any():
        return False
    lo = np.minimum(A, B) - 1e-9 * scale
    hi = np.maximum(A, B) + 1e-9 * scale

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (
            q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    chunk = max(1, 2_000_000 // k)
    jj = np.arange(k)
    for s in range(0, k, chunk):
        ii = np.arange(s, min(k, s + chunk))
        i = ii[:, None]
        valid = (jj[None, :] > i + 1) & ~((i == 0) & (jj[None, :] == k - 1))
        box = ((lo[i, 0] <= hi[None, :, 0]) & (lo[None, :, 0] <= hi[i, 0])
               & (lo[i, 1] <= hi[None, :, 1]) & (lo[None, :, 1] <= hi[i, 1]) & valid)
        if not box.any():
            continue
        a, b = np.nonzero(box)
        a = ii[a]
        pa, pb, qa, qb = A[a], B[a], A[b], B[b]
        o1, o2 = orient(pa, pb, qa), orient(pa, pb, qb)
        o3, o4 = orient(qa, qb, pa), orient(qa, qb, pb)

        def sgn(o):
            return np.where(np.abs(o) <= eps, 0.0, np.sign(o))

        if ((sgn(o1) * sgn(o2) <= 0) & (sgn(o3) * sgn(o4) <= 0)).any():
            return False
    return True


def _cotan_weights_2d(X: np.ndarray, T: np.ndarray, n: int) -> sp.csr_matrix:
    """Symmetric cotangent weight matrix (positive off-diagonal), shape ``(n, n)``."""
    rows, cols, vals = [], [], []
    P = X if X.shape[1] == 3 else np.c_[X, np.zeros(len(X))]
    c = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    dbl = np.maximum(np.linalg.norm(c, axis=1), 1e-300)
    for k in range(3):
        i, j, o = T[:, (k + 1) % 3], T[:, (k + 2) % 3], T[:, k]
        cot = np.einsum("ij,ij->i", P[i] - P[o], P[j] - P[o]) / dbl
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * cot, 0.5 * cot]
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, n))


def _harmonic(W: sp.csr_matrix, known: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Harmonic extension: rows of unknown vertices satisfy ``sum_j w_ij (x_j - x_i) = 0``."""
    from scipy.sparse.linalg import spsolve

    n = W.shape[0]
    out = np.zeros((n, values.shape[1]))
    out[known] = values
    unk = np.flatnonzero(~known)
    if len(unk) == 0:
        return out
    L = sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W
    L = L.tocsr()
    A = L[unk][:, unk].tocsc()
    rhs = -(L[unk][:, np.flatnonzero(known)] @ values)
    sol = spsolve(A, rhs)
    out[unk] = sol.reshape(len(unk), -1)
    return out


def _area_switch(max_area: float) -> str:
    """Triangle's ``a`` switch for a maximum triangle area, in positional notation: Triangle
    reads only digits and '.', so ``a6.3e-05`` would mean an area bound of 6.3 (and then the
    switches ``e`` and ``-``), leaving loops of small meshes unrefined."""
    return "a" + np.format_float_positional(float(max_area), precision=12, fractional=False,
                                            trim="-")


def _triangulate(Q: np.ndarray, segments: np.ndarray, max_area: float | None,
                 holes: np.ndarray | None = None, quality: bool = True) -> tuple[np.ndarray,
                                                                                  np.ndarray]:
    import triangle

    data = {"vertices": Q, "segments": segments}
    if holes is not None:
        data["holes"] = holes
    opts = "pYQ"
    if quality:
        opts += f"q{MIN_ANGLE:g}"
    if max_area is not None:
        opts += _area_switch(max_area)
    out = triangle.triangulate(data, opts)
    X = np.asarray(out["vertices"], dtype=np.float64)
    T = np.asarray(out.get("triangles", np.empty((0, 3))), dtype=np.int64).reshape(-1, 3)
    return X, T


def _plane_frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = n / np.linalg.norm(n)
    a = np.eye(3)[int(np.argmin(np.abs(n)))]
    e1 = np.cross(n, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    return e1, e2


def _vector_area(P: np.ndarray) -> np.ndarray:
    c = P.mean(axis=0)
    Q = P - c
    return 0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)


# ------------------------------------------------------------------------------------------------
# enclosing one loop
# ------------------------------------------------------------------------------------------------


@dataclass
class Patch:
    """Triangulated patch enclosing one loop (local numbering).

    Attributes
    ----------
    X : (k + m, 3) float64
        Positions: the ``k`` loop vertices first (in loop order), then ``m`` interior vertices.
    T : (t, 3) int64
        Triangles in local indices, traversing every loop edge ``(i, i+1)`` as ``(i+1, i)``.
    uv : (k + m, 2) float64
        The 2-D domain the patch was triangulated in.
    method : str
        ``"triangle"`` (3-loop), ``"plane"``, ``"pca-plane"``, ``"disc"``, ``"annulus"`` or
        ``"liepa"``.
    n_loop : int
        Number of loop vertices ``k`` (for an annulus, outer + inner).
    """

    X: np.ndarray
    T: np.ndarray
    uv: np.ndarray
    method: str
    n_loop: int


def _max_area_for(h2: float) -> float:
    # an equilateral triangle of side h2 has area sqrt(3)/4 h2^2; triangle's refinement keeps
    # the mean area well below the bound, so the bound is set 1.6 times the target
    return 1.6 * np.sqrt(3.0) / 4.0 * h2 * h2


def _orient_patch(T: np.ndarray, k: int) -> np.ndarray:
    """Flip ``T`` if it traverses the loop edge (0, 1) forwards; check all loop edges."""
    he = np.stack([T, np.roll(T, -1, axis=1)], axis=2).reshape(-1, 2)
    loop_fwd = np.c_[np.arange(k), (np.arange(k) + 1) % k]
    code = he[:, 0] * (T.max() + 1) + he[:, 1]
    fwd = np.isin(loop_fwd[:, 0] * (T.max() + 1) + loop_fwd[:, 1], code)
    if fwd.all():
        T = T[:, ::-1].copy()
    elif fwd.any():
        raise MeshRepairError("internal error: the 2-D triangulation of the hole is inconsistently "
                              "oriented along its boundary")
    return T


def _loop_positions(P) -> np.ndarray:
    """``P`` as a C-contiguous ``(k, 3)`` float64 array of finite loop positions, ``k >= 3``."""
    P = np.ascontiguousarray(P, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) < 3:
        raise MeshRepairError(f"a hole loop needs at least 3 vertices of shape (k, 3), got "
                              f"{P.shape}")
    if not np.isfinite(P).all():
        raise MeshRepairError("the hole loop has non-finite vertex positions")
    return P


def enclose_loop(P: np.ndarray, *, edge_length: float | None = None, method: str = "auto",
                 opposite: np.ndarray | None = None,
                 forbidden: np.ndarray | None = None) -> Patch:
    """Triangulate the hole bounded by the closed 3-D polygon ``P``.

    Parameters
    ----------
    P : (k, 3) float array, k >= 3
        Loop positions in the order of :attr:`Hole.vertices`.
    edge_length : float, optional
        Target interior edge length (default: the loop's mean edge length).
    method : ``"auto"`` or ``"liepa"``
        ``"auto"``: a planar view of the loop (vector-area plane, least-squares plane, else the
        unit disc) meshed by Triangle, interior vertices on the harmonic membrane.
        ``"liepa"``: :func:`min_weight_triangulation` of the loop (minimal largest dihedral
        angle, then area, against the faces in ``opposite``), refined to the edge length on that
        surface (see :func:`_enclose_liepa`); follows the surrounding faces where the loop is far
        from planar.
    opposite : (k, 3) float, optional
        ``"liepa"`` only: third vertex of the existing face on each loop edge.
    forbidden : (q, 2) int, optional
        ``"liepa"`` only: local index pairs that are existing edges (not to be used as chords).

    Returns
    -------
    Patch
        The first ``k`` rows of ``Patch.X`` are ``P``; ``Patch.T`` traverses every loop edge
        backwards, so the patch is consistently oriented with the faces that border the loop. The
        interior vertices are the harmonic interpolation of ``P`` (a membrane) or lie on the
        minimum-weight triangulation (``"liepa"``); use :func:`fair_vertices` for a curved fill.

    Raises
    ------
    MeshRepairError
        If the loop has fewer than 3 vertices, repeated or non-finite positions, or for an
        unknown ``method``.
    """
    if method not in ENCLOSE_METHODS:
        raise MeshRepairError(f"method must be one of {ENCLOSE_METHODS}, got {method!r}")
    P = _loop_positions(P)
    k = len(P)
    el = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1)
    if (el <= 0).any():
        raise MeshRepairError("the hole loop has two consecutive vertices at the same position "
                              "(zero-length boundary edge); merge or move them first")
    Lp = float(el.sum())
    h = float(el.mean()) if edge_length is None else float(edge_length)
    if not h > 0:
        raise MeshRepairError(f"edge_length must be > 0, got {edge_length}")
    if k == 3:
        return Patch(X=P.copy(), T=np.array([[0, 2, 1]], dtype=np.int64),
                     uv=np.zeros((3, 2)), method="triangle", n_loop=3)
    if method == "liepa":
        return _enclose_liepa(P, h, opposite, forbidden)
    segs = np.c_[np.arange(k), (np.arange(k) + 1) % k]
    c = P.mean(axis=0)
    candidates: list[tuple[str, np.ndarray]] = []
    va = _vector_area(P)
    if np.linalg.norm(va) > 1e-12 * Lp * Lp:
        candidates.append(("plane", -va))
    _, _, vt = np.linalg.svd(P - c, full_matrices=False)
    n_pca = vt[2] if np.dot(vt[2], -va) >= 0 else -vt[2]
    candidates.append(("pca-plane", n_pca))
    for method, n in candidates:
        e1, e2 = _plane_frame(n)
        Q = np.c_[(P - c) @ e1, (P - c) @ e2]
        if not _polygon_is_simple(Q):
            continue
        L2 = float(np.linalg.norm(Q - np.roll(Q, -1, axis=0), axis=1).sum())
        h2 = h * L2 / Lp
        X2, T = _triangulate(Q, segs, _max_area_for(h2))
        if len(T) == 0 or len(X2) < k or not np.allclose(X2[:k], Q):
            continue
        if (np.abs(X2[k:, None, :] - Q[None]).sum(axis=2) == 0).any() if len(X2) > k else False:
            continue
        T = _orient_patch(T, k)
        X = _embed(P, X2, T)
        return Patch(X=X, T=T, uv=X2, method=method, n_loop=k)
    # disc: cumulative arc length on the unit circle (always a convex, valid polygon)
    s = np.r_[0.0, np.cumsum(el)[:-1]] / Lp
    Q = np.c_[np.cos(2 * np.pi * s), np.sin(2 * np.pi * s)]
    # number of triangles from the area of a coarse membrane over the loop
    X2c, Tc = _triangulate(Q, segs, None)
    Xc = _embed(P, X2c, Tc)
    area3 = 0.5 * float(np.linalg.norm(np.cross(Xc[Tc[:, 1]] - Xc[Tc[:, 0]],
                                                Xc[Tc[:, 2]] - Xc[Tc[:, 0]]), axis=1).sum())
    n_tri = max(area3 / (np.sqrt(3.0) / 4.0 * h * h), 1.0)
    X2, T = _triangulate(Q, segs, 2.0 * np.pi / n_tri)
    T = _orient_patch(T, k)
    X = _embed(P, X2, T)
    return Patch(X=X, T=T, uv=X2, method="disc", n_loop=k)


def _embed(P: np.ndarray, X2: np.ndarray, T: np.ndarray) -> np.ndarray:
    """3-D positions of a 2-D triangulation whose first ``len(P)`` vertices are ``P``."""
    n = len(X2)
    known = np.zeros(n, bool)
    known[: len(P)] = True
    W = _cotan_weights_2d(X2, T, n)
    # clamp negative weights (obtuse pairs) for a maximum-principle, fold-free embedding
    W.data = np.maximum(W.data, 1e-8)
    return _harmonic(W, known, P)


def _enclose_annulus(Po: np.ndarray, Pi: np.ndarray, h: float) -> Patch | None:
    """Triangulate the region between an outer loop and an island loop (planar view only)."""
    ko, ki = len(Po), len(Pi)
    P = np.r_[Po, Pi]
    n = -_vector_area(Po)
    if not np.linalg.norm(n) > 0:
        return None
    e1, e2 = _plane_frame(n)
    c = Po.mean(axis=0)
    Q = np.c_[(P - c) @ e1, (P - c) @ e2]
    Qo, Qi = Q[:ko], Q[ko:]
    if not (_polygon_is_simple(Qo) and _polygon_is_simple(Qi)):
        return None
    segs = np.r_[np.c_[np.arange(ko), (np.arange(ko) + 1) % ko],
                 ko + np.c_[np.arange(ki), (np.arange(ki) + 1) % ki]]
    # a point strictly inside the island polygon
    Xi, Ti = _triangulate(Qi, segs[ko:] - ko, None, quality=False)
    if len(Ti) == 0:
        return None
    d1, d2 = Xi[Ti[:, 1]] - Xi[Ti[:, 0]], Xi[Ti[:, 2]] - Xi[Ti[:, 0]]
    areas = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    seed = Xi[Ti[int(np.argmax(areas))]].mean(axis=0)
    Lp = float(np.linalg.norm(Po - np.roll(Po, -1, axis=0), axis=1).sum())
    L2 = float(np.linalg.norm(Qo - np.roll(Qo, -1, axis=0), axis=1).sum())
    X2, T = _triangulate(Q, segs, _max_area_for(h * L2 / Lp), holes=seed[None])
    if len(T) == 0 or len(X2) < ko + ki or not np.allclose(X2[: ko + ki], Q):
        return None
    # orientation: outer loop edges must be traversed backwards
    he = np.stack([T, np.roll(T, -1, axis=1)], axis=2).reshape(-1, 2)
    m = int(T.max()) + 1
    code = set((he[:, 0] * m + he[:, 1]).tolist())
    if 1 in code:  # half-edge 0 -> 1 (code 0 * m + 1): the outer loop traversed forwards
        T = T[:, ::-1].copy()
        he = np.stack([T, np.roll(T, -1, axis=1)], axis=2).reshape(-1, 2)
        code = set((he[:, 0] * m + he[:, 1]).tolist())
    inner_back = [((ko + (j + 1) % ki) * m + ko + j) in code for j in range(ki)]
    outer_back = [(((j + 1) % ko) * m + j) in code for j in range(ko)]
    if not (all(inner_back) and all(outer_back)):
        return None
    return Patch(X=_embed(P, X2, T), T=T, uv=X2, method="annulus", n_loop=ko + ki)


# ------------------------------------------------------------------------------------------------
# Liepa's minimum-weight triangulation of the loop and its refinement
# ------------------------------------------------------------------------------------------------

LIEPA_MAX_LOOP = 1000
"""Largest loop (boundary vertices) :func:`meshrepair.fill.fill_holes` encloses with the O(k³)
dynamic program of :func:`min_weight_triangulation` (about 2 s and 90 MB at this size)."""

_DP_TOL = 1e-12
"""Bends ``1 - cos(dihedral angle)`` closer than this count as equal in the lexicographic
weight (angles of about 1e-6 rad and below are not told apart: the area decides)."""


def _np_liepa_dp(P: np.ndarray, N0: np.ndarray, has0: np.ndarray, forbid: np.ndarray,
                 tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Liepa's dynamic program (numpy twin of ``_nb_liepa_dp``, vectorised over each diagonal).

    For ``i < j`` the sub-polygon ``i, i+1, ..., j`` closed by the chord ``(i, j)`` is
    triangulated with the triangle ``(i, j, m)`` (patch orientation) on that chord and the best
    triangulations of ``[i, m]`` and ``[m, j]``. Its weight is (largest bend, total area), where
    the bend of two consistently oriented adjacent triangles is ``1 - cos`` of their dihedral
    angle (monotone in the angle, cheaper than ``arccos``); the triangle on ``(i, j)`` is compared
    with the triangles of the sub-solutions on ``(i, m)`` and ``(m, j)`` or, for a loop edge,
    with the existing face there. Candidates are compared by bend (within ``tol``), then area.

    Parameters
    ----------
    P : (k, 3) float64
        Loop positions.
    N0 : (k, 3) float64
        Unit normal of the existing face on loop edge ``(i, i+1)`` (edge ``k-1`` closes the loop).
    has0 : (k,) bool
        Which loop edges have such a face.
    forbid : (k, k) bool
        ``forbid[i, j]`` (``i < j``): the chord ``(i, j)`` must not be used.
    tol : float
        Bends closer than this are equal.

    Returns
    -------
    opt : (k, k) int64
        Best apex ``m`` of the sub-polygon ``[i, j]`` (-1 where infeasible or unused).
    bend, area : (k, k) float64
        Its weight (``inf`` where infeasible); ``[0, k-1]`` is the whole loop.
    """
    k = len(P)
    bend = np.full((k, k), np.inf)
    area = np.full((k, k), np.inf)
    opt = np.full((k, k), -1, np.int64)
    nrm = np.zeros((k, k, 3))
    hasn = np.zeros((k, k), bool)
    i1 = np.arange(k - 1)
    bend[i1, i1 + 1] = 0.0
    area[i1, i1 + 1] = 0.0
    nrm[i1, i1 + 1] = N0[:-1]
    hasn[i1, i1 + 1] = has0[:-1]
    deg = 1e-12 * float(np.ptp(P, axis=0).max()) ** 2
    for d in range(2, k):
        ii = np.arange(k - d)
        jj = ii + d
        mm = ii[:, None] + np.arange(1, d)[None, :]  # (n, d-1)
        I = np.broadcast_to(ii[:, None], mm.shape)
        J = np.broadcast_to(jj[:, None], mm.shape)
        e, f = P[J] - P[I], P[mm] - P[I]
        n = np.stack([e[..., 1] * f[..., 2] - e[..., 2] * f[..., 1],
                      e[..., 2] * f[..., 0] - e[..., 0] * f[..., 2],
                      e[..., 0] * f[..., 1] - e[..., 1] * f[..., 0]], axis=-1)
        q = np.sqrt(n[..., 0] * n[..., 0] + n[..., 1] * n[..., 1] + n[..., 2] * n[..., 2])
        good = q > deg
        nu = np.where(good[..., None], n / np.where(good, q, 1.0)[..., None], 0.0)
        c1 = np.where(hasn[I, mm], 1.0 - np.einsum("...i,...i->...", nu, nrm[I, mm]), 0.0)
        c2 = np.where(hasn[mm, J], 1.0 - np.einsum("...i,...i->...", nu, nrm[mm, J]), 0.0)
        a = np.maximum(np.maximum(bend[I, mm], bend[mm, J]), np.maximum(c1, c2))
        if d == k - 1 and has0[k - 1]:
            a = np.maximum(a, 1.0 - nu @ N0[k - 1])
        a = np.where(good, a, 2.0)
        a = np.where(np.isfinite(bend[I, mm]) & np.isfinite(bend[mm, J]), a, np.inf)
        s = 0.5 * q + area[I, mm] + area[mm, J]
        best = a.min(axis=1)
        s = np.where(a <= best[:, None] + tol, s, np.inf)
        b = np.argmin(s, axis=1)
        r = np.arange(len(ii))
        ok = np.isfinite(best) & ~forbid[ii, jj]
        ii, jj, b, r = ii[ok], jj[ok], b[ok], r[ok]
        bend[ii, jj] = best[ok]
        area[ii, jj] = s[r, b]
        opt[ii, jj] = mm[r, b]
        nrm[ii, jj] = nu[r, b]
        hasn[ii, jj] = good[r, b]
    return opt, bend, area


if HAVE_NUMBA:

    @njit(cache=True)
    def _nb_liepa_dp(P, N0, has0, forbid, tol):  # pragma: no cover - compiled
        """Liepa's dynamic program, O(k³): see :func:`_np_liepa_dp` (same results)."""
        k = P.shape[0]
        # row i of bend/area/nrm holds the sub-polygons [i, j]; row j of the transposed copies
        # (bendT, areaT, nrmT) the sub-polygons [m, j], so the inner loop reads contiguously
        bend = np.full((k, k), np.inf)
        area = np.full((k, k), np.inf)
        bendT = np.full((k, k), np.inf)
        areaT = np.full((k, k), np.inf)
        opt = np.full((k, k), -1, np.int64)
        nrm = np.zeros((k, k, 3))
        nrmT = np.zeros((k, k, 3))
        hasn = np.zeros((k, k), np.bool_)
        hasnT = np.zeros((k, k), np.bool_)
        for i in range(k - 1):
            hasn[i, i + 1] = has0[i]
            hasnT[i + 1, i] = has0[i]
            bend[i, i + 1] = 0.0
            area[i, i + 1] = 0.0
            bendT[i + 1, i] = 0.0
            areaT[i + 1, i] = 0.0
            for c in range(3):
                nrm[i, i + 1, c] = N0[i, c]
                nrmT[i + 1, i, c] = N0[i, c]
        lmax = 0.0
        for c in range(3):
            lmax = max(lmax, P[:, c].max() - P[:, c].min())
        deg = 1e-12 * lmax * lmax
        ca = np.empty(k)
        cs = np.empty(k)
        cn = np.empty((k, 3))
        cg = np.empty(k, np.bool_)
        for d in range(2, k):
            for i in range(k - d):
                j = i + d
                if forbid[i, j]:
                    continue
                ex = P[j, 0] - P[i, 0]
                ey = P[j, 1] - P[i, 1]
                ez = P[j, 2] - P[i, 2]
                best = np.inf
                for t in range(d - 1):
                    m = i + 1 + t
                    b1 = bend[i, m]
                    b2 = bendT[j, m]
                    ca[t] = np.inf
                    if b1 == np.inf or b2 == np.inf:
                        continue
                    fx = P[m, 0] - P[i, 0]
                    fy = P[m, 1] - P[i, 1]
                    fz = P[m, 2] - P[i, 2]
                    nx = ey * fz - ez * fy
                    ny = ez * fx - ex * fz
                    nz = ex * fy - ey * fx
                    q = np.sqrt(nx * nx + ny * ny + nz * nz)
                    if q > deg:
                        nx /= q
                        ny /= q
                        nz /= q
                        a = max(b1, b2)
                        if hasn[i, m]:
                            a = max(a, 1.0 - (nx * nrm[i, m, 0] + ny * nrm[i, m, 1]
                                              + nz * nrm[i, m, 2]))
                        if hasnT[j, m]:
                            a = max(a, 1.0 - (nx * nrmT[j, m, 0] + ny * nrmT[j, m, 1]
                                              + nz * nrmT[j, m, 2]))
                        if d == k - 1 and has0[k - 1]:
                            a = max(a, 1.0 - (nx * N0[k - 1, 0] + ny * N0[k - 1, 1]
                                              + nz * N0[k - 1, 2]))
                    else:
                        nx = ny = nz = 0.0
                        a = 2.0
                    ca[t] = a
                    cs[t] = 0.5 * q + area[i, m] + areaT[j, m]
                    cn[t, 0] = nx
                    cn[t, 1] = ny
                    cn[t, 2] = nz
                    cg[t] = q > deg
                    if a < best:
                        best = a
                if best == np.inf:
                    continue
                bt = -1
                bs = np.inf
                for t in range(d - 1):
                    if ca[t] <= best + tol and cs[t] < bs:
                        bs = cs[t]
                        bt = t
                bend[i, j] = best
                bendT[j, i] = best
                area[i, j] = bs
                areaT[j, i] = bs
                opt[i, j] = i + 1 + bt
                for c in range(3):
                    nrm[i, j, c] = cn[bt, c]
                    nrmT[j, i, c] = cn[bt, c]
                hasn[i, j] = cg[bt]
                hasnT[j, i] = cg[bt]
        return opt, bend, area


def _edge_normals(P: np.ndarray, opposite: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals of the existing faces ``(P_i, P_i+1, O_i)`` on the loop edges, ``(k, 3)``,
    and which of them exist (finite, non-degenerate)."""
    k = len(P)
    if opposite is None:
        return np.zeros((k, 3)), np.zeros(k, bool)
    O = np.asarray(opposite, dtype=np.float64)
    if O.shape != (k, 3):
        raise MeshRepairError(f"opposite must have shape ({k}, 3) (one point per loop edge), got "
                              f"{O.shape}")
    Pn = np.roll(P, -1, axis=0)
    n = np.cross(Pn - P, O - P)
    q = np.linalg.norm(n, axis=1)
    lmax = float(np.ptp(P, axis=0).max())
    ok = np.isfinite(q) & (q > 1e-12 * lmax * lmax)
    N = np.zeros((k, 3))
    N[ok] = n[ok] / q[ok, None]
    return N, ok


def min_weight_triangulation(P: np.ndarray, *, opposite: np.ndarray | None = None,
                             forbidden: np.ndarray | None = None) -> np.ndarray:
    """Liepa's minimum-weight triangulation of a closed 3-D polygon (no new vertices).

    Dynamic program over the sub-polygons ``i, i+1, ..., j`` (O(k³) time, O(k²) memory; a numba
    kernel, or numpy vectorised over each diagonal when numba is unavailable or
    ``MESHREPAIR_NO_NUMBA=1``). The weight of a triangle set is lexicographic: first the largest
    dihedral angle between adjacent triangles, including the existing face on each loop edge
    (``opposite``), then the total area (Liepa 2003, "Filling holes in meshes"; the weight of
    CGAL's ``triangulate_hole``). It therefore follows the surrounding faces instead of a
    projection plane.

    Parameters
    ----------
    P : (k, 3) float, k >= 3
        Loop positions in the order of :attr:`Hole.vertices`.
    opposite : (k, 3) float, optional
        Third vertex of the existing face ``(P_i, P_i+1, opposite_i)`` on each loop edge (rows
        of NaN where there is none); without it only the angles inside the patch count.
    forbidden : (q, 2) int, optional
        Local index pairs that must not become chords (they are edges of the mesh already and
        would get a third face). Ignored when no triangulation avoids them all.

    Returns
    -------
    (k - 2, 3) int64
        Triangles in local indices, ``(i, j, m)`` with ``i < m < j``: every loop edge ``(i, i+1)``
        is traversed as ``(i+1, i)``, like :attr:`Patch.T`.

    Raises
    ------
    MeshRepairError
        For a loop of fewer than 3 vertices or non-finite positions.
    """
    P = _loop_positions(P)
    k = len(P)
    N0, has0 = _edge_normals(P, opposite)
    forbid = np.zeros((k, k), bool)
    if forbidden is not None and len(forbidden):
        fb = np.asarray(forbidden, dtype=np.int64).reshape(-1, 2)
        if (fb < 0).any() or (fb >= k).any():
            raise MeshRepairError(f"forbidden chords must be local loop indices in [0, {k})")
        lo, hi = fb.min(axis=1), fb.max(axis=1)
        chord = (hi - lo >= 2) & ~((lo == 0) & (hi == k - 1))
        forbid[lo[chord], hi[chord]] = True
    dp = _nb_liepa_dp if HAVE_NUMBA else _np_liepa_dp
    opt, bend, _ = dp(P, N0, has0, forbid, _DP_TOL)
    if not np.isfinite(bend[0, k - 1]):
        log.info("no triangulation of the %d-loop avoids the existing edges; allowing them", k)
        opt, bend, _ = dp(P, N0, has0, np.zeros((k, k), bool), _DP_TOL)
    T = []
    stack = [(0, k - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        m = int(opt[i, j])
        T.append((i, j, m))
        stack += [(i, m), (m, j)]
    return np.asarray(T, dtype=np.int64).reshape(-1, 3)


def _tri_angles(P: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Corner angles ``(t, 3)`` of the triangles ``T`` of ``P``."""
    out = np.empty(T.shape)
    for c in range(3):
        u = P[T[:, (c + 1) % 3]] - P[T[:, c]]
        v = P[T[:, (c + 2) % 3]] - P[T[:, c]]
        out[:, c] = np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), np.einsum("ij,ij->i", u, v))
    return out


def _unfold(P: np.ndarray, T: np.ndarray) -> np.ndarray | None:
    """Isometric development of a triangulated polygon (all vertices on the loop) into the plane.

    The triangles are laid out along the dual tree, each reflected across the chord it shares
    with its parent, so every triangle keeps its 3-D shape. Returns the ``(k, 2)`` positions, or
    None when the development overlaps itself (the loop's 2-D image is not simple, or the
    triangles round a loop vertex span 360° or more).
    """
    k = len(P)
    nt = len(T)
    by_edge: dict[tuple[int, int], list[int]] = {}
    for t, tri in enumerate(T.tolist()):
        for c in range(3):
            a, b = tri[c], tri[(c + 1) % 3]
            by_edge.setdefault((min(a, b), max(a, b)), []).append(t)
    X = np.full((k, 2), np.nan)
    i, j, m = T[0]
    e = P[j] - P[i]
    le = float(np.linalg.norm(e))
    if not le > 0:
        return None
    X[i] = 0.0
    X[j] = (le, 0.0)
    f = P[m] - P[i]
    X[m] = (float(f @ e) / le, float(np.linalg.norm(np.cross(e, f))) / le)
    done = np.zeros(nt, bool)
    done[0] = True
    queue = [0]
    while queue:
        t = queue.pop()
        tri = T[t].tolist()
        for c in range(3):
            a, b = tri[c], tri[(c + 1) % 3]
            for u in by_edge[(min(a, b), max(a, b))]:
                if done[u]:
                    continue
                done[u] = True
                nb = T[u].tolist()
                r = nb.index(b)  # the shared edge is traversed b -> a in the neighbour
                p, q, w = nb[r], nb[(r + 1) % 3], nb[(r + 2) % 3]
                e3 = P[q] - P[p]
                le = float(np.linalg.norm(e3))
                if not le > 0:
                    return None
                f3 = P[w] - P[p]
                x = float(f3 @ e3) / le
                y = float(np.linalg.norm(np.cross(e3, f3))) / le
                d2 = (X[q] - X[p]) / le
                X[w] = X[p] + x * d2 + y * np.array([-d2[1], d2[0]])
                queue.append(u)
    if not (done.all() and np.isfinite(X).all()):
        return None
    # every corner angle at a loop vertex must add up to less than a full turn
    ang = _tri_angles(P, T)
    total = np.bincount(T.ravel(), ang.ravel(), minlength=k)
    if (total >= 2 * np.pi - 1e-6).any():
        return None
    d1, d2 = X[T[:, 1]] - X[T[:, 0]], X[T[:, 2]] - X[T[:, 0]]
    area2 = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    if not (area2 > 1e-12 * float(np.ptp(X, axis=0).max()) ** 2).all():
        return None
    if not _polygon_is_simple(X):
        return None
    return X


def _locate(Q: np.ndarray, Tc: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coarse triangle of ``Tc`` (a planar layout ``Q``) containing each point, ``(n,)``, and the
    barycentric coordinates ``(n, 3)`` (clipped to the triangle for points on its border)."""
    from matplotlib.tri import Triangulation

    try:
        finder = Triangulation(Q[:, 0], Q[:, 1], Tc).get_trifinder()
        owner = np.asarray(finder(pts[:, 0], pts[:, 1]), dtype=np.int64)
    except (RuntimeError, ValueError):  # a layout matplotlib finds degenerate: search all
        owner = np.full(len(pts), -1, np.int64)

    def bary(t, x):
        A, B, C = Q[Tc[t, 0]], Q[Tc[t, 1]], Q[Tc[t, 2]]
        u1, u2, w = B - A, C - A, x - A
        det = u1[..., 0] * u2[..., 1] - u1[..., 1] * u2[..., 0]
        det = np.where(det != 0, det, 1.0)
        b1 = (w[..., 0] * u2[..., 1] - w[..., 1] * u2[..., 0]) / det
        b2 = (u1[..., 0] * w[..., 1] - u1[..., 1] * w[..., 0]) / det
        return np.stack([1.0 - b1 - b2, b1, b2], axis=-1)

    miss = np.flatnonzero(owner < 0)  # e.g. points on the border (round-off): best triangle
    if len(miss):
        allt = np.arange(len(Tc))
        for s in range(0, len(miss), 512):
            mm = miss[s:s + 512]
            bc = bary(allt[None, :], pts[mm][:, None, :])
            owner[mm] = np.argmax(bc.min(axis=2), axis=1)
    bc = np.clip(bary(owner, pts), 0.0, None)
    return owner, bc / bc.sum(axis=1, keepdims=True)


def _refine_on_triangulation(k: int, S: np.ndarray, Ts: np.ndarray, Qs: np.ndarray, h: float, *,
                             isometric: bool, creases: np.ndarray | None = None
                             ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Remesh the triangulated surface ``(S, Ts)`` spanning a loop to edge length ``h``.

    ``S (n, 3)`` starts with the ``k`` loop vertices; ``Qs (n, 2)`` is a valid planar layout of
    ``Ts`` (every triangle positive, none overlapping) whose first ``k`` rows are a simple
    polygon containing the rest of the layout. Triangle meshes that polygon (no Steiner point on
    the loop, minimum angle :data:`MIN_ANGLE`) and every new vertex is mapped to 3-D by the affine
    map of the triangle of ``Ts`` containing it, so it lies on the surface. ``creases (q, 2)``
    (pairs of loop vertices: edges of ``Ts`` where it folds) are kept as constraints (Triangle
    may split them), so no new edge cuts across a fold and the new triangles lie on the surface
    too; other edges of ``Ts`` are not, because fans of chords meeting at small angles at a loop
    vertex force tiny triangles there. For an ``isometric`` layout the 3-D edge length is the
    2-D one; otherwise the area bounds are corrected by the 2-D/3-D area ratio of each new
    triangle with two rounds of Triangle's refinement (``r``).

    Returns
    -------
    (X (m, 3), T (t, 3), X2 (m, 2)), or None if Triangle changed the loop vertices.
    """
    import triangle

    Q = Qs[:k]
    segs = np.c_[np.arange(k), (np.arange(k) + 1) % k]
    if creases is not None and len(creases):
        segs = np.r_[segs, np.asarray(creases, dtype=np.int64).reshape(-1, 2)]
    target = _max_area_for(h)

    def lift(X2):
        X = np.empty((len(X2), 3))
        X[:k] = S[:k]
        if len(X2) > k:
            owner, bc = _locate(Qs, Ts, X2[k:])
            X[k:] = np.einsum("ij,ijk->ik", bc, S[Ts[owner]])
        return X

    def areas(X, T):
        if X.shape[1] == 2:
            d1, d2 = X[T[:, 1]] - X[T[:, 0]], X[T[:, 2]] - X[T[:, 0]]
            return 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        return 0.5 * np.linalg.norm(np.cross(X[T[:, 1]] - X[T[:, 0]], X[T[:, 2]] - X[T[:, 0]]),
                                    axis=1)

    amax = target
    if not isometric:
        amax *= float(areas(Qs, Ts).sum()) / max(float(areas(S, Ts).sum()), 1e-300)
    opts = f"pYQq{MIN_ANGLE:g}"
    out = triangle.triangulate({"vertices": Q, "segments": segs}, opts + _area_switch(amax))
    for _ in range(0 if isometric else 2):
        X2 = np.asarray(out["vertices"], dtype=np.float64)
        T = np.asarray(out["triangles"], dtype=np.int64)
        a2, a3 = areas(X2, T), areas(lift(X2), T)
        if (a3 <= 1.25 * target).all():
            break
        bound = np.where(a3 > 1.25 * target, a2 * target / np.maximum(a3, 1e-300), -1.0)
        out = triangle.triangulate({"vertices": X2, "segments": out["segments"], "triangles": T,
                                    "triangle_max_area": bound}, f"r{opts}a")
    X2 = np.asarray(out["vertices"], dtype=np.float64)
    T = np.asarray(out.get("triangles", np.empty((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(T) == 0 or len(X2) < k or not np.allclose(X2[:k], Q):
        return None
    return lift(X2), T, X2


def _subdivide(X: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """1-to-4 midpoint subdivision (old vertices keep their indices, midpoints appended)."""
    e = np.sort(np.r_[T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]], axis=1)
    uniq, inv = np.unique(e, axis=0, return_inverse=True)
    mid = len(X) + inv.reshape(3, -1).T  # (t, 3): midpoints of edges 01, 12, 20
    Xn = np.r_[X, 0.5 * (X[uniq[:, 0]] + X[uniq[:, 1]])]
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    ab, bc, ca = mid[:, 0], mid[:, 1], mid[:, 2]
    Tn = np.r_[np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]]
    return Xn, Tn


def _mean_value_layout(S: np.ndarray, T: np.ndarray, k: int) -> np.ndarray:
    """Floater's mean-value embedding ``(n, 2)`` of the disc ``(S, T)``, boundary on the unit
    circle by arc length (loop vertex 0 at angle 0; the ``k`` loop vertices first in ``S``).
    Positive weights and a convex boundary make it a valid (fold-free) layout."""
    from scipy.sparse.linalg import spsolve

    from .topology import boundary_loops

    n = len(S)
    bl = boundary_loops(T, n)
    b = max(bl, key=len)
    b = np.roll(b, -int(np.flatnonzero(b == 0)[0]))
    el = np.linalg.norm(S[b] - S[np.roll(b, -1)], axis=1)
    t = np.r_[0.0, np.cumsum(el)[:-1]] / el.sum()
    known = np.zeros(n, bool)
    known[b] = True
    U = np.zeros((n, 2))
    U[b] = np.c_[np.cos(2 * np.pi * t), -np.sin(2 * np.pi * t)]
    ang = _tri_angles(S, T)
    rows, cols, vals = [], [], []
    for c in range(3):
        i, j, m = T[:, c], T[:, (c + 1) % 3], T[:, (c + 2) % 3]
        tn = np.tan(0.5 * ang[:, c])
        for o in (j, m):
            rows.append(i)
            cols.append(o)
            vals.append(tn / np.maximum(np.linalg.norm(S[o] - S[i], axis=1), 1e-300))
    W = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n, n))
    L = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()
    unk = np.flatnonzero(~known)
    if len(unk):
        A = L[unk][:, unk].tocsc()
        rhs = -(L[unk][:, np.flatnonzero(known)] @ U[known])
        U[unk] = np.asarray(spsolve(A, rhs)).reshape(len(unk), 2)
    return U


LIEPA_CREASE = 20.0
"""Chords of the minimum-weight triangulation folding by more than this (degrees) stay edges of
the refined patch (:func:`_refine_on_triangulation`). 30° or less was needed for the unfaired
patch of one hole of the fandisk 3-disc cut not to cut into the surface (45° was not enough);
the price is a few short edges (1-5 % below 0.1 of the target) where folds fan out of a loop
vertex."""


def _creases(P: np.ndarray, T: np.ndarray, min_deg: float) -> np.ndarray:
    """Interior edges ``(q, 2)`` of the triangulated polygon with a dihedral angle > min_deg."""
    k = len(P)
    n = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    e = np.r_[T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]
    f = np.tile(np.arange(len(T)), 3)
    key = np.sort(e, axis=1)
    code = key[:, 0] * k + key[:, 1]
    order = np.argsort(code, kind="stable")
    cs = code[order]
    same = np.flatnonzero(cs[1:] == cs[:-1])
    a, b = f[order[same]], f[order[same + 1]]
    cosang = np.einsum("ij,ij->i", n[a], n[b])
    keep = cosang < np.cos(np.radians(min_deg))
    return key[order[same]][keep]


def _enclose_liepa(P: np.ndarray, h: float, opposite: np.ndarray | None,
                   forbidden: np.ndarray | None) -> Patch:
    """Liepa's triangulation of the loop, remeshed to edge length ``h`` on its own surface.

    1. :func:`min_weight_triangulation` (no interior vertices).
    2. A planar layout of it: the isometric development along its dual tree (:func:`_unfold`)
       when that does not overlap itself (no distortion at all); otherwise the coarse surface is
       subdivided 1-to-4 until its edges are at most ``2 h`` and laid out by Floater's
       mean-value embedding with the loop on the unit circle by arc length (a convex boundary:
       always valid, but anisotropic where the surface is far from developable).
    3. :func:`_refine_on_triangulation`: Triangle meshes the layout to the target size, keeping
       the folds of the coarse surface (:data:`LIEPA_CREASE`) as edges in the developed layout,
       and every new vertex is placed on the coarse surface by the affine map of the triangle it
       falls in; with the developed layout the patch lies on the coarse surface up to the
       smaller folds, with the mean-value layout its vertices do.
    """
    k = len(P)
    Tc = min_weight_triangulation(P, opposite=opposite, forbidden=forbidden)
    Tc = _orient_patch(Tc, k)  # already backwards along the loop; checks it
    Q = _unfold(P, Tc)
    res = None
    layout = "developed"
    if Q is not None:
        res = _refine_on_triangulation(k, P, Tc, Q, h, isometric=True,
                                       creases=_creases(P, Tc, LIEPA_CREASE))
    if res is None:
        S, Ts = P, Tc
        for _ in range(6):
            e = np.r_[Ts[:, [0, 1]], Ts[:, [1, 2]], Ts[:, [2, 0]]]
            if np.linalg.norm(S[e[:, 0]] - S[e[:, 1]], axis=1).max() <= 2.0 * h:
                break
            S, Ts = _subdivide(S, Ts)
        res = _refine_on_triangulation(k, S, Ts, _mean_value_layout(S, Ts, k), h,
                                       isometric=False)
        layout = "mean-value"
    if res is None:
        raise MeshRepairError("the minimum-weight triangulation of the loop could not be remeshed "
                              "(Triangle changed the loop vertices)")
    X, T, X2 = res
    log.debug("liepa: %d-loop, %d coarse triangles, %s layout, %d triangles", k, len(Tc),
              layout, len(T))
    return Patch(X=X, T=_orient_patch(T, k), uv=X2, method="liepa", n_loop=k)


# ------------------------------------------------------------------------------------------------
# enclosing several holes of a mesh
# ------------------------------------------------------------------------------------------------


def _split_chords(patch: Patch, bad: set[tuple[int, int]]) -> Patch:
    """Split the local edges in ``bad`` (pairs of local indices) at their midpoints."""
    X, T, uv = patch.X.copy(), patch.T.copy(), patch.uv.copy()
    for a, b in sorted(bad):
        idx = np.flatnonzero((T == a).any(axis=1) & (T == b).any(axis=1))
        if len(idx) != 2:
            continue
        m = len(X)
        X = np.r_[X, 0.5 * (X[a] + X[b])[None]]
        uv = np.r_[uv, 0.5 * (uv[a] + uv[b])[None]]
        new = []
        for f in idx:
            t = T[f].tolist()
            r = t.index(a)
            t = t[r:] + t[:r]  # a first
            if t[1] == b:  # (a, b, c) -> (a, m, c), (m, b, c)
                new += [[a, m, t[2]], [m, b, t[2]]]
            else:  # (a, c, b) -> (a, c, m), (m, c, b)
                new += [[a, t[1], m], [m, t[1], b]]
        T = np.r_[np.delete(T, idx, axis=0), np.asarray(new, dtype=np.int64)]
    return Patch(X=X, T=T, uv=uv, method=patch.method, n_loop=patch.n_loop)


def _loop_side_points(V: np.ndarray, F: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Centroids of the faces bordering the loop edges, shape ``(k, 3)``."""
    sel = np.isin(F, loop).sum(axis=1) >= 2
    Fs = F[sel]
    third = {}
    for f in Fs.tolist():
        for j in range(3):
            third[(f[j], f[(j + 1) % 3])] = f[(j + 2) % 3]
    nxt = np.roll(loop, -1)
    w = np.array([third.get((u, v), -1) for u, v in zip(loop.tolist(), nxt.tolist(),
                                                          strict=True)])
    ok = w >= 0
    return (V[loop[ok]] + V[nxt[ok]] + V[w[ok]]) / 3.0


def _nested_in(V: np.ndarray, F: np.ndarray, outer: Hole, inner: Hole) -> bool:
    """True when loop ``inner`` lies inside the hole bounded by ``outer`` (an island)."""
    Po, Pi = V[outer.vertices], V[inner.vertices]
    lo, hi = Po.min(axis=0), Po.max(axis=0)
    pad = 0.5 * float((hi - lo).max())
    if (Pi < lo - pad).any() or (Pi > hi + pad).any():
        return False
    va = _vector_area(Po)
    if not np.linalg.norm(va) > 0:
        return False
    n = -va / np.linalg.norm(va)
    c = Po.mean(axis=0)
    rad = float(np.linalg.norm(Po - c, axis=1).max())
    if np.abs((Pi - c) @ n).max() > 0.5 * rad:
        return False
    e1, e2 = _plane_frame(n)

    def proj(X):
        return np.c_[(X - c) @ e1, (X - c) @ e2]

    Qo, Qi = proj(Po), proj(Pi)
    if not _polygon_is_simple(Qo):
        return False
    from matplotlib.path import Path as MPath

    poly = MPath(Qo)
    if not poly.contains_points(Qi).all():
        return False
    # a hole has its surface outside the loop (a border of a surface piece has it inside)
    side = _loop_side_points(V, F, outer.vertices)
    if len(side) == 0 or poly.contains_points(proj(side)).mean() > 0.5:
        return False
    # an island boundary turns the other way round than the hole it sits in
    area_i = 0.5 * float(np.sum(Qi[:, 0] * np.roll(Qi[:, 1], -1) - np.roll(Qi[:, 0], -1)
                                * Qi[:, 1]))
    return area_i > 0


def _opposite_points(V: np.ndarray, F: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Third vertex of the face on each loop edge ``(loop[i], loop[i+1])``, ``(k, 3)`` (NaN rows
    where the edge has no face traversing it in that direction)."""
    n = np.int64(max(int(F.max(initial=0)), int(loop.max())) + 1)
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    third = np.roll(F, -2, axis=1).ravel()
    code = he[:, 0] * n + he[:, 1]
    order = np.argsort(code, kind="stable")
    code = code[order]
    want = loop * n + np.roll(loop, -1)
    pos = np.clip(np.searchsorted(code, want), 0, max(len(code) - 1, 0))
    out = np.full((len(loop), 3), np.nan)
    if len(code):
        hit = code[pos] == want
        out[hit] = V[third[order[pos[hit]]]]
    return out


def _loop_chords(F: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Edges of ``F`` joining two non-consecutive loop vertices, as local pairs ``(q, 2)``."""
    k = len(loop)
    n = max(int(F.max(initial=0)), int(loop.max())) + 1
    local = np.full(n, -1, np.int64)
    local[loop] = np.arange(k)
    Fs = F[(local[F] >= 0).sum(axis=1) >= 2]
    e = local[np.r_[Fs[:, [0, 1]], Fs[:, [1, 2]], Fs[:, [2, 0]]]]
    e = np.sort(e[(e >= 0).all(axis=1)], axis=1)
    d = e[:, 1] - e[:, 0]
    return np.unique(e[(d >= 2) & (d != k - 1)], axis=0)


def _existing_edge_codes(F: np.ndarray, n: int) -> np.ndarray:
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    return np.unique(e[:, 0] * np.int64(n) + e[:, 1])


def enclose_holes(V: np.ndarray, F: np.ndarray, holes: Sequence[Hole],
                  skip: dict[int, str] | None = None, *, edge_length: float | None = None,
                  check: bool = True, intersections: bool = True,
                  method: str | Mapping[int, str] = "auto"
                  ) -> tuple[np.ndarray, np.ndarray, list[HoleReport]]:
    """Enclose the selected holes of a mesh with initial (membrane) patches.

    Parameters
    ----------
    V : (nV, 3) float64
    F : (nF, 3) int64
    holes : list of Hole, from :func:`find_holes` on ``(V, F)``
    skip : dict of int to str, optional
        Holes not to fill and why (from :func:`select_holes`).
    edge_length : float, optional
        Target edge length of every patch (default: each loop's mean edge length).
    check : bool
        Refuse (skip, with the reason) a patch that lies on the existing surface (the border of
        an open surface filled a second time).
    intersections : bool
        Also refuse a patch whose membrane position intersects the mesh (with ``check``).
    method : str or mapping of int to str
        How each loop is triangulated (:func:`enclose_loop`: ``"auto"`` or ``"liepa"``), for all
        holes or per hole index (missing indices: ``"auto"``). Islands are always filled as
        planar annuli.

    Returns
    -------
    V_new : (nV + m, 3) float64
        ``V`` followed by the new interior vertices (hole by hole).
    F_new : (nF + t, 3) int64
        ``F`` followed by the new faces (hole by hole).
    reports : list of HoleReport, one per hole in ``holes`` order.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    nV = len(V)
    skip = dict(skip or {})
    methods = {h.index: method if isinstance(method, str) else method.get(h.index, "auto")
               for h in holes}
    bad = sorted(set(methods.values()) - set(ENCLOSE_METHODS))
    if bad:
        raise MeshRepairError(f"method must be one of {ENCLOSE_METHODS}, got {bad[0]!r}")
    reports: dict[int, HoleReport] = {}
    by_index = {h.index: h for h in holes}

    # islands: a loop nested inside another hole is filled together with it as an annulus
    partner: dict[int, int] = {}
    for ho in holes:
        for hi in holes:
            if hi.index == ho.index or hi.index in partner or ho.index in partner:
                continue
            if hi.length < ho.length and _nested_in(V, F, ho, hi):
                partner[ho.index] = hi.index
                partner[hi.index] = ho.index
    for h in holes:
        if h.index in partner:
            o = partner[h.index]
            if h.length < by_index[o].length:  # h is the island
                if o in skip:
                    skip[h.index] = (f"island inside hole {o}, which is not filled (loop bounds a "
                                     "separate surface piece inside that hole)")
                else:
                    skip.pop(h.index, None)

    code_n = np.int64(1) << np.int64(31)
    edge_set = set(_existing_edge_codes(F, code_n).tolist())
    newV: list[np.ndarray] = []
    newF: list[np.ndarray] = []
    n_added = 0
    Vcur = V
    Fcur = F
    for h in holes:
        if h.index in reports:  # an island already reported with its outer loop
            continue
        rep = HoleReport(index=h.index, n_boundary=h.n_boundary, length=h.length,
                         status="skipped", loop=h.vertices.copy())
        reports[h.index] = rep
        if h.index in skip:
            rep.reason = skip[h.index]
            continue
        if h.index in partner and h.length < by_index[partner[h.index]].length:
            rep.reason = (f"island inside hole {partner[h.index]}, which could not be filled "
                          "(see there)")
            continue  # island: handled with its outer loop
        h_len = edge_length
        try:
            if h.index in partner:
                isl = by_index[partner[h.index]]
                gverts = np.r_[h.vertices, isl.vertices]
                if h_len is None:
                    h_len = (h.length + isl.length) / (h.n_boundary + isl.n_boundary)
                patch = _enclose_annulus(V[h.vertices], V[isl.vertices], h_len)
                if patch is None:
                    rep.reason = (f"hole {isl.index} is an island inside this hole and the "
                                  "region between them could not be triangulated in a planar "
                                  "view; fill it manually or exclude both")
                    reports[isl.index] = HoleReport(
                        index=isl.index, n_boundary=isl.n_boundary, length=isl.length,
                        status="skipped", reason=f"island inside hole {h.index} (see there)",
                        loop=isl.vertices.copy())
                    continue
            elif methods[h.index] == "liepa":
                gverts = h.vertices
                patch = enclose_loop(V[h.vertices], edge_length=h_len, method="liepa",
                                     opposite=_opposite_points(V, F, h.vertices),
                                     forbidden=_loop_chords(Fcur, h.vertices))
            else:
                gverts = h.vertices
                patch = enclose_loop(V[h.vertices], edge_length=h_len)
        except MeshRepairError as exc:
            rep.reason = f"cannot triangulate: {exc}"
            continue
        k = patch.n_loop
        # chords (patch edges between two loop vertices) must not duplicate an existing edge
        for _ in range(4):
            he = np.sort(np.concatenate([patch.T[:, [0, 1]], patch.T[:, [1, 2]],
                                         patch.T[:, [2, 0]]]), axis=1)
            he, n_faces = np.unique(he, axis=0, return_counts=True)
            chords = he[(he[:, 1] < k) & (n_faces == 2)]  # loop edges have one patch face
            g = np.sort(gverts[chords], axis=1)
            dup = {tuple(c) for c, gc in zip(chords.tolist(), g.tolist(), strict=True)
                   if gc[0] * code_n + gc[1] in edge_set}
            if not dup:
                break
            patch = _split_chords(patch, dup)
        if k == 3 and h.index not in partner:
            tri = np.sort(gverts)
            if (np.sort(Fcur, axis=1) == tri).all(axis=1).any():
                rep.reason = ("the loop bounds a single isolated triangle; filling it would "
                              "create a two-sided sliver")
                continue
        m = len(patch.X) - k
        gmap = np.r_[gverts, nV + n_added + np.arange(m)]
        Fp = gmap[patch.T]
        Vp = patch.X[k:]
        if check and m > 0:
            Vtry = np.r_[Vcur, Vp]
            reason = _patch_problem(Vtry, Fcur, Fp, np.arange(nV + n_added, nV + n_added + m),
                                    h_len if h_len is not None else h.length / h.n_boundary,
                                    intersections)
            if reason:
                rep.reason = reason
                continue
        newV.append(Vp)
        newF.append(Fp)
        n_added += m
        Vcur = np.r_[Vcur, Vp]
        Fcur = np.r_[Fcur, Fp]
        e = np.sort(np.concatenate([Fp[:, [0, 1]], Fp[:, [1, 2]], Fp[:, [2, 0]]]), axis=1)
        edge_set.update((e[:, 0] * code_n + e[:, 1]).tolist())
        rep.status = "filled"
        rep.reason = patch.method
        rep.n_new_vertices = m
        rep.n_new_faces = len(Fp)
        if h.index in partner:
            isl = by_index[partner[h.index]]
            rep.reason = f"annulus with island hole {isl.index}"
            reports[isl.index] = HoleReport(
                index=isl.index, n_boundary=isl.n_boundary, length=isl.length, status="filled",
                reason=f"island: filled together with hole {h.index}", loop=isl.vertices.copy())
    return Vcur, Fcur, [reports[h.index] for h in holes]


def _patch_problem(V: np.ndarray, F: np.ndarray, Fp: np.ndarray, interior: np.ndarray,
                   h: float, intersections: bool) -> str:
    """Reason to refuse a patch (empty string if fine)."""
    from .metrics import point_to_surface

    d = point_to_surface(V[interior], V, F)
    if np.mean(d < 0.2 * h) > 0.5:
        return ("the patch would lie on the existing surface (the loop is probably the outer "
                "border of an open surface: use keep_border or exclude it)")
    if not intersections:
        return ""
    Fall = np.r_[F, Fp]
    pairs = self_intersections(V, Fall, np.arange(len(F), len(Fall)))
    if len(pairs):
        return (f"the patch would intersect the surface ({len(pairs)} face pairs): the loop is "
                "too twisted for a direct fill; exclude it or fill it manually")
    return ""


# ------------------------------------------------------------------------------------------------
# fairing
# ------------------------------------------------------------------------------------------------


def fair_vertices(V: np.ndarray, F: np.ndarray, free: np.ndarray, *, order: int = 2,
                  weights: str = "cotan", iterations: int = 1) -> np.ndarray:
    """Move the ``free`` vertices to a fair (harmonic or bi-Laplacian) position.

    ``order=2`` minimises ``sum_r A_r |(Δx)_r|²`` over the free vertices and their neighbours
    (``Δ = A⁻¹ C``, ``C`` the cotangent or umbrella weights, ``A`` barycentric areas) with all
    other vertices fixed: the free region continues position *and* tangent plane of the
    surrounding 1-ring (least-squares meshes / thin-plate fairing). ``order=1`` solves
    ``(Δx)_i = 0`` on the free vertices only (a membrane: minimal area for cotangent weights).
    Rows of vertices on a remaining open boundary are left out (their Laplacian is one-sided).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    free : (nV,) bool or int indices of the vertices to move
    order : 1 or 2
    weights : ``"cotan"`` (geometry-aware, from the current positions) or ``"uniform"``
        (umbrella; also regularises the vertex distribution)
    iterations : int
        Recompute the cotangent weights from the new positions and solve again this many times.

    Returns
    -------
    (nV, 3) float64, a new array (only the free rows differ from ``V``).
    """
    from scipy.sparse.linalg import spsolve

    V = np.array(V, dtype=np.float64, copy=True)
    F = np.asarray(F, dtype=np.int64)
    nV = len(V)
    fm = np.zeros(nV, bool)
    fm[np.asarray(free)] = True
    if not fm.any():
        return V
    if order not in (1, 2):
        raise MeshRepairError(f"order must be 1 or 2, got {order}")
    if weights not in ("cotan", "uniform"):
        raise MeshRepairError(f"weights must be 'cotan' or 'uniform', got {weights!r}")
    # local mesh: faces touching the free vertices and their neighbours
    touch = fm[F].any(axis=1)
    rows = np.zeros(nV, bool)
    rows[F[touch].ravel()] = True
    if order == 1:
        rows = fm.copy()
    Floc = F[rows[F].any(axis=1)]
    topo = edge_topology(F, nV)
    on_bnd = np.zeros(nV, bool)
    on_bnd[topo.edges[topo.boundary].ravel()] = True
    rows &= ~(on_bnd & ~fm)
    r_idx = np.flatnonzero(rows)
    u_idx = np.flatnonzero(fm)
    for _ in range(max(1, iterations)):
        if weights == "cotan":
            W = _cotan_weights_2d(V, Floc, nV)
        else:
            e = np.sort(np.concatenate([Floc[:, [0, 1]], Floc[:, [1, 2]], Floc[:, [2, 0]]]),
                        axis=1)
            e = np.unique(e, axis=0)
            W = sp.csr_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]],
                                                      np.r_[e[:, 1], e[:, 0]])), shape=(nV, nV))
        C = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()
        if weights == "cotan":
            c = np.cross(V[Floc[:, 1]] - V[Floc[:, 0]], V[Floc[:, 2]] - V[Floc[:, 0]])
            area = np.zeros(nV)
            np.add.at(area, Floc.ravel(), np.repeat(np.linalg.norm(c, axis=1) / 6.0, 3))
        else:
            area = np.ones(nV)
        k_idx = np.flatnonzero(~fm)
        if order == 1:
            A = C[u_idx][:, u_idx].tocsc()
            rhs = -(C[u_idx][:, k_idx] @ V[k_idx])
        else:
            Cr = C[r_idx]
            w = sp.diags(1.0 / np.maximum(area[r_idx], 1e-300))
            CU = Cr[:, u_idx]
            CK = Cr[:, k_idx]
            A = (CU.T @ w @ CU).tocsc()
            rhs = -(CU.T @ (w @ (CK @ V[k_idx])))
        sol = spsolve(A, rhs)
        V[u_idx] = np.asarray(sol).reshape(len(u_idx), 3)
        if weights == "uniform":
            break
    return V


# ------------------------------------------------------------------------------------------------
# intersections
# ------------------------------------------------------------------------------------------------


def _seg_tri(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray,
             tol: float) -> np.ndarray:
    """Row-wise: does segment pq cross triangle abc (Möller-Trumbore, closed, tolerance tol)."""
    d = q - p
    e1 = b - a
    e2 = c - a
    hv = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, hv)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(np.cross(e1, e2), axis=1)
    ok = np.abs(det) > 1e-12 * np.maximum(scale, 1e-300)
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = p - a
    u = inv * np.einsum("ij,ij->i", s, hv)
    qv = np.cross(s, e1)
    v = inv * np.einsum("ij,ij->i", d, qv)
    t = inv * np.einsum("ij,ij->i", e2, qv)
    return ok & (u >= -tol) & (v >= -tol) & (u + v <= 1 + tol) & (t >= -tol) & (t <= 1 + tol)


def self_intersections(V: np.ndarray, F: np.ndarray, faces: np.ndarray | None = None, *,
                       tol: float = 1e-9) -> np.ndarray:
    """Pairs of faces that intersect other than along their shared vertices or edge.

    Faces without a common vertex intersect when an edge of one crosses the other; faces sharing
    one vertex when the opposite edge of one crosses the other; faces sharing an edge when they
    are folded onto each other (dihedral angle within 0.1° of 180°). Candidate pairs come from a
    k-d tree on face centroids. Exactly coplanar overlaps of faces without a shared element are
    not detected (they do not occur in practice).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    faces : (q,) int, optional
        Only pairs involving at least one of these faces are tested (default: all faces).
    tol : float
        Relative tolerance of the barycentric and segment-parameter tests (touching counts).

    Returns
    -------
    (n, 2) int64 face index pairs, ``pairs[:, 0] < pairs[:, 1]``.
    """
    from scipy.spatial import cKDTree

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    q_faces = np.arange(len(F)) if faces is None else np.unique(np.asarray(faces, np.int64))
    if len(q_faces) == 0 or len(F) < 2:
        return np.empty((0, 2), np.int64)
    cen = V[F].mean(axis=1)
    rad = np.linalg.norm(V[F] - cen[:, None, :], axis=2).max(axis=1)
    # candidate pairs: centroids closer than the sum of the circumradii. Faces are put in classes
    # of radius within a factor 2, one k-d tree per class, each queried with the query face's
    # radius plus the class's largest: tight even when a few faces are much larger than the rest
    # (a coarse patch over a big hole made the single-radius search generate 10^7 candidates)
    med = max(float(np.median(rad)), 1e-300)
    cls = np.floor(np.log2(np.maximum(rad, 1e-300) / med)).astype(np.int64)
    cls = np.clip(cls, -8, None)
    a_parts, b_parts = [], []
    for c in np.unique(cls):
        members = np.flatnonzero(cls == c)
        tree = cKDTree(cen[members])
        lists = tree.query_ball_point(cen[q_faces], r=rad[q_faces] + float(rad[members].max()))
        counts = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(lists))
        if counts.sum() == 0:
            continue
        a_parts.append(np.repeat(q_faces, counts))
        b_parts.append(members[np.fromiter(itertools.chain.from_iterable(lists), dtype=np.int64,
                                           count=int(counts.sum()))])
    if not a_parts:
        return np.empty((0, 2), np.int64)
    a = np.concatenate(a_parts)
    b = np.concatenate(b_parts)
    # each (query face, face) pair is found once; a pair of two query faces twice: keep a < b
    qset = np.zeros(len(F), bool)
    qset[q_faces] = True
    keep = (a != b) & (~qset[b] | (a < b))
    a, b = np.minimum(a[keep], b[keep]), np.maximum(a[keep], b[keep])
    if len(a) == 0:
        return np.empty((0, 2), np.int64)
    close = np.linalg.norm(cen[a] - cen[b], axis=1) <= rad[a] + rad[b]
    a, b = a[close], b[close]
    Fa, Fb = F[a], F[b]
    shared = (Fa[:, :, None] == Fb[:, None, :])
    n_sh = shared.any(axis=2).sum(axis=1)
    hit = np.zeros(len(a), bool)
    # no shared vertex: 6 segment-triangle tests
    m0 = np.flatnonzero(n_sh == 0)
    if len(m0):
        A, B = V[Fa[m0]], V[Fb[m0]]
        h0 = np.zeros(len(m0), bool)
        for k in range(3):
            h0 |= _seg_tri(A[:, k], A[:, (k + 1) % 3], B[:, 0], B[:, 1], B[:, 2], tol)
            h0 |= _seg_tri(B[:, k], B[:, (k + 1) % 3], A[:, 0], A[:, 1], A[:, 2], tol)
        hit[m0] = h0
    # one shared vertex: the opposite edges
    m1 = np.flatnonzero(n_sh == 1)
    if len(m1):
        sa = shared[m1].any(axis=2)  # which corner of a is shared
        sb = shared[m1].any(axis=1)
        ka = np.argmax(sa, axis=1)
        kb = np.argmax(sb, axis=1)
        r = np.arange(len(m1))
        A, B = V[Fa[m1]], V[Fb[m1]]
        pa, qa = A[r, (ka + 1) % 3], A[r, (ka + 2) % 3]
        pb, qb = B[r, (kb + 1) % 3], B[r, (kb + 2) % 3]
        # strict parameters so the shared vertex itself does not count
        h1 = _seg_tri(pa, qa, B[:, 0], B[:, 1], B[:, 2], -tol)
        h1 |= _seg_tri(pb, qb, A[:, 0], A[:, 1], A[:, 2], -tol)
        hit[m1] = h1
    # shared edge: folded faces
    m2 = np.flatnonzero(n_sh == 2)
    if len(m2):
        na = np.cross(V[Fa[m2, 1]] - V[Fa[m2, 0]], V[Fa[m2, 2]] - V[Fa[m2, 0]])
        nb = np.cross(V[Fb[m2, 1]] - V[Fb[m2, 0]], V[Fb[m2, 2]] - V[Fb[m2, 0]])
        cosang = np.einsum("ij,ij->i", na, nb) / np.maximum(
            np.linalg.norm(na, axis=1) * np.linalg.norm(nb, axis=1), 1e-300)
        hit[m2] = cosang < -np.cos(np.radians(0.1))
    pairs = np.c_[a[hit], b[hit]].astype(np.int64)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
