"""Open borders of a mesh, recognised by their size relative to the surface they bound.

A scan (or a model cut open) has a border that is not a hole: filling it would cap the whole
surface with a second sheet (a pillow) or cut through it. :func:`find_borders` calls a loop the
*border* of its connected component when all of these hold:

* it is the longest loop of that component (a component has at most one outer border);
* it has at least :data:`BORDER_MIN_EDGES` edges (a small loop is never the border);
* it is large relative to the component's area ``A``: its vector area (the area of its
  projection onto the plane it "looks through", ``|½ Σ p_i × p_{i+1}|``) is at least
  :data:`BORDER_AREA_RATIO` ``A``, or its isoperimetric area ``L² / 4π`` (the largest planar
  region of that perimeter) is at least :data:`BORDER_ISO_RATIO` ``A``.

Why these numbers (measured on the shared meshes with real holes; ratios ``va/A``, ``L²/4πA``):
the borders of the two open scans are at (0.73, 8.7) and (0.73, 5.6) (565 and 1104 edges); the
holes of closed models are at most (0.37, 0.73) (a statue's cut base, 253 edges, which is
filled), the others far below (a cut neck (0.069, 0.080), a small scan hole (0.005, 0.018)).
A crack running all the way round a sphere has ``L² / 4πA = 1``, a single-view height-field scan
of a square has ``va / A ≈ 1`` and ``L² / 4πA ≥ 4/π``. Both thresholds leave a factor of at least
1.35 on either side on the shared meshes.

The two size measures say different things: the vector area measures how one-sided the surface
is (a surface seen from one side, as a scan is, projects onto its border's plane with little
overlap; a body closed apart from its holes has a vector area of only the holes' own projected
area, its normals cancel), the isoperimetric area how long the loop is. A scan's border is large
in both; a loop that only one of them calls large (a long loop of a body whose normals cancel, or
a short loop bounding a one-sided piece of surface) is left open only when the rest of the
surface clearly does not enclose it (enclosure below :data:`UNCERTAIN`); between
:data:`UNCERTAIN` and :data:`ENCLOSED` it is uncertain, and filled with a note.

A loop the size rule calls a border is still a *hole* when the rest of the surface encloses the
region it bounds (:func:`meshrepair.holes.closure.loop_enclosure` at least
:data:`ENCLOSED`): a body closed apart from its holes is never left open because one of them
is large. On the shared meshes the enclosure of the open scans' borders is 0.75-0.79 and that
of the holes of closed bodies at least 0.88 (cut bases, discs of 8 and 24 l̄); :data:`ENCLOSED`
is the midpoint of the gap on one half of the meshes, and the other half falls on the same
sides except one disc of 24 l̄ cut from a small CAD part (0.82), which the size rule does not
call a border either (docs/holes.md lists the readings).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from meshrepair.holes._geom2d import _vector_area
from meshrepair.holes.detect import Hole

BORDER_AREA_RATIO = 0.5
"""A loop whose vector area is at least this fraction of its component's area is a border."""

BORDER_ISO_RATIO = 2.0
"""A loop with ``L² / 4π`` at least this multiple of its component's area is a border."""

BORDER_MIN_EDGES = 10
"""Loops with fewer edges are never called a border."""

ENCLOSED = 0.84
"""A loop whose enclosure (:func:`meshrepair.holes.closure.loop_enclosure`) is at least this is
a hole of a body closed apart from its holes: never a border, never refused."""

UNCERTAIN = 0.6
"""A loop the size rule does not call a border, or calls one by only one of its two measures,
with an enclosure between this and :data:`ENCLOSED`, is uncertain: filled, and a patch
intersecting the surface after every enclosing method is kept with a note (below it, such a
patch is refused). The smallest enclosure of a hole of a closed body measured on the shared
meshes is 0.82; the borders of the open scans, large by both measures, are at 0.75-0.79."""


def component_areas(V: np.ndarray, F: np.ndarray, comp: np.ndarray) -> np.ndarray:
    """Surface area of every connected component (``comp`` is the vertex label array)."""
    a = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    return np.bincount(comp[F[:, 0]], a, minlength=int(comp.max(initial=0)) + 1)


def border_ratios(V: np.ndarray, hole: Hole, area: float) -> tuple[float, float]:
    """``(vector area / A, L² / (4π A))`` of a loop, ``A`` the area of its component."""
    va = float(np.linalg.norm(_vector_area(V[hole.vertices])))
    iso = hole.length ** 2 / (4.0 * np.pi)
    a = max(float(area), 1e-300)
    return va / a, iso / a


def find_borders(V: np.ndarray, F: np.ndarray, holes: Sequence[Hole]) -> dict[int, str]:
    """Loops that are the open border of their component, with the reason.

    Parameters
    ----------
    V : (nV, 3) float64
    F : (nF, 3) int64
    holes : list of Hole, from :func:`meshrepair.holes.find_holes` on ``(V, F)``

    Returns
    -------
    dict of int to str
        Hole index -> why it is taken for the border (see the module docstring for the rule).
    """
    return classify_loops(V, F, holes)[0]


def classify_loops(V: np.ndarray, F: np.ndarray, holes: Sequence[Hole]
                   ) -> tuple[dict[int, str], dict[int, float], dict[int, str]]:
    """Borders (as :func:`find_borders`), the enclosure of every loop, and notes for loops the
    size rule calls a border but the enclosure calls a hole (filled: the report says why).

    Returns
    -------
    borders : dict of int to str
        Hole index -> why it is left open.
    enclosure : dict of int to float
        Hole index -> :func:`meshrepair.holes.closure.loop_enclosure`.
    notes : dict of int to str
        Hole index -> what to tell the user about a filled loop the two rules disagree on.
    """
    if not holes:
        return {}, {}, {}
    from meshrepair.holes.closure import loop_enclosure
    from meshrepair.mesh.topology import connected_components

    enclosure = loop_enclosure(V, F, holes)
    notes: dict[int, str] = {}

    _, comp = connected_components(F, len(V))
    areas = component_areas(V, F, comp)
    longest: dict[int, Hole] = {}
    for h in holes:
        cur = longest.get(h.component)
        if cur is None or h.length > cur.length:
            longest[h.component] = h
    out: dict[int, str] = {}
    for c, h in longest.items():
        if h.n_boundary < BORDER_MIN_EDGES:
            continue
        ra, ri = border_ratios(V, h, areas[c])
        if not (ra >= BORDER_AREA_RATIO or ri >= BORDER_ISO_RATIO):
            continue
        w = enclosure.get(h.index, 0.0)
        both = ra >= BORDER_AREA_RATIO and ri >= BORDER_ISO_RATIO
        if not both and w >= UNCERTAIN and w < ENCLOSED:
            notes[h.index] = (f"uncertain: large loop by one size measure only (projected area "
                              f"{ra:.2f} of the surface's, L²/4π {ri:.2f} of it; an open "
                              f"border is at >= {BORDER_AREA_RATIO:g} and >= "
                              f"{BORDER_ISO_RATIO:g}) and partly enclosed by the rest of the "
                              f"surface (winding {w:.2f}, holes of closed bodies >= "
                              f"{ENCLOSED:g}): filled; check it, or keep it open with "
                              f"exclude=[{h.index}] (CLI --exclude {h.index})")
            continue
        if w >= ENCLOSED:
            notes[h.index] = (f"large loop (projected area {ra:.2f} of the surface's, L²/4π "
                              f"{ri:.2f} of it) but the rest of the surface encloses it "
                              f"(winding {w:.2f} >= {ENCLOSED:g}): filled as a hole; keep it "
                              f"open with exclude=[{h.index}] (CLI --exclude {h.index})")
            continue
        limit = ENCLOSED if both else UNCERTAIN
        out[h.index] = (f"open border of the surface ({h.n_boundary} edges; its projected area "
                        f"is {ra:.2f} of the surface's, L²/4π is {ri:.2f} of it, borders are at "
                        f">= {BORDER_AREA_RATIO:g} or >= {BORDER_ISO_RATIO:g}; the rest of the "
                        f"surface does not enclose it: winding {w:.2f} < {limit:g}"
                        f"{'' if both else ', large by one measure only'}): left open; fill it "
                        f"anyway with holes=[{h.index}] (CLI --holes {h.index})")
    return out, enclosure, notes
