"""Context-aware completion: replace a damaged region of a mesh with a template patch (Sect. 5).

Given a mesh ``M0 = (V0, T0)``, a region ``(V̄, T̄)`` bounded by a loop ``b0`` and a template patch
``P = (V_P, T_P)`` bounded by one loop ``b_P``, :func:`complete` builds

.. math:: V^{(0)} = (V_0 \\setminus \\bar V) \\cup V_P, \\qquad
          T^* = (T_0 \\setminus \\bar T) \\cup T_P

with the boundary vertices of ``b_P`` merged into those of ``b0``, and blends the two parts by
minimising energy (6) with the shared :class:`~meshrepair.model.solver.ADMMSolver`:

1. **Region.** Face indices ``T̄`` (main form), a vertex selection (the faces with all three
   vertices selected) or an existing hole (``hole=k``: ``T̄ = V̄ = ∅``). The region must be a
   topological disc: connected, one simple boundary loop, Euler characteristic 1, not touching
   the mesh boundary. ``b0`` follows the orientation of the remaining faces.
2. **Correspondence.** Both loops are resampled to the same number of points by arc length and
   the best cyclic shift and direction is found over all shifts at once
   (:func:`~meshrepair.complete.correspondence.best_cyclic_alignment`).
3. **Alignment** (:mod:`meshrepair.complete.alignment`), from the intact surface only: rigid (or,
with
   ``allow_scale=True``, similarity) Umeyama fit of ``b_P`` onto ``b0`` from that
   correspondence, ICP of ``b_P`` against the polyline ``b0``, refits on matched boundary
   vertices, and, when the template is a piece of a mesh, point-to-plane ICP of its boundary and
   its own context rings against the remaining faces around ``b0`` (never the faces ``T̄``
   being replaced). Or a user-given 4x4 ``transform`` (no automatic alignment). With
   ``template="mirror"`` the template is the mirrored counterpart of the region across the
   mesh's symmetry plane (:mod:`meshrepair.complete.symmetry`).
4. **Suitable subdivision.** The two aligned loops are refined to a common sampling
   (:func:`~meshrepair.complete.correspondence.align_loops`, a cyclic sequence alignment): each
   vertex
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
   on both sides. ``M_V = 1`` outside it; on it 0 (the paper) in smooth and sharp modes, and in
   adaptive mode ``strip_fidelity * max(0, 1 - g / 0.25)`` with ``g`` the nearby normal seam gap
   in mean edge lengths (:func:`_strip_fidelity`: where the template meets the mesh the stitched
   surface is kept); ``M_E`` on strip edges is forced smooth
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

import numpy as np

from meshrepair.complete.alignment import ICP_MODES, alignment_report, place_template
from meshrepair.complete.blend import GAP_FREE, _strip_fidelity, blend_seam  # noqa: F401
from meshrepair.complete.inputs import (  # noqa: F401  (re-exported: the public API of this module)
    _check_template,
    _compact,
    _face_selection,
    _region_loop,
    _template_arrays,
    _template_context,
    extract_patch,
    load_transform,
    region_from_vertices,
)
from meshrepair.complete.modes import MODES, ORIENTATIONS  # the CLI reads them there
from meshrepair.complete.result import CompletionResult
from meshrepair.complete.stitch import (  # noqa: F401  (re-exported)
    _harmonic_displacement,
    _rings,
    _split_ears,
    _to_loop_params,
    stitch_template,
)
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.geometry import mean_edge_length

log = logging.getLogger(__name__)

__all__ = ["MODES", "CompletionResult", "complete", "extract_patch", "load_transform",
           "region_from_vertices"]



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
    strip_fidelity: float | None = None,
    max_symmetry_residual: float = 0.1,
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
        ``trimesh.Trimesh`` / ``MeshData``, ``(V_src, F_src, faces)`` selecting faces of a mesh
        (the same or another one; its context rings then take part in the alignment), or
        ``"mirror"``: the mirror image of the region's counterpart across the mesh's symmetry
        plane, detected on the intact surface (refused when the mesh is not symmetric enough).
    region_vertices : vertex selection (indices, boolean/0-1 mask or mask file); the region is
        the faces with all three vertices selected.
    hole : index of an existing hole of the mesh, numbered as everywhere else
        (:func:`meshrepair.holes.find_holes`: simple loops, longest first, as ``meshrepair fill
        --list`` shows them) to complete; then nothing is removed. A pinched hole (sharing a
        vertex with another) is refused.
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
    icp : refinement of the automatic alignment
    (:func:`meshrepair.complete.alignment.place_template`).
        ``"context"`` (what ``"auto"``, the default, means): ICP of ``b_P`` against the polyline
        ``b0`` and refits on matched boundary vertices, then, for a template given as a piece of
        a mesh, trimmed point-to-plane ICP of its boundary and its own context rings
        (``icp_rings`` rings of the source mesh outside it) against the remaining faces around
        ``b0``; the faces being replaced are never used. ``"boundary"``: the boundary steps
        only. ``"surface"`` (opt-in for an undamaged region): the boundary steps, then the
        template's vertices within ``icp_rings`` rings of ``b_P`` fitted to the surface around
        the hole *including the region's faces*. ``"none"`` (or False): the coarse fit only.
    icp_rings : rings of template vertices (``"surface"``) or of template context (``"context"``)
        used by the ICP (0: the boundary only).
    strip_fidelity : weight of the gap-adaptive fidelity on the strip (default 16 in adaptive
        mode, 0 in smooth and sharp modes: the paper's free strip).
    max_symmetry_residual : with ``template="mirror"``, refuse when the symmetry residual (mean
        edge lengths) is above this.
    fix_outside : vertices outside the strip never move (default True; False with ``denoise``).
        The solve then runs only on the band of ``strip_rings + 2`` rings around the seam.
    denoise : solve on the whole mesh with the two-stage denoising schedule
        (:func:`meshrepair.denoise.api.default_stages`) and λ from the estimated noise, i.e. denoise
        the context while blending.
    lam : fidelity weight λ (default 1; with ``denoise`` from the noise estimate). It only acts
        on vertices outside the strip, so it has no effect when ``fix_outside`` is True.
    th : dihedral threshold (degrees) of the adaptive ``M_E``.
    a : MC non-convexity of the blending stage.
    iterations : iteration cap of the blending stage (or of the feature stage with ``denoise``).
    mask_update_every : refresh the adaptive ``M_E`` every this many iterations (0: never).
    relax : tangential relaxation weight per iteration (:class:`~meshrepair.model.solver.Stage`);
        default 0.2 in ``"smooth"`` mode (without it the edge-Willmore energy can fold a strip
        triangle to shorten an edge across a smoothed crease) and 0 otherwise.
    tol : rule (35) tolerance.
    inner_solver : V-subproblem solver of :class:`~meshrepair.model.solver.SolverOptions`.
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
        stitched result that is not manifold, a mesh not symmetric enough for
        ``template="mirror"`` (the residual is in the message), or invalid options.
    """
    from meshrepair.mesh.array_contract import as_arrays
    from meshrepair.mesh.validate import check_mesh

    # ---- options ------------------------------------------------------------------------------
    if mode not in MODES:
        raise MeshRepairError(f"mode must be one of {MODES}, got {mode!r}")
    if orientation not in ORIENTATIONS:
        raise MeshRepairError(f"orientation must be one of {ORIENTATIONS}, got {orientation!r}")
    from meshrepair.options import MAX_ITERATIONS, check_angle, check_bool, check_int, check_number

    strip_rings = check_int("strip_rings", strip_rings, low=1)
    iterations = check_int("iterations", iterations, low=0, high=MAX_ITERATIONS)
    max_size_ratio = check_number("max_size_ratio", max_size_ratio, low=1)
    lam = check_number("lam", lam, low=0, allow_none=True)
    th = check_angle("th", th)
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
    from meshrepair.options import check_callable

    check_callable("callback", callback)
    if strip_fidelity is None:
        strip_fidelity = 16.0 if mode == "adaptive" else 0.0
    strip_fidelity = check_number("strip_fidelity", strip_fidelity, low=0)
    max_symmetry_residual = check_number("max_symmetry_residual (mean edge lengths)",
                                         max_symmetry_residual, low=0, low_open=True)

    # ---- inputs -------------------------------------------------------------------------------
    V, F = as_arrays(V, F)
    check_mesh(V, F, name="input mesh")
    nV, nF = len(V), len(F)
    given = [x is not None for x in (region, region_vertices, hole)]
    if sum(given) != 1:
        raise MeshRepairError("give exactly one of region (face indices), region_vertices (a "
                              "vertex selection) or hole (a hole index, as 'meshrepair fill "
                              "--list' numbers it)")
    if hole is not None:
        from meshrepair.holes import _find_holes

        holes = _find_holes(V, F)
        if not holes:
            raise MeshRepairError("the mesh is closed (no hole); select the region to replace "
                                  "with region= or region_vertices=")
        if (isinstance(hole, bool) or not isinstance(hole, (int, np.integer, float))
                or not np.isfinite(hole) or int(hole) != hole or not 0 <= hole < len(holes)):
            raise MeshRepairError(f"hole must be an integer in [0, {len(holes) - 1}] (the mesh "
                                  f"has {len(holes)} holes, longest first, numbered as "
                                  f"'meshrepair fill --list' shows them), got {hole}")
        h = holes[int(hole)]
        if h.pinched:
            raise MeshRepairError(f"hole {h.index} is pinched (it shares a vertex with another "
                                  "hole, see 'meshrepair fill --list'); it cannot be stitched "
                                  "to one template loop: fill it with 'meshrepair fill --holes "
                                  f"{h.index}' or select a region around it")
        b0 = h.vertices
        region_faces = np.zeros(0, np.int64)
        removed = np.zeros(nV, bool)
    else:
        if region is not None:
            region_faces = _face_selection(region, nF, "region")
        else:
            region_faces = region_from_vertices(F, region_vertices, nV)
        b0, removed = _region_loop(V, F, region_faces)

    icp_mode = "context" if icp == "auto" else icp
    sym_info = None
    if isinstance(template, str) and template == "mirror":
        from meshrepair.complete.symmetry import mirror_template

        template, sym_info = mirror_template(V, F, region_faces, b0,
                                             max_residual=max_symmetry_residual)
    elif isinstance(template, str):
        raise MeshRepairError(f"template must be a patch, a face selection of a mesh, or "
                              f"'mirror', got the string {template!r}")
    VP, FP = _template_arrays(template)
    bP = _check_template(VP, FP)
    context = _template_context(template, icp_rings) if icp_mode == "context" else None
    T_user = None if transform is None else load_transform(transform)

    # ---- placement (alignment.py) ---------------------------------------------------------------
    pl = place_template(V, F, b0, region_faces, VP, FP, bP, context=context, transform=T_user,
                        allow_scale=allow_scale, max_size_ratio=max_size_ratio,
                        orientation=orientation, icp=icp_mode, icp_rings=icp_rings)
    T, ca, icp_info = pl.T, pl.cyclic, pl.icp
    unit = mean_edge_length(V, F)
    report = alignment_report(V, F, b0, VP, bP, T, context=context, target=pl.context_target,
                              unit=unit)
    nA, nB = len(b0), len(bP)

    # ---- suitable subdivision and stitching (stitch.py) ----------------------------------------
    st = stitch_template(V, F, region_faces, removed, b0, VP, FP, bP, T, ca.reversed,
                         strip_rings=strip_rings, hole=hole is not None, unit=unit)
    V_init, F_star, seam, new_index, n_mesh = st.V_init, st.F_star, st.seam, st.new_index, st.n_mesh
    rev, flipped = ca.reversed, not ca.reversed

    # ---- masks and blending (blend.py) ---------------------------------------------------------
    bl = blend_seam(V_init, F_star, seam, st.gap_l, strip_rings=strip_rings, mode=mode,
                    strip_fidelity=strip_fidelity, fix_outside=fix_outside, denoise=denoise,
                    lam=lam, th=th, a=a, iterations=iterations,
                    mask_update_every=mask_update_every, relax=relax, tol=tol,
                    inner_solver=inner_solver, callback=callback)
    V_out, M_V, M_E, topo, edge_force, strip, fixed = (bl.V, bl.M_V, bl.M_E, bl.topo,
                                                        bl.edge_force, bl.strip, bl.fixed)
    history, n_it, stop, lam_used = bl.history, bl.iterations, bl.stop_reason, bl.lam
    nVs = len(V_init)

    vertex_map = new_index[:nV].copy()
    corr = {
        "shift": int(ca.shift),
        "reversed": bool(rev),
        "flipped": bool(flipped),
        "n_hole": int(nA),
        "n_template": int(nB),
        "n_seam": int(len(seam)),
        "inserted_region": int(st.inserted_region),
        "inserted_template": int(st.inserted_template),
        "transform": T.copy(),
        "fit": pl.fit,
        "rms_before": pl.rms_before,
        "rms_coarse": float(ca.rms),
        "rms_other_direction": pl.rms_other_direction,
        "icp": icp_info,
        "rms_after": float(st.rms_after),
        "max_gap": st.max_gap,
        "ears_split": int(st.ears_split),
        "size_ratio": pl.size_ratio,
    }
    params = {"strip_rings": strip_rings, "mode": mode, "allow_scale": allow_scale,
              "max_size_ratio": max_size_ratio, "orientation": orientation, "icp": icp_mode,
              "fix_outside": bool(fix_outside), "denoise": denoise, "lam": lam_used, "th": th,
              "a": a, "iterations": int(iterations), "mask_update_every": mask_update_every,
              "relax": float(relax), "tol": tol, "inner_solver": inner_solver,
              "hole": None if hole is None else int(hole), "strip_fidelity": strip_fidelity,
              "template": "mirror" if sym_info is not None else "given"}
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
        alignment=report,
        symmetry=sym_info,
    )

