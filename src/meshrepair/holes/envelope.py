"""The patch of a hole whose surround is piecewise planar, placed on the surround's planes.

Around a hole in a polyhedral part (a box, a prism, a dodecahedron) the faces lie on a few
planes, and the surface that the hole removed is the one those planes bound: where the
part is convex there, the boundary of the intersection of their half-spaces; where it is
concave, of their union. The crease routes of :mod:`.creases` rebuild one corner, two corners
or a straight crease; a hole that swallows a chain of corners (several corners joined by edges
wholly inside it) has more structure than those routes describe, and its faired patch
cuts across the faces. The planes describe it whole.

**Reading** (:func:`surround_planes`). The faces within :data:`RINGS` rings of the loop,
outside the patch, are grouped by their normals (a face joins the first group whose first
face's normal is within :data:`PLANE_TOL` of its own); the surround is piecewise planar when
every group has at least :data:`MIN_FACES` faces and faces of two groups that share an edge
meet at a crease (normals at least the sharp-edge threshold ``th`` apart: a tessellated
cylinder's facets, a few degrees apart, are a curved surface). Each group gives a plane
``n·x = d`` (its mean unit normal, the median offset of its vertices).

**Envelope** (:func:`place_on_planes`). Seen along a direction ``h`` (either orientation of the
loop's vector-area normal), the surface bounded by the planes facing ``h`` (``n_s·h ≥``
:data:`MIN_FACING`) is a height field: a point ``x`` moves to ``x + t h`` with

.. math:: t_s = \\frac{d_s - n_s·x}{n_s·h}, \\qquad t = \\min_s t_s \\text{ (convex)}, \\quad
          t = \\max_s t_s \\text{ (concave)}.

Moving every patch vertex along one direction keeps the patch's triangulation seen along
``h``, so no face turns over. The envelope is used only when the loop itself lies on it (every
loop vertex within :data:`RIM_TOL` mean edge lengths): the loop is data, and a surround whose
planes do not bound it (a curved part) is left to the faired patch; and only when it stays
within the hole's extent (no vertex farther from the loop's centroid than the loop's farthest
vertex): a face of the part wholly inside the hole has no plane in the surround, and without
it the envelope rises towards where the other planes meet.

Everything is in the input's units and invariant to rotation, translation and uniform scale.
"""

from __future__ import annotations

import numpy as np

RINGS = 3
"""Rings of surround faces read around the loop."""
PLANE_TOL = 3.0
"""Degrees: faces whose normals are this close to a group's first face share its plane."""
MIN_FACES = 3
"""Fewest faces of one plane: a smaller group is not a plane of the surround (a curved part
whose every face turns by more than :data:`PLANE_TOL` makes groups of one or two)."""
MIN_FACING = 0.05
"""Least ``n_s·h`` of a plane used along ``h`` (a plane nearly parallel to ``h`` is not a
height field there)."""
RIM_TOL = 0.02
"""Mean edge lengths: the loop lies on the envelope when every loop vertex is this close."""


def surround_planes(V: np.ndarray, F: np.ndarray, loop: np.ndarray, patch_faces: np.ndarray,
                    th: float = 30.0, incidence=None) -> np.ndarray | None:
    """The planes of a piecewise-planar surround (module docstring, *Reading*).

    Parameters
    ----------
    V : (nV, 3) float64; F : (nF, 3) int64, the mesh with the patch
    loop : (k,) int64, the hole's loop vertices
    patch_faces : (m,) int64, the patch's faces (not read as surround)
    th : degrees, the sharp-edge threshold: two planes of the surround meet at a crease, their
        faces across it at a dihedral angle of at least ``th`` (a tessellated cylinder, whose
        facets turn by a few degrees, is a curved surround)
    incidence : the ``(nV, nF)`` vertex-face incidence of ``F``
        (:func:`meshrepair.mesh.topology.vertex_face_incidence`), when the caller has it: the
        rings are then grown locally instead of over every face

    Returns
    -------
    (p, 4) float64 rows ``(n_x, n_y, n_z, d)``, or None when the surround is not piecewise planar
    """
    from meshrepair.mesh.geometry import face_normals
    from meshrepair.mesh.topology import edge_topology, vertex_face_incidence

    vf = vertex_face_incidence(F, len(V)) if incidence is None else incidence
    skip = np.zeros(len(F), bool)
    skip[patch_faces] = True
    verts = np.unique(np.asarray(loop, np.int64))
    idx = np.zeros(0, np.int64)
    for _ in range(RINGS):
        idx = np.unique(vf[verts].indices)
        idx = idx[~skip[idx]]
        verts = np.unique(F[idx].ravel())
    if len(idx) < MIN_FACES:
        return None
    N = face_normals(V, F[idx])
    cos_tol = np.cos(np.radians(PLANE_TOL))
    left = np.ones(len(idx), bool)
    label = np.full(len(idx), -1)
    planes = []
    while left.any():
        first = int(np.flatnonzero(left)[0])
        grp = left & (N @ N[first] >= cos_tol)
        left &= ~grp
        if grp.sum() < MIN_FACES:
            return None
        label[grp] = len(planes)
        n = N[grp].mean(axis=0)
        n /= np.linalg.norm(n)
        d = float(np.median(V[F[idx[grp]]].reshape(-1, 3) @ n))
        planes.append((*n, d))
    # faces of two planes that share an edge meet at a crease
    ef = edge_topology(F[idx], len(V)).edge_faces
    a, b = ef[ef[:, 1] >= 0].T
    cross = label[a] != label[b]
    if np.any(np.einsum("ij,ij->i", N[a[cross]], N[b[cross]]) > np.cos(np.radians(th))):
        return None
    return np.asarray(planes, float)


def place_on_planes(V: np.ndarray, loop: np.ndarray, inner: np.ndarray, planes: np.ndarray,
                    edge_length: float) -> np.ndarray | None:
    """The patch's inner vertices placed on the envelope of ``planes`` (module docstring).

    Parameters
    ----------
    V : (nV, 3) float64, the mesh with the patch
    loop : (k,) int64, the loop's vertices; ``inner`` (q,) int64 the patch's own vertices
    planes : (p, 4) float64, :func:`surround_planes`
    edge_length : the mesh's mean edge length (the unit of :data:`RIM_TOL`)

    Returns
    -------
    (q, 3) float64 new positions of ``inner``, or None when the loop lies on no envelope
    """
    from meshrepair.holes._geom2d import _vector_area, within_reach

    P = V[loop]
    va = _vector_area(P)
    if not np.linalg.norm(va) > 0:
        return None
    nrm, off = planes[:, :3], planes[:, 3]
    best = None
    for h in (va / np.linalg.norm(va), -va / np.linalg.norm(va)):
        facing = nrm @ h >= MIN_FACING
        if not facing.any():
            continue
        ns, ds, nh = nrm[facing], off[facing], nrm[facing] @ h
        t_rim = (ds[None] - P @ ns.T) / nh[None]
        t_in = (ds[None] - V[inner] @ ns.T) / nh[None]
        for pick in (np.min, np.max):  # convex, concave
            miss = float(np.abs(pick(t_rim, axis=1)).max())
            if miss <= RIM_TOL * edge_length and (best is None or miss < best[0]):
                best = (miss, V[inner] + pick(t_in, axis=1)[:, None] * h)
    if best is None:
        return None
    # a plane missing from the surround (a face wholly inside the hole) leaves the envelope
    # rising towards where the others meet, beyond the hole's extent
    return best[1] if within_reach(P)(best[1]) else None
