"""Locality (Morton, Z-curve) ordering of a mesh and the edge re-indexing back.

Big meshes are solved on a reordered copy (``meshrepair.denoise.run.REORDER_MIN_VERTICES``): every
kernel is memory-bound there, and vertices and faces that are close in space are then close in
memory. The result is mapped back to the input order exactly.
"""

from __future__ import annotations

import numpy as np


def locality_order(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertex and face permutations along a Morton (Z-order) curve.

    Returns
    -------
    pv : (nV,) int64, new vertex i is old vertex ``pv[i]``
    pf : (nF,) int64, order of the faces (in the renumbered mesh)
    """
    from meshrepair._kernels import face_centroids, morton

    pv = np.argsort(morton(V), kind="stable")
    # the faces' centroids (the renumbering moves no vertex: the same points)
    pf = np.argsort(morton(face_centroids(V, F)), kind="stable")
    return pv, pf


def reordered(Vs: np.ndarray, F: np.ndarray, topo) -> tuple:
    """The Morton order of a large mesh: ``(pv, pf, inv, Fw, topo_w)``, vertex and face
    permutations, the inverse vertex permutation, the renumbered faces and their topology."""
    from meshrepair._kernels import renumbered_faces
    from meshrepair.mesh.topology import permuted_topology

    pv, pf = locality_order(Vs, F)
    inv = np.empty_like(pv)
    inv[pv] = np.arange(len(pv))
    Fw = renumbered_faces(F, inv, pf)
    return pv, pf, inv, Fw, permuted_topology(topo, inv, pf, Fw)


def _edge_values_to(topo, topo_w, pf: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Re-index per-edge ``values`` of the reordered mesh ``topo_w`` (its face m is face
    ``pf[m]`` of ``topo``, corners in the same order) onto ``topo.edges``, through the face-edge
    tables (edge k of a face joins its corners k and k + 1): two gathers instead of a search."""
    out = np.zeros(topo.n_edges, dtype=values.dtype)
    out[topo.face_edges[pf]] = values[topo_w.face_edges]
    return out
