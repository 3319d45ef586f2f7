"""The result of :func:`meshrepair.complete` (context-aware completion, Sect. 5)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["CompletionResult"]


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
    alignment : dict, the alignment report (:func:`meshrepair.complete.alignment.alignment_report`):
        ``boundary_rms``, ``boundary_max``, ``context_rms``, ``context_max`` in mean edge
        lengths of the input (context values None for a template without context),
        ``context_points``, ``unit``, ``warning``
    symmetry : dict or None, with ``template="mirror"``: the plane (``normal``, ``point``,
        ``offset``), ``residual`` (mean distance of the mirrored intact surface to itself, in
        mean edge lengths), ``residual_max``, ``candidates`` and the counterpart's face count
        (see :func:`meshrepair.complete.symmetry.detect_symmetry`)
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
    alignment: dict = field(default_factory=dict)
    symmetry: dict | None = None

    @property
    def mesh(self):
        """The result as a ``trimesh.Trimesh`` (no processing, same vertex order)."""
        import trimesh

        return trimesh.Trimesh(self.V, self.F, process=False)
