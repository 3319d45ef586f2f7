"""What a viewer pane shows for a mesh: scalars, highlighted faces, sharp edges, holes/regions."""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.render.framing import Frame, frame_faces, frame_loop
from meshrepair.viewer.page import ViewerMesh

__all__ = ["HIGHLIGHT_ATTRIBUTES", "hole_regions", "mesh_pane", "mesh_regions"]

log = logging.getLogger(__name__)

#: per-vertex 0/1 attributes written by meshrepair commands, highlighted in this order of
#: preference (fill/inpaint write ``filled``, complete writes ``template``)
HIGHLIGHT_ATTRIBUTES = ("filled", "template", "inpainted", "region", "hole", "strip")
MAX_REGIONS = 500


def _is_mask(a: np.ndarray) -> bool:
    return a.dtype == bool or bool(np.all(np.isin(a, (0, 1))))


def mesh_pane(
    V: np.ndarray,
    F: np.ndarray,
    title: str,
    *,
    attributes: Mapping[str, np.ndarray] | None = None,
    highlight: np.ndarray | None = None,
    highlight_label: str | None = None,
    sharp_threshold: float | None = 30.0,
    sharp_mask: np.ndarray | None = None,
) -> ViewerMesh:
    """A :class:`ViewerMesh` with mean curvature, the per-vertex attributes as scalars, the
    highlighted faces and the sharp edges ``M_E``.

    Parameters
    ----------
    V : (nV, 3) float
    F : (nF, 3) int
    title : str
    attributes : dict of str to (nV,) array, optional
        Per-vertex attributes of the mesh file (numeric ones become colour choices).
    highlight : (nF,) bool, optional
        Faces to highlight; default: the faces with a vertex set in the first attribute of
        :data:`HIGHLIGHT_ATTRIBUTES` present (0/1 values; ``filled`` marks the new vertices of
        a fill, so these are its patch faces, except patch faces made of three rim vertices).
    highlight_label : str, optional
        Default: ``"<attribute> faces"``.
    sharp_threshold : float or None
        Dihedral angle (degrees) of the sharp-edge overlay when ``sharp_mask`` is not given;
        None: no overlay.
    sharp_mask : (nE,) bool, optional
        ``M_E`` aligned with ``edge_topology(F).edges`` (e.g. the solver's).
    """
    from meshrepair.mesh.geometry import face_normals, sharp_edge_mask
    from meshrepair.mesh.operators import mean_curvature
    from meshrepair.mesh.topology import edge_topology

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    with np.errstate(all="ignore"):
        scalars = {"mean curvature": mean_curvature(V, F)}
    attrs = dict(attributes or {})
    for name, a in attrs.items():
        arr = np.asarray(a)
        if arr.ndim == 1 and len(arr) == len(V) and (np.issubdtype(arr.dtype, np.number)
                                                     or arr.dtype == bool):
            scalars[str(name)] = arr.astype(np.float64)
    if highlight is None:
        for name in HIGHLIGHT_ATTRIBUTES:
            a = attrs.get(name)
            if a is not None and len(np.ravel(a)) == len(V) and _is_mask(np.ravel(a)):
                m = np.ravel(a).astype(bool)
                if m.any():  # the new (patch) vertices: a patch face has at least one
                    highlight = m[F].any(axis=1)
                    highlight_label = highlight_label or f"{name} faces"
                break
    sharp = None
    topo = edge_topology(F, len(V))
    if sharp_mask is not None:
        m = np.asarray(sharp_mask).ravel()
        if len(m) != topo.n_edges:
            raise MeshRepairError(f"sharp_mask has {len(m)} entries for {topo.n_edges} edges")
        sharp = topo.edges[m > 0.5]
    elif sharp_threshold is not None:
        sharp = topo.edges[sharp_edge_mask(face_normals(V, F), topo, sharp_threshold) > 0.5]
    return ViewerMesh(title, V, F, scalars=scalars, highlight=highlight,
                      highlight_label=highlight_label or "highlighted faces", sharp_edges=sharp)


def _face_components(F: np.ndarray, faces: np.ndarray, nV: int) -> list[np.ndarray]:
    """Face index arrays of the vertex-connected components of ``F[faces]``, largest first."""
    from meshrepair.mesh.topology import connected_components

    if len(faces) == 0:
        return []
    _, labels = connected_components(F[faces], nV)
    lab = labels[F[faces, 0]]
    comps = [faces[lab == k] for k in np.unique(lab)]
    return sorted(comps, key=len, reverse=True)


def mesh_regions(V: np.ndarray, F: np.ndarray, *, highlight: np.ndarray | None = None,
                 label: str = "region", prefix: str = "") -> tuple[list[Frame], list[str]]:
    """Frames of the open holes of a mesh (numbered as ``meshrepair fill --list``) and of the
    connected parts of the highlighted faces; with one description each."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    frames: list[Frame] = []
    details: list[str] = []
    try:
        from meshrepair.holes import find_holes

        holes = find_holes(V, F)
        loops = [(h.index, h.vertices, f"open: {len(h.vertices)} boundary edges, length "
                  f"{h.length:.4g}") for h in holes]
    except MeshRepairError as exc:  # e.g. non-manifold: fall back to the raw boundary loops
        from meshrepair.mesh.topology import boundary_loops

        log.info("hole list of the viewer from raw boundary loops (%s)", exc)
        loops = [(k, lp, f"open: {len(lp)} boundary edges")
                 for k, lp in enumerate(boundary_loops(F, len(V)))]
    for k, loop, what in loops[:MAX_REGIONS]:
        frames.append(frame_loop(V, F, loop, name=f"{prefix}hole {k}"))
        details.append(what)
    if highlight is not None:
        faces = np.flatnonzero(np.asarray(highlight).ravel())
        for k, comp in enumerate(_face_components(F, faces, len(V))[:MAX_REGIONS]):
            frames.append(frame_faces(V, F, comp, name=f"{prefix}{label} {k}"))
            details.append(f"{len(comp)} faces")
    return frames, details


def hole_regions(V: np.ndarray, F: np.ndarray, holes: Sequence) -> tuple[list[Frame], list[str]]:
    """Frames of the holes of a fill/inpaint result, from its ``HoleReport`` records (their
    ``loop`` is numbered in the output mesh ``V, F``)."""
    frames, details = [], []
    for h in list(holes)[:MAX_REGIONS]:
        loop = np.asarray(getattr(h, "loop", np.empty(0)), dtype=np.int64)
        if loop.size == 0:
            continue
        frames.append(frame_loop(V, F, loop, name=f"hole {h.index}"))
        details.append(hole_outcome(h.as_dict() if hasattr(h, "as_dict") else dict(h)))
    return frames, details


def hole_outcome(rec: Mapping) -> str:
    """One-line description of a hole record: ``filled (plane; 12 vertices, 20 faces)`` or
    ``skipped: <reason>``."""
    status = str(rec.get("status", "?"))
    reason = str(rec.get("reason", "") or "")
    if status == "filled":
        return (f"filled ({reason}; {rec.get('n_new_vertices', 0)} vertices, "
                f"{rec.get('n_new_faces', 0)} faces)")
    return f"{status}: {reason}" if reason else status
