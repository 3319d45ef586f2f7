"""The fill task: :func:`fill_holes` (steps 1-4 of :mod:`meshrepair.fill`)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence

from meshrepair.errors import MeshRepairError
from meshrepair.fill.core import _fill_core
from meshrepair.fill.options import _check_options, _solve_options
from meshrepair.fill.result import FillResult
from meshrepair.holes import select_holes
from meshrepair.holes.budget import check_budget

log = logging.getLogger("meshrepair.fill")


def fill_holes(
    V,
    F=None,
    *,
    max_hole_size: int | None = None,
    keep_border: bool = False,
    exclude: Sequence[int] = (),
    holes: Sequence[int] | None = None,
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
    """Fill the holes of a triangle mesh smoothly, optionally denoising it in the same solve.

    Parameters
    ----------
    V : (nV, 3) float array, or a ``trimesh.Trimesh`` (then ``F`` is omitted)
    F : (nF, 3) int array
    max_hole_size : int, optional
        Fill only holes with at most this many boundary vertices (= edges).
    keep_border : bool
        Leave the longest loop open (the intended border of a scan or of a model cut open).
        Independently of it, a loop recognised as the open border of its surface by its size
        (:func:`meshrepair.holes.border.find_borders`) is left open with the reason, unless it
        is listed in ``holes``.
    exclude : sequence of int
        Hole indices (see :func:`meshrepair.holes.find_holes`: longest first) to leave open.
    holes : sequence of int, optional
        Fill only these holes.
    denoise : bool
        Also denoise the rest of the mesh in the same ADMM solve (``M_V = 1`` outside the holes,
        λ from the estimated noise unless ``lam`` is given); otherwise the original vertices do not
        move.
    initial : ``"bilaplacian"`` or ``"harmonic"``
        Initial position of the new vertices: thin-plate fairing with the surrounding ring as
        boundary condition (curved), or the membrane of the enclosing step (flat).
    refine : bool
        Run the ADMM solve (always done when ``denoise=True``).
    edge_length : float, optional
        Target edge length in the patches (default: each loop's mean edge length).
    lam : float, optional
        Fidelity weight λ (``denoise=True`` only).
    th : float
        Dihedral threshold (degrees) of the sharp-edge mask outside the patches.
    a : float
        MC non-convexity of the feature stage (``denoise=True``) / scale of β1 (fill only).
    max_iter : int
        ADMM iterations of the fill-only solve.
    tol : float
        Stopping tolerance (rule (35)).
    rings : int
        Rings of fixed faces around the patches included in the fill-only solve.
    relax : float
        Tangential relaxation weight per fill-only ADMM iteration (0 disables).
    inner_solver, inner_iters : V-subproblem solver and its iterations per ADMM iteration.
    check : bool
        Refuse patches that would intersect or lie on the surface, and count intersections of the
        final patches (``HoleReport.n_intersections``). A patch that intersects is tried
        faired, then unfaired, then with the next enclosing method of
        :data:`meshrepair.fill.options.ENCLOSE_ORDER`
        (``HoleReport.reason`` says which was kept: e.g. ``"plane"``, ``"plane, membrane"``,
        ``"liepa"``, ``"liepa, unfaired"``) before the hole is refused.
    callback : called with each ADMM history entry.
    progress : called as ``progress(done, total)`` before each selected hole is enclosed (the
        CLI feeds a progress bar over holes with it).
    creases : bool
        Continue the sharp creases (dihedral angle above ``th``) that end on a hole's loop
        through the patch: paired across the hole or meeting at a corner, routed as
        constrained edges, placed on their curves and kept sharp by the MC penalty
        (:mod:`meshrepair.holes.creases`; ``HoleReport.n_creases``).
    curvature : bool
        With ``initial="bilaplacian"``: curvature continuity (the patch's Laplacian fitted to
        the surround's mean curvature interpolated over it, :func:`meshrepair.holes.fair_vertices`
        ``curvature=True``); False gives the plain thin plate.
    triharmonic : bool
        With ``initial="bilaplacian"``: also compute the triharmonic (curvature-continuous)
        fairing with two rings of the surround as data
        (:func:`meshrepair.holes.triharmonic.fair_triharmonic`) and keep it for each hole whose
        seam angle it lowers (``", triharmonic"`` in the hole's reason).
    fitted : bool
        With ``initial="bilaplacian"``: for each hole without crease routes, also fair the
        patch relative to a local surface fitted to its surround
        (:mod:`meshrepair.holes.fitted`) and keep it where it predicts a probe band of the
        surround better than the fairing kept for it (``", fitted dD kK"`` in the hole's
        reason). Off by default: not better on the design meshes (docs/holes.md, section 5).

    Returns
    -------
    FillResult
        Original vertices and faces first in their original order, the new ones after. The input
        arrays are never modified. The patches do not depend on the mesh's vertex or face order,
        rotation, scale or translation (the same new vertices and faces, positions up to the
        rounding the solve carries; docs/holes.md, section 3).

    Raises
    ------
    MeshRepairError
        For invalid meshes (:func:`meshrepair.mesh.validate.check_mesh`) or options (e.g. a hole
        index that does not exist, a non-finite or out-of-range number), or when the selected holes
        would need more than :data:`meshrepair.holes.budget.MAX_NEW_FACES` new faces (estimated
        before any work; the message gives the count).
    """
    opts = _solve_options(locals())
    from meshrepair.holes import _find_holes
    from meshrepair.holes.border import ENCLOSED, UNCERTAIN, classify_loops
    from meshrepair.mesh.array_contract import as_arrays
    from meshrepair.mesh.validate import check_mesh

    V, F = as_arrays(V, F)
    check_mesh(V, F, name="input mesh")
    opts = _check_options(opts)
    from meshrepair.options import check_bool

    check_bool("keep_border", keep_border)
    holes, exclude = _index_list("holes", holes), _index_list("exclude", exclude) or []
    both = sorted(set(holes or ()) & set(exclude))
    if both:
        raise MeshRepairError(f"hole {both[0]} is both selected (holes=, --holes) and excluded "
                              "(exclude=, --exclude): name it in one of them")
    if keep_border and holes is not None and 0 in holes:
        raise MeshRepairError("hole 0 is the longest loop, which keep_border (--keep-border) "
                              "keeps open as the mesh border: drop keep_border to fill it")
    found = _find_holes(V, F)
    borders, enclosure, notes = classify_loops(V, F, found)
    skip = select_holes(found, max_hole_size=max_hole_size, keep_border=keep_border,
                        exclude=exclude, indices=holes, borders=borders)
    # loops the rest of the surface encloses, and loops the caller asked for, are never refused
    known = {i for i, w in enclosure.items() if w >= ENCLOSED}
    if holes is not None:
        known |= {int(i) for i in holes}
    check_budget([h for h in found if h.index not in skip], edge_length, what="fill_holes")
    log.info("fill_holes: %d holes found, %d selected%s", len(found), len(found) - len(skip),
             f" ({len(borders)} open border(s) left open)" if borders else "")
    # uncertain: partly enclosed, not a border by size; an intersecting patch is kept and said
    uncertain = {i for i, w in enclosure.items()
                 if UNCERTAIN <= w < ENCLOSED and i not in borders and i not in known}
    for i in uncertain - set(notes):
        notes[i] = (f"uncertain: the rest of the surface encloses it only partly (winding "
                    f"{enclosure[i]:.2f}; holes of closed bodies >= {ENCLOSED:g}): filled; "
                    f"check it, or keep it open with exclude=[{i}] (CLI --exclude {i})")
    res = _fill_core(V, F, found, skip, **opts, known_holes=known, kept_holes=uncertain,
                     notes=notes)
    if check and not denoise:
        # a loop whose patch intersects the surface may be two loops touching at a narrow place
        from meshrepair.fill.split import retry_split

        res = retry_split(V, F, found, skip, res, opts, known, uncertain, notes)
    res.params.update(enclosure={int(i): round(w, 4) for i, w in enclosure.items()})
    res.params.update(max_hole_size=max_hole_size, keep_border=keep_border,
                      exclude=exclude, holes=holes)
    return res


def _index_list(name: str, value) -> list | None:
    """Hole indices as a list (one index as a list of one; None stays None), checked for their
    values by :func:`meshrepair.holes.select_holes`; MeshRepairError for what is not a
    sequence."""
    from meshrepair.options import is_whole

    if value is None:
        return None
    if is_whole(value):
        return [int(value)]
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise MeshRepairError(f"{name} must be hole indices (a list of int) or None, got "
                              f"{value!r}")
    return list(value)
