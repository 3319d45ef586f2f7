"""Holes of a mesh: detection (boundary loops split into simple loops) and selection."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import boundary_loops, connected_components
from meshrepair.options import is_whole


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
    n_creases : int
        Crease segments routed through the patch (:mod:`meshrepair.holes.creases`).
    sharp_edges : (q, 2) int64
        Patch edges on those creases (output vertex numbering), MC penalty in the solve.
    note : str
        What the user should check about a filled hole (an uncertain border decision, a patch
        kept although it lies on or intersects the surface), empty when nothing.
    quality : dict
        Per-hole read-out of a filled hole (:func:`meshrepair.fill.quality.hole_quality`):
        ``seam_deg``, ``surround_deg``, ``curvature_ratio``, ``check``.
    n_folds : int
        Liepa patches (reason ``"liepa"``): folds of the minimum-weight triangulation kept as
        patch edges (:mod:`meshrepair.holes.liepa_refine`; 0 with its mean-value layout).
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
    n_creases: int = 0
    sharp_edges: np.ndarray = field(default_factory=lambda: np.empty((0, 2), np.int64),
                                    repr=False)
    note: str = ""
    quality: dict = field(default_factory=dict)
    n_folds: int = field(default=0, repr=False)

    def add_note(self, text: str) -> None:
        """Append ``text`` to :attr:`note` (``"; "``-separated)."""
        self.note = f"{self.note}; {text}" if self.note else text

    def as_dict(self) -> dict:
        """The report as plain Python values (for JSON logs)."""
        return {"index": self.index, "n_boundary": self.n_boundary, "length": self.length,
                "status": self.status, "reason": self.reason,
                "n_new_vertices": self.n_new_vertices, "n_new_faces": self.n_new_faces,
                "n_intersections": self.n_intersections, "n_creases": self.n_creases,
                "note": self.note, "quality": dict(self.quality)}


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
        For meshes :func:`meshrepair.mesh.validate.check_mesh` refuses (e.g. non-manifold edges).
    """
    from meshrepair.mesh.array_contract import as_arrays
    from meshrepair.mesh.validate import check_mesh

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


def check_max_hole_size(max_hole_size) -> None:
    """MeshRepairError unless ``max_hole_size`` is None or an integer >= 3."""
    if max_hole_size is not None and (not is_whole(max_hole_size) or max_hole_size < 3):
        raise MeshRepairError(f"max_hole_size must be an integer >= 3 (boundary vertices of "
                              f"the largest hole to fill), got {max_hole_size!r}")


def _check_indices(name: str, idx: Sequence[int] | None, n: int) -> list[int]:
    if idx is None:
        return []
    if isinstance(idx, (int, np.integer)):
        idx = [int(idx)]
    out = []
    for i in idx:
        if not is_whole(i):
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
                 indices: Sequence[int] | None = None,
                 borders: Mapping[int, str] | None = None) -> dict[int, str]:
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
        Fill only these holes (default: all). A hole listed here is filled even when it is in
        ``borders``.
    borders : mapping of int to str, optional
        Loops recognised as the open border of their surface
        (:func:`meshrepair.holes.border.find_borders`), with the reason: not filled unless
        listed in ``indices``.

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
    check_max_hole_size(max_hole_size)
    excl = set(_check_indices("exclude", exclude, n))
    only = None if indices is None else set(_check_indices("holes", indices, n))
    skipped: dict[int, str] = {}
    for h in holes:
        if keep_border and h.index == 0:
            skipped[h.index] = ("kept as the mesh border (keep_border: longest loop); fill it "
                                "without keep_border (CLI --keep-border)")
        elif h.index in excl:
            skipped[h.index] = "excluded"
        elif only is not None and h.index not in only:
            skipped[h.index] = "not selected"
        elif borders and h.index in borders and only is None:
            skipped[h.index] = borders[h.index]
        elif max_hole_size is not None and h.n_boundary > max_hole_size:
            skipped[h.index] = (f"larger than max_hole_size ({h.n_boundary} > {max_hole_size}); "
                                f"fill it with a larger max_hole_size (CLI --max-hole-size) or "
                                f"holes=[{h.index}] (CLI --holes {h.index})")
    return skipped
