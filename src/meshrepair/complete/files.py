"""Completion arguments from the files a user names (the ``complete`` command and batch jobs):
the template (a mesh, a piece of a mesh, or the mirror image), the region (a face list or a
per-vertex mask file), the per-vertex attributes written with a PLY output and where the
template's own vertices are in the result (to keep their colours and texture coordinates)."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.io.masks import read_face_selection

log = logging.getLogger(__name__)

_MASK_SUFFIXES = (".ply", ".npy")


def _selection(path: str, V: np.ndarray, F: np.ndarray) -> dict:
    """``{"region": faces}`` or ``{"region_vertices": mask}`` from a selection file."""
    if Path(path).suffix.lower() in _MASK_SUFFIXES:
        from meshrepair.io.masks import read_vertex_mask

        return {"region_vertices": read_vertex_mask(path, len(V))}
    return {"region": read_face_selection(path, len(F))}


def complete_arguments(mesh, tmesh, options: dict) -> tuple:
    """``(template, kw)`` for :func:`meshrepair.complete` from the read meshes (``tmesh`` None
    with ``mirror``) and :func:`complete_options`' values (selection files are read here)."""
    from meshrepair.complete.api import extract_patch

    kw = dict(options)
    region, hole, template_region = kw.pop("region"), kw.pop("hole"), kw.pop("template_region")
    mirror = bool(kw.pop("mirror", False))
    if mirror:
        if template_region is not None or kw.get("transform") is not None:
            raise MeshRepairError("--mirror finds the template itself: drop --template-region "
                                  "and --transform")
        template = "mirror"
    elif tmesh is None:
        raise MeshRepairError("complete needs a template mesh (or --mirror)")
    elif template_region is not None:
        sel = _selection(template_region, tmesh.V, tmesh.F)
        if "region" in sel:
            faces = sel["region"]
        else:
            faces = np.flatnonzero(sel["region_vertices"][tmesh.F].all(axis=1))
            if faces.size == 0:
                raise MeshRepairError("--template-region selects no face of the template")
        extract_patch(tmesh.V, tmesh.F, faces)  # a clear error for an empty/invalid selection
        # a piece of a mesh: its context rings around the selection take part in the alignment
        template = (tmesh.V, tmesh.F, faces)
    else:
        template = (tmesh.V, tmesh.F)
    if region is not None:
        kw.update(_selection(region, mesh.V, mesh.F))
    elif hole is not None:
        kw["hole"] = hole
    else:
        raise MeshRepairError("complete needs --region FILE or --hole K")
    return template, kw


def output_attributes(res, out: str | Path) -> dict | None:
    """Per-vertex m_v, strip and template attributes written with a PLY output (else None)."""
    if Path(out).suffix.lower() != ".ply":
        return None
    nV = len(res.V)
    strip = np.zeros(nV, np.uint8)
    strip[res.strip_vertices] = 1
    tmpl = np.zeros(nV, np.uint8)
    tmpl[res.template_vertices] = 1
    return {"m_v": res.M_V.astype(np.float32), "strip": strip, "template": tmpl}


def template_vertex_map(tmesh, template, res) -> np.ndarray | None:
    """Pairs ``(template file vertex, result vertex)`` for the template's interior vertices.

    The result holds the template's interior vertices in the order of the template's used
    vertices (after the vertices of the input and those inserted on the seam), then the
    vertices added by splitting ears (:mod:`meshrepair.complete`); None for a mirror template
    or when the counts do not agree (the template's values are then interpolated).
    """
    from meshrepair.mesh.topology import boundary_loops

    if tmesh is None or not isinstance(template, tuple):
        return None
    F = tmesh.F if len(template) == 2 else tmesh.F[np.asarray(template[2])]
    used = np.zeros(len(tmesh.V), bool)
    used[F.ravel()] = True
    idx = np.flatnonzero(used)
    loops = boundary_loops((np.cumsum(used) - 1)[F], len(idx))
    if len(loops) != 1:
        return None
    interior = np.ones(len(idx), bool)
    interior[loops[0]] = False
    tv, n = res.template_vertices, int(interior.sum())
    if len(tv) != n + int(res.correspondence.get("ears_split", 0)):
        log.warning("the template's vertices could not be matched in the result: its "
                    "attributes are interpolated from the border instead")
        return None
    return np.stack([idx[interior], tv[:n]], axis=1)
