"""The repair solve shared by :func:`meshrepair.fill.fill_holes` and
:func:`meshrepair.fill.inpaint` (step 4 of :mod:`meshrepair.fill`): the patches placed by
:mod:`meshrepair.fill.place`, then the ADMM solve (17)-(21) of energy (6) (fill only: the
patches and ``rings`` rings of fixed faces; fill + denoise: the whole mesh) and the final
intersection count."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np

from meshrepair.fill.patches import (
    _blocks,
    _crease_edges,
    _edge_ids,
    _finite_rows,
    _intersecting,
    _ring_faces,
)
from meshrepair.fill.place import _place_patches
from meshrepair.fill.result import FillResult
from meshrepair.holes import self_intersections
from meshrepair.mesh.topology import edge_topology
from meshrepair.model.solver import ADMMSolver, SolverOptions, Stage

log = logging.getLogger("meshrepair.fill")


def _fill_core(V: np.ndarray, F: np.ndarray, holes, skip: dict[int, str], *, denoise: bool,
               initial: str, refine: bool, edge_length: float | None, lam: float | None,
               th: float, a: float, max_iter: int, tol: float, rings: int, relax: float,
               inner_solver: str, inner_iters: int, check: bool,
               callback: Callable[[dict], None] | None,
               progress: Callable[[int, int], None] | None = None,
               creases: bool = True, curvature: bool = True,
               triharmonic: bool = True, fitted: bool = False,
               known_holes: set[int] | frozenset[int] = frozenset(),
               kept_holes: set[int] | frozenset[int] = frozenset(),
               notes: dict[int, str] | None = None) -> FillResult:
    from meshrepair.mesh.geometry import face_normals, sharp_edge_mask

    t0 = time.perf_counter()
    nV, nF = len(V), len(F)
    V1, F1, reports, t_enclose, t_initial = _place_patches(
        V, F, holes, skip, initial=initial, edge_length=edge_length, th=th, check=check,
        progress=progress, creases=creases, curvature=curvature, triharmonic=triharmonic,
        fitted=fitted, known_holes=known_holes, kept_holes=kept_holes)
    for rep in reports:
        if rep.status == "filled" and notes and rep.index in notes:
            rep.add_note(notes[rep.index])
    t2 = time.perf_counter()
    new_v = np.arange(nV, len(V1), dtype=np.int64)
    new_f = np.arange(nF, len(F1), dtype=np.int64)
    M_V = np.ones(len(V1))
    M_V[new_v] = 0.0
    topo = edge_topology(F1, len(V1))
    patch_edges = np.zeros(topo.n_edges, bool)
    patch_edges[topo.face_edges[new_f].ravel()] = True
    edge_force = np.full(topo.n_edges, -1, np.int8)
    edge_force[patch_edges] = 0
    crease_e = _edge_ids(topo, _crease_edges(reports), len(V1))
    edge_force[crease_e] = 1  # routed creases: the MC penalty rebuilds them sharp
    history: list[dict] = []
    iterations = 0
    stop_reason = "no solve"
    params: dict = {"denoise": denoise, "initial": initial, "refine": refine, "th": th}
    M_E = sharp_edge_mask(face_normals(V1, F1), topo, th).astype(bool) & ~patch_edges
    M_E[crease_e] = True
    V_before = V1
    if denoise:
        from meshrepair.model.noise import estimate_noise
        from meshrepair.model.schedule import default_stages, lambda_from_noise

        gamma = estimate_noise(V, F)
        lam_used = lambda_from_noise(gamma) if lam is None else float(lam)
        opts = SolverOptions(lam=lam_used, th=th, stages=default_stages(a=a), tol=tol,
                             inner_solver=inner_solver, inner_iters=inner_iters,
                             mask_update_every=3)
        solver = ADMMSolver(F1, len(V1), M_V=M_V, edge_force=edge_force, options=opts, topo=topo)
        res = solver.solve(V1, callback=callback)
        V1 = res.V
        M_E = np.asarray(res.M_E, bool)
        history, iterations, stop_reason = res.history, res.iterations, res.stop_reason
        params.update(lam=lam_used, noise_estimate=gamma, a=a)
    elif refine and len(new_v):
        # local solve: the patches and `rings` rings of fixed faces around them
        fm = _ring_faces(F1, new_v, len(V1), rings)
        fidx = np.flatnonzero(fm)
        used = np.unique(F1[fidx].ravel())
        loc = -np.ones(len(V1), np.int64)
        loc[used] = np.arange(len(used))
        Fl = loc[F1[fidx]]
        fixed = M_V[used] > 0
        topo_l = edge_topology(Fl, len(used))
        ef = np.full(topo_l.n_edges, -1, np.int8)
        ef[topo_l.face_edges[fidx >= nF].ravel()] = 0
        ce = _crease_edges(reports)
        if len(ce):
            ef[_edge_ids(topo_l, loc[ce], len(used))] = 1
        stage = Stage(a=a, eps=1.2, beta2_ratio=5.0, mask="none", max_iter=max_iter,
                      min_iter=min(max_iter, 30), relax=relax, name="fill")
        opts = SolverOptions(lam=1.0, th=th, stages=(stage,), tol=tol, inner_solver=inner_solver,
                             inner_iters=inner_iters)
        solver = ADMMSolver(Fl, len(used), M_V=M_V[used], edge_force=ef, fixed=fixed,
                            options=opts, topo=topo_l)
        res = solver.solve(V1[used], callback=callback)
        V1 = V1.copy()
        V1[used[~fixed]] = res.V[~fixed]
        V1 = _finite_rows(V1, V_before, new_v, "the ADMM solve")
        history, iterations, stop_reason = res.history, res.iterations, res.stop_reason
        params.update(rings=rings, max_iter=max_iter, relax=relax)
    if creases and len(new_v):
        V1 = _on_surround_planes(V1, F1, holes, reports, nV, nF, th)
    t3 = time.perf_counter()
    if check:
        pairs1 = self_intersections(V1, F1, new_f) if len(new_f) else None
        by_rep = {r.index: r for r in reports}
        for i, (bv, bf) in _blocks(reports, nV, nF).items():
            rep = by_rep[i]
            rep.n_intersections = _intersecting(V1, F1, bf, pairs=pairs1)
            if rep.n_intersections and not denoise and V1 is not V_before:
                # the solve's patch intersects: the initial one is kept unless it intersects
                # more (a kept patch that intersected already)
                solved = V1[bv].copy()
                n_solved = rep.n_intersections
                V1[bv] = V_before[bv]
                rep.n_intersections = _intersecting(V1, F1, bf)
                if n_solved <= rep.n_intersections:
                    V1[bv] = solved
                    rep.n_intersections = n_solved
                else:
                    log.warning("hole %d: the solve made the patch intersect the mesh; kept "
                                "the initial patch", i)
            if rep.n_intersections:
                log.warning("hole %d: %d face pairs of the patch intersect the mesh", i,
                            rep.n_intersections)
    from meshrepair.fill.quality import hole_quality

    hole_quality(V1, F1, reports, nV, nF)
    return FillResult(
        V=V1, F=F1, M_V=M_V, M_E=M_E, edges=topo.edges.copy(),
        history=history, holes=reports, new_vertices=new_v, new_faces=new_f,
        vertex_map=np.arange(nV, dtype=np.int64), iterations=iterations,
        stop_reason=stop_reason, params=params,
        timings={"enclose": t_enclose, "initial": t_initial, "solve": t3 - t2,
                 "total": time.perf_counter() - t0},
    )


def _on_surround_planes(V1, F1, holes, reports, nV: int, nF: int, th: float) -> np.ndarray:
    """Each filled patch whose surround is piecewise planar placed on the envelope of its planes
    (:mod:`meshrepair.holes.envelope`); the others unchanged."""
    from meshrepair.holes.envelope import place_on_planes, surround_planes
    from meshrepair.mesh.geometry import mean_edge_length
    from meshrepair.mesh.topology import vertex_face_incidence

    by_index = {h.index: h for h in holes}
    by_rep = {r.index: r for r in reports}
    vf = vertex_face_incidence(F1, len(V1))
    le = None
    for i, (bv, bf) in _blocks(reports, nV, nF).items():
        h = by_index.get(i)
        if h is None or not len(bv):
            continue
        planes = surround_planes(V1, F1, h.vertices, bf, th, incidence=vf)
        if planes is None:
            continue
        le = mean_edge_length(V1[:nV], F1[:nF]) if le is None else le
        X = place_on_planes(V1, h.vertices, bv, planes, le)
        if X is None:
            continue
        V1 = V1.copy()
        V1[bv] = X
        by_rep[i].reason += f", on the surround's {len(planes)} planes"
        log.info("hole %d: patch placed on the %d planes of its surround", i, len(planes))
    return V1

