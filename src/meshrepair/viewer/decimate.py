"""Display copies of big meshes for the 3-D viewer: vertex clustering (Rossignac-Borrel 1993).

The page embeds every mesh as binary arrays; above a face budget that gets slow to load and to
draw, so the viewer shows a *decimated copy* and says so. Vertex clustering is enough for a
display copy and is a few vectorised numpy passes: snap the vertices to a grid of cell size
``h``, merge the vertices of each cell into their mean, re-index the faces, drop the faces that
collapsed (two corners in one cell) and the duplicates. ``h`` starts at
``h_0 = l_mean * sqrt(nF / budget)`` (a cell holding about ``nF / budget`` original vertices)
and grows by ``max(1.1, sqrt(nF' / budget))`` until at most ``budget`` faces remain. It is not a
quality decimation (no error metric, topology may change); the viewer only uses it to look, the
repair itself always runs on the full mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from meshrepair.errors import MeshRepairError

__all__ = ["Decimation", "cluster_decimate"]


@dataclass
class Decimation:
    """A display copy of a mesh.

    Attributes
    ----------
    V : (nV', 3) float64
    F : (nF', 3) int64
    vertex_map : (nV,) int64
        Vertex of the copy each original vertex was merged into (-1 when its cell holds no
        face of the copy).
    face_origin : (nF',) int64
        An original face each face of the copy comes from.
    cell : float
        Grid cell size used (0 when the mesh was within the budget and is returned unchanged).
    """

    V: np.ndarray
    F: np.ndarray
    vertex_map: np.ndarray
    face_origin: np.ndarray
    cell: float = 0.0

    @property
    def decimated(self) -> bool:
        return self.cell > 0.0

    def vertex_values(self, values: np.ndarray, *, reduce: str = "mean") -> np.ndarray:
        """Per-vertex ``values (nV,)`` of the original mesh carried to the copy (mean or max of
        each cell's finite values; NaN when a cell has none)."""
        v = np.asarray(values, dtype=np.float64).ravel()
        if not self.decimated:
            return v
        n = len(self.V)
        ok = np.isfinite(v) & (self.vertex_map >= 0)
        if reduce == "max":
            out = np.full(n, -np.inf)
            np.maximum.at(out, self.vertex_map[ok], v[ok])
            out[~np.isfinite(out)] = np.nan
            return out
        s = np.bincount(self.vertex_map[ok], weights=v[ok], minlength=n)
        c = np.bincount(self.vertex_map[ok], minlength=n)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(c > 0, s / np.maximum(c, 1), np.nan)

    def edges(self, edges: np.ndarray) -> np.ndarray:
        """Vertex pairs ``(k, 2)`` of the original mesh carried to the copy (collapsed and
        duplicate edges dropped)."""
        e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        if not self.decimated or len(e) == 0:
            return e
        e = np.sort(self.vertex_map[e], axis=1)
        e = e[(e[:, 0] != e[:, 1]) & (e[:, 0] >= 0)]
        return np.unique(e, axis=0)


def cluster_decimate(V: np.ndarray, F: np.ndarray, max_faces: int) -> Decimation:
    """Vertex-clustering display copy with at most ``max_faces`` faces.

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    max_faces : int
        Face budget (>= 100). A mesh within it is returned unchanged (``cell == 0``).

    Returns
    -------
    Decimation
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    max_faces = int(max_faces)
    if max_faces < 100:
        raise MeshRepairError(f"the face budget must be at least 100, got {max_faces}")
    if len(F) <= max_faces:
        return Decimation(V, F, np.arange(len(V), dtype=np.int64),
                          np.arange(len(F), dtype=np.int64))
    lo = V.min(axis=0)
    P = V[F]
    mean_edge = float(np.mean(np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2)))
    extent = float(np.max(V.max(axis=0) - lo))
    cell = max(mean_edge, extent * 1e-6) * np.sqrt(len(F) / max_faces)
    for _ in range(60):
        g = np.floor((V - lo) / cell).astype(np.int64)
        dims = g.max(axis=0) + 1
        key = (g[:, 0] * dims[1] + g[:, 1]) * dims[2] + g[:, 2]
        _, vmap = np.unique(key, return_inverse=True)
        vmap = vmap.ravel().astype(np.int64)
        G = vmap[F]
        ok = (G[:, 0] != G[:, 1]) & (G[:, 1] != G[:, 2]) & (G[:, 0] != G[:, 2])
        keep = np.flatnonzero(ok)
        _, first = np.unique(np.sort(G[keep], axis=1), axis=0, return_index=True)
        keep = keep[np.sort(first)]
        if len(keep) <= max_faces:
            break
        cell *= max(1.1, float(np.sqrt(len(keep) / max_faces)))
    n = int(vmap.max()) + 1
    cnt = np.bincount(vmap, minlength=n).astype(np.float64)
    Vd = np.stack([np.bincount(vmap, weights=V[:, k], minlength=n) for k in range(3)], 1)
    Vd /= cnt[:, None]
    # drop the cells no kept face uses, renumber
    used = np.zeros(n, bool)
    used[G[keep].ravel()] = True
    renum = np.cumsum(used) - 1
    vertex_map = np.where(used[vmap], renum[vmap], -1)
    return Decimation(Vd[used], renum[G[keep]], vertex_map, keep, float(cell))
