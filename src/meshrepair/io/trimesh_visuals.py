"""A ``trimesh.Trimesh`` with its visuals to and from :class:`MeshData`.

Colours: trimesh's per-vertex colours (``visual.kind == "vertex"``) are ``red, green, blue,
alpha`` uchar vertex attributes; per-face colours (``"face"``) the same names as face
attributes. Textures: ``TextureVisuals`` per-vertex ``uv`` are the ``s, t`` vertex attributes,
and the material object is handed back unchanged by :func:`to_trimesh`. Vertex order and faces
are kept (``process=False``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from meshrepair.io.attributes import uv_pair
from meshrepair.io.common import MeshData

__all__ = ["from_trimesh", "to_trimesh", "is_trimesh"]

_RGBA = ("red", "green", "blue", "alpha")


def is_trimesh(obj: object) -> bool:
    """True for a ``trimesh.Trimesh`` (without importing trimesh for other objects)."""
    if not type(obj).__module__.startswith("trimesh"):
        return False
    import trimesh

    return isinstance(obj, trimesh.Trimesh)


def from_trimesh(mesh: Any) -> MeshData:
    """A :class:`MeshData` with the mesh's vertices, faces, colours and texture coordinates."""
    V = np.asarray(mesh.vertices, dtype=np.float64).copy()
    F = np.asarray(mesh.faces, dtype=np.int64).copy()
    out = MeshData(V=V, F=F)
    vis = mesh.visual
    kind = getattr(vis, "kind", None)
    if kind == "vertex":
        C = np.asarray(vis.vertex_colors, dtype=np.uint8)
        out.vertex_attributes.update({n: C[:, k].copy() for k, n in enumerate(_RGBA)})
    elif kind == "face":
        C = np.asarray(vis.face_colors, dtype=np.uint8)
        out.face_attributes.update({n: C[:, k].copy() for k, n in enumerate(_RGBA)})
    elif kind == "texture" and getattr(vis, "uv", None) is not None and len(vis.uv) == len(V):
        uv = np.asarray(vis.uv, dtype=np.float64)
        out.vertex_attributes.update({"s": uv[:, 0].copy(), "t": uv[:, 1].copy()})
    return out


def to_trimesh(mesh: MeshData, material: Any = None) -> Any:
    """A ``trimesh.Trimesh`` (``process=False``) with colour or texture visuals from ``mesh``'s
    attributes: per-vertex colours, else per-face colours, else per-vertex texture
    coordinates with ``material`` (a trimesh material, e.g. the source mesh's)."""
    import trimesh

    va, fa = mesh.vertex_attributes, mesh.face_attributes
    visual = None
    if all(n in va for n in _RGBA[:3]):
        visual = trimesh.visual.ColorVisuals(vertex_colors=_rgba(va, len(mesh.V)))
    elif all(n in fa for n in _RGBA[:3]):
        visual = trimesh.visual.ColorVisuals(face_colors=_rgba(fa, len(mesh.F)))
    elif uv_pair(va) is not None:
        s, t = uv_pair(va)
        uv = np.stack([np.asarray(va[s], np.float64), np.asarray(va[t], np.float64)], axis=1)
        visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
    return trimesh.Trimesh(mesh.V, mesh.F, visual=visual, process=False)


def _rgba(attrs: dict, n: int) -> np.ndarray:
    cols = []
    for name in _RGBA:
        a = np.asarray(attrs.get(name, np.full(n, 255)))
        if a.dtype.kind == "f":
            a = np.clip(np.rint(a * 255.0), 0, 255)
        cols.append(a.astype(np.uint8))
    return np.stack(cols, axis=1)
