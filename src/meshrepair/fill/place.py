"""Placement of the patches before the repair solve (steps 2-3 of :mod:`meshrepair.fill`):
enclosing, the initial position (thin plate, triharmonic candidate), and the intersection and
seam checks that retry a hole with a blend of the fairing, its unfaired surface or the next
enclosing method of :data:`meshrepair.fill.options.ENCLOSE_ORDER`, or refuse it."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np

from meshrepair.fill.patches import (
    _blocks,
    _crease_edges,
    _drop_patches,
    _finite_rows,
    _intersecting,
    _seam_angle,
    _sharp_vertices,
)
from meshrepair.holes import (
    LIEPA_MAX_LOOP,
    HoleReport,
    enclose_holes,
    fair_vertices,
    self_intersections,
)
from meshrepair.holes.creases import find_crease_routes
from meshrepair.holes.fairing import LIEPA_COT_RANGE
from meshrepair.holes.triharmonic import fair_triharmonic

log = logging.getLogger("meshrepair.fill")

_METHOD_NAMES = {"auto": "planar projection", "liepa": "minimum-weight triangulation"}


def _enclose_methods(hole) -> list[str]:
    """Enclosing methods to try on ``hole``, in order (``"liepa"`` only up to
    :data:`meshrepair.holes.LIEPA_MAX_LOOP` boundary vertices)."""
    from meshrepair.fill.options import ENCLOSE_ORDER  # read on each call: a caller may set it

    out = [m for m in ENCLOSE_ORDER if m != "liepa" or hole.n_boundary <= LIEPA_MAX_LOOP]
    return out or ["auto"]

CREASE_TRIAL = True
"""A hole whose crease routes include a loosely inferred one (:func:`_loose`) and whose patch
does not intersect the surface is also faired without them, and the patch with the smaller seam
angle (mean dihedral across the loop edges) is kept: a wrong pairing or corner of the crease
ends bends the patch away from its surround's tangent planes, which the seam shows. Routes
inferred tightly (pairs along their chord, corners of at most three arms) are kept as they are:
on small holes the seam of the faired patch does not tell them from the smooth patch."""

CONFORMING_RETRY = True
"""A Liepa patch (folds of its coarse triangulation divided into pieces of the edge length)
whose faired position intersects the surface is meshed again with its folds split by Triangle
for its angle bound (``enclose_loop(conforming=True)``) before any of the fairing is given up:
much finer along the folds, its thin plate bends less away from the coarse surface, which
follows the surround (docs/holes.md section 3)."""

CORNER_MAX_ARMS = 3
"""A corner with more arms than this is a loose inference (the arms beyond the two meeting
exactly only point at the corner within 45°)."""


def _loose(route, k: int) -> bool:
    """True when a crease route of a ``k``-vertex loop has a kinked pair (ends within 60° of
    their chord) or a corner point (numbered ``k, k + 1, ...``) with more than
    :data:`CORNER_MAX_ARMS` arms."""
    if "kinked" in route.kinds:
        return True
    seg = np.asarray(route.segments).reshape(-1, 2)
    if len(route.points) == 0 or len(seg) == 0:
        return False
    arms = np.bincount(seg[seg >= k] - k, minlength=len(route.points))
    return bool((arms > CORNER_MAX_ARMS).any())

BLEND_STEPS = (0.5, 0.25)
"""When the faired patch intersects the surround, these fractions of the fairing (from the
initial surface) are tried before the initial surface itself."""

SEAM_RETRY_FACTOR = 1.5
SEAM_RETRY_MARGIN = 3.0
"""A planar patch whose mean dihedral angle across its loop exceeds
``SEAM_RETRY_FACTOR * surround + SEAM_RETRY_MARGIN`` degrees (surround: the original edges within
3 rings) is enclosed again by Liepa's triangulation and the smoother seam kept. On the peers
benchmark (docs/holes.md) the seams the rule catches read 2-3× their surround (14-25° against
5-8°) and Liepa's enclosure brings them to 6-9°; seams below the rule are left as they
are."""


def _place_patches(V: np.ndarray, F: np.ndarray, holes, skip: dict[int, str], *, initial: str,
                   edge_length: float | None, th: float, check: bool,
                   progress: Callable[[int, int], None] | None, creases: bool, curvature: bool,
                   triharmonic: bool, fitted: bool = False,
                   known_holes: set[int] | frozenset[int] = frozenset(),
                   kept_holes: set[int] | frozenset[int] = frozenset()
                   ) -> tuple[np.ndarray, np.ndarray, list[HoleReport], float, float]:
    """Enclose the selected holes and place their patches; returns ``(V1, F1, reports,
    t_enclose, t_initial)`` with the refused patches already removed (their reports say why).

    ``known_holes``: loops known to be holes (the rest of the surface encloses them, or the
    caller selected them): never refused; a patch lying on the surface, or still intersecting
    it after every enclosing method, is kept, with a note in its report. ``kept_holes``: more
    loops whose patch is kept with a note when it intersects or lies on the surface (the
    uncertain ones: filled, and the report says what to check)."""
    nV, nF = len(V), len(F)
    by_index = {h.index: h for h in holes}
    stage: dict[int, int] = {}  # hole index -> position in its list of enclosing methods
    t_enclose = t_initial = 0.0
    first = True
    seam_prev: dict[int, float] = {}  # hole -> seam angle of its planar patch (seam trial)
    locked: set[int] = set()
    revert: list[int] = []
    unpair: set[int] = set()  # loops whose annulus intersected: enclosed without their island
    # a kept patch that intersects with every method: the variant with the fewest face pairs
    fewest: dict[int, tuple[int, int, float]] = {}  # hole -> (pairs, stage, fraction faired)
    final: dict[int, float] = {}  # hole -> fraction of the fairing to apply, no more trials
    goto: dict[int, int] = {}  # hole -> stage to enclose it with on the next pass
    # crease trial: a hole with crease routes is faired again without them, and the patch
    # meeting its surround more smoothly is kept (CREASE_TRIAL)
    routed_seam: dict[int, float] = {}  # hole -> seam angle of its patch with crease routes
    no_routes: set[int] = set()  # holes enclosed without their crease routes
    route_done: set[int] = set()  # holes whose crease trial is decided
    route_stage: dict[int, int] = {}  # hole -> its enclosing stage with the routes
    conforming: set[int] = set()  # holes whose Liepa patch is meshed conforming to its folds

    def _seen(i: int, n_x: int, frac: float) -> None:
        st = stage.get(i, 0)
        if i not in fewest or n_x < fewest[i][0]:
            fewest[i] = (n_x, st, frac)

    while True:
        ta = time.perf_counter()
        method = {h.index: _enclose_methods(h)[stage.get(h.index, 0)] for h in holes}
        if first:
            routes = find_crease_routes(V, F, holes, skip, th) if creases else {}
            sharp_v = np.flatnonzero(_sharp_vertices(V, F, th, nV))
        V1, F1, reports = enclose_holes(
            V, F, holes, skip, edge_length=edge_length, check=check, intersections=False,
            method=method, creases={i: r for i, r in routes.items() if i not in no_routes},
            known_holes=set(known_holes) | set(kept_holes),
            unpair=set(unpair), conforming=set(conforming),
            progress=None if progress is None or not first else progress)
        first = False
        tb = time.perf_counter()
        Vm = V1
        if initial == "bilaplacian" and len(V1) > nV:
            ce = _crease_edges(reports)
            on_crease = np.unique(ce)
            free = np.setdiff1d(np.arange(nV, len(V1)), on_crease)
            # Liepa's patches: bounded cotangents in the faces round them (anisotropic
            # triangles, docs/holes.md section 5); planar patches keep the exact ones
            liepa_f = np.zeros(len(F1), bool)
            for i, (_, bf) in _blocks(reports, nV, nF).items():
                if method[i] == "liepa":
                    liepa_f[bf] = True
            near = np.zeros(len(V1), bool)
            near[F1[liepa_f].ravel()] = True
            V1 = fair_vertices(V1, F1, free, order=2, weights="cotan", iterations=3,
                               exclude_rows=on_crease, curvature=curvature,
                               curvature_exclude=sharp_v,
                               cot_range=LIEPA_COT_RANGE if liepa_f.any() else None,
                               cot_faces=near[F1].any(axis=1))
            if triharmonic:
                # curvature-continuous (triharmonic) candidate, two rings of the surround as
                # data; kept per hole where it meets the surround more smoothly (docs/holes.md
                # section 5)
                Vt = fair_triharmonic(V1, F1, free, iterations=3,
                                      exclude_rows=np.union1d(on_crease, sharp_v))
                Vt = _finite_rows(Vt, V1, np.arange(nV, len(V1)), "the triharmonic fairing")
                V1 = V1.copy()
                by_rep = {r.index: r for r in reports}
                for i, (bv, bf) in _blocks(reports, nV, nF).items():
                    s_thin = _seam_angle(V1, F1, bf, nF)
                    s_tri = _seam_angle(Vt, F1, bf, nF)
                    if s_tri < s_thin:
                        V1[bv] = Vt[bv]
                        by_rep[i].reason += ", triharmonic"
                        log.info("hole %d: triharmonic fairing kept (seam %.2f° vs thin plate "
                                 "%.2f°)", i, s_tri, s_thin)
            V1 = _finite_rows(V1, Vm, np.arange(nV, len(V1)), "the thin-plate fairing")
            if fitted:
                from meshrepair.fill.fitted import _fitted_candidates

                V1 = _fitted_candidates(V, F, V1, Vm, F1, reports, method, on_crease, sharp_v,
                                        curvature, nV, nF)
        drop: dict[int, str] = {}
        retry: list[int] = []
        again = False
        if check:
            dropped = np.zeros(len(F1), bool)  # faces of patches already refused
            blocks = _blocks(reports, nV, nF)
            all_new = np.arange(nF, len(F1))
            pairs0 = self_intersections(V1, F1, all_new) if len(all_new) else None
            by_rep = {r.index: r for r in reports}
            for i, (bv, bf) in blocks.items():
                rep = by_rep[i]
                if i in final:
                    V1 = V1.copy()
                    V1[bv] = Vm[bv] + final[i] * (V1[bv] - Vm[bv])
                    n_x = _intersecting(V1, F1, bf, dropped)
                    unf = "unfaired" if method[i] == "liepa" else "membrane"
                    rep.reason += ("" if final[i] == 1.0 else f", {final[i]:g} faired"
                                   if final[i] > 0 else f", {unf}")
                    note = (f"the patch intersects the surface ({n_x} face pairs, the fewest of "
                            f"every enclosing method and fairing fraction tried); kept, not "
                            "refused (a hole of a closed surface, a selected or an uncertain "
                            "loop): check it")
                    rep.add_note(note)
                    log.warning("hole %d: %s", i, note)
                    continue
                n_x = _intersecting(V1, F1, bf, dropped, pairs=pairs0)
                if n_x and i in no_routes and i not in route_done:
                    # the patch without crease routes intersects: back to the routed one
                    route_done.add(i)
                    no_routes.discard(i)
                    goto[i] = route_stage[i]
                    again = True
                    continue
                if n_x and CONFORMING_RETRY and method[i] == "liepa" and i not in conforming \
                        and rep.n_folds > 0 and initial == "bilaplacian":
                    # the faired Liepa patch intersects: meshed again with its folds split for
                    # the angle bound (finer along them, the fairing bends less away from the
                    # coarse surface) before any of the fairing is given up; a patch that kept
                    # no folds (the mean-value layout) would come out the same
                    log.debug("hole %d (liepa): faired patch, %d face pairs; meshing it again "
                              "conforming to its folds", i, n_x)
                    conforming.add(i)
                    again = True
                    continue
                _seen(i, n_x, 1.0)
                if n_x and initial == "bilaplacian":
                    # keep as much of the fairing as stays clear of the surround: the patch
                    # moved back towards its initial surface by halves, then the initial one
                    unfaired = "unfaired" if method[i] == "liepa" else "membrane"
                    Vf = V1[bv].copy()
                    V1 = V1.copy()
                    log.debug("hole %d (%s): faired patch, %d face pairs", i, method[i], n_x)
                    for frac in BLEND_STEPS:
                        V1[bv] = Vm[bv] + frac * (Vf - Vm[bv])
                        n_x = _intersecting(V1, F1, bf, dropped)
                        _seen(i, n_x, frac)
                        log.debug("hole %d (%s): %g faired, %d face pairs", i, method[i], frac,
                                  n_x)
                        if not n_x:
                            log.info("hole %d: the faired patch intersects the mesh; kept %g of "
                                     "the fairing", i, frac)
                            rep.reason += f", {frac:g} faired"
                            break
                    if n_x:
                        log.info("hole %d: the faired patch intersects the mesh; using the %s",
                                 i, "unfaired surface" if unfaired == "unfaired" else "membrane")
                        V1[bv] = Vm[bv]
                        n_x = _intersecting(V1, F1, bf, dropped)
                        _seen(i, n_x, 0.0)
                        log.debug("hole %d (%s): %s, %d face pairs", i, method[i], unfaired, n_x)
                        if not n_x:
                            rep.reason += f", {unfaired}"
                if not n_x and CREASE_TRIAL and i not in route_done and (
                        i in no_routes or (rep.n_creases > 0 and i not in locked
                                           and i in routes
                                           and _loose(routes[i], by_index[i].n_boundary))):
                    # choose by measurement: the patch with crease routes against the patch
                    # faired without them, the smoother seam kept
                    seam = _seam_angle(V1, F1, bf, nF)
                    if i not in no_routes:
                        routed_seam[i] = seam
                        route_stage[i] = stage.get(i, 0)
                        no_routes.add(i)
                        locked.add(i)
                        again = True
                    else:
                        route_done.add(i)
                        if not seam < routed_seam[i]:
                            no_routes.discard(i)
                            goto[i] = route_stage[i]
                            again = True
                        log.info("hole %d: seam %.2f° with crease routes, %.2f° without; "
                                 "keeping the patch %s them", i, routed_seam[i], seam,
                                 "without" if i in no_routes else "with")
                    continue
                if not n_x:
                    # choose by measurement: a planar patch meeting its surround at a kink is
                    # tried again with Liepa's triangulation, and the smoother seam is kept
                    if i in seam_prev and method[i] == "liepa" and i not in locked:
                        seam = _seam_angle(V1, F1, bf, nF)
                        if not seam < seam_prev[i]:
                            log.info("hole %d: the minimum-weight patch's seam (%.1f°) is no "
                                     "smoother than the planar one (%.1f°); keeping the planar",
                                     i, seam, seam_prev[i])
                            revert.append(i)
                        locked.add(i)
                    elif (initial == "bilaplacian" and method[i] == "auto" and i not in locked
                          and rep.n_creases == 0 and not rep.reason.startswith("annulus")
                          and len(_enclose_methods(by_index[i])) > 1):
                        seam, ring = _seam_angle(V1, F1, bf, nF, ring=True)
                        if seam > SEAM_RETRY_FACTOR * ring + SEAM_RETRY_MARGIN:
                            log.info("hole %d: the planar patch meets its surround at %.1f° "
                                     "(surround %.1f°); trying the minimum-weight "
                                     "triangulation", i, seam, ring)
                            seam_prev[i] = seam
                            retry.append(i)
                    continue
                if i in seam_prev and method[i] == "liepa" and i not in locked:
                    locked.add(i)  # the seam trial intersects: back to the planar patch
                    revert.append(i)
                    continue
                dropped[bf] = True
                nxt = stage.get(i, 0) + 1
                if nxt < len(_enclose_methods(by_index[i])) and not rep.reason.startswith(
                        "annulus"):
                    log.info("hole %d: the %s patch intersects the mesh (%d face pairs); "
                             "trying %s", i, method[i], n_x, _enclose_methods(by_index[i])[nxt])
                    retry.append(i)
                    continue
                tried = ", ".join(_METHOD_NAMES[m] for m in _enclose_methods(by_index[i])
                                  ) if not rep.reason.startswith("annulus") else "annulus"
                if rep.reason.startswith("annulus") and i not in unpair:
                    # the loop and the island it was paired with are enclosed separately: an
                    # island found by the planar view can be a hole next to it (a cut near a
                    # statue's flat base)
                    log.info("hole %d: its annulus intersects the mesh (%d face pairs); "
                             "enclosing it and its island separately", i, n_x)
                    unpair.add(i)
                    again = True
                    continue
                if i in known_holes or i in kept_holes:
                    dropped[bf] = False
                    best = fewest.get(i)
                    if best is not None and best[0] < n_x:
                        # an earlier method or fairing fraction intersected less: enclose the
                        # hole with it again and keep that variant
                        final[i] = best[2]
                        goto[i] = best[1]
                        again = True
                        continue
                    note = (f"the patch intersects the surface ({n_x} face pairs; tried: "
                            f"{tried}); kept, not refused (a hole of a closed surface, a selected "
                            "or an uncertain loop): check it")
                    if note not in rep.note:
                        rep.add_note(note)
                        log.warning("hole %d: %s", i, note)
                    continue
                drop[i] = (f"the patch would intersect the surface ({n_x} face pairs; tried: "
                           f"{tried}): the loop is too twisted for a direct fill (e.g. it wraps "
                           "round a thin wall or is the border of an open scan: use "
                           f"keep_border); keep the patch anyway by selecting it (holes=[{i}], "
                           f"CLI --holes {i})")
        t_enclose += tb - ta
        t_initial += time.perf_counter() - tb
        if not retry and not revert and not again:
            break
        for i in retry:
            stage[i] = stage.get(i, 0) + 1
        for i in revert:
            stage[i] = 0
        for i, st in goto.items():
            stage[i] = st
        revert = []
        goto = {}
    if drop:
        V1, F1 = _drop_patches(V1, F1, reports, nV, nF, drop)
    return V1, F1, reports, t_enclose, t_initial
