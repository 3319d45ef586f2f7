"""Holes of a triangle mesh: detection, selection and "trivial enclosing" (Sect. 5 of the paper).

Subpackage layout (one concept per module): :mod:`.detect` (loops, selection), :mod:`._geom2d`
(2-D helpers, :class:`Patch`), :mod:`.planar` (planar enclosing of one loop), :mod:`.liepa`
(minimum-weight triangulation), :mod:`.liepa_refine` (its refinement on its own surface),
:mod:`.enclose` (several holes of a mesh; :mod:`.islands`: annuli, :mod:`.refuse`: refused
patches), :mod:`.fairing`, :mod:`.triharmonic` (curvature-continuous fairing), :mod:`.fitted`
(a local surface fitted to a hole's surround and the fairing relative to it),
:mod:`.intersect`.

A *hole* is a simple closed boundary loop. :func:`find_holes` takes the loops of
:func:`meshrepair.mesh.topology.boundary_loops` (which follow the face orientation) and splits a
loop
that passes twice through a pinched vertex (two holes touching at one vertex) into simple loops,
so every hole visits each of its vertices once.

:func:`enclose_loop` builds the initial patch of one hole (the region ``S_D`` of the paper):

1. *2-D domain.* The loop is projected onto the plane orthogonal to its vector area (the plane it
   "looks through"); if that polygon is not simple (a loop folding over itself in that view, e.g.
   a band around a cylinder) the projection onto the least-squares plane is tried, and as a last
   resort the loop is mapped to the unit circle by cumulative arc length (a convex polygon, always
   valid).
2. *Triangulation.* Shewchuk's constrained Delaunay mesher (the ``triangle`` package) meshes the
   polygon with a minimum angle of 28° (``q``) and a maximum triangle area (``a``) chosen so that
   interior edges match the loop's mean edge length; ``Y`` forbids Steiner points on the boundary,
   so the patch boundary is exactly the loop.
3. *Embedding.* Interior vertices get the harmonic interpolation of the loop positions with the
   cotangent weights of the 2-D triangulation (linear precision: a planar loop gives back the
   planar triangulation). The patch traverses every loop edge in the opposite direction, so it is
   consistently oriented with the rest of the mesh.

``enclose_loop(P, method="liepa")`` is the fallback for loops no planar view serves (a reflex
spike of the surround poking into the hole, a hole straddling a sharp crease, a loop wrapping
round a thin wall): :func:`min_weight_triangulation` (Liepa 2003, as in CGAL's
``triangulate_hole`` and MeshLab) triangulates the loop without new vertices, minimising the
largest dihedral angle (against the faces on the loop edges too), then the area, by an O(k³)
dynamic program (numba kernel, numpy twin), or over the facets of the loop's Delaunay
tetrahedralisation only (:mod:`.liepa_delaunay`, CGAL's search space; :func:`enclose_holes`
refines whichever of the two crosses fewer faces of the mesh); that coarse surface is developed
isometrically into the plane (or, when the development overlaps itself, subdivided and laid out on
the unit disc by mean-value coordinates), meshed by Triangle to the edge length and every new
vertex placed back on the coarse surface, which follows the surrounding faces.

:func:`enclose_holes` encloses several holes of one mesh at once (appending the new vertices and
faces), removes chords that would duplicate an existing edge, fills an annulus when a loop is an
island inside another hole, and refuses patches that would intersect or lie on the surface.
:func:`fair_vertices` then moves the new vertices to a bi-Laplacian (least-squares-meshes /
thin-plate) position with the surrounding 1-ring as Dirichlet data, which continues the
surrounding curvature into the hole; the ADMM solve of :mod:`meshrepair.fill` refines it.
:func:`self_intersections` is an exact (up to round-off) triangle-triangle intersection test used
to check patches.
"""

from __future__ import annotations

from meshrepair._kernels import HAVE_NUMBA
from meshrepair.holes._geom2d import Patch
from meshrepair.holes._triangle import MIN_ANGLE
from meshrepair.holes.detect import Hole, HoleReport, _find_holes, find_holes, select_holes
from meshrepair.holes.enclose import _opposite_points, enclose_holes
from meshrepair.holes.fairing import fair_vertices
from meshrepair.holes.intersect import self_intersections
from meshrepair.holes.liepa import LIEPA_MAX_LOOP, min_weight_triangulation
from meshrepair.holes.liepa_refine import LIEPA_CREASE
from meshrepair.holes.planar import ENCLOSE_METHODS, enclose_loop

__all__ = [
    "ENCLOSE_METHODS",
    "HAVE_NUMBA",
    "LIEPA_CREASE",
    "LIEPA_MAX_LOOP",
    "MIN_ANGLE",
    "Hole",
    "HoleReport",
    "Patch",
    "_find_holes",
    "_opposite_points",
    "enclose_holes",
    "enclose_loop",
    "fair_vertices",
    "find_holes",
    "min_weight_triangulation",
    "select_holes",
    "self_intersections",
]
