"""Placing a template patch over a hole from the intact surface only (completion, Sect. 5).

The paper assumes the template ``P`` is already placed over the hole bounded by ``b0``. This
module finds the placement ``T`` (rigid, or a similarity with ``allow_scale``) from what is
*known to be right*: the hole's boundary ``b0`` and the rings of remaining surface around it,
never the faces ``T̄`` being replaced (a user completes a region because it is damaged):

1. **Coarse.** Both loops resampled to ``m`` points by arc length; the best cyclic shift,
   direction and closed-form fit over all shifts at once
   (:func:`~meshrepair.complete.correspondence.best_cyclic_alignment`).
2. **Boundary.** ICP of ``b_P`` against the polyline ``b0``
   (:func:`~meshrepair.complete.icp.icp_loop_to_polyline`), then Umeyama refits on matched boundary
   vertices (:func:`~meshrepair.complete.loopmatch.monotone_loop_match`) while they lower the RMS.
3. **Context** (``icp="context"``, the default, when the template is a piece of a mesh).
   Trimmed point-to-plane ICP (:func:`~meshrepair.complete.icp.icp_to_surface`) of the template's
   boundary and of its own context rings (the source mesh's vertices within ``icp_rings``
   rings outside the template) against the remaining faces within ``icp_rings + 1`` rings of
   ``b0``: both sides' intact surroundings are matched, the region's faces are not used.

``icp="surface"`` (opt-in, for an undamaged region) instead fits the template's vertices within
``icp_rings`` rings of ``b_P`` to the context *plus the region's faces*; ``"boundary"`` stops
after step 2; ``"none"`` after step 1.

The alignment report (:func:`alignment_report`) gives, in mean edge lengths ``l`` of the mesh,
the residual on the boundary (closest-point distances between the placed ``b_P`` and ``b0``,
both ways) and on the context rings (distances of the placed template context to the mesh's
context faces).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from meshrepair.complete.correspondence import (
    CyclicAlignment,
    arc_length_parameters,
    best_cyclic_alignment,
    resample_polyline,
)
from meshrepair.complete.icp import (
    closest_points_on_loop,
    closest_points_on_mesh,
    icp_loop_to_polyline,
    icp_to_surface,
)
from meshrepair.complete.loopmatch import monotone_loop_match
from meshrepair.complete.modes import ICP_MODES  # the CLI reads it there
from meshrepair.complete.rigid import apply_transform, umeyama
from meshrepair.complete.stitch import _rings
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import edge_topology

log = logging.getLogger(__name__)

__all__ = ["ICP_MODES", "Placement", "alignment_report", "place_template"]

#: boundary or context RMS residual (mean edge lengths) above which a warning is logged
WARN_RESIDUAL = 0.5


@dataclass
class Placement:
    """Result of :func:`place_template`.

    Attributes
    ----------
    T : (4, 4) float64, the transform applied to the template
    cyclic : CyclicAlignment, the coarse correspondence (``reversed``: the template loop runs
        against its own orientation, the orientation-consistent case)
    rms_other_direction : float, the coarse RMS of the other direction
    rms_before : float, RMS boundary distance of the template as given (resampled loops)
    fit : ``"rigid"``, ``"similarity"`` or ``"user"``
    size_ratio : float, template / hole loop length
    icp : dict or None, what the refinement did (target, RMS before and after)
    context_target : (k, 3) int64, the mesh's context faces used (or empty)
    """

    T: np.ndarray
    cyclic: CyclicAlignment
    rms_other_direction: float
    rms_before: float
    fit: str
    size_ratio: float
    icp: dict | None
    context_target: np.ndarray


def _context_faces(F: np.ndarray, nV: int, b0: np.ndarray, region_faces: np.ndarray,
                   rings: int) -> np.ndarray:
    """Remaining faces with a vertex within ``rings`` edge rings of ``b0`` (never the region)."""
    d = _rings(edge_topology(F, nV), b0, rings)
    sel = d[F].min(axis=1) <= rings
    sel[region_faces] = False
    return F[sel]


def place_template(V: np.ndarray, F: np.ndarray, b0: np.ndarray, region_faces: np.ndarray,
                   VP: np.ndarray, FP: np.ndarray, bP: np.ndarray, *,
                   context: np.ndarray | None = None, transform: np.ndarray | None = None,
                   allow_scale: bool = False, max_size_ratio: float = 5.0,
                   orientation: str = "template", icp: str = "context",
                   icp_rings: int = 2) -> Placement:
    """Find the placement of the template ``(VP, FP)`` (loop ``bP``) over the hole ``b0``.

    Parameters
    ----------
    V, F : the mesh (with the region still in it, if any)
    b0 : (n,) int64, the hole's loop, following the remaining faces' orientation
    region_faces : (k,) int64, the faces being replaced (never used by ``"context"``)
    VP, FP, bP : the template and its boundary loop
    context : (c, 3) float, optional, the template's own context rings (see
        :func:`meshrepair.complete.inputs._template_context`)
    transform : (4, 4), optional, a user placement (no automatic alignment)
    icp : one of ``"context"``, ``"boundary"``, ``"surface"``, ``"none"`` (``"auto"`` resolved)

    Returns
    -------
    Placement
    """
    A = V[b0]
    B_raw = VP[bP]
    B = B_raw if transform is None else apply_transform(transform, B_raw)
    L0 = arc_length_parameters(A)[1]
    LP = arc_length_parameters(B)[1]
    ratio = LP / L0
    if not allow_scale and not (1.0 / max_size_ratio <= ratio <= max_size_ratio):
        raise MeshRepairError(
            f"the template's boundary is {ratio:.3g} times as long as the hole's ({LP:.4g} vs "
            f"{L0:.4g}), beyond the allowed factor {max_size_ratio:g}: use a template of the "
            "hole's size, pass allow_scale=True to fit a uniform scale, or give a transform")
    if not allow_scale and transform is None and not (2 / 3 <= ratio <= 1.5):
        log.warning("the template's boundary is %.3g times as long as the hole's and the "
                    "alignment is rigid; pass allow_scale=True to fit a uniform scale", ratio)

    # ---- 1. coarse cyclic correspondence ------------------------------------------------------
    nA, nB = len(A), len(B)
    m = int(np.clip(max(nA, nB), 32, 1024))
    Ar = resample_polyline(A, m)
    Br = resample_polyline(B, m)
    fit = "none" if transform is not None else ("similarity" if allow_scale else "rigid")
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
    log.info("completion: hole loop %d vertices, template loop %d, %s fit, coarse RMS %.3g "
             "(other direction %.3g)", nA, nB, fit, ca.rms, other)
    empty = np.zeros((0, 3), np.int64)
    if transform is not None:
        return Placement(T=np.asarray(transform, np.float64), cyclic=ca,
                         rms_other_direction=float(other), rms_before=rms_before, fit="user",
                         size_ratio=float(ratio), icp=None, context_target=empty)
    T = ca.transform
    if icp == "none":
        return Placement(T=T, cyclic=ca, rms_other_direction=float(other),
                         rms_before=rms_before, fit=fit, size_ratio=float(ratio), icp=None,
                         context_target=empty)

    # ---- 2. boundary ICP, then refits on matched boundary vertices ------------------------------
    dT, r0, r1 = icp_loop_to_polyline(apply_transform(T, Br), A, scale=allow_scale)
    info: dict = {"target": "boundary", "rms_before": r0, "rms_after": r1}
    T = dT @ T
    bseq = bP[::-1] if ca.reversed else bP

    def pair_match(T_: np.ndarray):
        Bt = apply_transform(T_, VP[bseq])
        if nA <= nB:
            jj, r = monotone_loop_match(A, Bt)
            return r, VP[bseq][jj], A
        jj, r = monotone_loop_match(Bt, A)
        return r, VP[bseq], A[jj]

    pair_rms, src, dst = pair_match(T)
    for _ in range(3):
        T2 = umeyama(src, dst, scale=allow_scale)
        r2, s2, d2 = pair_match(T2)
        if not r2 < pair_rms * (1 - 1e-6):
            break
        T, pair_rms, src, dst = T2, r2, s2, d2

    # ---- 3. context rings (or, opted in, the region's own faces) ------------------------------
    target = _context_faces(F, len(V), b0, region_faces, icp_rings + 1)
    if icp == "context" and context is not None and len(context) and len(target):
        P = np.vstack([VP[bP], context])
        dT, r0, r1 = icp_to_surface(apply_transform(T, P), V, target, scale=allow_scale)
        info = {"target": "context", "boundary": info, "rms_before": r0, "rms_after": r1,
                "points": int(len(P)), "target_faces": int(len(target))}
        T = dT @ T
    elif icp == "surface":
        ring = _rings(edge_topology(FP, len(VP)), bP, icp_rings) <= icp_rings
        d_in = _rings(edge_topology(F, len(V)), b0, 3)
        tsel = d_in[F].min(axis=1) <= 3
        tsel[region_faces] = True
        dT, r0, r1 = icp_to_surface(apply_transform(T, VP[ring]), V, F[tsel], scale=allow_scale)
        info = {"target": "surface", "boundary": info, "rms_before": r0, "rms_after": r1,
                "points": int(ring.sum()), "target_faces": int(tsel.sum())}
        T = dT @ T
    return Placement(T=T, cyclic=ca, rms_other_direction=float(other), rms_before=rms_before,
                     fit=fit, size_ratio=float(ratio), icp=info, context_target=target)


def alignment_report(V: np.ndarray, F: np.ndarray, b0: np.ndarray, VP: np.ndarray,
                     bP: np.ndarray, T: np.ndarray, *, context: np.ndarray | None,
                     target: np.ndarray, unit: float) -> dict:
    """Residuals of a placement on the boundary and on the context rings, in units of ``unit``.

    Parameters
    ----------
    V, F : the mesh; b0 : its hole loop
    VP, bP : the template (before ``T``) and its loop
    T : (4, 4), the placement
    context : (c, 3) or None, the template's context rings (before ``T``)
    target : (k, 3) int, the mesh's context faces
    unit : float > 0, the mean edge length of the mesh

    Returns
    -------
    dict
        ``boundary_rms``, ``boundary_max`` (closest-point distances between the placed ``b_P``
        and the polyline ``b0``, both ways), ``context_rms``, ``context_max`` (placed template
        context to the mesh's context faces; None without a template context),
        ``context_points``, ``unit`` (the mean edge length), ``warning`` (bool).
    """
    A = V[b0]
    B = apply_transform(T, VP[bP])
    _, d1 = closest_points_on_loop(B, A)
    _, d2 = closest_points_on_loop(A, B)
    d = np.r_[d1, d2] / unit
    rep = {"boundary_rms": float(np.sqrt(np.mean(d ** 2))), "boundary_max": float(d.max()),
           "context_rms": None, "context_max": None, "context_points": 0, "unit": float(unit)}
    if context is not None and len(context) and len(target):
        _, dc, _ = closest_points_on_mesh(apply_transform(T, context), V, target)
        dc = dc / unit
        rep.update(context_rms=float(np.sqrt(np.mean(dc ** 2))), context_max=float(dc.max()),
                   context_points=int(len(dc)))
    big = rep["boundary_rms"] > WARN_RESIDUAL or (rep["context_rms"] or 0.0) > WARN_RESIDUAL
    rep["warning"] = bool(big)
    if big:
        ctx = ("n/a" if rep["context_rms"] is None else f"{rep['context_rms']:.3g}")
        log.warning("the template does not fit the hole's surroundings: alignment residual "
                    "%.3g mean edge lengths on the boundary, %s on the context rings (warning "
                    "above %g); check the template, its size (allow_scale) or give a transform",
                    rep["boundary_rms"], ctx, WARN_RESIDUAL)
    return rep
