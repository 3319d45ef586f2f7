"""The inpaint task: :func:`inpaint` removes a damaged region and fills the holes it opens."""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.fill.core import _fill_core
from meshrepair.fill.options import _check_options, _solve_options
from meshrepair.fill.region import _remove_region, region_mask
from meshrepair.fill.result import FillResult
from meshrepair.holes.budget import check_budget

log = logging.getLogger("meshrepair.fill")


def inpaint(
    V,
    F,
    region,
    *,
    keep_border: bool = False,
    denoise: bool = False,
    initial: str = "bilaplacian",
    refine: bool = True,
    edge_length: float | None = None,
    lam: float | None = None,
    th: float = 30.0,
    a: float = 10.0,
    max_iter: int = 150,
    tol: float = 1e-5,
    rings: int = 3,
    relax: float = 0.0,
    inner_solver: str = "armijo",
    inner_iters: int = 3,
    check: bool = True,
    callback: Callable[[dict], None] | None = None,
    progress: Callable[[int, int], None] | None = None,
    creases: bool = True,
    curvature: bool = True,
    triharmonic: bool = True,
    fitted: bool = False,
) -> FillResult:
    """Replace a damaged region of a mesh by a smooth patch.

    The faces with at least one corner in the region are removed (plus dangling faces, faces
    around vertices the removal would leave pinched, and small pieces it would cut off; see
    ``FillResult.removed_faces``); the vertices no longer used by any face are dropped; every hole
    this opens is filled as in :func:`fill_holes`. Holes the input already had are left alone.

    Inpainting never closes what the user did not mark: a region that reaches an open border
    (or a hole) of the input would merge with it into one loop, and filling that loop would
    close the border too. By default such a loop is refused (its report says so); with
    ``keep_border=True`` the faces touching the input's boundary are kept (a one-face strip
    along the border), so the region opens a hole of its own, which is filled, and the border
    stays open (the hole's note says so).

    Parameters
    ----------
    V : (nV, 3) float array, or a ``trimesh.Trimesh`` (then pass ``F=None``)
    F : (nF, 3) int array or None
    region : vertex indices, a bool (or 0/1) mask of length nV, ``("sphere", center, radius)`` or
        ``("box", lo, hi)`` (see :func:`region_mask`).
    keep_border : bool
        Where the region reaches an open border of the input: False (default) refuses to fill
        the merged loop; True keeps the faces along the border and fills the rest.
    denoise, initial, refine, edge_length, lam, th, a, max_iter, tol, rings, relax, inner_solver,
    inner_iters, check, callback, progress, creases, curvature, triharmonic, fitted : as in
        :func:`fill_holes`.

    Returns
    -------
    FillResult
        ``vertex_map[i]`` is the output index of input vertex ``i`` (-1 if dropped); kept input
        vertices come first in their original order, the new vertices after. ``F`` holds the
        kept input faces in their original order, then the new faces. ``holes`` reports only the
        holes opened by the removal.

    Raises
    ------
    MeshRepairError
        For an invalid mesh or region, an empty region, or a region covering the whole mesh.
    """
    opts = _solve_options(locals())
    from meshrepair.holes import _find_holes
    from meshrepair.mesh.array_contract import as_arrays
    from meshrepair.mesh.validate import _check_mesh

    V, F = as_arrays(V, F)
    vmask = region_mask(V, region)
    # faces touching the region are removed and rebuilt: degenerate ones there are the damage
    # (with keep_border, faces along the border stay: then every face must be valid)
    inside = (vmask[F].any(axis=1) if F.ndim == 2 and F.size and F.min() >= 0
              and F.max() < len(V) and keep_border is False else None)
    _check_mesh(V, F, name="input mesh", replaced=inside)
    opts = _check_options(opts)
    nV, _nF = len(V), len(F)
    if not vmask.any():
        raise MeshRepairError("the inpainting region contains no vertex of the mesh; check its "
                              "position and size (coordinates are in mesh units)")
    if not isinstance(keep_border, (bool, np.bool_)):
        raise MeshRepairError(f"keep_border must be True or False, got {keep_border!r}")
    from meshrepair.mesh.topology import edge_topology

    topo0 = edge_topology(F, nV)
    on_border = np.zeros(nV, bool)
    on_border[topo0.edges[topo0.boundary].ravel()] = True
    protect = on_border[F].any(axis=1) & vmask[F].any(axis=1) if keep_border else None
    removed, notes = _remove_region(F, nV, vmask, protect=protect)
    if protect is not None and protect.any():
        notes.append(f"{int(protect.sum())} faces along the open border kept (keep_border)")
    if removed.all():
        raise MeshRepairError("the inpainting region covers the whole mesh; nothing would be "
                              "left to fill from: use a smaller region")
    for n in notes:
        log.info("inpaint: %s", n)
    keepF = F[~removed]
    used_before = np.zeros(nV, bool)
    used_before[F.ravel()] = True
    used_after = np.zeros(nV, bool)
    used_after[keepF.ravel()] = True
    drop = used_before & ~used_after
    vmap = np.full(nV, -1, np.int64)
    kept = np.flatnonzero(~drop)
    vmap[kept] = np.arange(len(kept))
    V2 = V[kept]
    F2 = vmap[keepF]
    # holes opened by the removal: loops through a vertex of a removed face
    found = _find_holes(V2, F2)
    old_edges: set[tuple[int, int]] = set()
    for h in _find_holes(V, F):
        old_edges.update(zip(h.vertices.tolist(), np.roll(h.vertices, -1).tolist(), strict=True))
    skip: dict[int, str] = {}
    for h in found:
        lp = kept[h.vertices]
        if set(zip(lp.tolist(), np.roll(lp, -1).tolist(), strict=True)) <= old_edges:
            skip[h.index] = "hole of the input, not part of the region (use fill_holes for it)"
    # a loop through a vertex of the input's boundary: the region merged with an open border
    # (or a hole) of the input; filling it would close what the user did not mark
    border_v = np.flatnonzero(on_border[kept])
    touch = np.zeros(len(V2), bool)
    touch[border_v] = True
    touched: list[int] = []
    for h in found:
        if h.index not in skip and touch[h.vertices].any():
            n_old = int(touch[h.vertices].sum())
            skip[h.index] = (f"the region reaches an open border (or a hole) of the input: this "
                             f"loop runs along {n_old} of its boundary vertices, and filling it "
                             "would close that border too; left open. Use keep_border=True "
                             "(CLI --keep-border) to fill the region and keep the border open, "
                             "or a region away from the border")
            touched.append(h.index)
    # removal that cuts a component into several large parts: refuse the loops of those parts
    from meshrepair.mesh.topology import connected_components

    lab0 = connected_components(F, nV)[1]
    lab2 = connected_components(F2, len(V2))[1]
    part_orig: dict[int, set[int]] = {}
    for p, o in zip(lab2[F2[:, 0]].tolist(), lab0[kept[F2[:, 0]]].tolist(), strict=True):
        part_orig.setdefault(o, set()).add(p)
    cut_parts = {p for parts in part_orig.values() if len(parts) > 1 for p in parts}
    for h in found:
        if h.index not in skip and int(lab2[h.vertices[0]]) in cut_parts:
            n_parts = max(len(v) for v in part_orig.values())
            skip[h.index] = (f"the region cuts the mesh into {n_parts} parts; filling each cut "
                             "separately would cap the parts instead of rejoining them: use a "
                             "region that does not go all the way round")
    check_budget([h for h in found if h.index not in skip], edge_length, what="inpaint")
    res = _fill_core(V2, F2, found, skip, **opts)
    res.vertex_map = vmap
    res.removed_faces = np.flatnonzero(removed).astype(np.int64)
    res.params.update(region_vertices=int(vmask.sum()), removal_notes=notes,
                      keep_border=bool(keep_border),
                      border="kept: faces along the open border not removed" if (
                          protect is not None and protect.any()) else
                      "refused: the region reaches an open border" if touched else
                      "the region does not reach an open border")
    if protect is not None and protect.any():
        for h in res.holes:
            if h.status == "filled":
                h.add_note("the region reached an open border of the input: the faces along "
                           "the border were kept and the border left open (keep_border)")
    res.holes = [h for h in res.holes if not h.reason.startswith("hole of the input")]
    return res
