"""Enclosing several holes of one mesh: chords, islands (annuli), refusals."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import MeshRepairError
from ._geom2d import Patch, _plane_frame, _polygon_is_simple, _vector_area
from .detect import Hole, HoleReport
from .intersect import self_intersections
from .planar import ENCLOSE_METHODS, _enclose_annulus, enclose_loop


def _split_chords(patch: Patch, bad: set[tuple[int, int]]) -> Patch:
    """Split the local edges in ``bad`` (pairs of local indices) at their midpoints."""
    X, T, uv = patch.X.copy(), patch.T.copy(), patch.uv.copy()
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
    return Patch(X=X, T=T, uv=uv, method=patch.method, n_loop=patch.n_loop)


def _loop_side_points(V: np.ndarray, F: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Centroids of the faces bordering the loop edges, shape ``(k, 3)``."""
    sel = np.isin(F, loop).sum(axis=1) >= 2
    Fs = F[sel]
    third = {}
    for f in Fs.tolist():
        for j in range(3):
            third[(f[j], f[(j + 1) % 3])] = f[(j + 2) % 3]
    nxt = np.roll(loop, -1)
    w = np.array([third.get((u, v), -1) for u, v in zip(loop.tolist(), nxt.tolist(),
                                                          strict=True)])
    ok = w >= 0
    return (V[loop[ok]] + V[nxt[ok]] + V[w[ok]]) / 3.0


def _nested_in(V: np.ndarray, F: np.ndarray, outer: Hole, inner: Hole) -> bool:
    """True when loop ``inner`` lies inside the hole bounded by ``outer`` (an island)."""
    Po, Pi = V[outer.vertices], V[inner.vertices]
    lo, hi = Po.min(axis=0), Po.max(axis=0)
    pad = 0.5 * float((hi - lo).max())
    if (Pi < lo - pad).any() or (Pi > hi + pad).any():
        return False
    va = _vector_area(Po)
    if not np.linalg.norm(va) > 0:
        return False
    n = -va / np.linalg.norm(va)
    c = Po.mean(axis=0)
    rad = float(np.linalg.norm(Po - c, axis=1).max())
    if np.abs((Pi - c) @ n).max() > 0.5 * rad:
        return False
    e1, e2 = _plane_frame(n)

    def proj(X):
        return np.c_[(X - c) @ e1, (X - c) @ e2]

    Qo, Qi = proj(Po), proj(Pi)
    if not _polygon_is_simple(Qo):
        return False
    from matplotlib.path import Path as MPath

    poly = MPath(Qo)
    if not poly.contains_points(Qi).all():
        return False
    # a hole has its surface outside the loop (a border of a surface piece has it inside)
    side = _loop_side_points(V, F, outer.vertices)
    if len(side) == 0 or poly.contains_points(proj(side)).mean() > 0.5:
        return False
    # an island boundary turns the other way round than the hole it sits in
    area_i = 0.5 * float(np.sum(Qi[:, 0] * np.roll(Qi[:, 1], -1) - np.roll(Qi[:, 0], -1)
                                * Qi[:, 1]))
    return area_i > 0


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
                  method: str | Mapping[int, str] = "auto"
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

    # islands: a loop nested inside another hole is filled together with it as an annulus
    partner: dict[int, int] = {}
    for ho in holes:
        for hi in holes:
            if hi.index == ho.index or hi.index in partner or ho.index in partner:
                continue
            if hi.length < ho.length and _nested_in(V, F, ho, hi):
                partner[ho.index] = hi.index
                partner[hi.index] = ho.index
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
    newV: list[np.ndarray] = []
    newF: list[np.ndarray] = []
    n_added = 0
    Vcur = V
    Fcur = F
    for h in holes:
        if h.index in reports:  # an island already reported with its outer loop
            continue
        rep = HoleReport(index=h.index, n_boundary=h.n_boundary, length=h.length,
                         status="skipped", loop=h.vertices.copy())
        reports[h.index] = rep
        if h.index in skip:
            rep.reason = skip[h.index]
            continue
        if h.index in partner and h.length < by_index[partner[h.index]].length:
            rep.reason = (f"island inside hole {partner[h.index]}, which could not be filled "
                          "(see there)")
            continue  # island: handled with its outer loop
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
                patch = enclose_loop(V[h.vertices], edge_length=h_len, method="liepa",
                                     opposite=_opposite_points(V, F, h.vertices),
                                     forbidden=_loop_chords(Fcur, h.vertices))
            else:
                gverts = h.vertices
                patch = enclose_loop(V[h.vertices], edge_length=h_len)
        except MeshRepairError as exc:
            rep.reason = f"cannot triangulate: {exc}"
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
            tri = np.sort(gverts)
            if (np.sort(Fcur, axis=1) == tri).all(axis=1).any():
                rep.reason = ("the loop bounds a single isolated triangle; filling it would "
                              "create a two-sided sliver")
                continue
        m = len(patch.X) - k
        gmap = np.r_[gverts, nV + n_added + np.arange(m)]
        Fp = gmap[patch.T]
        Vp = patch.X[k:]
        if check and m > 0:
            Vtry = np.r_[Vcur, Vp]
            reason = _patch_problem(Vtry, Fcur, Fp, np.arange(nV + n_added, nV + n_added + m),
                                    h_len if h_len is not None else h.length / h.n_boundary,
                                    intersections)
            if reason:
                rep.reason = reason
                continue
        newV.append(Vp)
        newF.append(Fp)
        n_added += m
        Vcur = np.r_[Vcur, Vp]
        Fcur = np.r_[Fcur, Fp]
        e = np.sort(np.concatenate([Fp[:, [0, 1]], Fp[:, [1, 2]], Fp[:, [2, 0]]]), axis=1)
        edge_set.update((e[:, 0] * code_n + e[:, 1]).tolist())
        rep.status = "filled"
        rep.reason = patch.method
        rep.n_new_vertices = m
        rep.n_new_faces = len(Fp)
        if h.index in partner:
            isl = by_index[partner[h.index]]
            rep.reason = f"annulus with island hole {isl.index}"
            reports[isl.index] = HoleReport(
                index=isl.index, n_boundary=isl.n_boundary, length=isl.length, status="filled",
                reason=f"island: filled together with hole {h.index}", loop=isl.vertices.copy())
    return Vcur, Fcur, [reports[h.index] for h in holes]


def _patch_problem(V: np.ndarray, F: np.ndarray, Fp: np.ndarray, interior: np.ndarray,
                   h: float, intersections: bool) -> str:
    """Reason to refuse a patch (empty string if fine)."""
    from ..metrics import point_to_surface

    d = point_to_surface(V[interior], V, F)
    if np.mean(d < 0.2 * h) > 0.5:
        return ("the patch would lie on the existing surface (the loop is probably the outer "
                "border of an open surface: use keep_border or exclude it)")
    if not intersections:
        return ""
    Fall = np.r_[F, Fp]
    pairs = self_intersections(V, Fall, np.arange(len(F), len(Fall)))
    if len(pairs):
        return (f"the patch would intersect the surface ({len(pairs)} face pairs): the loop is "
                "too twisted for a direct fill; exclude it or fill it manually")
    return ""
