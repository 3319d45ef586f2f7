"""The result dataclass of :func:`meshrepair.fill.fill_holes` and
:func:`meshrepair.fill.inpaint`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from meshrepair.holes import HoleReport

__all__ = ["FillResult"]


@dataclass
class FillResult:
    """Result of :func:`fill_holes` and :func:`inpaint`.

    Attributes
    ----------
    V : (nV', 3) float64
        Vertices: the kept original vertices first, in their original order, then the new
        vertices (hole by hole).
    F : (nF', 3) int64
        Faces: the kept original faces first, in their original order, then the new faces.
    M_V : (nV',) float64
        Fidelity mask: 0 on new vertices (the region ``S_D``), 1 elsewhere.
    M_E : (nE,) bool
        Sharp-edge mask of the last solver stage (False on every edge of a new face).
    edges : (nE, 2) int64
        The edges ``M_E`` refers to (``edge_topology(F).edges``).
    history : list of dict
        One entry per ADMM iteration (see :class:`meshrepair.model.solver.SolverResult`).
    holes : list of HoleReport
        One report per boundary loop of the (cut) input: filled or skipped, and why.
    new_vertices : (m,) int64
        Indices of the new vertices in ``V``.
    new_faces : (t,) int64
        Indices of the new faces in ``F``.
    vertex_map : (nV_in,) int64
        Output index of every input vertex, -1 for dropped ones (only :func:`inpaint` drops the
        vertices of the removed region); the identity for :func:`fill_holes`.
    removed_faces : (r,) int64
        Input faces removed by :func:`inpaint` (empty for :func:`fill_holes`).
    iterations : int
    stop_reason : str
    params : dict
        The options actually used.
    timings : dict
        Seconds per step (``enclose``, ``initial``, ``solve``, ``total``).
    """

    V: np.ndarray
    F: np.ndarray
    M_V: np.ndarray
    M_E: np.ndarray
    edges: np.ndarray
    history: list[dict] = field(default_factory=list)
    holes: list[HoleReport] = field(default_factory=list)
    new_vertices: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    new_faces: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    vertex_map: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    removed_faces: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    iterations: int = 0
    stop_reason: str = ""
    params: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)

    @property
    def n_filled(self) -> int:
        """Number of holes filled."""
        return sum(h.status == "filled" for h in self.holes)

    @property
    def n_skipped(self) -> int:
        """Number of holes left open."""
        return sum(h.status != "filled" for h in self.holes)

    @property
    def filled_mask(self) -> np.ndarray:
        """(nV',) uint8: 1 on new vertices (for a PLY vertex attribute)."""
        m = np.zeros(len(self.V), np.uint8)
        m[self.new_vertices] = 1
        return m

    @property
    def mesh(self):
        """The result as a ``trimesh.Trimesh`` (no processing, same vertex order)."""
        import trimesh

        return trimesh.Trimesh(self.V, self.F, process=False)

    def summary(self) -> str:
        """Human-readable summary: holes found, filled, skipped and why."""
        lines = [f"{len(self.holes)} holes found, {self.n_filled} filled, {self.n_skipped} "
                 f"skipped; {len(self.new_vertices)} new vertices, {len(self.new_faces)} new "
                 f"faces"]
        if len(self.removed_faces):
            lines.insert(0, f"removed {len(self.removed_faces)} faces of the damaged region")
        for h in self.holes:
            what = (f"filled ({h.reason}; {h.n_new_vertices} vertices, {h.n_new_faces} faces)"
                    if h.status == "filled" else f"skipped: {h.reason}")
            lines.append(f"  hole {h.index}: {h.n_boundary} boundary edges, length "
                         f"{h.length:.6g}: {what}")
            if h.quality:
                from meshrepair.fill.quality import quality_line

                lines.append(f"    quality: {quality_line(h.quality)}")
            if h.note:
                lines.append(f"    note: {h.note}")
        return "\n".join(lines)
