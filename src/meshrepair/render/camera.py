"""The renderer's orthographic camera: axes from angles or a view direction, fitting, aiming.

Camera: orthographic. Without angles or a view direction it shows the object's front with its up
vertical (:mod:`meshrepair.render.autocam`). ``azimuth`` rotates about the vertical ``+y`` axis
and ``elevation`` tilts towards it (degrees); ``azimuth = elevation = 0`` looks from ``+z``
towards ``-z`` with ``+y`` up.
The view is fitted so that the projected mesh (or the ``fit_bounds`` box, or in
:func:`compare_figure` the union of all meshes) fills the picture with a 4 % margin.
A camera can instead be *aimed*: ``view_dir`` (the direction it looks in) replaces the angles,
and ``look_at`` with ``radius`` fits the sphere around that point into the picture (4 % margin)
and, by default, clips away what lies between the camera and the sphere (depth test against the
near plane ``depth(look_at) - radius``). :mod:`meshrepair.render.framing` computes such spheres and
normals for a hole or a region.
"""

from __future__ import annotations

import numpy as np

from meshrepair.errors import MeshRepairError

_MARGIN = 0.04  # fraction of the viewport left empty on each side


def _camera_axes(azimuth: float, elevation: float) -> np.ndarray:
    """Rows: camera right, up and towards-viewer unit vectors, shape ``(3, 3)``."""
    az, el = np.radians(azimuth), np.radians(elevation)
    z = np.array([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)])
    x = np.array([np.cos(az), 0.0, -np.sin(az)])
    y = np.cross(z, x)
    return np.stack([x, y / np.linalg.norm(y), z])


def _box_corners(bounds: np.ndarray) -> np.ndarray:
    """The 8 corners ``(8, 3)`` of an axis-aligned box ``[min_xyz, max_xyz]``."""
    return np.array(
        [[bounds[i, 0], bounds[j, 1], bounds[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )


def _view_window(points: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Projected extent ``[[xmin, ymin], [xmax, ymax]]`` of ``points`` in camera coordinates."""
    p = points @ axes[:2].T
    return np.stack([p.min(axis=0), p.max(axis=0)])


def _project(
    V: np.ndarray, axes: np.ndarray, window: np.ndarray, width: int, height: int
) -> tuple[np.ndarray, float]:
    """Orthographic projection that fits the camera-plane rectangle ``window`` into the image.

    Returns
    -------
    xyz : (nV, 3) screen x, screen y (pixels, y down) and depth (smaller is closer)
    world_per_px : float
    """
    lo, hi = window
    ext = hi - lo
    ext = np.maximum(ext, max(float(ext.max()), 1e-12) * 1e-6)  # degenerate (flat/point) views
    usable = 1.0 - 2.0 * _MARGIN
    ppu = min(usable * width / ext[0], usable * height / ext[1])
    mid = 0.5 * (lo + hi)
    p = V @ axes.T
    xyz = np.empty_like(p)
    xyz[:, 0] = (p[:, 0] - mid[0]) * ppu + 0.5 * width
    xyz[:, 1] = 0.5 * height - (p[:, 1] - mid[1]) * ppu
    xyz[:, 2] = -p[:, 2]
    return xyz, 1.0 / ppu



def _up_for(view_dir, up: np.ndarray | None) -> np.ndarray | None:
    """``up`` unless it is (nearly) along ``view_dir`` (then None: view_axes' own choice)."""
    if up is None:
        return None
    d = np.asarray(view_dir, dtype=np.float64).ravel()
    nd = float(np.linalg.norm(d)) if d.shape == (3,) else 0.0
    if not (nd > 0 and np.all(np.isfinite(d))) or abs(float(d @ up)) / nd > 0.99:
        return None
    return up


def _aim(azimuth, elevation, view_dir, look_at, radius, clip, V=None, F=None):
    """Camera axes, the fitted window (None: fit the mesh) and the near clipping depth.

    Without angles or ``view_dir`` and with a mesh ``(V, F)``, the camera is the object's
    default view (:func:`meshrepair.render.autocam.default_view`: its front, its up); a given
    ``view_dir`` keeps the object's up (:func:`~meshrepair.render.autocam.object_up`) so the
    picture is never upside down. Angles are world angles about ``+y``, as documented."""
    from meshrepair.render.autocam import default_view, object_up
    from meshrepair.render.framing import view_axes

    if view_dir is not None:
        if azimuth is not None or elevation is not None:
            raise MeshRepairError("pass either view_dir or azimuth/elevation, not both")
        up = object_up(V, F) if V is not None and len(F) else None
        axes = view_axes(view_dir, _up_for(view_dir, up))
    elif azimuth is None and elevation is None and V is not None and len(F):
        d, up = default_view(V, F)
        axes = view_axes(d, _up_for(d, up))
    else:
        axes = _camera_axes(azimuth or 0.0, elevation or 0.0)
    if look_at is None:
        if radius is not None:
            raise MeshRepairError("radius needs look_at (the point to frame)")
        return axes, None, -np.inf
    c = np.asarray(look_at, dtype=np.float64).ravel()
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise MeshRepairError(f"look_at must be 3 finite numbers, got {look_at}")
    try:
        r = float(radius)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise MeshRepairError("look_at needs radius=<size of the region to frame>") from exc
    if not (np.isfinite(r) and r > 0):
        raise MeshRepairError(f"radius must be a finite number > 0, got {radius}")
    if V is not None and len(V):
        diag = float(np.linalg.norm(np.ptp(np.asarray(V, dtype=np.float64), axis=0)))
        if r < 1e-9 * diag:  # the picture's scale would round away (pixels of ~1e-16 diag)
            raise MeshRepairError(f"radius {radius} is below 1e-9 of the mesh's size (bounding-box "
                                  f"diagonal {diag:.4g}): frame a region of at least "
                                  f"{1e-9 * diag:.3g}")
    pc = axes[:2] @ c
    window = np.stack([pc - r, pc + r])
    near = float(-(c @ axes[2]) - r) if clip else -np.inf
    return axes, window, near

