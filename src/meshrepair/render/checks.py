"""Input checks of the renderer: mesh arrays, masks, bounds and per-mesh options."""

from __future__ import annotations

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import edge_topology

_SHADINGS = ("flat", "smooth")


def _check_shading(shading: str) -> None:
    if shading not in _SHADINGS:
        raise MeshRepairError(f"shading must be one of {_SHADINGS}, got {shading!r}")


def _check_mesh(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3:
        raise MeshRepairError(
            f"vertices must have shape (nV, 3), got {V.shape}; pass the (nV, 3) float array of "
            "vertex positions"
        )
    if F.ndim != 2 or F.shape[1] != 3:
        raise MeshRepairError(
            f"faces must have shape (nF, 3), got {F.shape}; triangulate the mesh first"
        )
    if len(F) == 0 or len(V) == 0:
        raise MeshRepairError("cannot render an empty mesh: it needs at least one triangle")
    if not np.issubdtype(F.dtype, np.integer):
        raise MeshRepairError(f"faces must be integer vertex indices, got dtype {F.dtype}")
    F = F.astype(np.int64, copy=False)
    if F.min() < 0 or F.max() >= len(V):
        raise MeshRepairError(
            f"face indices must lie in [0, {len(V) - 1}] (got {F.min()}..{F.max()}); "
            "the face array does not belong to these vertices"
        )
    if not np.all(np.isfinite(V)):
        raise MeshRepairError("vertex coordinates contain NaN or inf; remove or fix those vertices")
    return V, F


def _as_bool_mask(mask: np.ndarray, name: str) -> np.ndarray:
    m = np.asarray(mask)
    if m.ndim != 1:
        raise MeshRepairError(f"{name} must be a 1-D array, got shape {m.shape}")
    if m.dtype == bool:
        return m
    if not np.issubdtype(m.dtype, np.number):
        raise MeshRepairError(f"{name} must be boolean or numeric 0/1, got dtype {m.dtype}")
    return np.nan_to_num(m.astype(np.float64)) > 0.5



def _check_bounds(b: np.ndarray) -> np.ndarray:
    b = np.asarray(b, dtype=np.float64)
    if b.shape != (2, 3) or not np.all(np.isfinite(b)):
        raise MeshRepairError("fit_bounds must be a finite (2, 3) array [min_xyz, max_xyz]")
    return np.stack([b.min(axis=0), b.max(axis=0)])


def _selected_edges(F: np.ndarray, nV: int, edge_mask: np.ndarray | None) -> np.ndarray | None:
    """The ``(k, 2)`` vertex pairs of the edges selected by ``edge_mask`` (validated)."""
    if edge_mask is None:
        return None
    m = _as_bool_mask(edge_mask, "edge_mask")
    edges = edge_topology(F, nV).edges
    if m.shape[0] != len(edges):
        raise MeshRepairError(
            f"edge_mask has {m.shape[0]} entries but the mesh has {len(edges)} edges; build it "
            "aligned with meshrepair.mesh.topology.edge_topology(F).edges"
        )
    return edges[m]


def _face_highlight(F: np.ndarray, nV: int, region_mask: np.ndarray | None) -> np.ndarray | None:
    if region_mask is None:
        return None
    m = _as_bool_mask(region_mask, "region_mask")
    if m.shape[0] == nV:
        return m[F].all(axis=1)
    if m.shape[0] == len(F):
        return m
    raise MeshRepairError(
        f"region_mask has {m.shape[0]} entries; pass one per vertex ({nV}) or per face ({len(F)})"
    )



def _per_mesh(x, n: int, name: str) -> list:
    """Broadcast an option to one entry per mesh (a list/tuple of length n is taken as is)."""
    if x is None:
        return [None] * n
    if isinstance(x, (list, tuple)):
        if len(x) != n:
            raise MeshRepairError(f"{name} has {len(x)} entries for {n} meshes; give one per mesh")
        return list(x)
    if n == 1:
        return [x]
    raise MeshRepairError(f"{name} must be a list with one array (or None) per mesh")
