"""The array contract of the public API: ``(V, F)`` as float64 ``(nV, 3)`` and int64 ``(nF, 3)``.

Every public function converts its inputs here before anything else (:mod:`meshrepair.mesh.validate`
then checks the mesh itself). The conversions refuse, with a
:class:`~meshrepair.errors.MeshRepairError` that says what was given and how to fix it:
non-numeric input, booleans, non-integral face indices (integral floats such as ``2.0`` are
accepted and converted), indices that do not fit int64, and arrays of the wrong shape (with a hint
for the usual mistakes: quads, polygons, 2-D points, flat coordinate lists).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from meshrepair.errors import MeshRepairError

_MAX_LISTED = 5  # how many offending elements a message lists


def _first(idx: np.ndarray, k: int = _MAX_LISTED) -> str:
    """Format the first ``k`` entries of an index array for a message."""
    idx = np.asarray(idx)
    head = ", ".join(str(int(i)) for i in idx[:k])
    return f"[{head}{', ...' if len(idx) > k else ''}]"


def _as_vertex_array(V: object, name: str) -> np.ndarray:
    """Convert ``V`` to a float64 array (no shape check); refuse non-numeric input."""
    if V is None:
        raise MeshRepairError(f"{name}: no vertex array given (V is None)")
    try:
        arr = np.asarray(V)
    except Exception as exc:  # ragged lists etc.
        raise MeshRepairError(
            f"{name}: V cannot be converted to an array ({exc}); expected an (nV, 3) float array"
        ) from exc
    if arr.dtype == bool or not (
        np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)
    ):
        raise MeshRepairError(
            f"{name}: V must be a real numeric (nV, 3) array, got dtype {arr.dtype}"
        )
    return arr.astype(np.float64, copy=False)


def _as_face_array(F: object, name: str) -> np.ndarray:
    """Convert ``F`` to an int64 array (no shape check); refuse non-integer values."""
    if F is None:
        raise MeshRepairError(
            f"{name}: no face array given (F is None); a point cloud is not a surface mesh, "
            "reconstruct a triangle mesh first"
        )
    try:
        arr = np.asarray(F)
    except Exception as exc:
        raise MeshRepairError(
            f"{name}: F cannot be converted to an array ({exc}); expected an (nF, 3) integer "
            "array of vertex indices"
        ) from exc
    if np.issubdtype(arr.dtype, np.integer) and arr.dtype != bool:
        if arr.dtype == np.uint64 and arr.size and int(arr.max()) > np.iinfo(np.int64).max:
            raise MeshRepairError(
                f"{name}: face indices out of range (max {int(arr.max())} does not fit int64)"
            )
        return arr.astype(np.int64, copy=False)
    if np.issubdtype(arr.dtype, np.floating):
        integral = np.isfinite(arr) & (arr == np.round(arr))
        if not integral.all():
            rows = integral.reshape(len(integral), -1).all(axis=1) if integral.ndim else integral
            bad = np.flatnonzero(~np.atleast_1d(rows))
            raise MeshRepairError(
                f"{name}: F must hold integer vertex indices, but {int((~integral).sum())} "
                f"entries are non-integer or non-finite (first rows: {_first(bad)}); "
                "pass an integer array (indices start at 0)"
            )
        if arr.size and (np.abs(arr) > 2.0**53).any():
            raise MeshRepairError(f"{name}: face indices out of range (|index| > 2**53)")
        return arr.astype(np.int64)
    raise MeshRepairError(
        f"{name}: F must be an (nF, 3) integer array of vertex indices, got dtype {arr.dtype}"
    )


def _check_shapes(V: np.ndarray, F: np.ndarray, name: str) -> None:
    if V.size == 0:
        raise MeshRepairError(f"{name}: empty mesh: no vertices (V has shape {V.shape})")
    if F.size == 0:
        raise MeshRepairError(
            f"{name}: empty mesh: no faces (F has shape {F.shape}); a point cloud is not a "
            "surface, reconstruct a triangle mesh first"
        )
    if V.ndim != 2 or V.shape[1] != 3:
        hint = ""
        if V.ndim == 2 and V.shape[1] == 2:
            hint = "; for planar data add a zero z column, e.g. np.c_[V, np.zeros(len(V))]"
        elif V.ndim == 1 and V.size % 3 == 0:
            hint = "; a flat coordinate list can be reshaped with V.reshape(-1, 3)"
        raise MeshRepairError(
            f"{name}: expected V of shape (nV, 3) (one x, y, z row per vertex), "
            f"got shape {V.shape}{hint}"
        )
    if F.ndim != 2 or F.shape[1] != 3:
        if F.ndim == 2 and F.shape[1] == 4:
            hint = ("; these look like quads: triangulate them first, e.g. "
                    "np.r_[F[:, [0, 1, 2]], F[:, [0, 2, 3]]]")
        elif F.ndim == 2 and F.shape[1] > 4:
            hint = "; these look like polygons: triangulate them first (e.g. fan triangulation)"
        elif F.ndim == 2 and F.shape[1] < 3:
            hint = ("; faces need 3 vertex indices (edges or points are not a surface; "
                    "a point cloud must be reconstructed into a triangle mesh first)")
        elif F.ndim == 1 and F.size % 3 == 0:
            hint = "; a flat index list can be reshaped with F.reshape(-1, 3)"
        else:
            hint = ""
        raise MeshRepairError(
            f"{name}: expected F of shape (nF, 3) (triangles: 3 vertex indices per face), "
            f"got shape {F.shape}{hint}"
        )


def check_arrays(V, F, *, name: str = "mesh") -> tuple[np.ndarray, np.ndarray]:
    """Light check for functions that need no topology (e.g. :func:`meshrepair.add_noise`):
    float64/int64 copies of ``(V, F)`` with shapes (nV, 3)/(nF, 3), finite vertices and indices
    in range; MeshRepairError otherwise."""
    V, F = as_arrays(V, F)
    _check_shapes(V, F, name)
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise MeshRepairError(f"{name}: {int(bad.sum())} vertices have NaN or infinite "
                              f"coordinates (first: {_first(np.flatnonzero(bad))})")
    if F.min() < 0 or F.max() >= len(V):
        raise MeshRepairError(f"{name}: face indices out of range [0, {len(V) - 1}] (got "
                              f"[{int(F.min())}, {int(F.max())}])")
    return V, F


def as_arrays(mesh_or_V: Any, F: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Float64/int64 copies of a mesh given as arrays, a trimesh.Trimesh or a MeshData.

    Only dtypes are converted here; use :func:`meshrepair.mesh.validate.check_mesh` for shapes and
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
    if _is_meshdata(mesh_or_V):
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


def _is_meshdata(obj: object) -> bool:
    """A :class:`meshrepair.io.MeshData` (checked by name so that this module, below ``io``,
    does not import it)."""
    return type(obj).__name__ == "MeshData" and type(obj).__module__.startswith("meshrepair.io")
