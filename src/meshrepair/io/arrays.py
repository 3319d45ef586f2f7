"""Meshes given as arrays, a ``trimesh.Trimesh`` or a :class:`MeshData`: :func:`as_arrays`."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..array_contract import _as_face_array, _as_vertex_array
from ..errors import MeshRepairError
from .common import MeshData


def as_arrays(mesh_or_V: Any, F: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Float64/int64 copies of a mesh given as arrays, a trimesh.Trimesh or a MeshData.

    Only dtypes are converted here; use :func:`meshrepair.validate.check_mesh` for shapes and
    topology.

    Parameters
    ----------
    mesh_or_V : (nV, 3) array_like, trimesh.Trimesh or MeshData
    F : (nF, 3) array_like of int, optional
        Required with an array ``V``; must be omitted with a mesh object.

    Returns
    -------
    V : (nV, 3) float64
        A new array (never a view of the caller's data).
    F : (nF, 3) int64
        A new array; integral floats are converted.

    Raises
    ------
    MeshRepairError
        For any other input, missing/extra ``F``, non-numeric arrays or non-integer faces.
    """
    if isinstance(mesh_or_V, MeshData):
        if F is not None:
            raise MeshRepairError("pass either a MeshData or (V, F) arrays, not both")
        V_in, F_in = mesh_or_V.V, mesh_or_V.F
    elif _is_trimesh(mesh_or_V):
        if F is not None:
            raise MeshRepairError("pass either a trimesh.Trimesh or (V, F) arrays, not both")
        V_in, F_in = mesh_or_V.vertices, mesh_or_V.faces
    elif isinstance(mesh_or_V, (np.ndarray, list, tuple)):
        if F is None:
            raise MeshRepairError(
                "missing face array F: pass (V, F) arrays, a trimesh.Trimesh or a MeshData"
            )
        V_in, F_in = mesh_or_V, F
    else:
        raise MeshRepairError(
            f"expected (V, F) arrays, a trimesh.Trimesh or a MeshData, got "
            f"{type(mesh_or_V).__name__}"
        )
    V_out = _as_vertex_array(V_in, "mesh")
    F_out = _as_face_array(F_in, "mesh")
    # never hand back (a view of) the caller's memory
    if V_out is V_in or np.may_share_memory(V_out, V_in):
        V_out = V_out.copy()
    if F_out is F_in or np.may_share_memory(F_out, F_in):
        F_out = F_out.copy()
    return np.ascontiguousarray(V_out), np.ascontiguousarray(F_out)


def _is_trimesh(obj: object) -> bool:
    if not type(obj).__module__.startswith("trimesh"):
        return False
    import trimesh

    return isinstance(obj, trimesh.Trimesh)
