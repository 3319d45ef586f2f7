"""Enclosing several holes of one mesh: chords, islands (annuli, :mod:`.islands`), refusals
(:mod:`.refuse`)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from itertools import chain

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.holes._geom2d import Patch
from meshrepair.holes.detect import Hole, HoleReport
from meshrepair.holes.intersect import self_intersections
from meshrepair.holes.islands import pair_islands
from meshrepair.holes.liepa import delaunay_optima, delaunay_optimum, min_weight_triangulation
from meshrepair.holes.planar import ENCLOSE_METHODS, _enclose_annulus, enclose_loop
from meshrepair.holes.refuse import _coincident_loop_vertices, _LocalFaces, _patch_problem

log = logging.getLogger(__name__)


def _split_chords(patch: Patch, bad: set[tuple[int, int]]) -> Patch:
    """Split the local edges in ``bad`` (pairs of local indices) at their midpoints."""
    X, T, uv = patch.X.copy(), patch.T.copy(), patch.uv.copy()
    sharp = [tuple(e) for e in patch.sharp_edges.tolist()]
    for a, b in sorted(bad):
        idx = np.flatnonzero((T == a).any(axis=1) & (T == b).any(axis=1))
        if len(idx) != 2:
            continue
        m = len(X)
        X = np.r_[X, 0.5 * (X[a] + X[b])[None]]
        uv = np.r_[uv, 0.5 * (uv[a] + uv[b])[None]]
        new = []
        for f in idx:
            t = T[f].tolist()
            r = t.index(a)
            t = t[r:] + t[:r]  # a first
            if t[1] == b:  # (a, b, c) -> (a, m, c), (m, b, c)
                new += [[a, m, t[2]], [m, b, t[2]]]
            else:  # (a, c, b) -> (a, c, m), (m, c, b)
                new += [[a, t[1], m], [m, t[1], b]]
        T = np.r_[np.delete(T, idx, axis=0), np.asarray(new, dtype=np.int64)]
        if (a, b) in sharp or (b, a) in sharp:
            sharp = [e for e in sharp if set(e) != {a, b}] + [(a, m), (m, b)]
    return Patch(X=X, T=T, uv=uv, method=patch.method, n_loop=patch.n_loop,
                 sharp_edges=np.asarray(sharp, np.int64).reshape(-1, 2),
                 n_creases=patch.n_creases, n_folds=patch.n_folds)


def _opposite_points(V: np.ndarray, F: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Third vertex of the face on each loop edge ``(loop[i], loop[i+1])``, ``(k, 3)`` (NaN rows
    where the edge has no face traversing it in that direction)."""
    n = np.int64(max(int(F.max(initial=0)), int(loop.max())) + 1)
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    third = np.roll(F, -2, axis=1).ravel()
    code = he[:, 0] * n + he[:, 1]
    order = np.argsort(code, kind="stable")
    code = code[order]
    want = loop * n + np.roll(loop, -1)
    pos = np.clip(np.searchsorted(code, want), 0, max(len(code) - 1, 0))
    out = np.full((len(loop), 3), np.nan)
    if len(code):
        hit = code[pos] == want
        out[hit] = V[third[order[pos[hit]]]]
    return out


def _loop_chords(F: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Edges of ``F`` joining two non-consecutive loop vertices, as local pairs ``(q, 2)``."""
    k = len(loop)
    n = max(int(F.max(initial=0)), int(loop.max())) + 1
    local = np.full(n, -1, np.int64)
    local[loop] = np.arange(k)
    Fs = F[(local[F] >= 0).sum(axis=1) >= 2]
    e = local[np.r_[Fs[:, [0, 1]], Fs[:, [1, 2]], Fs[:, [2, 0]]]]
    e = np.sort(e[(e >= 0).all(axis=1)], axis=1)
    d = e[:, 1] - e[:, 0]
    return np.unique(e[(d >= 2) & (d != k - 1)], axis=0)


def _existing_edge_codes(F: np.ndarray, n: int) -> np.ndarray:
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    return np.unique(e[:, 0] * np.int64(n) + e[:, 1])


def enclose_holes(V: np.ndarray, F: np.ndarray, holes: Sequence[Hole],
                  skip: dict[int, str] | None = None, *, edge_length: float | None = None,
                  check: bool = True, intersections: bool = True,
                  method: str | Mapping[int, str] = "auto",
                  creases: Mapping[int, np.ndarray] | None = None,
                  progress: Callable[[int, int], None] | None = None,
                  known_holes: set[int] | frozenset[int] = frozenset(),
                  unpair: set[int] | frozenset[int] = frozenset(),
                  conforming: set[int] | frozenset[int] = frozenset()
                  ) -> tuple[np.ndarray, np.ndarray, list[HoleReport]]:
    """Enclose the selected holes of a mesh with initial (membrane) patches.

    Parameters
    ----------
    V : (nV, 3) float64
    F : (nF, 3) int64
    holes : list of Hole, from :func:`find_holes` on ``(V, F)``
    skip : dict of int to str, optional
        Holes not to fill and why (from :func:`select_holes`).
    edge_length : float, optional
        Target edge length of every patch (default: each loop's mean edge length).
    check : bool
        Refuse (skip, with the reason) a patch that lies on the existing surface (the border of
        an open surface filled a second time).
    intersections : bool
        Also refuse a patch whose membrane position intersects the mesh (with ``check``).
    method : str or mapping of int to str
        How each loop is triangulated (:func:`enclose_loop`: ``"auto"`` or ``"liepa"``), for all
        holes or per hole index (missing indices: ``"auto"``). Islands are always filled as
        planar annuli.
    creases : mapping of int to (q, 2) int, optional
        Per hole index, pairs of loop positions joined by a crease polyline through the patch
        (constrained edges of the planar triangulation, see :mod:`.creases`).
    progress : callable, optional
        Called as ``progress(done, total)`` before each selected hole is enclosed.
    known_holes : set of int
        Loops known to be holes (enclosed by the rest of the surface, or asked for): a patch
        lying on the surface is kept with a note in the report instead of refused.
    unpair : set of int
        Loops never paired with an island (each is enclosed on its own): the caller's retry
        when their annulus intersects the surface.
    conforming : set of int
        Loops whose Liepa patch is meshed with its folds split by Triangle
        (``enclose_loop(conforming=True)``): the caller's retry when the faired patch
        intersects the surface.

    Returns
    -------
    V_new : (nV + m, 3) float64
        ``V`` followed by the new interior vertices (hole by hole).
    F_new : (nF + t, 3) int64
        ``F`` followed by the new faces (hole by hole).
    reports : list of HoleReport, one per hole in ``holes`` order.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    nV = len(V)
    skip = dict(skip or {})
    methods = {h.index: method if isinstance(method, str) else method.get(h.index, "auto")
               for h in holes}
    bad = sorted(set(methods.values()) - set(ENCLOSE_METHODS))
    if bad:
        raise MeshRepairError(f"method must be one of {ENCLOSE_METHODS}, got {bad[0]!r}")
    reports: dict[int, HoleReport] = {}
    by_index = {h.index: h for h in holes}
    longest_of_component: dict[int, int] = {}
    for h in holes:  # holes are sorted longest first
        longest_of_component.setdefault(h.component, h.index)

    partner = {a: b for a, b in pair_islands(V, F, holes).items()
               if a not in unpair and b not in unpair}
    for h in holes:
        if h.index in partner:
            o = partner[h.index]
            if h.length < by_index[o].length:  # h is the island
                if o in skip:
                    skip[h.index] = (f"island inside hole {o}, which is not filled (loop bounds a "
                                     "separate surface piece inside that hole)")
                else:
                    skip.pop(h.index, None)

    code_n = np.int64(1) << np.int64(31)
    edge_set = set(_existing_edge_codes(F, code_n).tolist())
    vf_ptr, vf_idx = _vertex_faces(F, nV)
    fbox = _LocalFaces(V, F)  # face bounding boxes of the input, for local checks
    newV: list[np.ndarray] = []
    newF: list[np.ndarray] = []
    n_added = 0
    notes: dict[int, str] = {}
    todo = [h for h in holes if h.index not in skip]
    n_todo, n_done = len(todo), 0
    for h in holes:
        if h.index in reports:  # an island already reported with its outer loop
            continue
        rep = HoleReport(index=h.index, n_boundary=h.n_boundary, length=h.length,
                         status="skipped", loop=h.vertices.copy())
        reports[h.index] = rep
        if h.index in skip:
            rep.reason = skip[h.index]
            continue
        n_done += 1
        if progress is not None:
            progress(n_done, n_todo)
        log.debug("hole %d (%d/%d): %d boundary edges", h.index, n_done, n_todo, h.n_boundary)
        if h.index in partner and h.length < by_index[partner[h.index]].length:
            rep.reason = (f"island inside hole {partner[h.index]}, which could not be filled "
                          "(see there)")
            continue  # island: handled with its outer loop
        zero = _coincident_loop_vertices(V, h.vertices)
        if zero is not None:
            rep.reason = (f"zero-width hole: loop vertices {zero[0]} and {zero[1]} are at the "
                          "same position (a seam of duplicated vertices); merge duplicate "
                          "vertices (e.g. trimesh merge_vertices) instead of filling it")
            continue
        h_len = edge_length
        try:
            if h.index in partner:
                isl = by_index[partner[h.index]]
                gverts = np.r_[h.vertices, isl.vertices]
                if h_len is None:
                    h_len = (h.length + isl.length) / (h.n_boundary + isl.n_boundary)
                patch = _enclose_annulus(V[h.vertices], V[isl.vertices], h_len)
                if patch is None:
                    rep.reason = (f"hole {isl.index} is an island inside this hole and the "
                                  "region between them could not be triangulated in a planar "
                                  "view; fill it manually or exclude both")
                    reports[isl.index] = HoleReport(
                        index=isl.index, n_boundary=isl.n_boundary, length=isl.length,
                        status="skipped", reason=f"island inside hole {h.index} (see there)",
                        loop=isl.vertices.copy())
                    continue
            elif methods[h.index] == "liepa":
                gverts = h.vertices
                Fcur = np.concatenate([F, *newF]) if newF else F
                opp = _opposite_points(V, F, h.vertices)
                forb = _loop_chords(Fcur, h.vertices)
                patch = enclose_loop(V[h.vertices], edge_length=h_len, method="liepa",
                                     opposite=opp, forbidden=forb,
                                     conforming=h.index in conforming,
                                     coarse=_liepa_coarse(h.vertices, opp, forb, fbox, newV,
                                                          newF, nV))
            else:
                gverts = h.vertices
                cr = None if creases is None else creases.get(h.index)
                patch = enclose_loop(V[h.vertices], edge_length=h_len,
                                     **({} if cr is None else {"creases": cr}))
        except MeshRepairError as exc:
            rep.reason = f"cannot triangulate: {exc}"
            continue
        if not np.isfinite(patch.X).all():
            rep.reason = "degenerate loop: its patch has non-finite positions"
            continue
        k = patch.n_loop
        # chords (patch edges between two loop vertices) must not duplicate an existing edge
        for _ in range(4):
            he = np.sort(np.concatenate([patch.T[:, [0, 1]], patch.T[:, [1, 2]],
                                         patch.T[:, [2, 0]]]), axis=1)
            he, n_faces = np.unique(he, axis=0, return_counts=True)
            chords = he[(he[:, 1] < k) & (n_faces == 2)]  # loop edges have one patch face
            g = np.sort(gverts[chords], axis=1)
            dup = {tuple(c) for c, gc in zip(chords.tolist(), g.tolist(), strict=True)
                   if gc[0] * code_n + gc[1] in edge_set}
            if not dup:
                break
            patch = _split_chords(patch, dup)
        if k == 3 and h.index not in partner:
            inc = F[vf_idx[vf_ptr[gverts[0]]:vf_ptr[gverts[0] + 1]]]
            if (np.sort(inc, axis=1) == np.sort(gverts)).all(axis=1).any():
                rep.reason = ("the loop bounds a single isolated triangle; filling it would "
                              "create a two-sided sliver")
                continue
        m = len(patch.X) - k
        gmap = np.r_[gverts, nV + n_added + np.arange(m)]
        Fp = gmap[patch.T]
        Vp = patch.X[k:]
        if check and m > 0:
            hh = h_len if h_len is not None else h.length / h.n_boundary
            Vl, Fl, Fpl, il = fbox.local(Vp, Fp, newV, newF, nV, pad=2.0 * hh)
            reason, note = _patch_problem(Vl, Fl, Fpl, il, hh, intersections,
                                          border=h.index == longest_of_component[h.component],
                                          hole=h.index in known_holes)
            if reason:
                rep.reason = reason
                continue
            if note:
                log.warning("hole %d: %s", h.index, note)
                notes[h.index] = note
        newV.append(Vp)
        newF.append(Fp)
        n_added += m
        e = np.sort(np.concatenate([Fp[:, [0, 1]], Fp[:, [1, 2]], Fp[:, [2, 0]]]), axis=1)
        edge_set.update((e[:, 0] * code_n + e[:, 1]).tolist())
        rep.status = "filled"
        rep.reason = patch.method
        rep.n_new_vertices = m
        rep.n_new_faces = len(Fp)
        rep.n_folds = patch.n_folds
        if len(patch.sharp_edges):
            rep.sharp_edges = gmap[patch.sharp_edges]
            rep.n_creases = patch.n_creases
            rep.reason += f", {patch.n_creases} crease{'s' if patch.n_creases > 1 else ''}"
        if h.index in notes:
            rep.add_note(notes[h.index])
        if h.index in partner:
            isl = by_index[partner[h.index]]
            rep.reason = f"annulus with island hole {isl.index}"
            reports[isl.index] = HoleReport(
                index=isl.index, n_boundary=isl.n_boundary, length=isl.length, status="filled",
                reason=f"island: filled together with hole {h.index}", loop=isl.vertices.copy())
    Vout = np.concatenate([V, *newV]) if newV else V
    Fout = np.concatenate([F, *newF]) if newF else F
    return Vout, Fout, [reports[h.index] for h in holes]


def _liepa_coarse(loop: np.ndarray, opposite: np.ndarray, forbidden: np.ndarray,
                  fbox: _LocalFaces, newV: list, newF: list, nV: int) -> np.ndarray:
    """Liepa's coarse triangulation of a loop of the mesh: of the minimum-weight triangulations
    over all triangles and over the loop's Delaunay facets
    (:func:`meshrepair.holes.min_weight_triangulation`), the one whose triangles cross fewer
    faces of the mesh (and of the patches placed before), the first on a tie; when both cross,
    the Delaunay-facet optima from the alternative roots
    (:func:`meshrepair.holes.liepa.delaunay_optima`) are tried in turn until one crosses none.

    The weight sees only the loop and the faces on its edges: where its optimum over all
    triangles crosses the surface further away (a long loop winding through space), the
    Delaunay facets, which span the loop's own hull, usually do not; elsewhere the optimum
    follows the surround at least as closely (its largest dihedral angle is the least).
    """
    P = fbox.V[loop]

    def crossings(T: np.ndarray) -> int:
        Vl, Fl, Fpl, _ = fbox.local(np.empty((0, 3)), loop[T], newV, newF, nV, pad=0.0)
        pairs = self_intersections(Vl, np.r_[Fl, Fpl], np.arange(len(Fl), len(Fl) + len(Fpl)))
        return int((pairs.min(axis=1) < len(Fl)).sum()) if len(pairs) else 0

    full = min_weight_triangulation(P, opposite=opposite, forbidden=forbidden, search="all")
    best, n_best = full, crossings(full)
    if n_best == 0:
        return full
    dela = delaunay_optimum(P, opposite=opposite, forbidden=forbidden)
    alternatives = [] if dela is None else [dela]
    alternatives = chain(alternatives, delaunay_optima(P, opposite=opposite,
                                                       forbidden=forbidden))
    for T in alternatives:
        n = crossings(T)
        if n < n_best:
            best, n_best = T, n
        if n == 0:
            break
    return best


def _vertex_faces(F: np.ndarray, nV: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertex -> incident faces in CSR form: faces of ``v`` are ``idx[ptr[v]:ptr[v + 1]]``."""
    flat = F.ravel()
    order = np.argsort(flat, kind="stable")
    ptr = np.r_[0, np.cumsum(np.bincount(flat, minlength=nV))]
    return ptr, order // 3
