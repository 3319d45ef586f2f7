"""Smooth hole filling and inpainting of damaged regions (Sect. 5 of the paper), optionally with
denoising in the same solve.

Pipeline of :func:`fill_holes`:

1. *Detection and selection* (:mod:`meshrepair.holes`): boundary loops split into simple loops,
   the intended border kept (``keep_border``), ``exclude`` / ``holes`` / ``max_hole_size``.
2. *Trivial enclosing*: each selected loop gets a triangulated patch whose boundary is exactly the
   loop, with interior edges matching the loop's edge length and a membrane initial position
   (:func:`meshrepair.holes.enclose_holes`). The new vertices form the region ``S_D``. A hole
   whose patch intersects the surface (faired and membrane) is enclosed again with the next
   method of :data:`meshrepair.fill.options.ENCLOSE_ORDER` (Liepa's minimum-weight triangulation,
   faired, then on its
   own surface) before it is refused.
3. *Initial position* (``initial``): ``"bilaplacian"`` (default) moves the new vertices to the
   bi-Laplacian (thin-plate) fairing with the surrounding 1-ring as Dirichlet data, which continues
   the surrounding curvature into the hole; ``"harmonic"`` keeps the flat membrane. With
   ``triharmonic=True`` (default) the screened triharmonic fairing (two rings of the surround as
   data, curvature continuity; :mod:`meshrepair.holes.triharmonic`) is computed too and kept for
   each hole whose seam angle it lowers. With ``fitted=True`` (off by default) each hole without
   crease routes is also faired relative to a local surface fitted to its surround
   (:mod:`meshrepair.holes.fitted`), kept where it predicts a probe band of the surround better.
4. *Repair solve* with the shared :class:`~meshrepair.model.solver.ADMMSolver`: ``M_V = 0`` on the
new
   vertices, ``M_E`` forced to 0 (edge-Willmore) on every edge of a new face (the patch interior
   and the loop itself, so the patch joins its surround smoothly), the dihedral-threshold mask
   elsewhere.

   * ``denoise=False`` (fill only): all original vertices are ``fixed``; only the patch moves.
     The solve runs on the patches plus ``rings`` rings of surrounding faces (faces further away
     cannot influence the patch: their vertices are fixed) with one stage whose mask is
     ``"none"``: every free edge is edge-Willmore, which is what the paper prescribes inside
     ``S_D``; fixed faces far from the patch contribute constants only.
   * ``denoise=True`` (fill + denoise): the whole mesh is solved with the denoising schedule of
     :func:`meshrepair.denoise.api.default_stages` and λ from the estimated noise
     (:func:`meshrepair.denoise.api.lambda_from_noise`); ``M_V = 1`` outside the patches.

:func:`inpaint` first removes a damaged region (its faces), then fills the holes that this opens.
"""

from __future__ import annotations

# the package is split by concept: result (FillResult), options (shared options and their
# checks), patches (patch bookkeeping and measurements), place (enclosing, initial position,
# intersection and seam retries), core (the repair solve shared by both tasks), filling
# (fill_holes), region (the damaged region of inpaint), inpainting (inpaint)
from meshrepair.fill.core import _fill_core  # noqa: F401
from meshrepair.fill.filling import fill_holes
from meshrepair.fill.inpainting import inpaint
from meshrepair.fill.options import INITIAL_MODES, SOLVE_OPTIONS, _check_options  # noqa: F401
from meshrepair.fill.patches import (  # noqa: F401
    _blocks,
    _crease_edges,
    _drop_patches,
    _edge_ids,
    _finite_rows,
    _intersecting,
    _ring_faces,
    _seam_angle,
    _sharp_vertices,
)
from meshrepair.fill.place import (  # noqa: F401
    _METHOD_NAMES,
    BLEND_STEPS,
    SEAM_RETRY_FACTOR,
    SEAM_RETRY_MARGIN,
    _enclose_methods,
    _place_patches,
)
from meshrepair.fill.region import _pinched, _remove_region, region_mask  # noqa: F401
from meshrepair.fill.result import FillResult

__all__ = ["FillResult", "fill_holes", "inpaint", "region_mask"]

