"""Where to look: framing a region, a hole or a point of a mesh for pictures and the 3-D viewer.

A *frame* is a bounding sphere (``center``, ``radius``) and an outward ``normal`` of a part of a
mesh. :func:`meshrepair.render.render_mesh` (``look_at``/``radius``/``view_dir``) and the viewer's
"go to" buttons (:mod:`meshrepair.viewer`) aim their camera with it: the camera looks along
``-normal`` at ``center`` and fits the sphere into the picture.

The normal of a set of faces is their area-weighted mean normal
``n = sum_f A_f n_f / |sum_f A_f n_f|``; for a boundary loop ``v_0 .. v_{k-1}`` (an open hole) it
is the loop's vector area ``(1/2) sum_i v_i x v_{i+1}``, oriented to agree with the faces around
the loop. Both are undefined for a closed or symmetric region (the sum cancels); then
``normal`` is ``None`` and the caller keeps its current view direction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from meshrepair.errors import MeshRepairError

__all__ = ["Frame", "frame_faces", "frame_hole", "frame_vertices", "view_axes"]


@dataclass
class Frame:
    """A part of a mesh to aim a camera at.

    Attributes
    ----------
    name : str
        Label shown to the user (e.g. ``"hole 3 (filled)"``).
    center : (3,) float64
        Centre of the part's bounding box.
    radius : float
        Radius of the sphere around ``center`` that holds the part (> 0).
    normal : (3,) float64 or None
        Unit outward normal to look against, or None when the part has no clear side.
    """

    name: str
    center: np.ndarray
    radius: float
    normal: np.ndarray | None = None

    def as_dict(self) -> dict:
        """Plain Python values (for JSON)."""
        return {"name": self.name, "center": [float(x) for x in self.center],
                "radius": float(self.radius),
                "normal": None if self.normal is None else [float(x) for x in self.normal]}


def _unit(v: np.ndarray) -> np.ndarray | None:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-12 and np.isfinite(n) else None


def _sphere(P: np.ndarray) -> tuple[np.ndarray, float]:
    lo, hi = P.min(axis=0), P.max(axis=0)
    c = 0.5 * (lo + hi)
    r = float(np.sqrt(((P - c) ** 2).sum(axis=1).max())) if len(P) else 0.0
    return c, r


def _floor_radius(V: np.ndarray, r: float) -> float:
    """Never a zero radius: at least 1e-3 of the mesh's bounding-box diagonal."""
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0))) or 1.0
    return max(r, 1e-3 * diag)


def _face_normal_sum(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    P = V[F]
    return 0.5 * np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]).sum(axis=0)


def frame_faces(V: np.ndarray, F: np.ndarray, faces: np.ndarray, name: str = "region") -> Frame:
    """Frame of the faces ``F[faces]`` (index array or boolean ``(nF,)`` mask).

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    faces : (k,) int or (nF,) bool
    name : str

    Returns
    -------
    Frame
        Sphere around the faces' vertices; normal: their area-weighted mean normal.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    idx = _indices(faces, len(F), "faces")
    sub = F[idx]
    c, r = _sphere(V[np.unique(sub)])
    return Frame(name, c, _floor_radius(V, r), _unit(_face_normal_sum(V, sub)))


def frame_vertices(
    V: np.ndarray, F: np.ndarray | None, vertices: np.ndarray, name: str = "region"
) -> Frame:
    """Frame of the vertices ``V[vertices]`` (index array or boolean ``(nV,)`` mask).

    The normal is that of the faces with all three vertices selected (if ``F`` is given and
    there are any), else of the faces touching the selection.
    """
    V = np.asarray(V, dtype=np.float64)
    idx = _indices(vertices, len(V), "vertices")
    c, r = _sphere(V[idx])
    normal = None
    if F is not None:
        F = np.asarray(F, dtype=np.int64)
        sel = np.zeros(len(V), bool)
        sel[idx] = True
        inside = sel[F]
        fm = inside.all(axis=1)
        if not fm.any():
            fm = inside.any(axis=1)
        if fm.any():
            normal = _unit(_face_normal_sum(V, F[fm]))
    return Frame(name, c, _floor_radius(V, r), normal)


def frame_loop(V: np.ndarray, F: np.ndarray, loop: np.ndarray, name: str = "hole") -> Frame:
    """Frame of a boundary loop (ordered vertex indices): the loop's vector area, oriented to
    agree with the faces touching the loop, gives the normal."""
    V = np.asarray(V, dtype=np.float64)
    loop = np.asarray(loop, dtype=np.int64)
    if loop.size == 0 or loop.min() < 0 or loop.max() >= len(V):
        raise MeshRepairError(f"loop of {name!r} has no valid vertex indices")
    P = V[loop]
    c, r = _sphere(P)
    area = 0.5 * np.cross(P, np.roll(P, -1, axis=0)).sum(axis=0)
    n = _unit(area)
    F = np.asarray(F, dtype=np.int64)
    sel = np.zeros(len(V), bool)
    sel[loop] = True
    around = sel[F].any(axis=1)
    ref = _face_normal_sum(V, F[around]) if around.any() else None
    if n is not None and ref is not None and float(n @ ref) < 0:
        n = -n
    if n is None and ref is not None:
        n = _unit(ref)
    return Frame(name, c, _floor_radius(V, r), n)


def frame_hole(V: np.ndarray, F: np.ndarray, index: int) -> Frame:
    """Frame of hole ``index`` as numbered by :func:`meshrepair.holes.find_holes` (longest
    first, the numbering of ``meshrepair fill --list``).

    Raises
    ------
    MeshRepairError
        If the mesh has no such hole.
    """
    from meshrepair.holes import find_holes

    holes = find_holes(V, F)
    if not 0 <= int(index) < len(holes):
        raise MeshRepairError(
            f"hole {index} does not exist: the mesh has {len(holes)} holes (numbered 0.."
            f"{len(holes) - 1}, longest first; list them with 'meshrepair fill MESH --list')"
            if holes else f"hole {index} does not exist: the mesh has no holes (it is closed)")
    h = holes[int(index)]
    return frame_loop(V, F, h.vertices, name=f"hole {h.index}")


def view_axes(view_dir: np.ndarray, up: np.ndarray | None = None) -> np.ndarray:
    """Camera axes for a camera looking along ``view_dir``.

    Parameters
    ----------
    view_dir : (3,) float
        Direction the camera looks in (from the eye towards the scene); ``(0, 0, -1)`` is the
        default view of :func:`meshrepair.render.render_mesh`.
    up : (3,) float, optional
        Rough up direction, default ``+y`` (``+z`` when ``view_dir`` is nearly vertical).

    Returns
    -------
    (3, 3) float64
        Rows: camera right, up, and towards-viewer (``-view_dir``) unit vectors.
    """
    d = np.asarray(view_dir, dtype=np.float64).ravel()
    if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) < 1e-12:
        raise MeshRepairError(f"view direction must be 3 finite numbers, not all 0; got {view_dir}")
    z = -d / np.linalg.norm(d)
    if up is None:
        up = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.99 else np.array([0.0, 0.0, -np.sign(z[1])])
    u = np.asarray(up, dtype=np.float64).ravel()
    x = np.cross(u, z)
    if np.linalg.norm(x) < 1e-9:
        raise MeshRepairError("the up direction is parallel to the view direction")
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z])


def _indices(sel: np.ndarray, n: int, what: str) -> np.ndarray:
    s = np.asarray(sel)
    if s.dtype == bool:
        if s.shape != (n,):
            raise MeshRepairError(f"{what} mask must have {n} entries, got {s.shape}")
        idx = np.flatnonzero(s)
    else:
        if not np.issubdtype(s.dtype, np.integer) and s.size:
            raise MeshRepairError(f"{what} must be integer indices or a boolean mask")
        idx = s.astype(np.int64).ravel()
        if idx.size and (idx.min() < 0 or idx.max() >= n):
            raise MeshRepairError(f"{what} indices must lie in [0, {n - 1}]")
    if idx.size == 0:
        raise MeshRepairError(f"the {what} to frame are empty: select at least one")
    return np.unique(idx)
