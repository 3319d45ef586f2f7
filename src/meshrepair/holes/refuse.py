"""Refusals of a hole's initial patch (§5, the region S_D): a zero-width loop (a seam of
duplicated vertices), a patch lying on the existing surface (the border of an open surface, or
another sheet covering the hole), and a patch intersecting the surface (checked against the faces
near the patch only).
"""

from __future__ import annotations

import numpy as np

from meshrepair.holes.intersect import self_intersections


def _coincident_loop_vertices(V: np.ndarray, loop: np.ndarray) -> tuple[int, int] | None:
    """Two distinct loop vertices at the same position (a zero-width hole along a seam of
    duplicated vertices), or None. O(k log k)."""
    from scipy.spatial import cKDTree

    P = V[loop]
    scale = float(np.ptp(P, axis=0).max()) if len(P) else 0.0
    if not scale > 0:
        return (int(loop[0]), int(loop[1]))
    pairs = cKDTree(P).query_pairs(1e-9 * scale, output_type="ndarray")
    if len(pairs) == 0:
        return None
    i, j = pairs[0]
    return int(loop[i]), int(loop[j])


class _LocalFaces:
    """Faces of a mesh near a box, from precomputed face bounding boxes (so checking one patch
    costs O(nF) vectorised comparisons, not a k-d tree over the whole mesh)."""

    def __init__(self, V: np.ndarray, F: np.ndarray):
        self.V, self.F = V, F
        T = V[F]
        self.lo, self.hi = T.min(axis=1), T.max(axis=1)

    def local(self, Vp, Fp, newV, newF, nV, pad):
        """Local mesh of the faces overlapping the patch box: ``(Vl, Fl, Fpl, interior)`` with
        the existing faces ``Fl``, the patch faces ``Fpl`` and the patch's interior vertices."""
        Vall_new = np.concatenate([*newV, Vp]) if newV else Vp
        Fall_prev = np.concatenate(newF) if newF else np.empty((0, 3), np.int64)

        def pos(idx):
            out = np.empty((len(idx), 3))
            old = idx < nV
            out[old] = self.V[idx[old]]
            out[~old] = Vall_new[idx[~old] - nV]
            return out

        Pp = pos(Fp.ravel())
        lo, hi = Pp.min(axis=0) - pad, Pp.max(axis=0) + pad
        sel = np.flatnonzero(((self.lo <= hi) & (self.hi >= lo)).all(axis=1))
        parts = [self.F[sel]]
        if len(Fall_prev):
            T = pos(Fall_prev.ravel()).reshape(-1, 3, 3)
            ok = ((T.min(axis=1) <= hi) & (T.max(axis=1) >= lo)).all(axis=1)
            parts.append(Fall_prev[ok])
        Fl_g = np.concatenate(parts)
        used = np.unique(np.r_[Fl_g.ravel(), Fp.ravel()])
        loc = {int(g): i for i, g in enumerate(used.tolist())}
        remap = np.vectorize(loc.__getitem__, otypes=[np.int64])
        Vl = pos(used)
        Fl = remap(Fl_g) if len(Fl_g) else np.empty((0, 3), np.int64)
        Fpl = remap(Fp)
        interior = np.flatnonzero(used >= nV + (len(Vall_new) - len(Vp)))
        return Vl, Fl.reshape(-1, 3), Fpl, interior


def _patch_problem(V: np.ndarray, F: np.ndarray, Fp: np.ndarray, interior: np.ndarray,
                   h: float, intersections: bool, border: bool = True,
                   hole: bool = False) -> tuple[str, str]:
    """Reason to refuse a patch (empty string if fine) and a note for a kept one.

    ``border``: the loop is the longest of its component (only such a loop is said to be a
    border). ``hole``: the loop is known to be a hole (the rest of the surface encloses it,
    :mod:`.closure`, or the caller asked for it): a patch lying on the surface is kept, with a
    note saying so, instead of refused.
    """
    from meshrepair.metrics import point_to_surface

    # a few interior vertices near the surface say nothing (a crease corner of a small hole
    # lies close to the surround): the test is for big patches doubling a sheet
    if len(F) and len(interior) >= 8:
        d = point_to_surface(V[interior], V, F)
        near = float(np.mean(d < 0.2 * h))
        if near > 0.5:
            if hole:
                return "", (f"uncertain: {near:.0%} of the patch lies within 0.2 edge lengths "
                            "of the existing surface (a doubled sheet?): check it")
            if border:
                return ("the patch would lie on the existing surface (the loop is probably the "
                        "outer border of an open surface, which the rest of the surface does "
                        "not enclose); fill it anyway by selecting it (holes=[...], CLI "
                        "--holes)"), ""
            return ("the patch would lie on the existing surface (another sheet of the mesh "
                    "covers the hole); fill it anyway by selecting it (holes=[...], CLI "
                    "--holes)"), ""
    if not intersections:
        return "", ""
    Fall = np.r_[F, Fp]
    pairs = self_intersections(V, Fall, np.arange(len(F), len(Fall)))
    if len(pairs):
        return (f"the patch would intersect the surface ({len(pairs)} face pairs): the loop is "
                "too twisted for a direct fill; exclude it or fill it manually"), ""
    return "", ""
