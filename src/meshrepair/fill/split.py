"""Loops that are two loops touching at a narrow place: split there by a chord and fill the parts.

When a hole reaches another hole, or the open border of the surface, the two merge into one
boundary loop. Where they meet at a vertex, :func:`meshrepair.holes.detect.find_holes` splits the
loop there (a pinched vertex). Where they meet over a narrow gap, the loop's two sides come close
without touching: a patch over the whole loop has to span both regions and the gap between them,
and the faired surface of such a patch crosses the surface (the two regions face different
ways). The gap is the *narrowest place* of the loop: the pair of loop vertices ``(i, j)``
minimising

    ``|p_i - p_j| / min(arc_ij, arc_ji)``

(chord over the shorter of the two loop arcs between them; 0 at a pinched vertex). A loop whose
narrowest place is below :data:`NECK_RATIO` is cut there by a straight chord of new vertices
(spaced like the loop's edges) into two loops, each split again the same way; every part is then
enclosed, faired and checked by the usual pipeline, the chord vertices fixed on the chord.

A convex or round loop has a narrowest place of at least ``2/π`` (a circle: diameter over half
the perimeter); two discs touching over a gap ``g`` at a distance of ``2r`` have about
``g / (π r)``. The split is tried only for a loop whose whole patch intersects the surface after
every enclosing method (:func:`meshrepair.fill.filling.fill_holes` keeps the split when its parts
intersect the surface less): a merged loop whose whole patch is clean is filled as one, its patch
continues the surround across the gap.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.holes.detect import Hole

log = logging.getLogger("meshrepair.fill")

NECK_RATIO = 0.15
"""A loop is split where its chord / shorter-arc ratio is at most this (see the module
docstring)."""

MIN_ARC = 4.0
"""Both arcs of a split are at least this many of the loop's mean edge lengths (a notch of a few
edges is not a second loop)."""

ROW_BLOCK = 512
"""Rows of the pairwise chord / arc table computed at a time (a loop of thousands of vertices
then needs a few tens of MB, not its whole n² table)."""

MAX_DEPTH = 4
"""Splits of splits, at most."""


def narrowest_place(P: np.ndarray) -> tuple[float, int, int] | None:
    """``(ratio, i, j)`` with ``i < j`` minimising chord / shorter arc over the vertex pairs of the
    closed polygon ``P`` whose arcs both are at least :data:`MIN_ARC` mean edge lengths; None
    when no pair qualifies."""
    n = len(P)
    seg = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1)
    L = float(seg.sum())
    if n < 6 or L <= 0:
        return None
    cum = np.r_[0.0, np.cumsum(seg)][:n]
    best = (np.inf, 0, 0)
    for r0 in range(0, n, ROW_BLOCK):  # rows in blocks: memory O(ROW_BLOCK · n), not O(n²)
        rows = slice(r0, min(r0 + ROW_BLOCK, n))
        A = np.abs(cum[rows, None] - cum[None, :])
        A = np.minimum(A, L - A)
        D = np.linalg.norm(P[rows, None, :] - P[None, :, :], axis=2)
        R = np.where(A >= MIN_ARC * L / n, D / np.maximum(A, 1e-300), np.inf)
        k = int(np.argmin(R))
        i, j = divmod(k, n)
        if R.flat[k] < best[0]:
            best = (float(R.flat[k]), r0 + i, j)
    if not np.isfinite(best[0]):
        return None
    return best[0], min(best[1], best[2]), max(best[1], best[2])


def split_loop(V: np.ndarray, loop: np.ndarray, extra: list[np.ndarray], n_base: int,
               depth: int = 0) -> list[np.ndarray]:
    """Parts of ``loop`` (vertex indices, in order) cut at their narrowest places below
    :data:`NECK_RATIO`; chord vertices are appended to ``extra`` (positions) and numbered from
    ``n_base + (vertices already in extra)``. Every part keeps the loop's orientation."""
    pos = np.concatenate([V, *extra]) if extra else V
    P = pos[loop]
    found = narrowest_place(P) if depth < MAX_DEPTH else None
    if found is None or found[0] > NECK_RATIO:
        return [loop]
    _, i, j = found
    a, b = P[i], P[j]
    h = float(np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean())
    m = max(int(round(float(np.linalg.norm(b - a)) / h)) - 1, 0)
    t = np.linspace(0.0, 1.0, m + 2)[1:-1]
    first = n_base + sum(len(x) for x in extra)
    chord = first + np.arange(m)  # from loop[i] towards loop[j]
    if m:
        extra.append(a + t[:, None] * (b - a))
    # part 1: loop[i..j] then back along the chord; part 2: loop[j..] + loop[..i] then the chord
    p1 = np.r_[loop[i:j + 1], chord[::-1]]
    p2 = np.r_[loop[j:], loop[:i + 1], chord]
    return (split_loop(V, p1, extra, n_base, depth + 1)
            + split_loop(V, p2, extra, n_base, depth + 1))


def split_holes(V: np.ndarray, holes: Sequence[Hole], which: Sequence[int]
                ) -> tuple[np.ndarray, list[Hole], dict[int, list[int]]]:
    """The loops ``which`` split at their narrow places.

    Returns
    -------
    V_aug : (nV + c, 3) float64
        ``V`` followed by the chord vertices.
    holes_aug : list of Hole
        The holes not split, unchanged, then the parts (indices from ``len(holes)`` on).
    parts : dict of int to list of int
        Split hole index -> its parts' indices (only loops that were actually split).
    """
    extra: list[np.ndarray] = []
    parts: dict[int, list[int]] = {}
    nxt = len(holes)
    pieces = {h.index: split_loop(V, h.vertices, extra, len(V)) for h in holes
              if h.index in set(which)}
    V_aug = np.concatenate([V, *extra]) if extra else V
    out: list[Hole] = []
    for h in holes:  # the parts take the place of their loop (the list stays longest first)
        if len(pieces.get(h.index, ())) < 2:
            out.append(h)
            continue
        parts[h.index] = []
        for p in pieces[h.index]:
            length = float(np.linalg.norm(V_aug[p] - V_aug[np.roll(p, -1)], axis=1).sum())
            out.append(Hole(index=nxt, vertices=np.asarray(p, np.int64), length=length,
                            pinched=h.pinched, component=h.component))
            parts[h.index].append(nxt)
            nxt += 1
    return V_aug, out, parts


def retry_split(V: np.ndarray, F: np.ndarray, holes: Sequence[Hole], skip: dict[int, str],
                res, opts: dict, known: set[int], kept: set[int], notes: dict[int, str]):
    """``res`` (a :class:`meshrepair.fill.result.FillResult` of ``holes``) or, when loops whose
    patch intersects the surface split at their narrow places and the parts' patches intersect
    it less, the fill of the split loops (one report per original loop, its reason listing the
    parts)."""
    from meshrepair.fill.core import _fill_core
    from meshrepair.holes import HoleReport

    bad = [r.index for r in res.holes if r.status == "filled" and r.n_intersections > 0]
    if not bad:
        return res
    V_aug, holes2, parts = split_holes(V, holes, bad)
    if not parts:
        return res

    def inherit(s: set[int]) -> set[int]:
        return set(s) | {p for i, ps in parts.items() if i in s for p in ps}

    opts = dict(opts, progress=None)  # the progress bar ran over the holes once
    try:
        res2 = _fill_core(V_aug, F, holes2, skip, **opts, known_holes=inherit(known),
                          kept_holes=inherit(kept), notes=notes)
    except MeshRepairError as exc:  # the retry is optional: the whole loops' fill stands
        log.warning("the fill of the split loops failed (%s); the whole loops' patches are "
                    "kept", exc)
        return res
    by1 = {r.index: r for r in res.holes}
    by2 = {r.index: r for r in res2.holes}
    before = sum(by1[i].n_intersections for i in parts)
    after = sum(by2[p].n_intersections for ps in parts.values() for p in ps)
    if not all(by2[p].status == "filled" for ps in parts.values() for p in ps) or after >= before:
        return res
    nV = len(V)
    reports = []
    for r in res.holes:
        if r.index not in parts:
            reports.append(by2[r.index])
            continue
        ps = [by2[p] for p in parts[r.index]]
        ratio = narrowest_place(V[r.loop])
        main = max(ps, key=lambda x: x.n_new_faces)
        rep = HoleReport(
            index=r.index, n_boundary=r.n_boundary, length=r.length, status="filled",
            reason=(f"split at its narrow places into {len(ps)} loops (chord / arc "
                    f"{ratio[0] if ratio else float('nan'):.3f} <= {NECK_RATIO:g}): "
                    + "; ".join(f"{p.n_boundary} edges {p.reason}" for p in ps)),
            n_new_vertices=sum(p.n_new_vertices for p in ps), loop=r.loop.copy(),
            n_new_faces=sum(p.n_new_faces for p in ps), n_intersections=after,
            n_creases=sum(p.n_creases for p in ps),
            sharp_edges=np.concatenate([p.sharp_edges for p in ps]).reshape(-1, 2),
            quality=dict(main.quality, check=any(p.quality.get("check") for p in ps)))
        if r.index in notes:  # the loop's own note (its border decision), once
            rep.add_note(notes[r.index])
        for p in ps:
            if p.note:
                rep.add_note(f"{p.n_boundary}-edge part: {p.note}")
        reports.append(rep)
    res2.holes = reports
    res2.M_V = res2.M_V.copy()
    res2.M_V[nV:len(V_aug)] = 0.0  # the chord vertices are new
    res2.new_vertices = np.arange(nV, len(res2.V), dtype=np.int64)
    res2.vertex_map = np.arange(nV, dtype=np.int64)
    res2.params["split"] = {int(i): len(ps) for i, ps in parts.items()}
    return res2
